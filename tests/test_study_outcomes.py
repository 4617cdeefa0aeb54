"""Outcome codes (study_app.outcomes): one code per way a session ends, each with its review action; the
consent page's "I do not agree" exit; re-opening the link after the end shows the code again. The browser
tests follow each outcome in Chromium to the link back to Prolific (intercepted) with its own code."""
from __future__ import annotations

import datetime as dt
import pathlib

import numpy as np
import pytest
import study_helpers as h
from browser_helpers import ARGS, Server, chromium
from study_fixtures import make_app

from study_app import create_app
from study_app.context import store_of
from study_app.definition import load_study
from study_app.errors import StudyDefinitionError
from study_app.headphones import correct_choice
from study_app.outcomes import code_for, outcome_of
from study_app.storage import ParticipantSession, Plan

CODES = {"completed": "DONE1234", "no_consent": "NOCONS01", "screened_out": "HEADPH01",
         "attention_checks": "ATTN0001", "timed_out": "LATE0001"}
OUTCOMES_YAML = """outcomes:
  completed: {code: DONE1234, action: AUTOMATICALLY_APPROVE}
  no_consent: NOCONS01
  screened_out: {code: HEADPH01, action: REQUEST_RETURN}
  attention_checks: {code: ATTN0001, action: REJECT}
  timed_out: {code: LATE0001}
"""


def _yaml(outcomes: str = OUTCOMES_YAML) -> str:
    text = h.STUDY_YAML.format(sessions=6)
    return text.replace("completion_code: DONE1234\nfailure_code: FAIL5678\n", outcomes)


@pytest.fixture(scope="module")
def outcome_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("outcomes")
    h.make_study(folder, seconds=0.5, yaml_text=_yaml())
    return folder


def test_outcomes_in_the_definition_with_actions_and_shorthands(outcome_dir):
    study = load_study(outcome_dir / "study.yaml")
    assert {k: (v.code, v.action) for k, v in study.outcomes.items()} == {
        "completed": ("DONE1234", "AUTOMATICALLY_APPROVE"), "no_consent": ("NOCONS01", "REQUEST_RETURN"),
        "screened_out": ("HEADPH01", "REQUEST_RETURN"), "attention_checks": ("ATTN0001", "REJECT"),
        "timed_out": ("LATE0001", "REQUEST_RETURN")}
    assert study.completion_code == "DONE1234"
    # the old keys: completion_code for completed, failure_code for every other outcome
    (outcome_dir / "old.yaml").write_text(h.STUDY_YAML.format(sessions=6))
    old = load_study(outcome_dir / "old.yaml")
    assert {k: v.code for k, v in old.outcomes.items()} == {
        "completed": "DONE1234", "no_consent": "FAIL5678", "screened_out": "FAIL5678",
        "attention_checks": "FAIL5678", "timed_out": "FAIL5678"}
    assert old.outcomes["attention_checks"].action == "MANUALLY_REVIEW"
    assert outcome_of("failed", "headphone_check") == "screened_out"
    assert outcome_of("failed", "honeypot") == "attention_checks"
    assert outcome_of("expired", "") == "timed_out"
    assert outcome_of("active", "") is None
    assert code_for(study, "failed", "no_consent").code == "NOCONS01"


@pytest.mark.parametrize("outcomes, field, says", [
    ("outcomes: {finished: X1}\n", "outcomes.finished", "unknown outcome"),
    ("outcomes: {completed: {code: C1, action: PAY_DOUBLE}}\n", "outcomes.completed.action", "AUTOMATICALLY_APPROVE"),
    ("outcomes: {completed: C1, no_consent: C1}\n", "outcomes.no_consent", "same code as completed"),
    ("outcomes: {completed: 'C 1'}\n", "outcomes.completed", "letters, digits"),
    ("outcomes: {no_consent: [C1]}\n", "outcomes.no_consent", "a code or a mapping"),
    ("completion_code: C1\noutcomes: {completed: C2}\n", "outcomes.completed", "given twice"),
])
def test_wrong_outcomes_are_one_line_errors(outcome_dir, outcomes, field, says):
    path = outcome_dir / "bad.yaml"
    path.write_text(_yaml(outcomes))
    with pytest.raises(StudyDefinitionError) as exc:
        load_study(path)
    assert field in str(exc.value) and says in str(exc.value)


def test_each_outcome_gets_its_own_code_and_reentry_shows_it(outcome_dir, sqlite_url):
    app = make_app(outcome_dir, sqlite_url)
    rng = np.random.default_rng(1)
    ends = {}
    # completed, and failed attention checks
    ends["completed"] = h.run_participant(app, app.test_client(), "oc-done01", rng)[0]
    ends["attention_checks"] = h.run_participant(app, app.test_client(), "oc-attn01", rng, fail_checks=2)[0]
    # "I do not agree"
    p = h.Participant(app.test_client(), "oc-nocons1")
    p.enter()
    _, data, csrf = p.page()
    r = p.submit(data, csrf, {"agree": False})
    assert r.status_code == 200 and r.get_json()["session_status"] == "failed"
    ends["no_consent"] = p
    # timed out: the reservation ran out
    p, _ = h.run_participant(app, app.test_client(), "oc-late001", rng, stop_after=2)
    with store_of(app).Session.begin() as db:
        plan = db.query(Plan).filter_by(session_id=p.sid).one()
        plan.reserved_until = dt.datetime(2000, 1, 1)
    ends["timed_out"] = p
    for outcome, p in ends.items():
        html = p.client.get(f"/s/{p.sid}/").get_data(as_text=True)
        assert f">{CODES[outcome]}<" in html, outcome
        assert f"submissions/complete?cc={CODES[outcome]}" in html, outcome
        again = h.Participant(app.test_client(), p.pid).enter()            # the link opened again
        assert f">{CODES[outcome]}<" in again.get_data(as_text=True), outcome
    with store_of(app).Session() as db:
        s = db.query(ParticipantSession).filter_by(participant=ends["no_consent"].pid).one()
        assert (s.status, s.end_reason) == ("failed", "no_consent")
        assert db.query(Plan).filter_by(session_id=s.id).count() == 0          # its plan went back


# --------------------------------------------------------------------------------------------- in Chromium

@pytest.fixture(scope="module")
def browser_env(outcome_dir):
    db = f"sqlite:///{outcome_dir / 'browser.db'}"
    server = Server(lambda: create_app({"STUDY": str(outcome_dir / "study.yaml"), "DATABASE_URL": db,
                                        "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN,
                                        "SESSION_COOKIE_SECURE": False,
                                        "INSTANCE_PATH": str(outcome_dir / "inst")}))
    from playwright.sync_api import sync_playwright
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium(), headless=True,
                                     args=[*ARGS, "--autoplay-policy=no-user-gesture-required"])
        yield server, browser
        browser.close()
    server.stop()


def _to_prolific(page) -> str:
    """Follow the page's "Return to Prolific" link; the address it reaches (intercepted, not fetched)."""
    reached = []
    page.route("https://app.prolific.com/**", lambda route: (reached.append(route.request.url),
                                                             route.fulfill(status=200, body="prolific")))
    page.click("#return-link")
    page.wait_for_url("https://app.prolific.com/**")
    return reached[0]


def _next(page):
    page.wait_for_selector("#next:not([disabled])")
    with page.expect_navigation():
        page.click("#next")


@pytest.mark.browser
@pytest.mark.slow
@pytest.mark.parametrize("outcome", list(CODES))
def test_each_outcome_reaches_prolific_with_its_code_in_chromium(browser_env, outcome, tmp_path):
    server, browser = browser_env
    app = server.app
    pid = h.valid_pid(f"ocb-{outcome}"[:12])
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    page = context.new_page()
    page.set_default_timeout(20000)
    if outcome in ("completed", "attention_checks", "timed_out"):
        # the long part of the session as a scripted participant, with the same Prolific attempt
        p, _ = h.run_participant(app, app.test_client(), pid, np.random.default_rng(3),
                                 fail_checks=2 if outcome == "attention_checks" else 0,
                                 stop_after=2 if outcome == "timed_out" else None)
        if outcome == "timed_out":
            with store_of(app).Session.begin() as db:
                db.query(Plan).filter_by(session_id=p.sid).one().reserved_until = dt.datetime(2000, 1, 1)
        page.goto(server.url + h.prolific_url(pid))
    else:
        page.goto(server.url + h.prolific_url(pid))
        if outcome == "no_consent":
            with page.expect_navigation():
                page.click("#decline")
        else:   # screened out by the headphone check: consent, questionnaire, then the wrong tones
            page.check("#agree")
            _next(page)
            page.fill("#q-age", "30")
            page.select_option("#q-gender", "other")
            _next(page)
            sid = page.url.split("/s/")[1].strip("/")
            spec = h.plan_pages(app, sid)[2]
            page.click("#calibration-play")            # step 1: set the volume with the calibration noise
            page.wait_for_selector("#calibration-done:not([disabled])")
            page.click("#calibration-done")
            for k in range(len(spec["trials"])):
                page.click(f"button.play[data-slot='{k}']")
                page.wait_for_selector(f".status[data-slot='{k}'].ok")
            for k, order in enumerate(spec["trials"]):
                page.check(f"input[name='t-{k}'][value='{correct_choice(order) % 3 + 1}']")
            _next(page)
    code = page.locator("#completion-code, #failure-code").text_content()
    assert code == CODES[outcome]
    page.screenshot(path=str(pathlib.Path(tmp_path) / f"{outcome}.png"))
    assert _to_prolific(page) == f"https://app.prolific.com/submissions/complete?cc={CODES[outcome]}"
    # re-opening the study link after the end shows the code and the return link again
    page.goto(server.url + h.prolific_url(pid))
    assert page.locator("#completion-code, #failure-code").text_content() == CODES[outcome]
    assert page.locator("#return-link").get_attribute("href").endswith(f"cc={CODES[outcome]}")
    context.close()


def test_declining_while_every_plan_is_taken_still_gets_the_no_consent_code(outcome_dir, sqlite_url):
    app = make_app(outcome_dir, sqlite_url)
    reader = h.Participant(app.test_client(), "oc-reader1")        # reads the consent page ...
    assert reader.enter().status_code == 302
    _, data, csrf = reader.page()
    with store_of(app).Session() as db:
        n_plans = db.query(Plan).count()
    for i in range(n_plans):                                        # ... while others take every place
        p = h.Participant(app.test_client(), f"oc-full{i:03d}")
        p.enter()
        assert p.consent().status_code == 200
    r = reader.submit(data, csrf, {"agree": False})
    assert r.status_code == 200 and r.get_json()["session_status"] == "failed"
    assert ">NOCONS01<" in reader.client.get(f"/s/{reader.sid}/").get_data(as_text=True)
