"""scripts/deploy-check (docs/deploy.md "Checking the recipe on a clean machine"): the blocks it takes from the
doc and the export check it runs. The check itself needs root, debootstrap and the network (not run here)."""
from __future__ import annotations

import csv
import importlib.util
import json
import pathlib
import re
import subprocess

from click.testing import CliRunner

ROOT = pathlib.Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "scripts" / "deploy-check"
DOC = ROOT / "docs" / "deploy.md"


def _browser_module():
    spec = importlib.util.spec_from_file_location("deploy_check_browser", ROOT / "scripts" / "deploy_check_browser.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_check_runs_every_marked_block_of_the_doc_in_order():
    out = subprocess.run(["bash", str(SCRIPT), "--print-blocks"], capture_output=True, text=True, check=True).stdout
    names = re.findall(r"^# --- block '(\w+)'$", out, re.M)
    assert names == ["install", "database", "configure", "start", "backup", "restore"]
    # every marker in the doc is run by the check, and each marks a shell block
    assert sorted(re.findall(r"<!-- deploy-check: (\w+) -->\n```sh\n", DOC.read_text())) == sorted(names)
    blocks = dict(zip(names, re.split(r"^# --- block '\w+'\n", out, flags=re.M)[1:]))
    assert "pip install \"/opt/evalsuite/src[serve,postgres]\"" in blocks["install"]
    assert "systemctl daemon-reload && systemctl enable --now evalsuite-study" in blocks["start"]
    assert "runuser -u evalsuite -- pg_restore --no-owner" in blocks["restore"]
    subprocess.run(["bash", "-n"], input=out, text=True, check=True)          # the blocks are valid bash


def test_a_missing_marker_is_an_error(tmp_path):
    (tmp_path / "scripts").mkdir()
    (tmp_path / "docs").mkdir()
    (tmp_path / "scripts" / "deploy-check").write_text(SCRIPT.read_text())
    (tmp_path / "docs" / "deploy.md").write_text(DOC.read_text().replace("<!-- deploy-check: backup -->", ""))
    r = subprocess.run(["bash", str(tmp_path / "scripts" / "deploy-check"), "--print-blocks"],
                       capture_output=True, text=True)
    assert r.returncode == 1 and "no block <!-- deploy-check: backup -->" in r.stderr


def test_help_describes_every_option():
    out = subprocess.run(["bash", str(SCRIPT), "--help"], capture_output=True, text=True, check=True).stdout
    parsed = re.findall(r"^ +(--[a-z-]+)\)", SCRIPT.read_text(), re.M)       # the option parser's cases
    assert len(parsed) == 7
    for option in parsed:
        assert re.search(rf"^  {option}\b.* {{2,}}\w", out, re.M), option


def _export(tmp_path, rows):
    path = tmp_path / "results.csv"
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    return path


def test_check_export_accepts_the_participants_answers_and_refuses_others(tmp_path):
    mod = _browser_module()
    done = tmp_path / "participant.json"
    done.write_text(json.dumps({"session": "S1", "code": mod.CODE, "videos": 4,
                                "answers": [{"trial": 1, "choice": "left"}, {"trial": 2, "choice": "right"}]}))
    raw = tmp_path / "raw.json"
    raw.write_text('{"sessions": [{"id": "S1"}]}')

    def row(trial, position_a, answer, implausible="0", session="S1"):
        return {"participant": mod.PID, "session": session, "session_status": "finished", "trial": trial,
                "question": "human_likeness", "position_a": position_a, "answer": answer,
                "playback_implausible": implausible, "playback_reason": ""}

    good = [row(1, "left", "a"), row(2, "left", "b"), row(1, "left", "b", session="S2")]
    ok = CliRunner().invoke(mod.main, ["check-export", str(done), str(_export(tmp_path, good)), str(raw)])
    assert ok.exit_code == 0, ok.output
    assert "2 answers of session S1" in ok.output
    for bad, says in [([row(1, "left", "a"), row(2, "right", "b")], "trial 2: answer 'b'"),
                      ([row(1, "left", "a")], "trial 2: no row"),
                      ([row(1, "left", "a"), row(2, "left", "b", implausible="1")], "trial 2: playback '1'")]:
        r = CliRunner().invoke(mod.main, ["check-export", str(done), str(_export(tmp_path, bad)), str(raw)])
        assert r.exit_code == 1 and says in r.output, r.output
