"""Layout for comparing, measured in a real browser (headless Debian Chromium, Playwright).

A participant goes through a pairwise page, MUSHRA pages with 5 and 6 videos (side-by-side grid and the
HEMVIP display), and Likert pages; on each page the test measures bounding boxes at 1366x768 (a common
laptop) and 390x844 (a phone, with phones allowed): the question and Next are visible without
scrolling, every MUSHRA video and slider is visible at once in one row or grid (on the phone: the pairwise
videos one above the other and one MUSHRA video per row, at full width), Likert point columns are
equally wide, band labels do not overlap and nothing overflows sideways. Screenshots go to
$STUDY_SCREENSHOTS (or the test's tmp dir).
"""
from __future__ import annotations

import json
import os
import pathlib
import urllib.request
from types import SimpleNamespace

import numpy as np
import pytest
import study_helpers as h
from browser_helpers import ARGS as BASE_ARGS
from browser_helpers import Server, chromium
from layout_helpers import make_layout_study, make_more_study

from study_app import create_app
from study_app.context import store_of, study_of
from study_app.storage import Event

pytestmark = [pytest.mark.browser, pytest.mark.slow]

ARGS = [*BASE_ARGS, "--disable-background-networking",
        "--disable-component-update", "--no-first-run", "--disable-dev-shm-usage",
        "--autoplay-policy=no-user-gesture-required"]
LAPTOP = {"width": 1366, "height": 768}
PHONE = {"width": 390, "height": 844}


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    folder = tmp_path_factory.mktemp("layout")
    path = make_layout_study(folder)
    shots = pathlib.Path(os.environ.get("STUDY_SCREENSHOTS") or folder / "screens")
    shots.mkdir(parents=True, exist_ok=True)
    app = create_app({"STUDY": str(path), "DATABASE_URL": f"sqlite:///{folder / 'layout.db'}",
                      "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                      "INSTANCE_PATH": str(folder / "inst"), "ADMIN_REFRESH_SECONDS": 1})
    server = Server(lambda: app)
    from playwright.sync_api import sync_playwright
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium(), args=ARGS, headless=True)
        yield SimpleNamespace(folder=folder, shots=shots, server=server, browser=browser, app=app)
        browser.close()
    server.stop()


class Journey:
    """One participant going through the layout study page by page (pages in definition order)."""

    def __init__(self, env, pid, study_id="layout-test"):
        self.env = env
        self.context = env.browser.new_context(viewport=LAPTOP)
        self.page = self.context.new_page()
        self.page.set_default_timeout(20000)
        self.page.goto(env.server.url + h.prolific_url(pid, study_id))
        assert "/s/" in self.page.url
        self.sid = self.page.url.split("/s/")[1].strip("/")

    def data(self):
        return json.loads(self.page.locator("#page-data").text_content())

    def block(self):
        return h.plan_pages(self.env.app, self.sid)[self.data()["index"]]["block"]

    def goto(self, block):
        """Answer pages until the current page belongs to ``block``."""
        while self.block() != block:
            self.answer()
        self.page.set_viewport_size(LAPTOP)
        self.page.wait_for_timeout(100)

    def play_all(self):
        for k in range(self.page.locator("video[data-slot]").count()):
            if "ok" not in (self.page.get_attribute(f".status[data-slot='{k}']", "class") or ""):
                self.page.click(f"button.play[data-slot='{k}']")
                self.page.wait_for_selector(f".status[data-slot='{k}'].ok")

    def answer(self):
        self.page.set_viewport_size(LAPTOP)
        self.play_all()
        self.page.evaluate("""() => {
          document.querySelectorAll('input[type=range]').forEach((r, i) => {
            r.value = String(20 + 10 * i); r.dispatchEvent(new Event('input', {bubbles: true})); });
          const last = {};
          document.querySelectorAll('input[type=radio]').forEach(r => { last[r.name] = r; });
          Object.values(last).forEach(r => { r.checked = true; r.dispatchEvent(new Event('input', {bubbles: true})); });
          document.querySelectorAll('input[name=reason]').forEach(c => {
            c.checked = true; c.dispatchEvent(new Event('change', {bubbles: true})); });
        }""")
        self.page.wait_for_selector("#next:not([disabled])")
        with self.page.expect_navigation():
            self.page.click("#next")

    def at(self, viewport, name):
        """Resize the window, let the page settle, take a screenshot."""
        self.page.set_viewport_size(viewport)
        self.page.wait_for_timeout(250)
        self.page.screenshot(path=str(self.env.shots / f"{name}-{viewport['width']}x{viewport['height']}.png"))

    def box(self, selector):
        return self.page.eval_on_selector(selector, BOX_JS)

    def boxes(self, selector):
        return self.page.eval_on_selector_all(selector, f"els => els.map({BOX_JS})")

    def viewport(self):
        return self.page.evaluate("() => ({w: window.innerWidth, h: window.innerHeight, sx: window.scrollX, "
                                  "sy: window.scrollY, sw: document.documentElement.scrollWidth})")


BOX_JS = ("el => { const r = el.getBoundingClientRect(); "
          "return {x: r.left, y: r.top, r: r.right, b: r.bottom, w: r.width, h: r.height}; }")


def assert_visible(j, box, what):
    """The box lies inside the window as it is shown (no scrolling)."""
    vp = j.viewport()
    assert vp["sy"] == 0
    assert box["w"] > 0 and box["h"] > 0, what
    assert box["y"] >= 0 and box["b"] <= vp["h"] + 0.5, f"{what} not inside the window height {vp['h']}: {box}"
    assert box["x"] >= 0 and box["r"] <= vp["w"] + 0.5, f"{what} not inside the window width {vp['w']}: {box}"


def assert_no_sideways_overflow(j):
    vp = j.viewport()
    assert vp["sw"] <= vp["w"], f"the page is {vp['sw']} px wide in a {vp['w']} px window"


def assert_apart(boxes, what):
    """No two boxes overlap (touching is fine)."""
    for a in range(len(boxes)):
        for b in range(a + 1, len(boxes)):
            p, q = boxes[a], boxes[b]
            overlap_x = min(p["r"], q["r"]) - max(p["x"], q["x"])
            overlap_y = min(p["b"], q["b"]) - max(p["y"], q["y"])
            assert overlap_x <= 0.5 or overlap_y <= 0.5, f"{what} {a} and {b} overlap: {p} {q}"


@pytest.fixture(scope="module")
def journey(env):
    j = Journey(env, "5f3a1c9e8b7d6a5f4e3d2c1b")
    yield j
    j.context.close()


def test_pairwise_question_and_next_visible_without_scrolling(journey):
    j = journey
    j.goto("hl")
    for vp in (LAPTOP, {"width": 1366, "height": 657}):   # 657: a 1366x768 screen minus the browser's bars
        j.at(vp, "pairwise")
        videos = j.boxes("video[data-slot]")
        assert len(videos) == 2
        assert abs(videos[0]["y"] - videos[1]["y"]) < 1, "the two videos side by side"
        for k, v in enumerate(videos):
            assert_visible(j, v, f"video {k}")
            assert v["h"] >= 150, "videos stay large enough to compare"
            assert abs(v["w"] / v["h"] - 16 / 9) < 0.02, "16:9 clips keep their aspect ratio"
        assert_visible(j, j.box("fieldset.question"), "the question")
        assert_visible(j, j.box("fieldset.reasons"), "the reasons")
        assert_visible(j, j.box("#next"), "Next")
        assert_no_sideways_overflow(j)
    j.at(PHONE, "pairwise")
    assert_no_sideways_overflow(j)
    videos = j.boxes("video[data-slot]")
    assert videos[1]["y"] >= videos[0]["b"], "one above the other on a phone (HEMVIP's layout)"
    for k, v in enumerate(videos):
        assert v["w"] >= 300 and v["x"] >= 0 and v["r"] <= PHONE["width"], f"video {k} at full width: {v}"


def check_mushra_grid(j, n, name, numbers, rows=1):
    j.at(LAPTOP, name)
    videos = j.boxes("video[data-slot]")
    sliders = j.boxes("input[type=range]")
    assert len(videos) == len(sliders) == n
    assert len({round(v["y"]) for v in videos}) == rows, f"all videos in {rows} row(s)"
    per_row = -(-n // rows)
    assert len({round(v["x"]) for v in videos}) == per_row
    assert all(videos[k]["x"] < videos[k + 1]["x"] for k in range(n - 1) if (k + 1) % per_row)
    for k in range(n):
        assert_visible(j, videos[k], f"video {k + 1}")
        assert_visible(j, sliders[k], f"slider {k + 1}")
        assert videos[k]["h"] >= 96
    assert_apart(videos, "videos")
    assert_visible(j, j.box("#next"), "Next")
    assert_no_sideways_overflow(j)
    assert j.page.locator("output[data-slot]").count() == (n if numbers else 0)
    check_band_labels(j)
    j.at(PHONE, name)
    assert_no_sideways_overflow(j)
    videos = j.boxes("video[data-slot]")
    lefts, tops = sorted({round(v["x"]) for v in videos}), sorted({round(v["y"]) for v in videos})
    assert len(lefts) == 1 and len(tops) == n, "one video per row on a phone"
    assert all(v["w"] >= 300 for v in videos) and all(s["w"] >= 250 for s in j.boxes("input[type=range]"))
    assert_apart(j.boxes(".rating-card"), "cards")
    for card in j.boxes(".rating-card"):
        assert card["x"] >= 0 and card["r"] <= PHONE["width"]
    check_band_labels(j)


def check_band_labels(j, names=("Bad", "Poor", "Fair", "Good", "Excellent")):
    cards = j.page.locator(".rating-card")
    for c in range(cards.count()):
        labels = cards.nth(c).locator(".band-label").evaluate_all(f"els => els.map({BOX_JS})")
        card = cards.nth(c).evaluate(BOX_JS)
        assert [t.strip() for t in cards.nth(c).locator(".band-label").all_text_contents()] == list(names)
        assert_apart(labels, f"band labels of card {c + 1}")
        for lab in labels:
            assert card["x"] <= lab["x"] and lab["r"] <= card["r"] + 0.5, "a band label leaves its card"
        # left to right in band order
        centres = [(lab["x"] + lab["r"]) / 2 for lab in labels]
        assert centres == sorted(centres)


def test_mushra_five_videos_side_by_side(journey):
    journey.goto("m5")
    check_mushra_grid(journey, 5, "mushra-5", numbers=True)


def test_mushra_six_videos_side_by_side_without_numbers(journey):
    journey.goto("m6")
    check_mushra_grid(journey, 6, "mushra-6", numbers=False)


def check_hemvip(j, n, name, numbers=False):
    """One visible player whose clip the buttons choose; vertical sliders side by side on one labelled
    scale (Excellent at the top, Bad at the bottom); no numbers."""
    for vp in (LAPTOP, PHONE):
        j.at(vp, name)
        assert_no_sideways_overflow(j)
        shown = j.boxes("video[data-slot]:not([hidden])")
        assert len(shown) == 1 and j.page.locator("video[data-slot]").count() == n
        assert_visible(j, shown[0], "the player")
        buttons, sliders = j.boxes("button.play"), j.boxes("input[type=range]")
        assert len(buttons) == len(sliders) == n
        for k in range(n):
            assert_visible(j, buttons[k], f"button {k + 1}")
            assert_visible(j, sliders[k], f"slider {k + 1}")
            assert sliders[k]["h"] > 4 * sliders[k]["w"], "vertical sliders"
            assert buttons[k]["b"] <= sliders[k]["y"], "each button above its slider"
            assert abs((buttons[k]["x"] + buttons[k]["r"]) - (sliders[k]["x"] + sliders[k]["r"])) < 2
        assert len({round(s["y"]) for s in sliders}) == 1 and len({round(s["b"]) for s in sliders}) == 1, \
            "one scale: every slider spans the same height"
        assert all(sliders[k]["r"] <= sliders[k + 1]["x"] for k in range(n - 1)), "side by side"
        labels = j.boxes(".hv-axis .band-label")
        names = [t.strip() for t in j.page.locator(".hv-axis .band-label").all_text_contents()]
        assert names == ["Excellent", "Good", "Fair", "Poor", "Bad"]
        assert_apart(labels, "scale labels")
        # each label sits in its fifth of the slider's travel (the thumb's centre), left of the sliders
        top, bottom = sliders[0]["y"] + 8, sliders[0]["b"] - 8
        for k, lab in enumerate(labels):
            centre = (lab["y"] + lab["b"]) / 2
            assert top + k * (bottom - top) / 5 < centre < top + (k + 1) * (bottom - top) / 5
            assert lab["r"] <= sliders[0]["x"]
        assert j.page.locator("output").count() == (n if numbers else 0), "slider_numbers"
        if numbers:
            for k, out in enumerate(j.boxes("output")):
                assert_visible(j, out, f"number {k + 1}")
                assert abs((out["x"] + out["r"]) - (sliders[k]["x"] + sliders[k]["r"])) < 2, "under its slider"
        assert_visible(j, j.box("#next"), "Next")
    j.at(LAPTOP, name)
    # a button chooses the clip shown, and plays it
    j.page.click("button.play[data-slot='3']")
    j.page.wait_for_selector(".status[data-slot='3'].ok")
    assert j.page.locator("video[data-slot]:not([hidden])").get_attribute("data-slot") == "3"
    assert "selected" in j.page.get_attribute(".hv-head[data-slot='3']", "class")
    j.page.click("button.play[data-slot='1']")
    j.page.wait_for_selector(".status[data-slot='1'].ok")
    assert j.page.locator("video[data-slot]:not([hidden])").get_attribute("data-slot") == "1"
    j.at(LAPTOP, name + "-played")


def test_mushra_hemvip_display(journey):
    journey.goto("hv")
    check_hemvip(journey, 6, "mushra-hemvip")


def check_likert(j, points, name):
    for vp in (LAPTOP, PHONE):
        j.at(vp, name)
        assert_no_sideways_overflow(j)
        table = j.box(".likert")
        card = j.box("#page-form")
        assert table["r"] <= card["r"] and table["x"] >= card["x"]
        heads = j.boxes(".lk-point")
        assert len(heads) == points
        rows = j.page.locator(".lk-row")
        for r in range(rows.count()):
            cells = rows.nth(r).locator(".lk-cell").evaluate_all(f"els => els.map({BOX_JS})")
            widths = [c["w"] for c in cells + heads]
            assert max(widths) - min(widths) < 1, f"unequal point columns: {widths}"
            for c, hd in zip(cells, heads):   # each point's heading above its column
                assert abs((c["x"] + c["r"]) / 2 - (hd["x"] + hd["r"]) / 2) < 1
            gaps = [cells[k + 1]["x"] - cells[k]["x"] for k in range(points - 1)]
            assert max(gaps) - min(gaps) < 1, "equally spaced"
        labels = j.boxes(".lk-label, .lk-end")
        assert_apart(labels, "scale labels")
        for lab in labels:
            assert lab["x"] >= card["x"] and lab["r"] <= card["r"]
        if vp is LAPTOP:
            assert_visible(j, j.box("#next"), "Next")
            for r in range(rows.count()):
                assert_visible(j, rows.nth(r).evaluate(BOX_JS), f"statement {r + 1}")


def test_likert_equal_columns_seven_points(journey):
    journey.goto("lk7")
    check_likert(journey, 7, "likert-7")


def test_likert_equal_columns_five_labelled_points(journey):
    journey.goto("lk5")
    check_likert(journey, 5, "likert-5")


def wait_for_text(page, selector, text):
    """Poll from Python (the study's CSP refuses the eval that wait_for_function needs)."""
    for _ in range(100):
        if text in (page.text_content(selector) or ""):
            return
        page.wait_for_timeout(100)
    assert text in (page.text_content(selector) or "")


def test_report_a_video_that_does_not_play(journey, env):
    """From a media page the participant reports a video that does not play; the admin sees it counted
    for that stimulus."""
    j = journey
    j.goto("lk5")
    spec = h.plan_pages(env.app, j.sid)[j.data()["index"]]
    assert j.page.is_hidden("#report-send")
    for vp in (LAPTOP, PHONE):
        j.page.set_viewport_size(vp)
        j.page.click("#report summary")
        j.page.wait_for_selector("#report-send", state="visible")
        assert_visible(j, j.box(".report-box"), "the report box")
        assert_visible(j, j.box("#next"), "Next") if vp is LAPTOP else None
        assert_no_sideways_overflow(j)
        j.at(vp, "report-open")
        j.page.click("#report summary")
    j.page.set_viewport_size(LAPTOP)
    j.page.click("#report summary")
    # one video on a Likert page: the only choice is "every video on this page"
    assert j.page.locator("#report-slot option").all_text_contents() == ["Every video on this page"]
    with j.page.expect_response(lambda r: "/events/" in r.url) as resp:
        j.page.click("#report-send")
    assert resp.value.status == 200
    wait_for_text(j.page, "#report-status", "Thank you")
    j.at(LAPTOP, "report-sent")
    status = json.loads(urllib.request.urlopen(urllib.request.Request(
        env.server.url + "/admin/status.json", headers={"Authorization": f"Bearer {h.ADMIN}"})).read())
    assert [(r["file"], r["reports"]) for r in status["reports"]] == [(spec["stimulus"], 1)]
    row = [p for p in status["participants"] if p["session"] == j.sid][0]
    assert row["reports"] == 1


def test_report_names_the_videos_of_a_pairwise_page(env):
    j = Journey(env, "6a4b2c0d9e8f7a6b5c4d3e2f")
    try:
        assert j.block() == "hl"
        j.page.click("#report summary")
        assert j.page.locator("#report-slot option").all_text_contents() == \
            ["Every video on this page", "Left video", "Right video"]
        j.page.select_option("#report-slot", "1")
        with j.page.expect_response(lambda r: "/events/" in r.url):
            j.page.click("#report-send")
        wait_for_text(j.page, "#report-status", "Thank you")
        with store_of(env.app).Session() as db:
            events = db.query(Event).filter_by(session_id=j.sid, kind="unplayable").all()
            assert [(e.page_index, e.slot) for e in events] == [(0, 1)]
            assert "1:ready=" in events[0].detail          # the player's state, for the researcher
    finally:
        j.context.close()


def test_admin_page_refreshes_by_itself(env):
    admin = env.browser.new_page(viewport=LAPTOP)
    try:
        admin.goto(env.server.url + "/admin/")
        admin.fill("input[name=token]", h.ADMIN)
        admin.click("button[type=submit]")
        admin.wait_for_selector("#participants")
        admin.evaluate("window.notReloaded = true")
        before = admin.locator("#participants tbody tr").count()
        started = int(admin.text_content("#sessions td[data-key='started']"))
        plans_before = admin.text_content("#plan-counts")
        newcomer = "7b5c3d1e0f9a8b7c6d5e4f3a"
        j = Journey(env, newcomer)
        try:
            for _ in range(100):    # the page polls every second here (15 s by default)
                if newcomer in admin.text_content("#participants"):
                    break
                admin.wait_for_timeout(100)
            assert newcomer in admin.text_content("#participants")
            assert admin.evaluate("window.notReloaded") is True, "updated in place, not reloaded"
            assert admin.locator("#participants tbody tr").count() == before + 1
            row = admin.locator(f"#participants tbody tr[data-session='{j.sid}'] td").all_text_contents()
            assert row[0] == newcomer
            assert row[1] == "prolific"
            assert row[2] == "active"
            assert row[3].startswith("1 of 7: hl (pairwise)")
            assert row[6:9] == ["0", "0", "0"]
            assert "Updated" in admin.text_content("#refreshed")
            # the counters refresh too: sessions started, and the plans (the newcomer's is reserved)
            assert int(admin.text_content("#sessions td[data-key='started']")) == started + 1
            assert admin.text_content("#plan-counts") != plans_before
            assert "reserved" in admin.text_content("#plan-counts")
            # and the answer counter, once someone answers a page
            answers = int(admin.text_content("#sessions td[data-key='answers']"))
            other = h.Participant(env.server.app.test_client(), "9d7e5f3a1b0c9d8e7f6a5b4c",
                                  study_of(env.server.app).id)
            assert other.enter().status_code == 302
            _, data, csrf = other.page()
            spec = h.plan_pages(env.server.app, other.sid)[data["index"]]
            answer = h.make_answer(study_of(env.server.app), spec, np.random.default_rng(0))
            assert other.submit(data, csrf, answer).status_code == 200
            for _ in range(100):
                if int(admin.text_content("#sessions td[data-key='answers']")) > answers:
                    break
                admin.wait_for_timeout(100)
            assert int(admin.text_content("#sessions td[data-key='answers']")) == answers + 1
            admin.screenshot(path=str(env.shots / "admin-participants.png"), full_page=True)
        finally:
            j.context.close()
    finally:
        admin.close()


@pytest.fixture(scope="module")
def more(env):
    """A second study: two pairwise questions, 8 MUSHRA videos, an 11-point Likert scale."""
    folder = env.folder / "more"
    path = make_more_study(folder)
    app = create_app({"STUDY": str(path), "DATABASE_URL": f"sqlite:///{folder / 'more.db'}",
                      "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                      "INSTANCE_PATH": str(folder / "inst")})
    server = Server(lambda: app)
    ns = SimpleNamespace(folder=folder, shots=env.shots, server=server, browser=env.browser, app=app)
    j = Journey(ns, "8c6d4e2f1a0b9c8d7e6f5a4b", study_id="layout-more")
    yield j
    j.context.close()
    server.stop()


def test_pairwise_two_questions_and_longer_text_fit(more):
    j = more
    j.goto("two")
    for vp in (LAPTOP, {"width": 1366, "height": 657}):
        j.at(vp, "pairwise-two-questions")
        for k, v in enumerate(j.boxes("video[data-slot]")):
            assert_visible(j, v, f"video {k}")
            assert v["h"] >= 95
        for k, q in enumerate(j.boxes("fieldset.question")):
            assert_visible(j, q, f"question {k + 1}")
        assert_visible(j, j.box("#next"), "Next")
        assert_no_sideways_overflow(j)
    j.at(PHONE, "pairwise-two-questions")
    assert_no_sideways_overflow(j)
    title = j.box("header.top .title")
    assert title["r"] <= PHONE["width"] and title["h"] < 30, "a long study title stays on one line"


def test_mushra_eight_videos_in_two_rows(more):
    more.goto("m8")
    check_mushra_grid(more, 8, "mushra-8", numbers=True, rows=2)


def test_mushra_eight_videos_hemvip(more):
    more.goto("hv8")
    check_hemvip(more, 8, "mushra-hemvip-8", numbers=True)


def test_likert_eleven_points(more):
    more.goto("lk11")
    check_likert(more, 11, "likert-11")


def test_pages_without_ratings_fit_a_small_phone(env):
    """Consent, questionnaire and headphone check (the standard test study, phones allowed) on a 360 px
    phone: nothing wider than the window, Next reachable."""
    folder = env.folder / "phone"
    text = h.STUDY_YAML.format(sessions=2).replace("min_width: 800", "min_width: 320\nblock_mobile: false")
    path = h.make_study(folder, yaml_text=text)
    app = create_app({"STUDY": str(path), "DATABASE_URL": f"sqlite:///{folder / 'phone.db'}",
                      "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                      "INSTANCE_PATH": str(folder / "inst")})
    server = Server(lambda: app)
    small = {"width": 360, "height": 740}
    try:
        ns = SimpleNamespace(folder=folder, shots=env.shots, server=server, browser=env.browser, app=app)
        j = Journey(ns, "9d7e5f3a2b1c0d9e8f7a6b5c", study_id="gesture-test")
        j.page.set_viewport_size(small)
        for name in ("consent", "questionnaire", "headphone-check"):
            j.at(small, name)
            assert_no_sideways_overflow(j)
            assert j.page.is_hidden("#gate")
            nxt = j.box("#next")
            assert nxt["x"] >= 0 and nxt["r"] <= small["width"]
            if name == "consent":
                j.page.check("#agree")
            elif name == "questionnaire":
                j.page.fill("#q-age", "30")
                j.page.select_option("#q-gender", "other")
            else:
                assert j.page.locator("#report summary").text_content() == "Sound does not play?"
                break
            with j.page.expect_navigation():
                j.page.click("#next")
        j.context.close()
    finally:
        server.stop()
