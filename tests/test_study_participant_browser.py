"""The participant's experience in a real browser (headless Debian Chromium, Playwright), at 1366x768 and
390x844: a stale second tab of the same session is warned and reloaded (nothing stored changes); Back asks
before leaving the study even on an untouched page; the questionnaire's Next waits for the required
answers and says what is missing; the headphone check sets the volume with a calibration noise before its
trials; on a phone the pairwise videos stack at full width and MUSHRA shows one video per row.
One study and one server serve every test; each test is its own participant.
"""
from __future__ import annotations

import json
import os
import pathlib
from types import SimpleNamespace

import pytest
import study_helpers as h
from browser_helpers import ARGS as BASE_ARGS
from browser_helpers import Server, chromium

from study_app import create_app
from study_app.context import store_of
from study_app.headphones import correct_choice
from study_app.storage.tables import Answer

pytestmark = [pytest.mark.browser, pytest.mark.slow]

ARGS = [*BASE_ARGS, "--disable-background-networking", "--disable-component-update", "--no-first-run",
        "--disable-dev-shm-usage", "--autoplay-policy=no-user-gesture-required"]
LAPTOP = {"width": 1366, "height": 768}
PHONE = {"width": 390, "height": 844}
VIEWPORTS = [pytest.param(LAPTOP, id="1366x768"), pytest.param(PHONE, id="390x844")]

STUDY = """\
id: px-test
title: Participant experience
stimuli: stim/manifest.csv
platform: prolific
sessions: 12
seed: 5
completion_code: DONE1234
failure_code: FAIL5678
min_width: 320
block_mobile: false
pages:
  - {type: consent, id: consent, title: Consent, text: You will watch short videos.}
  - type: questionnaire
    id: about
    title: About you
    questions:
      - {id: age, type: number, text: Your age, min: 18, max: 99}
      - {id: gender, type: choice, text: Gender, options: [female, male, other]}
      - {id: comments, type: text, text: "Anything else?", required: false, max_length: 50}
  - {type: headphone_check, id: headphones, trials: 1, pass: 1}
  - type: pairwise
    id: hl
    title: Which character moves more like a real person?
    conditions: [SYSALPHA, SYSBETA]
    levels: 5
    questions: [{id: human_likeness, text: "In which video does the character gesture more like a real person?"}]
    reasons: [{id: smooth, text: Smoother motion}, {id: rhythm, text: Better rhythm}]
    pages: 1
    muted: true
  - type: mushra
    id: ratings
    conditions: [SYSALPHA, SYSBETA]
    reference: NATURALGT
    question: {id: hl_rating, text: "How human-like does the gesture motion appear?"}
    pages: 1
    muted: true
  - {type: finish, id: finish, text: Thank you.}
"""


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    folder = tmp_path_factory.mktemp("px")
    path = h.make_study(folder, seconds=0.5, yaml_text=STUDY)
    shots = pathlib.Path(os.environ.get("STUDY_SCREENSHOTS") or folder / "screens")
    shots.mkdir(parents=True, exist_ok=True)
    app = create_app({"STUDY": str(path), "DATABASE_URL": f"sqlite:///{folder / 'px.db'}",
                      "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                      "INSTANCE_PATH": str(folder / "inst")})
    server = Server(lambda: app)
    from playwright.sync_api import sync_playwright
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium(), args=ARGS, headless=True)
        yield SimpleNamespace(app=app, server=server, browser=browser, shots=shots, n=[0])
        browser.close()
    server.stop()


class Person:
    """One participant in a browser context of the given size (a context shares its cookie between tabs)."""

    def __init__(self, env, viewport, start=True):
        env.n[0] += 1
        self.env, self.viewport = env, viewport
        self.pid = f"{0xa0 + env.n[0]:02x}" * 12
        self.context = env.browser.new_context(viewport=viewport)
        self.page = self.tab()
        if start:
            self.page.goto(env.server.url + h.prolific_url(self.pid, "px-test"))
            self.sid = self.page.url.split("/s/")[1].strip("/")

    def tab(self):
        page = self.context.new_page()
        page.set_default_timeout(20000)
        return page

    def index(self, page=None):
        return json.loads((page or self.page).locator("#page-data").text_content())["index"]

    def spec(self, page=None):
        return h.plan_pages(self.env.app, self.sid)[self.index(page)]

    def shot(self, name, page=None):
        size = f"{self.viewport['width']}x{self.viewport['height']}"
        (page or self.page).screenshot(path=str(self.env.shots / f"px-{name}-{size}.png"), full_page=True)

    def calibrate(self, page=None):
        page = page or self.page
        page.click("#calibration-play")
        page.wait_for_selector("#calibration-done:not([disabled])")
        page.click("#calibration-done")

    def answer(self):
        """Answer the current page as an attentive participant and go to the next one."""
        p, spec = self.page, self.spec()
        if spec["type"] == "consent":
            p.check("#agree")
        elif spec["type"] == "questionnaire":
            p.fill("#q-age", "30")
            p.select_option("#q-gender", "other")
        elif spec["type"] == "headphone_check":
            self.calibrate()
        if spec["type"] in ("headphone_check", "pairwise", "mushra"):
            for k in range(p.locator("[data-slot].status").count()):
                p.click(f"button.play[data-slot='{k}']")
                p.wait_for_selector(f".status[data-slot='{k}'].ok")
        if spec["type"] == "headphone_check":
            for k, order in enumerate(spec["trials"]):
                p.check(f"input[name='t-{k}'][value='{correct_choice(order)}']")
        p.evaluate("""() => {
          document.querySelectorAll('input[type=range]').forEach((r, i) => {
            r.value = String(30 + 10 * i); r.dispatchEvent(new Event('input', {bubbles: true})); });
          const first = {};
          document.querySelectorAll('fieldset.question input[type=radio]').forEach(r => { first[r.name] = first[r.name] || r; });
          Object.values(first).forEach(r => { r.checked = true; r.dispatchEvent(new Event('input', {bubbles: true})); });
        }""")
        p.wait_for_selector("#next:not([disabled])")
        with p.expect_navigation():
            p.click("#next")

    def goto(self, kind):
        while self.spec()["type"] != kind:
            self.answer()

    def close(self):
        self.context.close()


BOX_JS = ("el => { const r = el.getBoundingClientRect(); "
          "return {x: r.left, y: r.top, r: r.right, b: r.bottom, w: r.width, h: r.height}; }")


def boxes(page, selector):
    return page.eval_on_selector_all(selector, f"els => els.map({BOX_JS})")


def apart(bs, what):
    for a in range(len(bs)):
        for b in range(a + 1, len(bs)):
            p, q = bs[a], bs[b]
            assert min(p["r"], q["r"]) - max(p["x"], q["x"]) <= 0.5 or \
                min(p["b"], q["b"]) - max(p["y"], q["y"]) <= 0.5, f"{what} {a} and {b} overlap: {p} {q}"


def no_sideways_scroll(page):
    sw, w = page.evaluate("() => [document.documentElement.scrollWidth, window.innerWidth]")
    assert sw <= w, f"the page is {sw} px wide in a {w} px window"


def stored(env, sid, index):
    with store_of(env.app).Session() as db:
        return [a.data for a in db.query(Answer).filter_by(session_id=sid, page_index=index)]


def notice_text(page):
    page.wait_for_selector("#notice")
    return page.text_content("#notice")


@pytest.mark.parametrize("viewport", VIEWPORTS)
def test_a_stale_second_tab_is_warned_and_reloaded(env, viewport):
    """Two tabs on one session: the first answers the questionnaire; the second, still showing it, sends a
    different answer (409 'stale', nothing stored changes), warns and reloads to the current page. A stale
    tab that only autosaves (409 on the draft) catches up the same way."""
    person = Person(env, viewport)
    try:
        person.answer()                                  # consent
        first, second = person.page, person.tab()
        second.goto(env.server.url + f"/s/{person.sid}/")
        assert person.index(second) == person.index(first) == 1
        first.fill("#q-age", "30")
        first.select_option("#q-gender", "other")
        with first.expect_navigation():
            first.click("#next")
        assert person.index(first) == 2
        kept = stored(env, person.sid, 1)
        assert [k["responses"]["age"] for k in kept] == [30] and kept[0]["responses"]["gender"] == "other"
        # the stale tab answers differently and submits at once (before its autosave)
        with second.expect_navigation():
            with second.expect_response(lambda r: "/answer/" in r.url) as resp:
                second.evaluate("""() => {
                  const age = document.querySelector('#q-age'), gender = document.querySelector('#q-gender');
                  age.value = '45'; age.dispatchEvent(new Event('input', {bubbles: true}));
                  gender.value = 'male'; gender.dispatchEvent(new Event('change', {bubbles: true}));
                  document.querySelector('#page-form').requestSubmit();
                }""")
            assert resp.value.status == 409 and resp.value.json()["stale"] is True
            # warned in place before the reload
            assert "already answered in another tab" in notice_text(second)
        assert "already answered in another tab" in notice_text(second), "the warning stays after the reload"
        assert person.index(second) == 2, "the stale tab now shows the current page"
        assert stored(env, person.sid, 1) == kept, "the first tab's answer is kept"
        person.shot("stale-tab", second)
        # the first tab moves on again; the second only touches its (now stale) page: the autosave says so
        person.answer()                                  # the headphone check, in the first tab
        with second.expect_navigation():
            with second.expect_response(lambda r: "/draft/" in r.url) as draft:
                second.click("#calibration-play")
                second.wait_for_selector("#calibration-done:not([disabled])")
                second.click("#calibration-done")        # a change: the autosave gets 409
            assert draft.value.status == 409 and draft.value.json()["stale"] is True
        assert person.index(second) == person.index(first) == 3
        assert "already answered in another tab" in notice_text(second)
    finally:
        person.close()


@pytest.mark.parametrize("viewport", VIEWPORTS)
def test_back_asks_before_leaving_an_untouched_page(env, viewport):
    """Back on an untouched page opens the page's dialog instead of leaving: on the first page (the same
    document) and on a later one (answered pages leave no history entries of their own). Stay keeps the
    participant on the current page; Leave goes back to where they came from. No browser prompt."""
    person = Person(env, viewport, start=False)
    try:
        p = person.page
        prompts = []
        p.on("dialog", lambda d: (prompts.append(d.type), d.dismiss()))
        p.goto(env.server.url + "/")                     # where the participant came from (Prolific)
        p.goto(env.server.url + h.prolific_url(person.pid, "px-test"))
        person.sid = p.url.split("/s/")[1].strip("/")
        p.go_back()
        p.wait_for_selector("#leave-dialog[open]")
        assert "/s/" in p.url and person.index() == 0
        person.shot("back-dialog")
        p.click("#leave-stay")
        assert p.locator("#leave-dialog[open]").count() == 0
        person.answer()                                  # consent: now on the questionnaire, untouched
        assert person.index() == 1
        p.go_back()
        p.wait_for_selector("#leave-dialog[open]")
        assert "/s/" in p.url and person.index() == 1, "Back shows the current page, not the answered one"
        p.click("#leave-stay")
        p.go_back()
        p.wait_for_selector("#leave-dialog[open]")
        with p.expect_navigation():
            p.click("#leave-go")
        assert p.url == env.server.url + "/", "Leave goes back out of the study"
        assert prompts == []
    finally:
        person.close()


@pytest.mark.parametrize("viewport", VIEWPORTS)
def test_questionnaire_next_waits_for_the_required_answers(env, viewport):
    """Next is disabled until every required question has a valid answer; the hint (described by Next)
    names what is missing, a wrong value is marked invalid; optional questions may stay empty."""
    person = Person(env, viewport)
    try:
        person.goto("questionnaire")
        p = person.page
        assert p.is_disabled("#next")
        assert p.get_attribute("#next", "aria-describedby") == "message"
        hint = p.text_content("#message")
        assert "Your age" in hint and "Gender" in hint and "Anything else" not in hint
        p.fill("#q-age", "12")
        assert p.is_disabled("#next")
        assert "Your age (a number from 18 to 99)" in p.text_content("#message")
        assert p.get_attribute("#q-age", "aria-invalid") == "true"
        p.fill("#q-age", "30")
        assert p.get_attribute("#q-age", "aria-invalid") is None
        assert p.is_disabled("#next") and p.text_content("#message") == "Still to answer: Gender."
        p.select_option("#q-gender", "other")
        assert p.is_enabled("#next") and p.text_content("#message") == ""
        p.fill("#q-comments", "x" * 50)
        assert p.is_enabled("#next")
        person.shot("questionnaire")
        with p.expect_response(lambda r: "/answer/" in r.url) as resp, p.expect_navigation():
            p.click("#next")
        assert resp.value.status == 200
    finally:
        person.close()


@pytest.mark.parametrize("viewport", VIEWPORTS)
def test_headphone_check_sets_the_volume_before_the_trials(env, viewport):
    """Step 1 plays a calibration noise (as often as wanted); only 'The volume is comfortable' unlocks the
    trials, whose sounds still play once. The calibration survives a reload (the draft)."""
    person = Person(env, viewport)
    try:
        person.goto("headphone_check")
        p = person.page
        assert p.is_disabled("button.play[data-slot='0']"), "the trials wait for the calibration"
        assert p.is_disabled("#calibration-done")
        assert "volume" in p.text_content("#message")
        noise = p.request.get(env.server.url + p.get_attribute("#calibration-sound", "src"))   # its cookie
        assert noise.status == 200 and noise.headers["content-type"] == "audio/wav"
        p.click("#calibration-play")
        p.wait_for_selector("#calibration-done:not([disabled])")
        assert p.is_disabled("button.play[data-slot='0']")
        with p.expect_response(lambda r: "/draft/" in r.url):
            p.click("#calibration-done")
        assert p.is_enabled("button.play[data-slot='0']")
        assert p.is_enabled("#calibration-play"), "the noise can be played again"
        person.shot("headphone-calibrated")
        p.reload()
        assert p.is_enabled("button.play[data-slot='0']"), "the calibration is kept over a reload"
        p.click("button.play[data-slot='0']")
        p.wait_for_selector(".status[data-slot='0'].ok")
        assert p.is_disabled("button.play[data-slot='0']"), "each trial is still heard once"
        spec = person.spec()
        p.check(f"input[name='t-0'][value='{correct_choice(spec['trials'][0])}']")
        with p.expect_response(lambda r: "/answer/" in r.url) as resp, p.expect_navigation():
            p.click("#next")
        assert resp.value.status == 200
    finally:
        person.close()


def test_phone_layout_stacks_videos_and_gives_each_rating_a_row(env):
    """At 390x844: the pairwise videos one above the other, each at least 300 px wide; MUSHRA one video per
    row, each slider at least 250 px wide, band labels apart; nothing scrolls sideways. At 1366x768 the
    pairwise videos stay side by side."""
    person = Person(env, PHONE)
    try:
        p = person.page
        person.goto("pairwise")
        p.wait_for_timeout(250)
        no_sideways_scroll(p)
        videos = boxes(p, "video[data-slot]")
        assert len(videos) == 2
        assert videos[1]["y"] >= videos[0]["b"], "stacked"
        assert all(v["w"] >= 300 for v in videos), videos
        apart(boxes(p, ".player"), "players")
        person.shot("phone-pairwise")
        p.set_viewport_size(LAPTOP)
        p.wait_for_timeout(250)
        videos = boxes(p, "video[data-slot]")
        assert abs(videos[0]["y"] - videos[1]["y"]) < 1, "side by side on a laptop"
        p.set_viewport_size(PHONE)
        person.goto("mushra")
        p.wait_for_timeout(250)
        no_sideways_scroll(p)
        videos, sliders = boxes(p, "video[data-slot]"), boxes(p, "input[type=range]")
        cards = boxes(p, ".rating-card")
        assert len(videos) == len(sliders) == len(cards) == 3
        assert all(v["w"] >= 300 for v in videos), videos
        assert all(s["w"] >= 250 for s in sliders), sliders
        assert all(cards[k + 1]["y"] >= cards[k]["b"] for k in range(2)), "one video per row"
        apart(cards, "cards")
        for c in range(3):
            card = p.locator(".rating-card").nth(c)
            labels = card.locator(".band-label").evaluate_all(f"els => els.map({BOX_JS})")
            assert len(labels) == 5
            apart(labels, f"band labels of card {c + 1}")
            assert all(cards[c]["x"] <= lab["x"] and lab["r"] <= cards[c]["r"] + 0.5 for lab in labels)
        person.shot("phone-mushra")
    finally:
        person.close()
