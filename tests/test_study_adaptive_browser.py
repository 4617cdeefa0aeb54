"""An adaptive pairwise study (study_app.adaptive) walked in headless Chromium: each participant's trial
pages show the pair the server chose at the first view (stored in the plan), the browser plays exactly
those files to the end, the answers feed the estimate, and nobody is flagged for playback."""
from __future__ import annotations

import csv
import io
import time
from types import SimpleNamespace

import pytest
import study_helpers as h
from browser_helpers import Server, chromium
from test_study_browser import ARGS, Driver

from study_app import create_app
from study_app.adaptive import adaptive_status
from study_app.context import store_of, study_of
from study_app.storage.tables import MediaServed

pytestmark = [pytest.mark.browser, pytest.mark.slow]

YAML = h.STUDY_YAML.split("  - type: questionnaire")[0].replace(
    "min_width: 800", "min_width: 800\nnew_sessions_per_address: 0") + """\
  - type: pairwise
    id: hl
    conditions: [SYSALPHA, SYSBETA, NATURALGT]
    questions:
      - {{id: human_likeness, text: "In which video does the character gesture more like a real person?"}}
    pages: 3
    adaptive: true
    exploration: 0.2
  - type: finish
    id: finish
    text: Thank you for taking part.
"""


@pytest.fixture()
def env(tmp_path):
    path = h.make_study(tmp_path, yaml_text=YAML.format(sessions=3), seconds=0.5)
    db = f"sqlite:///{tmp_path / 'study.db'}"
    server = Server(lambda: create_app({"STUDY": str(path), "DATABASE_URL": db, "SECRET_KEY": h.SECRET,
                                        "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                                        "INSTANCE_PATH": str(tmp_path / "inst"), "ADMIN_REFRESH_SECONDS": 1}))
    shots = tmp_path / "screens"
    shots.mkdir()
    from playwright.sync_api import sync_playwright
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium(), args=ARGS, headless=True)
        yield SimpleNamespace(folder=tmp_path, shots=shots, server=server, browser=browser)
        browser.close()
    server.stop()


def test_adaptive_study_in_chromium(env):
    app = env.server.app
    study, store = study_of(app), store_of(app)
    by_file = study.manifest.by_file()
    shown = {}
    # the researcher watches the admin page while participants answer (Bearer token on every request)
    admin = env.browser.new_context(extra_http_headers={"Authorization": f"Bearer {h.ADMIN}"})
    board = admin.new_page()
    board.goto(env.server.url + "/admin/")
    assert board.locator("#adaptive tbody tr").count() == 1
    assert board.text_content("#adaptive tbody td:nth-child(2)") == "0"
    for pid in ("5f3a1c9e8b7d6a5f4e3d2c01", "5f3a1c9e8b7d6a5f4e3d2c02", "5f3a1c9e8b7d6a5f4e3d2c03"):
        d = Driver(env, pid)
        d.enter()
        while d.page.locator("#page-data").count():
            spec = d.answer_page(screenshot=False)
            if spec["type"] == "pairwise":
                stored = d.plan()[d.sent[-1][0]]
                assert stored["chosen"] in ("informative", "explore")
                shown[(d.sid, d.sent[-1][0])] = stored
        assert "DONE1234" in d.page.content()
        d.context.close()
    assert len(shown) == 9
    # the table refreshed by itself (status.json every second) to every vote, without a reload
    # (polled from here: the admin page's CSP forbids the eval that Playwright's string predicates need)
    votes = "#adaptive tbody td:nth-child(2)"
    deadline = time.monotonic() + 20.0
    while board.text_content(votes) != "9" and time.monotonic() < deadline:
        board.wait_for_timeout(200)
    assert board.text_content(votes) == "9"
    assert " > " in board.text_content("#adaptive tbody td:nth-child(3)")
    admin.close()
    # the browser was sent every byte of exactly the chosen files, in the sides the plan says
    with store.ReadSession() as db:
        served = {(r.session_id, r.page_index, r.slot): r.total for r in db.query(MediaServed)}
    for (sid, index), spec in shown.items():
        left, right = (spec["a"], spec["b"]) if spec["position_a"] == "left" else (spec["b"], spec["a"])
        assert served[(sid, index, 0)] == (study.manifest.root / left).stat().st_size
        assert served[(sid, index, 1)] == (study.manifest.root / right).stat().st_size
    auth = {"Authorization": f"Bearer {h.ADMIN}"}
    export = app.test_client().get("/admin/export/results.csv", headers=auth).get_data(as_text=True)
    rows = list(csv.DictReader(io.StringIO(export)))
    assert len(rows) == 9
    for r in rows:
        spec = shown[(r["session"], int(r["trial"]))]
        assert (r["condition_a"], r["condition_b"]) == (by_file[spec["a"]].condition, by_file[spec["b"]].condition)
        assert r["playback_implausible"] == "0", r["playback_reason"]
    status = adaptive_status(store, study)
    assert status[0]["votes"] == 9 and sorted(status[0]["order"]) == sorted(["SYSALPHA", "SYSBETA", "NATURALGT"])
