"""Layout options, "does not play" reports and the admin's participant table, through Flask's test client.

The layout itself is measured in a browser (tests/test_study_layout_browser.py); here: the MUSHRA
``layout`` and ``slider_numbers`` options (schema, defaults, errors naming the field, the HTML they give),
the report a participant sends from a media page (stored as an ``unplayable`` event, counted per stimulus
on the admin page and in its JSON), and the per-participant table with its JSON endpoint behind the admin
token.
"""
from __future__ import annotations

import re
import secrets

import numpy as np
import pytest
import study_helpers as h
from layout_helpers import LAYOUT_YAML, make_layout_study

from study_app import create_app
from study_app.context import store_of, study_of
from study_app.definition import load_study
from study_app.errors import StudyDefinitionError
from study_app.storage import Event

PIDS = [f"{k:02d}" + "5f3a1c9e8b7d6a5f4e3d2c" for k in range(10)]   # Prolific ids: 24 hex digits


@pytest.fixture(scope="module")
def layout_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("layout")
    make_layout_study(folder)
    return folder


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("study")
    h.make_study(folder)
    return folder


def make_app(folder, tmp_path, study_file):
    return create_app({"STUDY": str(folder / study_file), "DATABASE_URL": f"sqlite:///{tmp_path / 'study.db'}",
                       "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                       "INSTANCE_PATH": str(tmp_path / "inst")})


def bearer():
    return {"Authorization": f"Bearer {h.ADMIN}"}


# ------------------------------------------------------------------------------- schema

def test_mushra_layout_options_defaults_and_values(layout_dir):
    study = load_study(layout_dir / "layout.yaml")
    assert study.page("m5").cfg["layout"] == "grid"
    assert study.page("m5").cfg["slider_numbers"] is True
    assert study.page("m6").cfg["slider_numbers"] is False
    assert study.page("hv").cfg["layout"] == "hemvip"


@pytest.mark.parametrize("line, field, words", [
    ("    layout: vertical", "pages[3].layout", "grid, hemvip"),
    ("    layout: 3", "pages[3].layout", "grid or hemvip"),
    ("    slider_numbers: no-thanks", "pages[3].slider_numbers", "true or false"),
])
def test_mushra_layout_options_are_validated(layout_dir, tmp_path, line, field, words):
    text = LAYOUT_YAML.replace("    layout: hemvip", line)
    if "slider_numbers" in line:
        text = LAYOUT_YAML.replace("    layout: hemvip\n", "").replace(
            "    question: {id: hlhv", line + "\n    question: {id: hlhv").replace(
            "    slider_numbers: false\n    pages: 1\n    muted: true\n  - type: likert",
            "    pages: 1\n    muted: true\n  - type: likert")
    (tmp_path / "stim").symlink_to(layout_dir / "stim")
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(StudyDefinitionError) as err:
        load_study(path)
    assert field in str(err.value)
    assert words in str(err.value)


def test_layout_options_on_other_kinds_are_unknown_fields(layout_dir, tmp_path):
    (tmp_path / "stim").symlink_to(layout_dir / "stim")
    path = tmp_path / "bad.yaml"
    path.write_text(LAYOUT_YAML.replace("    points: 7\n", "    points: 7\n    layout: hemvip\n"))
    with pytest.raises(StudyDefinitionError, match=r"pages\[4\]\.layout: unknown field"):
        load_study(path)


# ------------------------------------------------------------------------------- HTML of the options

def walk_to(app, p, block):
    """Answer pages (fetching their media first) until the current page belongs to ``block``."""
    study = study_of(app)
    rng = np.random.default_rng(0)
    while True:
        r, data, csrf = p.page()
        spec = h.plan_pages(app, p.sid)[data["index"]]
        if spec.get("block") == block:
            return r.get_data(as_text=True), data, csrf
        for url in data["videos"]:
            p.get(url)
        assert p.submit(data, csrf, h.make_answer(study, spec, rng)).status_code == 200


def test_hemvip_and_slider_number_html(layout_dir, tmp_path):
    app = make_app(layout_dir, tmp_path, "layout.yaml")
    p = h.Participant(app.test_client(), PIDS[0], "layout-test")
    assert p.enter().status_code == 302
    html, data, _ = walk_to(app, p, "m5")
    assert 'class="players grid" data-n="5"' in html
    assert html.count("<output") == 5
    html, data, _ = walk_to(app, p, "m6")
    assert 'data-n="6"' in html
    assert "<output" not in html, "slider_numbers: false"
    html, data, _ = walk_to(app, p, "hv")
    assert 'class="hemvip"' in html
    videos = re.findall(r"<video [^>]*>", html)
    assert len(videos) == 6
    assert sum(" hidden" in v for v in videos) == 5, "one player visible"
    assert len(re.findall(r'<input type="range" class="vertical"', html)) == 6
    axis = re.search(r'<div class="hv-axis".*?</div>', html, re.S).group(0)
    assert re.findall(r'band-label">(\w+)<', axis) == ["Excellent", "Good", "Fair", "Poor", "Bad"]
    assert "<output" not in html
    # a report form on every media page, naming the videos by number only
    assert 'id="report-send"' in html
    assert "Video does not play?" in html


# ------------------------------------------------------------------------------- reports

def report(p, data, csrf, slot, detail="0:ready=0,net=3,error=4"):
    event = {"id": secrets.token_hex(8), "kind": "unplayable", "slot": slot, "t": None, "ms": 1, "detail": detail}
    return p.post(data["events_url"], {"events": [event]}, csrf)


def test_does_not_play_report_is_stored_and_counted_per_stimulus(layout_dir, tmp_path):
    app = make_app(layout_dir, tmp_path, "layout.yaml")
    study, store = study_of(app), store_of(app)
    by_file = study.manifest.by_file()
    a = h.Participant(app.test_client(), PIDS[1], "layout-test")
    b = h.Participant(app.test_client(), PIDS[2], "layout-test")
    for p in (a, b):
        assert p.enter().status_code == 302
    # a: slot 1 of the MUSHRA page, twice (one report), and every video of the pairwise page
    _, data, csrf = a.page()
    assert report(a, data, csrf, None).status_code == 200
    _, data_m5, csrf = walk_to(app, a, "m5")
    assert report(a, data_m5, csrf, 1).status_code == 200
    assert report(a, data_m5, csrf, 1).status_code == 200
    # b reports slot 0 (the left video) of its pairwise page
    _, data_b, csrf_b = b.page()
    assert report(b, data_b, csrf_b, 0).status_code == 200
    # bad reports: a slot the page lacks, a long detail
    assert report(b, data_b, csrf_b, 2).status_code == 422
    assert report(b, data_b, csrf_b, 0, detail="x" * 201).status_code == 422
    with store.Session() as db:
        kinds = [(e.page_index, e.slot) for e in db.query(Event).filter_by(kind="unplayable", session_id=a.sid)]
    assert sorted(kinds, key=str) == sorted([(0, None), (data_m5["index"], 1), (data_m5["index"], 1)], key=str)

    pa, pb = h.plan_pages(app, a.sid), h.plan_pages(app, b.sid)
    pair_b = pb[0]
    reported = [(PIDS[1], pa[0]["a"]), (PIDS[1], pa[0]["b"]),                  # every video of a's page 0
                (PIDS[1], pa[data_m5["index"]]["slots"][1]),                    # a's MUSHRA slot 1, once
                (PIDS[2], pair_b["a"] if pair_b["position_a"] == "left" else pair_b["b"])]  # b's left video
    status = app.test_client().get("/admin/status.json", headers=bearer()).get_json()
    got = {r["file"]: r for r in status["reports"]}
    assert set(got) == {f for _, f in reported}
    for f in got:
        assert got[f]["reports"] == sum(g == f for _, g in reported), "a repeated report counts once"
        assert got[f]["participants"] == len({who for who, g in reported if g == f})
        assert got[f]["condition"] == by_file[f].condition
        assert got[f]["segment"] == by_file[f].segment
    rows = {r["participant"]: r for r in status["participants"]}
    assert rows[PIDS[1]]["reports"] == 2
    assert rows[PIDS[2]]["reports"] == 1
    page = app.test_client().get("/admin/", headers=bearer()).get_data(as_text=True)
    table = re.search(r'<table id="reports">.*?</table>', page, re.S).group(0)
    for f in got:
        assert f in table


def test_report_from_a_headphone_check_names_the_generated_sound(study_dir, tmp_path):
    app = make_app(study_dir, tmp_path, "study.yaml")
    p = h.Participant(app.test_client(), PIDS[3])
    assert p.enter().status_code == 302
    study = study_of(app)
    rng = np.random.default_rng(1)
    while True:
        _, data, csrf = p.page()
        spec = h.plan_pages(app, p.sid)[data["index"]]
        if spec["type"] == "headphone_check":
            break
        assert p.submit(data, csrf, h.make_answer(study, spec, rng)).status_code == 200
    html = p.responses[-1].get_data(as_text=True)
    assert "Sound does not play?" in html
    assert report(p, data, csrf, 1).status_code == 200
    status = app.test_client().get("/admin/status.json", headers=bearer()).get_json()
    assert [(r["file"], r["kind"], r["reports"]) for r in status["reports"]] == \
        [("headphones: generated sound 2", "generated", 1)]


# ------------------------------------------------------------------------------- admin table

def test_participant_table_and_json_need_the_admin_token(study_dir, tmp_path):
    app = make_app(study_dir, tmp_path, "study.yaml")
    client = app.test_client()
    assert client.get("/admin/status.json").status_code == 403, "JSON: 403, not the login form"
    assert client.get("/admin/status.json", headers={"Authorization": "Bearer wrong-token-123"}).status_code == 403
    login = client.get("/admin/login").get_data(as_text=True)
    csrf = re.search(r'name="csrf_token" value="([^"]+)"', login).group(1)
    assert client.post("/admin/login", data={"token": h.ADMIN, "csrf_token": csrf}).status_code == 302
    r = client.get("/admin/status.json")       # the admin page's own polling: the login cookie
    assert r.status_code == 200
    assert r.headers["Cache-Control"] == "no-store"
    assert r.get_json()["participants"] == []
    # a participant's browser cannot read it
    p = h.Participant(app.test_client(), PIDS[4])
    p.enter()
    assert p.get("/admin/status.json").status_code == 403


def test_participant_table_rows(study_dir, tmp_path):
    app = make_app(study_dir, tmp_path, "study.yaml")
    rng = np.random.default_rng(5)
    done, _ = h.run_participant(app, app.test_client(), PIDS[5], rng, fail_checks=1)
    failed, _ = h.run_participant(app, app.test_client(), PIDS[6], rng, fail_checks=2)
    midway, _ = h.run_participant(app, app.test_client(), PIDS[7], rng, stop_after=3)
    pages = h.plan_pages(app, midway.sid)
    status = app.test_client().get("/admin/status.json", headers=bearer()).get_json()
    assert status["sessions"] == {"started": 3, "active": 1, "finished": 1, "failed": 1, "expired": 0}
    rows = {r["participant"]: r for r in status["participants"]}
    assert list(rows) == [PIDS[5], PIDS[6], PIDS[7]]
    assert rows[PIDS[5]]["status"] == "finished"
    assert (rows[PIDS[5]]["passed_checks"], rows[PIDS[5]]["failed_checks"]) == (1, 1)
    assert rows[PIDS[5]]["where"] == "finished"
    assert rows[PIDS[6]]["status"] == "failed"
    assert rows[PIDS[6]]["failed_checks"] == 2
    assert rows[PIDS[6]]["end_reason"]
    m = rows[PIDS[7]]
    assert m["status"] == "active"
    assert m["current_page"] == 3
    spec = pages[3]
    assert m["where"] == f"4 of {len(pages)}: {spec.get('block') or spec['page']} ({spec['type']})"
    for r in rows.values():
        assert r["platform"] == "prolific"
        assert r["seconds"] >= 0
        assert r["time_spent"].endswith(" s") or "min" in r["time_spent"]
        assert r["reports"] == 0
    # the admin page shows the same table, and the script that refreshes it
    page = app.test_client().get("/admin/", headers=bearer()).get_data(as_text=True)
    table = re.search(r'<table id="participants">.*?</table>', page, re.S).group(0)
    for pid in PIDS[5:8]:
        assert pid in table
    assert "checks failed" in table
    assert "admin.js" in page
    assert 'data-status-url="/admin/status.json"' in page


def test_duration_format():
    from study_app.monitor import duration
    assert [duration(s) for s in (None, 0, 59, 65, 3600, 3725)] == ["", "0 s", "59 s", "1 min 05 s",
                                                                      "1 h 00 min", "1 h 02 min"]
