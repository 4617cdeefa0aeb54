"""Session plans that a participant cannot see through (issue 11's design findings): practice pages never
show material the participant rates for real, and attention checks are not where, or what, one expects."""
from __future__ import annotations

from collections import Counter

import pytest
import study_helpers as h
import yaml

from study_app.definition import load_study
from study_app.design import build_plans
from study_app.errors import StudyDefinitionError
from study_app.pages import get_block_kind


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    f = tmp_path_factory.mktemp("plans")
    h.make_study(f)
    return f


def _variant(folder, mutate, name="variant.yaml", sessions=60):
    data = yaml.safe_load((folder / "study.yaml").read_text())
    data["sessions"] = sessions
    mutate(data)
    (folder / name).write_text(yaml.safe_dump(data))
    return load_study(folder / name)


def _material(study, page):
    return get_block_kind(page["type"]).material(study, page)


def _practice_overlaps(study, plans) -> int:
    bad = 0
    for plan in plans["plans"]:
        rated = {_material(study, p) for p in plan["pages"] if "block" in p and not p["training"]}
        practice = [_material(study, p) for p in plan["pages"] if p.get("training")]
        assert len(set(practice)) == len(practice)              # no practice page twice either
        bad += any(m in rated for m in practice)
    return bad


def test_practice_never_repeats_a_rated_trial(folder):
    def more_practice(data):
        data["pages"][4]["count"] = 2                           # two practice pages of the pairwise block
        data["pages"].insert(5, {"type": "training", "id": "practice-ratings", "of": "ratings"})

    study = _variant(folder, more_practice)
    plans = build_plans(study)
    assert _practice_overlaps(study, plans) == 0
    for plan in plans["plans"]:
        practice = [p for p in plan["pages"] if p.get("training")]
        assert [p["block"] for p in practice] == ["hl", "hl", "ratings"]
        rated_segments = {p["segment"] for p in plan["pages"] if p.get("block") == "ratings" and not p["training"]
                          and not p["check"]}
        assert practice[2]["segment"] not in rated_segments     # MUSHRA: a segment not rated for real
    # practice is still spread over the block's items
    pairs = Counter(_material(study, p) for plan in plans["plans"] for p in plan["pages"] if p.get("block") == "hl"
                    and p["training"])
    assert len(pairs) >= 6


def test_practice_in_the_demo_study(tmp_path):
    from study_app.demo import _stimuli, study_definition

    target = tmp_path / "study"
    target.mkdir()
    manifest = _stimuli(tmp_path, target, lambda *a: None)
    (target / "study.yaml").write_text(yaml.safe_dump(study_definition(manifest, target), sort_keys=False))
    study = load_study(target / "study.yaml")
    for sessions in (study.sessions, 40):
        study.sessions = sessions
        assert _practice_overlaps(study, build_plans(study)) == 0


def test_practice_without_material_of_its_own_is_a_build_error(folder):
    def impossible(data):
        ratings = next(p for p in data["pages"] if p["id"] == "ratings")
        ratings["pages"] = 3                                    # every segment rated for real
        data["pages"].insert(5, {"type": "training", "id": "practice-ratings", "of": "ratings"})

    study = _variant(folder, impossible, "impossible.yaml", sessions=2)
    with pytest.raises(StudyDefinitionError, match="no practice material left") as err:
        build_plans(study)
    assert "pages[5].segments" in str(err.value)


def _checks(plan, block):
    pages = [p for p in plan["pages"] if p.get("block") == block and not p["training"]]
    return pages, [i for i, p in enumerate(pages) if p["check"]]


def test_attention_checks_move_within_a_window_per_session(folder):
    study = _variant(folder, lambda d: None, "window.yaml")
    plans = build_plans(study)
    assert build_plans(study) == plans                           # seeded: the same plans on every build
    for block, configured in (("hl", 2), ("ratings", 1)):
        seen = Counter()
        for plan in plans["plans"]:
            _, at = _checks(plan, block)
            assert len(at) == 1
            assert at[0] != 0
            assert abs(at[0] - configured) <= 2
            seen[at[0]] += 1
        assert len(seen) >= 2, (block, seen)                    # not the same place in every plan
        assert set(seen) == set(range(max(1, configured - 2), min(configured + 2, 3 if block == "hl" else 2) + 1))
    # another seed, other places; a window of 0 keeps the configured positions
    other = _variant(folder, lambda d: d.update(seed=4), "seed4.yaml")
    assert [_checks(p, "hl")[1] for p in build_plans(other)["plans"]] != [_checks(p, "hl")[1] for p in plans["plans"]]
    fixed = _variant(folder, lambda d: next(p for p in d["pages"] if p["id"] == "ratings").update(attention_window=0),
                     "fixed.yaml")
    assert {tuple(_checks(p, "ratings")[1]) for p in build_plans(fixed)["plans"]} == {(1,)}


def test_mushra_check_is_not_a_rated_page_with_one_clip_swapped(folder):
    study = _variant(folder, lambda d: None, "mushra.yaml")
    pool_segments = {s.segment for s in study.manifest.stimuli if s.kind == "attention"
                     and get_block_kind("mushra").attention_fits(s, study.page("ratings").cfg)}
    slots, repeats, avoidable = Counter(), 0, 0
    for plan in build_plans(study)["plans"]:
        pages, at = _checks(plan, "ratings")
        check = pages[at[0]]
        rated = [p for p in pages if not p["check"]]
        slots[check["check_slot"]] += 1
        assert check["roles"][check["check_slot"]] == ""         # never in place of the hidden reference
        others = set(check["slots"]) - {check["slots"][check["check_slot"]]}
        repeat = any(others <= set(p["slots"]) for p in rated)
        repeats += repeat
        if pool_segments - {p["segment"] for p in rated}:
            avoidable += 1
            assert not repeat                                    # a segment this participant does not rate
    assert avoidable > 0
    assert repeats == 60 - avoidable
    assert len(slots) == 3                                       # the check clip in every non-reference slot


def test_attention_window_is_validated(folder):
    def bad(data):
        next(p for p in data["pages"] if p["id"] == "hl")["attention_window"] = -1

    with pytest.raises(StudyDefinitionError, match=r"attention_window"):
        _variant(folder, bad, "badwindow.yaml")


def _with_audio_check(folder, block_column=""):
    """The helper manifest with its 'good' MUSHRA check marked as a distorted-audio clip."""
    import csv

    src = folder / "stim" / "manifest.csv"
    rows = list(csv.DictReader(src.open(newline="")))
    for r in rows:
        r["check"] = "distorted_audio" if r["expected"] == "good" else ("instruction" if r["kind"] else "")
        r["block"] = block_column if r["expected"] == "good" else ""
    out = folder / "stim" / f"audio{block_column}.csv"
    with out.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=[*rows[0]])
        w.writeheader()
        w.writerows(rows)
    line = 2 + next(i for i, r in enumerate(rows) if r["expected"] == "good")
    return out.name, line


def test_an_audio_check_in_a_muted_block_is_refused(folder):
    name, line = _with_audio_check(folder)
    with pytest.raises(StudyDefinitionError) as err:
        _variant(folder, lambda d: d.update(stimuli=f"stim/{name}"), "deaf.yaml")
    msg = str(err.value)
    assert f"{name} line {line}" in msg and "check distorted_audio" in msg and "'ratings' is muted" in msg
    assert err.value.field == "pages[6].attention_checks"
    # unmuted, or the clip kept for another block: accepted, and the muted block never shows it
    def unmuted(d):
        d.update(stimuli=f"stim/{name}")
        next(p for p in d["pages"] if p["id"] == "ratings")["muted"] = False

    assert _variant(folder, unmuted, "loud.yaml").page("ratings").cfg["muted"] is False
    other, _ = _with_audio_check(folder, block_column="stmts")
    study = _variant(folder, lambda d: d.update(stimuli=f"stim/{other}"), "elsewhere.yaml")
    by_file = study.manifest.by_file()
    shown = {f for plan in build_plans(study)["plans"] for p in plan["pages"] for f in p.get("slots", [])}
    assert not any(by_file[f].needs_sound for f in shown)


def test_the_demo_leaves_audio_checks_out_of_its_muted_blocks(folder, tmp_path):
    from study_app.demo import silent_manifest, study_definition

    name, _ = _with_audio_check(folder)
    path = silent_manifest(folder / "stim" / name, lambda *a: None)
    assert path.name == "study-manifest.csv"
    assert "distorted_audio" not in path.read_text()
    target = folder / "demo-study"
    target.mkdir(exist_ok=True)
    (target / "study.yaml").write_text(yaml.safe_dump(study_definition(path, target), sort_keys=False))
    study = load_study(target / "study.yaml")
    assert all(b.cfg["muted"] for b in study.blocks.values())
    assert build_plans(study)["plans"]
    # the definition on the full manifest puts the audio check in the muted MUSHRA block: refused
    (target / "full.yaml").write_text(yaml.safe_dump(study_definition(folder / "stim" / name, target)))
    with pytest.raises(StudyDefinitionError, match="needs sound"):
        load_study(target / "full.yaml")
    assert silent_manifest(folder / "stim" / "manifest.csv", print) == folder / "stim" / "manifest.csv"


def test_build_warns_when_a_pages_files_differ_in_size(tmp_path):
    from click.testing import CliRunner

    from evalsuite.cli import main
    from renderers.filesize import pad_group
    from study_app.design import size_spread

    path = h.make_study(tmp_path)
    r = CliRunner().invoke(main, ["study", "build", str(path)])
    assert r.exit_code == 0, r.output
    assert "warning: on " in r.output and "differ in size by more than 10%" in r.output
    study = load_study(path)
    worst = size_spread(build_plans(study), study)[0]
    assert worst["ratio"] > 1.1 and f"{worst['ratio']:.1f}x on {worst['plan']}/{worst['page']}" in r.output
    # the sizes evened out per segment (as `render stimuli` does with equal_size): no warning
    for seg in h.SEGMENTS:
        pad_group(study.manifest.root / s.file for s in study.manifest.stimuli if s.segment == seg)
    r = CliRunner().invoke(main, ["study", "build", str(path)])
    assert r.exit_code == 0 and "differ in size" not in r.output
    assert size_spread(build_plans(study), study) == []


def test_the_demo_study_builds_on_a_single_segment(tmp_path):
    # The render step's bundled samples give one segment: every pair is rated, so no practice page is possible.
    from study_app.demo import study_definition
    from study_app.samples import make_sample_stimuli

    manifest = make_sample_stimuli(tmp_path / "stim", ["natural", "static", "jitter"], ["sample"], seconds=0.5)
    (tmp_path / "study.yaml").write_text(yaml.safe_dump(study_definition(manifest, tmp_path), sort_keys=False))
    study = load_study(tmp_path / "study.yaml")
    assert "training" not in {p.type for p in study.pages}
    assert build_plans(study)["plans"]
