"""docs/study_app.md: the documented way to script participants runs, as written, against a served study."""
from __future__ import annotations

import json
import pathlib
import re
import subprocess
import sys
import threading
import urllib.request

import study_helpers as h
from study_fixtures import make_app
from werkzeug.serving import make_server

DOC = pathlib.Path(__file__).resolve().parents[1] / "docs" / "study_app.md"


def documented_example() -> str:
    """The Python block of section 5b (Scripting participants)."""
    text = DOC.read_text(encoding="utf-8")
    section = text.split("## 5b. Scripting participants", 1)[1].split("\n## ", 1)[0]
    (code,) = re.findall(r"```python\n(.*?)```", section, re.S)
    return code


# Every page kind but the headphone check, whose guesses would screen the script out after its third page
# (its answers are accepted: the page is answered, then the participant is screened out), and attention
# checks that random answers may fail without ending the session.
STUDY = h.STUDY_YAML.format(sessions=6).replace(
    "  - type: headphone_check\n    id: headphones\n    trials: 2\n    pass: 2\n", "").replace(
    "max_failed_attention_checks: 2", "max_failed_attention_checks: 10")


def test_the_documented_participant_script_completes_the_study(tmp_path):
    assert "headphone_check" not in STUDY and "max_failed_attention_checks: 10" in STUDY
    h.make_study(tmp_path, yaml_text=STUDY)
    app = make_app(tmp_path, f"sqlite:///{tmp_path / 'study.db'}")
    server = make_server("127.0.0.1", 0, app, threaded=True)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        script = tmp_path / "simulate.py"
        script.write_text(documented_example(), encoding="utf-8")
        base = f"http://127.0.0.1:{server.server_port}"
        run = subprocess.run([sys.executable, str(script), base, "gesture-test", "2"], capture_output=True,
                             text=True, timeout=120)
        assert run.returncode == 0, run.stderr
        reported = dict(line.split(": ") for line in run.stdout.splitlines())
        request = urllib.request.Request(f"{base}/admin/export/raw.json",
                                         headers={"Authorization": f"Bearer {h.ADMIN}"})
        raw = json.loads(urllib.request.urlopen(request, timeout=30).read())
    finally:
        server.shutdown()
        thread.join(10)
    assert len(reported) == 2
    participant_of = {s["id"]: s["participant"] for s in raw["sessions"]}
    answers_by_participant: dict[str, int] = {}
    for a in raw["answers"]:
        pid = participant_of[a["session"]]
        answers_by_participant[pid] = answers_by_participant.get(pid, 0) + 1
    assert {pid: f"{n} answers stored" for pid, n in answers_by_participant.items()} == reported
    total = len(h.plan_pages(app, raw["answers"][0]["session"]))
    # every page was answered (a page kind the script cannot answer would have stopped it with a 422)
    assert set(answers_by_participant.values()) == {total - 1}, (answers_by_participant, total)  # all but finish
