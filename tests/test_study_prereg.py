"""`evalsuite study prereg`: a pre-registration draft with every OSF Preregistration item, filled from the
definition, its plans, the sample-size plan and analyze's settings (tested on the demo study)."""
from __future__ import annotations

import re

import pytest
import yaml
from click.testing import CliRunner

from evalsuite.cli import main
from study_app.definition import load_study
from study_app.prereg import ITEMS, TODO


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    from study_app.demo import _stimuli, study_definition

    root = tmp_path_factory.mktemp("prereg")
    target = root / "study"
    target.mkdir()
    manifest = _stimuli(root, target, lambda *a: None)
    (target / "study.yaml").write_text(yaml.safe_dump(study_definition(manifest, target), sort_keys=False))
    return target / "study.yaml"


def _items(text: str) -> dict[str, str]:
    parts = re.split(r"^### (.+)$", text, flags=re.MULTILINE)
    return {name.strip(): body.strip() for name, body in zip(parts[1::2], parts[2::2])}


def test_every_item_is_present_and_filled_from_the_definition(demo, tmp_path):
    out = tmp_path / "prereg.md"
    r = CliRunner().invoke(main, ["study", "prereg", str(demo), "-o", str(out), "--exclusion-rate", "0.1"])
    assert r.exit_code == 0, r.output
    text = out.read_text()
    items = _items(text)
    assert list(items) == [item for _, item in ITEMS]
    for section in dict.fromkeys(sec for sec, _ in ITEMS):
        assert f"\n## {section}\n" in text
    assert all(body for body in items.values())
    study = load_study(demo)
    # only what the researcher alone knows is left to complete
    assert {name for name, body in items.items() if body.startswith(TODO)} == {
        "Authors", "Hypotheses", "Existing data", "Exploratory analysis"}
    assert study.title in items["Title"]
    for c in study.conditions:
        assert c in items["Study design"] and c in items["Manipulated variables"]
    assert "vs" in items["Hypotheses"] and items["Hypotheses"].count("- H") == 3 + 3   # 3 pairs + 3 MUSHRA pairs
    assert f"{study.sessions} session plans" in items["Randomization"] and f"seed {study.seed}" in items["Randomization"]
    assert f"{study.sessions} sessions have finished" in items["Stopping rule"]
    assert "family of 3" in items["Sample size rationale"] and "0.1 of sessions" in items["Sample size rationale"]
    needed = int(re.search(r"needs (\d+) participants", items["Sample size"]).group(1))
    assert needed > study.sessions and f"at least {needed}" in items["Sample size"]
    for block in study.blocks.values():
        q = block.cfg.get("question") or block.cfg["questions"][0]
        assert q["text"] in items["Measured variables"]
    assert "prolific" in items["Data collection procedures"] and "DEMOFAIL" in items["Data collection procedures"]
    assert "2 or more failed attention checks" in items["Data exclusion"]
    assert "ties left out (`--tie-policy exclude`)" in items["Statistical models"]
    assert "Holm-Bonferroni per study" in items["Inference criteria"]
    assert "off (natural motion is no ceiling" in items["Data exclusion"] or "hidden reference" not in text


def test_the_analysis_plan_follows_the_preset(demo, tmp_path):
    out = tmp_path / "lb.md"
    r = CliRunner().invoke(main, ["study", "prereg", str(demo), "-o", str(out), "--preset", "leaderboard"])
    assert r.exit_code == 0, r.output
    items = _items(out.read_text())
    assert "any failed attention check" in items["Data exclusion"]
    assert "counted as half a win (`--tie-policy half`)" in items["Statistical models"]
    assert "10000 participant-bootstrap rounds" in items["Statistical models"]
    assert "`--preset leaderboard`" in items["Statistical models"]
