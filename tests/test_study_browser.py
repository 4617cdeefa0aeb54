"""End to end in a real browser: headless Debian Chromium (Playwright) against a real server.

A participant arrives from Prolific, goes through consent, questionnaire, training, pairwise,
MUSHRA, 5-level pairwise and Likert pages playing every video, passes one attention check and
fails another, reloads mid-study (and the server restarts) and resumes, finishes and gets the
completion code; a second entry with the same ID cannot start over; a second participant
fails two checks and gets the failure code; the admin export holds exactly the answers given.
The page passes a headphone screening first, and asks to confirm a reload once started. An
MTurk worker goes from the HIT preview to the external submit, and runs the study inside an
iframe of an mturk.com page.
Screenshots go to $STUDY_SCREENSHOTS (or the test's tmp dir).
"""
from __future__ import annotations

import csv
import io
import json
import os
import pathlib
import re
import urllib.parse
import urllib.request
import zlib
from types import SimpleNamespace

import numpy as np
import pytest
import study_helpers as h
from browser_helpers import ARGS as BASE_ARGS
from browser_helpers import Server, chromium

from study_app import create_app
from study_app.context import store_of, study_of
from study_app.storage import ParticipantSession

pytestmark = [pytest.mark.browser, pytest.mark.slow]

ARGS = [*BASE_ARGS, "--disable-background-networking",
        "--disable-component-update", "--no-first-run", "--disable-dev-shm-usage",
        "--autoplay-policy=no-user-gesture-required",
        # the MTurk test frames the loopback server in a (faked) public https page, which
        # Chromium's local-network-access checks would refuse; a real study server is public
        "--disable-features=LocalNetworkAccessChecks,BlockInsecurePrivateNetworkRequests"]


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    folder = tmp_path_factory.mktemp("browser")
    h.make_study(folder, sessions=4, seconds=0.5)
    shots = pathlib.Path(os.environ.get("STUDY_SCREENSHOTS") or folder / "screens")
    shots.mkdir(parents=True, exist_ok=True)
    db = f"sqlite:///{folder / 'study.db'}"

    def make_app():
        return create_app({"STUDY": str(folder / "study.yaml"), "DATABASE_URL": db,
                           "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN,
                           "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(folder / "inst")})
    server = Server(make_app)
    from playwright.sync_api import sync_playwright
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium(), args=ARGS, headless=True)
        ns = SimpleNamespace(folder=folder, shots=shots, server=server, browser=browser)
        yield ns
        browser.close()
    ns.server.stop()


class Driver:
    """Answers the study like a person would, recording every acknowledged answer."""

    def __init__(self, env, pid):
        self.env, self.pid = env, pid
        self.context = env.browser.new_context(viewport={"width": 1280, "height": 900})
        self.page = self.context.new_page()
        self.page.set_default_timeout(20000)
        self.sent = []
        self.sid = None
        self.rng = np.random.default_rng(zlib.crc32(pid.encode()))  # same answers every run
        self.shot_names = []
        self.reason_gates = 0
        # Everything the participant's browser received, for the leak check.
        self.seen_urls, self.seen_bodies = [], []
        self.page.on("request", lambda req: self.seen_urls.append(req.url))
        self.page.route(re.compile(r".*/s/[^/]+/(answer|draft|events)/\d+$"), self._record)

    def _record(self, route):
        """Pass the JSON API calls through, keeping a copy of each response body."""
        response = route.fetch()
        self.seen_bodies.append(response.text())
        route.fulfill(response=response)

    def shot(self, name):
        path = self.env.shots / f"{self.pid}-{len(self.shot_names):02d}-{name}.png"
        self.page.screenshot(path=str(path), full_page=True)
        self.shot_names.append(path)

    def data(self):
        return json.loads(self.page.locator("#page-data").text_content())

    def plan(self):
        return h.plan_pages(self.env.server.app, self.sid)

    def play_all(self):
        n = self.page.locator("video[data-slot], audio[data-slot]").count()
        for k in range(n):
            status = self.page.locator(f".status[data-slot='{k}']")
            if "ok" in (status.get_attribute("class") or ""):
                continue
            self.page.click(f"button.play[data-slot='{k}']")
            self.page.wait_for_selector(f".status[data-slot='{k}'].ok")

    def next(self):
        before = self.page.url, self.data()["index"]
        self.page.wait_for_selector("#next:not([disabled])")
        with self.page.expect_navigation(), self.page.expect_response(lambda r: "/answer/" in r.url) as resp:
            self.page.click("#next")
        assert resp.value.status == 200
        return before

    def answer_page(self, pass_check=True, screenshot=False, before_next=None):
        self.seen_bodies.append(self.page.content())
        data = self.data()
        spec = self.plan()[data["index"]]
        study = study_of(self.env.server.app)
        answer = h.make_answer(study, spec, self.rng, pass_check=pass_check)
        t = spec["type"]
        if t == "consent":
            self.page.check("#agree")
        elif t == "questionnaire":
            self.page.fill("#q-age", str(answer["age"]))
            self.page.select_option("#q-gender", answer["gender"])
            self.page.fill("#q-comments", answer["comments"])
        elif t == "headphone_check":
            # step 1: the calibration noise sets the volume; only then do the trials play
            assert self.page.is_disabled("button.play[data-slot='0']")
            self.page.click("#calibration-play")
            self.page.wait_for_selector("#calibration-done:not([disabled])")
            self.page.click("#calibration-done")
            self.play_all()
        elif t in ("pairwise", "mushra", "likert"):
            self.play_all()
        if t == "headphone_check":
            # each sound is heard once: after playing, no button can play it again
            buttons = self.page.locator("button.play")
            assert buttons.count() == len(spec["trials"])
            assert all(buttons.nth(k).is_disabled() for k in range(buttons.count()))
            for k, c in enumerate(answer["choices"]):
                self.page.check(f"input[name='t-{k}'][value='{c}']")
        if t == "pairwise":
            for q, v in answer["choices"].items():
                self.page.check(f"input[name='q-{q}'][value='{v}']")
            if data.get("reasons_required") and set(answer["choices"].values()) != {"equal"}:
                # a preference without a reason cannot be sent
                assert self.page.is_disabled("#next")
                assert "reason" in self.page.text_content("#message")
                self.reason_gates += 1
            for r in answer["reasons"]:
                self.page.check(f"input[name='reason'][value='{r}']")
        elif t == "mushra":
            for k, v in enumerate(answer["ratings"]):
                self.set_slider(k, v)
        elif t == "likert":
            for sid, v in answer["ratings"].items():
                self.page.check(f"input[name='s-{sid}'][value='{v}']")
        if screenshot:
            self.shot(spec["page"])
        if before_next:
            before_next(answer)
        self.next()
        self.sent.append((data["index"], answer))
        return spec

    def set_slider(self, k, v):
        self.page.eval_on_selector(
            f"input[name='rating-{k}']",
            "(el, v) => { el.value = String(v); el.dispatchEvent(new Event('input', {bubbles: true})); }", v)

    def enter(self):
        self.page.goto(self.env.server.url + h.prolific_url(self.pid))
        if "/s/" in self.page.url:
            self.sid = self.page.url.split("/s/")[1].strip("/")


def test_participant_journey_in_chromium(env):
    d = Driver(env, "5f3a1c9e8b7d6a5f4e3d2c1b")
    d.enter()
    d.shot("consent")
    seen_types, seen_blocks, checks = set(), set(), []
    reloaded = False
    while d.page.locator("#page-data").count():
        data = d.data()
        spec = d.plan()[data["index"]]
        if spec["type"] == "mushra" and not spec.get("check") and not reloaded:
            # Mid-study: watch the videos, move two sliders, wait for the autosave, then the
            # page is reloaded while the server restarts; everything must come back.
            d.play_all()
            with d.page.expect_response(lambda r: "/draft/" in r.url):
                d.set_slider(0, 33)
                d.set_slider(1, 77)
            d.shot("mushra-before-reload")
            env.server = env.server.restart()
            # a third slider moves just before the reload, inside the autosave delay: the
            # page's leave guard asks to confirm and saves that draft on the way out
            dialogs = []
            d.page.once("dialog", lambda dialog: (dialogs.append(dialog.type), dialog.accept()))
            d.set_slider(2, 55)
            d.page.reload()
            assert dialogs == ["beforeunload"]
            assert d.data()["index"] == data["index"]
            assert d.page.input_value("input[name='rating-0']") == "33"
            assert d.page.input_value("input[name='rating-1']") == "77"
            store = store_of(env.server.app)
            for _ in range(100):   # the keepalive request may land after the reload's GET
                draft = store.view_current_page(d.sid)[2].draft or {}
                if draft.get("fields", {}).get("rating-2") == "55":
                    break
                d.page.wait_for_timeout(50)
            assert draft["fields"]["rating-2"] == "55"
            assert 2 in draft["touched"]
            n = len(spec["slots"])
            for k in range(n):
                assert "ok" in d.page.locator(f".status[data-slot='{k}']").get_attribute("class")
            d.shot("mushra-after-reload")
            reloaded = True
        if spec.get("check"):
            checks.append(spec["type"])
        # pass the pairwise attention check, fail the MUSHRA one (one failure is allowed)
        d.answer_page(pass_check=spec["type"] != "mushra",
                      screenshot=spec.get("block", spec["type"]) not in seen_blocks or spec.get("check"))
        seen_types.add(spec["type"])
        seen_blocks.add(spec.get("block", spec["type"]))
    assert reloaded
    assert checks == ["pairwise", "mushra"]
    assert d.reason_gates > 0
    assert seen_types >= {"consent", "questionnaire", "instructions", "pairwise", "mushra", "likert", "headphone_check"}
    d.shot("finish")
    assert d.page.locator("#completion-code").text_content() == "DONE1234"
    assert d.page.get_attribute("#return-link", "href") == \
        "https://app.prolific.com/submissions/complete?cc=DONE1234"

    # the same Prolific link again, in a fresh browser: cannot start over, but sees its code again
    again = Driver(env, d.pid)
    again.enter()
    assert again.sid is None
    assert again.page.locator("#completion-code").text_content() == "DONE1234"
    again.shot("second-entry")

    # a second participant fails two attention checks and gets the failure code
    f = Driver(env, "6a4b2c0d9e8f7a6b5c4d3e2f")
    f.enter()
    while f.page.locator("#page-data").count():
        spec = f.plan()[f.data()["index"]]
        f.answer_page(pass_check=False)
    f.shot("failed")
    assert f.page.locator("#failure-code").text_content() == "FAIL5678"

    # nothing the participants' browsers received names a condition or a stimulus file
    study = study_of(env.server.app)
    hidden = set(study.conditions) | {s.file for s in study.manifest.stimuli}
    for drv in (d, f):
        drv.seen_bodies.append(drv.page.content())
        for text in drv.seen_urls + drv.seen_bodies:
            assert not any(x.lower() in text.lower() for x in hidden), text[:200]
    assert sum(len(drv.seen_urls) for drv in (d, f)) > 50

    # the admin export contains exactly the answers given
    req = urllib.request.Request(env.server.url + "/admin/export/results.csv",
                                 headers={"Authorization": f"Bearer {h.ADMIN}"})
    rows = list(csv.DictReader(io.StringIO(urllib.request.urlopen(req).read().decode())))
    keys = h.as_keys(rows)
    assert len(keys) == len(set(keys))
    assert set(keys) == h.expected_rows(env.server.app, [d, f])
    # a real browser's playback is judged watched by the server (every byte sent, time on the page)
    judged = [(r["playback_implausible"], r["playback_reason"]) for r in rows
              if r["session"] == d.sid and r["playback_implausible"] != ""]
    assert judged and set(judged) == {("0", "")}, judged
    raw = json.loads(urllib.request.urlopen(urllib.request.Request(
        env.server.url + "/admin/export/raw.json", headers={"Authorization": f"Bearer {h.ADMIN}"})).read())
    kinds = {e["kind"] for e in raw["events"]}
    assert {"play", "ended"} <= kinds

    # admin pages in the browser (login form with CSRF)
    admin = env.browser.new_page(viewport={"width": 1280, "height": 900})
    admin.goto(env.server.url + "/admin/")
    admin.fill("input[name=token]", h.ADMIN)
    admin.click("button[type=submit]")
    admin.wait_for_selector("#sessions")
    admin.screenshot(path=str(env.shots / "admin.png"), full_page=True)
    assert "6a4b2c0d9e8f7a6b5c4d3e2f" in admin.content()


def test_narrow_window_is_gated(env):
    d = Driver(env, "7b5c3d1e0f9a8b7c6d5e4f3a")
    d.page.set_viewport_size({"width": 600, "height": 800})
    d.enter()
    assert d.page.is_visible("#gate")
    # the overlay covers the page: nothing can be clicked; ticking the box by script does not
    # unlock Next either
    d.page.eval_on_selector("#agree", "el => { el.checked = true; el.dispatchEvent(new Event('input', {bubbles: true})); }")
    assert d.page.is_disabled("#next")
    d.shot("narrow-gate")
    d.page.set_viewport_size({"width": 1200, "height": 800})
    d.page.wait_for_selector("#gate", state="hidden")
    assert d.page.is_enabled("#next")


def test_mturk_hit_from_preview_to_external_submit(env):
    """An MTurk worker: the preview creates nothing, the accepted HIT runs the study, and the
    finish page's form posts the assignment and the code to the HIT's turkSubmitTo (caught
    in the browser: the test never reaches MTurk)."""
    text = h.STUDY_YAML.format(sessions=2).replace("platform: prolific", "platform: mturk").replace(
        "id: gesture-test", "id: gesture-mturk")
    h.make_study(env.folder, yaml_text=text, name="mturk.yaml")
    db = f"sqlite:///{env.folder / 'mturk.db'}"
    server = Server(lambda: create_app({
        "STUDY": str(env.folder / "mturk.yaml"), "DATABASE_URL": db, "SECRET_KEY": h.SECRET,
        "ADMIN_TOKEN": h.ADMIN, "INSTANCE_PATH": str(env.folder / "inst-mturk")}))
    try:
        d = Driver(SimpleNamespace(server=server, shots=env.shots, browser=env.browser), "A3MTURKWORKER1")
        base = f"{server.url}/start/gesture-mturk?hitId=HIT42"
        d.page.goto(base + "&assignmentId=ASSIGNMENT_ID_NOT_AVAILABLE")
        assert d.page.is_visible("#preview")
        assert "Accept the HIT" in d.page.content()
        with store_of(server.app).Session() as db_session:
            assert db_session.query(ParticipantSession).count() == 0
        d.page.goto(base + "&assignmentId=ASSIGN7&workerId=A3MTURKWORKER1"
                    "&turkSubmitTo=https%3A%2F%2Fworkersandbox.mturk.com")
        assert "/s/" in d.page.url
        d.sid = d.page.url.split("/s/")[1].strip("/")
        while d.page.locator("#page-data").count():
            d.answer_page()
        assert d.page.locator("#completion-code").text_content() == "DONE1234"
        d.shot("mturk-finish")
        posted = []

        def external_submit(route):
            posted.append((route.request.method, route.request.post_data))
            route.fulfill(status=200, content_type="text/html", body="<p>HIT submitted</p>")
        d.page.route("https://workersandbox.mturk.com/**", external_submit)
        with d.page.expect_navigation():
            d.page.click("form button[type=submit]")
        assert "HIT submitted" in d.page.content()
        method, body = posted[0]
        form = dict(urllib.parse.parse_qsl(body))
        assert method == "POST"
        assert form == {"assignmentId": "ASSIGN7", "completion_code": "DONE1234"}
        d.context.close()

        # MTurk shows an ExternalQuestion in an iframe on its own https page: the study must
        # allow that framing and its cookie must work there (SameSite=None; Secure; Partitioned).
        w = Driver(SimpleNamespace(server=server, shots=env.shots, browser=env.browser), "A3MTURKWORKER2")
        study_url = (base + "&assignmentId=ASSIGN8&workerId=A3MTURKWORKER2"
                     "&turkSubmitTo=https%3A%2F%2Fworkersandbox.mturk.com")
        host = "https://workersandbox.mturk.com/mturk/preview?groupId=G1"
        w.page.route(host, lambda route: route.fulfill(
            status=200, content_type="text/html",
            body=f'<!doctype html><iframe src="{study_url}" width="1250" height="850"></iframe>'))
        w.page.goto(host)
        frame = w.page.frame_locator("iframe")
        frame.locator("#agree").check()
        frame.locator("#next:not([disabled])").click()
        frame.locator("#q-age").wait_for()          # the next page, reached with the session cookie
        child = w.page.main_frame.child_frames[0]
        assert child.url.startswith(server.url + "/s/")
        assert "/s/" in child.url
        w.shot("mturk-in-iframe")
        with store_of(server.app).Session() as db_session:
            sess = db_session.query(ParticipantSession).filter_by(participant="A3MTURKWORKER2").one()
            assert sess.current_page == 1
            assert sess.platform_data["assignmentId"] == "ASSIGN8"
        w.context.close()
    finally:
        server.stop()
