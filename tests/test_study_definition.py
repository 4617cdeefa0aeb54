"""Study definition + manifest validation (every error) and balanced session plans."""
from __future__ import annotations

import copy
import json
from collections import Counter

import pytest
import study_helpers as h
import yaml
from click.testing import CliRunner

from study_app.definition import load_manifest, load_study
from study_app.design import balance_report, build_plans, read_plans, write_plans
from study_app.errors import StudyDefinitionError


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    f = tmp_path_factory.mktemp("studydef")
    h.make_study(f)
    return f


@pytest.fixture()
def base(folder):
    """The test study without its headphone check (the page indices below count without it)."""
    data = yaml.safe_load((folder / "study.yaml").read_text())
    data["pages"] = [p for p in data["pages"] if p["type"] != "headphone_check"]
    return data


def _load(folder, data, name="variant.yaml"):
    path = folder / name
    path.write_text(yaml.safe_dump(data) if name.endswith(".yaml") else json.dumps(data))
    return load_study(path)


def _page(data, pid):
    return next(p for p in data["pages"] if p["id"] == pid)


# (description, mutation, expected field path, fragment of the message)
def _set(path, value):
    def mutate(d):
        target = d
        for key in path[:-1]:
            target = _page(target, key) if isinstance(key, str) and key.startswith("@") is False and key in [
                p.get("id") for p in target.get("pages", [])] else target[key]
        target[path[-1]] = value
    return mutate


def _del(path):
    def mutate(d):
        target = d
        for key in path[:-1]:
            target = _page(target, key) if key in [p.get("id") for p in target.get("pages", [])] else target[key]
        del target[path[-1]]
    return mutate


def _pages(fn):
    def mutate(d):
        d["pages"] = fn(d["pages"])
    return mutate


# page indices in STUDY_YAML: 0 consent, 1 demographics, 2 intro, 3 training, 4 hl, 5 ratings,
# 6 app, 7 stmts, 8 finish
CASES = [
    ("missing id", _del(["id"]), "id", "missing"),
    ("bad id", _set(["id"], "has space"), "id", "expected an id"),
    ("unknown top key", _set(["colour"], "red"), "colour", "unknown field"),
    ("missing stimuli", _del(["stimuli"]), "stimuli", "missing"),
    ("bad platform", _set(["platform"], "facebook"), "platform", "expected one of prolific, mturk, anonymous"),
    ("sessions not int", _set(["sessions"], "ten"), "sessions", "expected an integer in 1..5000"),
    ("sessions bool", _set(["sessions"], True), "sessions", "expected an integer"),
    ("sessions zero", _set(["sessions"], 0), "sessions", "expected an integer in 1..5000"),
    ("prolific without code", _del(["completion_code"]), "completion_code", "missing; expected the completion code"),
    ("bad code", _set(["completion_code"], "a b"), "completion_code", "expected letters"),
    ("max failed", _set(["max_failed_attention_checks"], 0), "max_failed_attention_checks", "1..1000"),
    ("reservation", _set(["reservation_minutes"], -5), "reservation_minutes", "positive number"),
    ("full playback", _set(["require_full_playback"], "yes"), "require_full_playback", "true or false"),
    ("pages missing", _del(["pages"]), "pages", "missing"),
    ("pages empty", _set(["pages"], []), "pages", "at least one page"),
    ("page not mapping", _pages(lambda p: ["consent"] + p), "pages[0]", "expected a mapping"),
    ("page type", _pages(lambda p: [{**p[0], "type": "video"}] + p[1:]), "pages[0].type", "expected one of consent"),
    ("page unknown key", _pages(lambda p: [{**p[0], "colour": 1}] + p[1:]), "pages[0].colour", "unknown field"),
    ("duplicate page id", _pages(lambda p: p[:2] + [{**p[2], "id": "demographics"}] + p[3:]), "pages[2].id", "duplicate page id"),
    ("no finish", _pages(lambda p: p[:-1]), "pages[7]", "exactly one page of type finish"),
    ("finish not last", _pages(lambda p: p[:1] + [p[-1]] + p[1:-1]), "pages[1]", "exactly one page of type finish"),
    ("consent not first", _pages(lambda p: [p[2], p[0]] + p[3:]), "pages[1]", "consent page, as the first"),
    ("no blocks", _pages(lambda p: [p[0], p[-1]]), "pages", "at least one pairwise, mushra or likert"),
    ("question type", _pages(lambda p: p[:1] + [{**p[1], "questions": [{"id": "a", "type": "slider", "text": "x"}]}] + p[2:]),
     "pages[1].questions[0].type", "expected one of number, choice, text"),
    ("question dup", _pages(lambda p: p[:1] + [{**p[1], "questions": [p[1]["questions"][0]] * 2}] + p[2:]),
     "pages[1].questions[1].id", "duplicate question id"),
    ("choice options", _pages(lambda p: p[:1] + [{**p[1], "questions": [{"id": "g", "type": "choice", "text": "x", "options": ["one"]}]}] + p[2:]),
     "pages[1].questions[0].options", "at least 2 entries"),
    ("number min>max", _pages(lambda p: p[:1] + [{**p[1], "questions": [{"id": "g", "type": "number", "text": "x", "min": 5, "max": 1}]}] + p[2:]),
     "pages[1].questions[0].min", "min <= max"),
    ("questions empty", _pages(lambda p: p[:1] + [{**p[1], "questions": []}] + p[2:]), "pages[1].questions", "at least one question"),
    ("training of unknown", _pages(lambda p: p[:3] + [{**p[3], "of": "nope"}] + p[4:]), "pages[3].of", "id of a pairwise, mushra or likert"),
    ("training segment", _pages(lambda p: p[:3] + [{**p[3], "segments": ["seg99"]}] + p[4:]), "pages[3].segments[0]", "has no stimulus"),
    ("unknown condition", _pages(lambda p: p[:4] + [{**p[4], "conditions": ["SYSALPHA", "GHOST"]}] + p[5:]),
     "pages[4].conditions[1]", "unknown condition 'GHOST'"),
    ("one condition pairwise", _pages(lambda p: p[:4] + [{**p[4], "conditions": ["SYSALPHA"], "pairs": None}] + p[5:]),
     "pages[4].conditions", "at least 2 entries"),
    ("duplicate conditions", _pages(lambda p: p[:4] + [{**p[4], "conditions": ["SYSALPHA", "SYSALPHA"]}] + p[5:]),
     "pages[4].conditions", "distinct conditions"),
    ("headphone pass > trials", _pages(lambda p: p[:1] + [{"type": "headphone_check", "id": "hp", "trials": 3, "pass": 4}] + p[1:]),
     "pages[1].pass", "at most trials (3), got 4"),
    ("headphone trials", _pages(lambda p: p[:1] + [{"type": "headphone_check", "id": "hp", "trials": 0}] + p[1:]),
     "pages[1].trials", "1..30"),
    ("headphone on_fail", _pages(lambda p: p[:1] + [{"type": "headphone_check", "id": "hp", "on_fail": "warn"}] + p[1:]),
     "pages[1].on_fail", "expected one of end, continue, got 'warn'"),
    ("headphone unknown key", _pages(lambda p: p[:1] + [{"type": "headphone_check", "id": "hp", "volume": 3}] + p[1:]),
     "pages[1].volume", "unknown field"),
    ("reasons required without reasons", _pages(lambda p: p[:4] + [{**{k: v for k, v in p[4].items() if k != "reasons"}, "reasons_required": True}] + p[5:]),
     "pages[4].reasons_required", "needs a list of reasons"),
    ("reasons required not bool", _pages(lambda p: p[:4] + [{**p[4], "reasons_required": "yes"}] + p[5:]),
     "pages[4].reasons_required", "true or false"),
    ("levels", _pages(lambda p: p[:4] + [{**p[4], "levels": 4}] + p[5:]), "pages[4].levels", "expected 3 or 5, got 4"),
    ("bad pair", _pages(lambda p: p[:4] + [{**p[4], "pairs": [["SYSALPHA", "SYSALPHA"]]}] + p[5:]), "pages[4].pairs[0]", "two different conditions"),
    ("pages missing", _pages(lambda p: p[:4] + [{k: v for k, v in p[4].items() if k != "pages"}] + p[5:]), "pages[4].pages", "missing"),
    ("questions missing", _pages(lambda p: p[:4] + [{k: v for k, v in p[4].items() if k != "questions"}] + p[5:]), "pages[4].questions", "missing"),
    ("check at 0", _pages(lambda p: p[:4] + [{**p[4], "attention_checks": [0]}] + p[5:]), "pages[4].attention_checks[0]",
     "never the first page"),
    ("check beyond", _pages(lambda p: p[:4] + [{**p[4], "attention_checks": [9]}] + p[5:]), "pages[4].attention_checks[0]", "1..3"),
    ("unknown segment", _pages(lambda p: p[:4] + [{**p[4], "segments": ["seg77"]}] + p[5:]), "pages[4].segments[0]", "unknown segment"),
    ("mushra reference in conditions", _pages(lambda p: p[:5] + [{**p[5], "reference": "SYSALPHA"}] + p[6:]),
     "pages[5].reference", "also in conditions"),
    ("mushra unknown anchor", _pages(lambda p: p[:5] + [{**p[5], "anchor": "GHOST"}] + p[6:]), "pages[5].anchor", "unknown condition"),
    ("mushra question", _pages(lambda p: p[:5] + [{**p[5], "question": "How?"}] + p[6:]), "pages[5].question", "expected a mapping"),
    ("mushra tolerance", _pages(lambda p: p[:5] + [{**p[5], "tolerance": 80}] + p[6:]), "pages[5].tolerance", "0..50"),
    ("mismatched with pairs", _pages(lambda p: p[:6] + [{**p[6], "pairs": [["SYSALPHA", "SYSBETA"]]}] + p[7:]),
     "pages[6].pairs", "not allowed with mismatched"),
    ("likert points", _pages(lambda p: p[:7] + [{**p[7], "points": 1}] + p[8:]), "pages[7].points", "2..11"),
    ("likert labels", _pages(lambda p: p[:7] + [{**p[7], "labels": ["a", "b", "c"]}] + p[8:]), "pages[7].labels", "expected 2 labels"),
    ("likert statement dup", _pages(lambda p: p[:7] + [{**p[7], "statements": [p[7]["statements"][0]] * 2}] + p[8:]),
     "pages[7].statements[1].id", "duplicate id"),
    ("likert no checks pool", _pages(lambda p: p[:7] + [{**p[7], "attention_checks": [1]}] + p[8:]),
     "pages[7].attention_checks", "no attention-check stimulus"),
]


@pytest.mark.parametrize("desc,mutate,field,fragment", CASES, ids=[c[0] for c in CASES])
def test_definition_errors_name_file_field_and_expectation(folder, base, desc, mutate, field, fragment):
    data = copy.deepcopy(base)
    mutate(data)
    with pytest.raises(StudyDefinitionError) as info:
        _load(folder, data)
    err = info.value
    assert err.field == field, str(err)
    assert fragment in str(err), str(err)
    assert str(err).startswith(str(folder / "variant.yaml")), str(err)


def test_valid_definition_loads_from_yaml_and_json(folder, base):
    a = _load(folder, base, "same.yaml")
    b = _load(folder, base, "same.json")
    assert [p.id for p in a.pages] == [p.id for p in b.pages]
    assert a.blocks["hl"].cfg["pairs"] == [["SYSALPHA", "SYSBETA"], ["SYSALPHA", "NATURALGT"], ["SYSBETA", "NATURALGT"]]


def test_syntax_errors(folder):
    bad_yaml = folder / "bad.yaml"
    bad_yaml.write_text("id: x\npages: [\n")
    with pytest.raises(StudyDefinitionError, match="invalid YAML") as info:
        load_study(bad_yaml)
    assert info.value.line is not None
    bad_json = folder / "bad.json"
    bad_json.write_text('{"id": "x",\n "pages": }')
    with pytest.raises(StudyDefinitionError, match="invalid JSON") as info:
        load_study(bad_json)
    assert info.value.line == 2
    top = folder / "list.yaml"
    top.write_text("- 1\n- 2\n")
    with pytest.raises(StudyDefinitionError, match="mapping at the top level"):
        load_study(top)
    with pytest.raises(StudyDefinitionError, match="not found"):
        load_study(folder / "missing.yaml")
    latin1 = folder / "latin1.yaml"
    latin1.write_bytes("id: caf\xe9\n".encode("latin-1"))
    with pytest.raises(StudyDefinitionError, match="not UTF-8"):
        load_study(latin1)


MANIFEST_HEADER = "file,condition,segment,kind,expected,motion_segment\n"


@pytest.mark.parametrize("body,line,field,fragment", [
    ("file,condition\nx.mp4,A\n", 1, None, "missing column(s) segment"),
    (MANIFEST_HEADER + "{f0},,seg01,,,\n", 2, "condition", "empty value"),
    (MANIFEST_HEADER + "{f0},SYSALPHA,seg01,bonus,,\n", 2, "kind", "expected one of stimulus, attention"),
    (MANIFEST_HEADER + "../{f0},SYSALPHA,seg01,,,\n", 2, "file", "not a relative path inside"),
    (MANIFEST_HEADER + "/etc/passwd,SYSALPHA,seg01,,,\n", 2, "file", "not a relative path inside"),
    (MANIFEST_HEADER + "nothere.mp4,SYSALPHA,seg01,,,\n", 2, "file", "does not exist"),
    (MANIFEST_HEADER + "{f0},SYSALPHA,seg01,,,\n{f0},SYSBETA,seg01,,,\n", 3, "file", "duplicate file, already on line 2"),
    (MANIFEST_HEADER + "{f0},SYSALPHA,seg01,,,\n{f1},SYSALPHA,seg01,,,\n", 3, "file", "already on line 2"),
    (MANIFEST_HEADER + "{f0},,seg01,attention,,\n", 2, "expected", "attention-check rows need"),
    (MANIFEST_HEADER + "sysalpha_seg01.mp4,SYSALPHA,seg01,,,\n", 2, "file", "contains the condition name"),
    (MANIFEST_HEADER, None, None, "no stimuli"),
])
def test_manifest_errors(folder, body, line, field, fragment):
    files = sorted(p.name for p in (folder / "stim").glob("*.mp4"))
    (folder / "stim" / "sysalpha_seg01.mp4").write_bytes(b"x")
    path = folder / "stim" / "variant.csv"
    path.write_text(body.format(f0=files[0], f1=files[1]))
    with pytest.raises(StudyDefinitionError) as info:
        load_manifest(path)
    assert fragment in str(info.value), str(info.value)
    assert info.value.line == line
    assert info.value.field == field
    assert str(path) in str(info.value)


def test_manifest_not_found_and_not_utf8(folder):
    with pytest.raises(StudyDefinitionError, match="not found"):
        load_manifest(folder / "nope.csv")
    p = folder / "stim" / "latin1.csv"
    p.write_bytes("file,condition,segment\nx\xe9.mp4,A,s\n".encode("latin-1"))
    with pytest.raises(StudyDefinitionError, match="not UTF-8"):
        load_manifest(p)


def test_symlink_out_of_folder_is_refused(folder, tmp_path):
    outside = tmp_path / "secret.mp4"
    outside.write_bytes(b"x")
    link = folder / "stim" / "link0001.mp4"
    if not link.exists():
        link.symlink_to(outside)
    path = folder / "stim" / "sym.csv"
    path.write_text(MANIFEST_HEADER + "link0001.mp4,SYSALPHA,seg01,,,\n")
    with pytest.raises(StudyDefinitionError, match="outside the manifest's folder"):
        load_manifest(path)


# ------------------------------------------------------------------------------- design

def test_plans_are_balanced(folder):
    study = load_study(folder / "study.yaml")
    study.sessions = 12
    plans = build_plans(study)
    by_file = study.manifest.by_file()
    pair_counts, side_counts, check_positions = Counter(), Counter(), Counter()
    for plan in plans["plans"]:
        pages = plan["pages"]
        assert [p["page"] for p in pages][:4] == ["consent", "demographics", "headphones", "intro"]
        assert len(pages[2]["trials"]) == 2
        assert set(pages[2]["trials"]) <= set(range(6))
        assert pages[4]["training"]
        assert pages[4]["page"] == "training-01"
        hl = [p for p in pages if p.get("block") == "hl" and not p["training"]]
        assert len(hl) == 4
        at = [i for i, p in enumerate(hl) if p["check"]]
        assert len(at) == 1
        assert 1 <= at[0] <= 3                    # configured at 2, moved by up to attention_window (2)
        assert by_file[hl[at[0]]["a"]].kind == "attention"
        segs = [p["segment"] for p in hl if not p["check"]]
        assert len(set(segs)) == len(segs)                       # no segment twice in a block
        for p in hl:
            if p["check"]:
                continue
            key = frozenset((by_file[p["a"]].condition, by_file[p["b"]].condition))
            pair_counts[key] += 1
            side_counts[(key, p["position_a"])] += 1
        app = [p for p in pages if p.get("block") == "app"]
        for p in app:     # A is the matched video, B the same condition with other motion
            a, b = by_file[p["a"]], by_file[p["b"]]
            assert a.condition == b.condition
            assert not a.mismatched
            assert b.mismatched
            assert a.segment == b.segment == p["segment"]
        ratings = [p for p in pages if p.get("block") == "ratings"]
        assert ["check_slot" in p for p in ratings] in ([False, True, False], [False, False, True])
        for p in ratings:
            assert {by_file[f].segment for f in p["slots"]} == {p["segment"]}
            assert p["roles"].count("reference") == 1
        check_positions[tuple(i for i, p in enumerate(pages) if p.get("check"))] += 1
    # every comparison equally often, A left and A right equally often
    assert len(pair_counts) == 3
    assert set(pair_counts.values()) == {12}
    assert set(side_counts.values()) == {6}
    assert len(check_positions) > 1                               # checks move per session (window)
    rep = balance_report(plans, study)
    assert set(rep["pairs"].values()) == {6}
    # deterministic
    assert build_plans(study) == plans


def test_plans_file_round_trip_and_staleness(folder, tmp_path):
    study = load_study(folder / "study.yaml")
    path = write_plans(build_plans(study), tmp_path / "p.json")
    assert read_plans(path, study)["study"] == study.id
    study.sha256 = "0" * 64
    with pytest.raises(StudyDefinitionError, match="another version"):
        read_plans(path, study)
    with pytest.raises(StudyDefinitionError, match="run `evalsuite study build` first"):
        read_plans(tmp_path / "none.json", study)


def test_cli_build_prints_balance_and_errors_cleanly(folder, tmp_path):
    from evalsuite.cli import main
    runner = CliRunner()
    out = tmp_path / "plans.json"
    res = runner.invoke(main, ["study", "build", str(folder / "study.yaml"), "-o", str(out),
                               "--db", f"sqlite:///{tmp_path / 'db.sqlite'}"])
    assert res.exit_code == 0, res.output
    assert "6 session plans" in res.output
    assert "SYSALPHA vs SYSBETA: 3 / 3" in res.output
    assert "database ready" in res.output
    bad = folder / "broken.yaml"
    bad.write_text("id: x\nstimuli: stim/manifest.csv\npages: 3\n")
    res = runner.invoke(main, ["study", "build", str(bad)])
    assert res.exit_code == 1
    assert "Traceback" not in res.output
    assert "pages: expected a list of pages" in res.output
    for cmd in (["study", "--help"], ["study", "build", "--help"], ["study", "serve", "--help"],
                ["study", "export", "--help"], ["study", "admin-token", "--help"]):
        assert runner.invoke(main, cmd).exit_code == 0
    token = runner.invoke(main, ["study", "admin-token"]).output.strip()
    assert len(token) >= 24


def test_serve_and_gunicorn_factory_have_no_default_credentials(folder, monkeypatch):
    from evalsuite.cli import main
    from study_app.app import create_app_from_env
    from study_app.errors import StudyStateError
    monkeypatch.delenv("EVALSUITE_ADMIN_TOKEN", raising=False)
    res = CliRunner().invoke(main, ["study", "serve", str(folder / "study.yaml")])
    assert res.exit_code == 2
    assert "--admin-token" in res.output
    res = CliRunner().invoke(main, ["study", "serve", str(folder / "study.yaml"), "--admin-token", "short"])
    assert res.exit_code == 1
    assert "ADMIN_TOKEN" in res.output
    assert "Traceback" not in res.output
    monkeypatch.setenv("EVALSUITE_STUDY", str(folder / "study.yaml"))
    monkeypatch.delenv("EVALSUITE_SECRET_KEY", raising=False)
    with pytest.raises(StudyStateError, match="EVALSUITE_SECRET_KEY"):
        create_app_from_env()


def test_a_key_given_twice_is_refused_with_both_lines(folder):
    text = (folder / "study.yaml").read_text()
    path = folder / "twice.yaml"
    path.write_text(text.replace("sessions: 6\n", "sessions: 6\nseed: 1\nsessions: 7\n"))
    with pytest.raises(StudyDefinitionError, match=r"twice.yaml:\d+: key 'sessions' given twice \(lines 5 and 7\)"):
        load_study(path)
    path.write_text(text.replace("    id: ratings\n", "    id: ratings\n    muted: false\n"))  # nested: muted later
    with pytest.raises(StudyDefinitionError, match="key 'muted' given twice"):
        load_study(path)
    path.write_text(text.replace("  - {id: age,", "  - {id: age, id: age2,"))  # flow style, one line
    with pytest.raises(StudyDefinitionError, match="key 'id' given twice"):
        load_study(path)
    data = json.dumps(yaml.safe_load(text))
    json_path = folder / "twice.json"
    json_path.write_text(data.replace('"sessions": 6', '"sessions": 6, "sessions": 7'))
    with pytest.raises(StudyDefinitionError, match="key 'sessions' given twice"):
        load_study(json_path)


@pytest.mark.parametrize("desc,mutate,field,fragment", [
    ("huge integer", _set(["reservation_minutes"], 10 ** 300), "reservation_minutes", "a number of 301 digits"),
    ("reservation over a year", _set(["reservation_minutes"], 1e12), "reservation_minutes", "up to 525600"),
    ("sessions over the limit", _set(["sessions"], 100_000), "sessions", "expected an integer in 1..5000"),
    ("very long list", _set(["pages", 1, "questions", 1, "options"], [f"o{i}" for i in range(1001)]),
     "pages[1].questions[1].options", "a list of 1,001 entries; expected at most 1,000"),
    ("very long text", _set(["pages", 0, "text"], "x" * 20_001), "pages[0].text", "expected at most 20,000"),
    ("same completion and failure code", _set(["failure_code"], "DONE1234"), "failure_code", "completion_code"),
    ("duplicate option", _set(["pages", 1, "questions", 1, "options"], ["a", "b", "a"]),
     "pages[1].questions[1].options", "expected distinct options ('a' is entry 0 and entry 2)"),
    ("duplicate segment", _pages(lambda p: p[:4] + [{**p[4], "segments": ["seg01", "seg01"]}] + p[5:]),
     "pages[4].segments", "expected distinct segments"),
])
def test_limits_and_other_invalid_definitions_are_refused_promptly(folder, base, desc, mutate, field, fragment):
    import time

    data = copy.deepcopy(base)
    mutate(data)
    t0 = time.perf_counter()
    with pytest.raises(StudyDefinitionError) as info:
        _load(folder, data)
    assert time.perf_counter() - t0 < 1.0
    assert info.value.field == field, str(info.value)
    assert fragment in str(info.value), str(info.value)


def test_a_file_over_the_size_limit_is_refused_before_it_is_parsed(folder):
    from study_app.parse import MAX_FILE_BYTES

    path = folder / "huge.yaml"
    path.write_text((folder / "study.yaml").read_text() + "#" * MAX_FILE_BYTES)
    with pytest.raises(StudyDefinitionError, match=f"limit {MAX_FILE_BYTES:,} bytes"):
        load_study(path)


def test_an_unknown_field_suggests_the_closest_names_in_a_short_message(folder, base):
    data = copy.deepcopy(base)
    data["sesions"] = 3
    with pytest.raises(StudyDefinitionError) as info:
        _load(folder, data)
    assert "unknown field. Did you mean 'sessions'?" in str(info.value)
    assert len(info.value.reason) < 120


def test_a_long_bad_id_is_shown_cut_in_a_short_message(folder, base):
    data = copy.deepcopy(base)
    data["id"] = "x" * 5000 + "!"
    with pytest.raises(StudyDefinitionError) as info:
        _load(folder, data)
    assert info.value.field == "id"
    assert len(info.value.reason) < 300, info.value.reason
