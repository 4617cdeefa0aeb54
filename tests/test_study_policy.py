"""The session policy (study_app.policy): pure, and through the app (a participant who fails the attention
checks or fills in the honeypot ends the session; a failed participant's plan is handed out again)."""
from __future__ import annotations

import numpy as np
import study_helpers as h
from study_fixtures import make_app

from study_app.context import store_of
from study_app.pages import Outcome
from study_app.policy import Rules, SessionState, after_answer
from study_app.storage import ParticipantSession, Plan


def _pages(*types):
    return [{"type": t} for t in types]


def test_policy_moves_to_the_next_page_and_finishes_on_the_last_kind():
    rules = Rules(max_failed_attention_checks=2)
    pages = _pages("consent", "pairwise", "finish")
    move = after_answer(SessionState(0), Outcome(), pages, rules)
    assert (move.current_page, move.status) == (1, "active")
    move = after_answer(SessionState(1), Outcome(attention=True), pages, rules)
    assert (move.current_page, move.status, move.end_reason) == (2, "finished", "completed")
    assert move.passed_checks == 1


def test_policy_ends_sessions_for_the_documented_reasons():
    rules = Rules(max_failed_attention_checks=2)
    pages = _pages("consent", "pairwise", "pairwise", "finish")
    honeypot = after_answer(SessionState(0), Outcome(honeypot=True), pages, rules)
    assert (honeypot.status, honeypot.end_reason, honeypot.honeypot) == ("failed", "honeypot", True)
    screening = after_answer(SessionState(0), Outcome(end_reason="headphone_check"), pages, rules)
    assert (screening.status, screening.end_reason) == ("failed", "headphone_check")
    once = after_answer(SessionState(1), Outcome(attention=False), pages, rules)
    assert (once.status, once.failed_checks) == ("active", 1)
    twice = after_answer(SessionState(2, failed_checks=1), Outcome(attention=False), pages, rules)
    assert (twice.status, twice.end_reason) == ("failed", "attention_checks")


def test_attention_failures_end_the_session_and_release_the_plan(study_dir, db_url):
    app = make_app(study_dir, db_url)
    store = store_of(app)
    p, r = h.run_participant(app, app.test_client(), "pattn0001", np.random.default_rng(4), fail_checks=2)
    assert r.status_code == 200
    assert "did not pass enough" in r.get_data(as_text=True)
    with store.Session() as db:
        sess = db.get(ParticipantSession, p.sid)
        assert (sess.status, sess.end_reason, sess.failed_checks) == ("failed", "attention_checks", 2)
        plan = db.get(Plan, sess.plan_id)
        assert plan.status == "free"
        assert plan.times_released == 1
    # further answers are refused
    _, data, _ = p.page()
    assert data is None
    # the released plan goes to the next participant, who fails one check only and finishes
    q, r = h.run_participant(app, app.test_client(), "pattn0002", np.random.default_rng(4), fail_checks=1)
    assert "DONE1234" in r.get_data(as_text=True)
    with store.Session() as db:
        assert db.get(ParticipantSession, q.sid).plan_id == sess.plan_id
        assert db.get(Plan, sess.plan_id).status == "used"


def test_honeypot_ends_the_session(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "pbot00001")
    p.enter()
    _, data, csrf = p.page()
    assert p.submit(data, csrf, {"agree": True, "website": "http://spam"}).status_code == 200
    with store_of(app).Session() as db:
        sess = db.get(ParticipantSession, p.sid)
        assert sess.honeypot
        assert sess.status == "failed"
        assert sess.end_reason == "honeypot"
