"""The store (study_app.storage): one answer per page however often it is sent, plan reservations that
expire and are handed out again, a full study, drafts kept across a server restart, and a database holding
other plans refused. Through Flask's test client, on SQLite and on a real throwaway PostgreSQL."""
from __future__ import annotations

import json
import threading

import numpy as np
import pytest
import study_helpers as h
from study_fixtures import make_app, walk_to

from study_app.context import store_of
from study_app.errors import StudyStateError
from study_app.pages import Outcome
from study_app.storage import Answer, Event, ParticipantSession, Plan, SubmitStatus
from study_app.submission import Submission


def test_replayed_and_double_submissions_store_one_answer(study_dir, db_url):
    app = make_app(study_dir, db_url)
    store = store_of(app)
    client = app.test_client()
    p = h.Participant(client, "pdup00001")
    p.enter()
    _, data, csrf = p.page()
    body = {"agree": True, "website": ""}
    r1 = p.submit(data, csrf, body, token="tok-consent-1")
    r2 = p.submit(data, csrf, body, token="tok-consent-1")          # network retry
    assert r1.get_json()["status"] == "stored"
    assert r2.get_json()["status"] == "duplicate"
    # the same page again with a new token: refused, the first answer is kept
    r3 = p.submit(data, csrf, {"agree": True, "website": "x"}, token="tok-consent-2")
    assert r3.status_code == 409
    with store.Session() as db:
        answers = db.query(Answer).filter_by(session_id=p.sid).all()
        assert len(answers) == 1
        assert answers[0].data["honeypot"] is False
    # concurrent double clicks (same token) and concurrent different answers to one page
    _, data, csrf = p.page()
    answer = {"age": 30, "gender": "male", "comments": ""}
    statuses = []

    def submit(token):
        def evaluate(pages, played):
            return Submission(data=dict(responses=answer), outcome=Outcome())
        statuses.append(store.submit(p.sid, data["index"], token, evaluate)[0])

    threads = [threading.Thread(target=submit, args=("tok-q-same",)) for _ in range(6)]
    threads += [threading.Thread(target=submit, args=(f"tok-q-other{i}",)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert statuses.count("stored") == 1
    with store.Session() as db:
        rows = db.query(Answer).filter_by(session_id=p.sid, page_index=data["index"]).all()
        assert len(rows) == 1
        if rows[0].submit_token == "tok-q-same":
            assert statuses.count("duplicate") == 5
            assert statuses.count("conflict") == 4
        sess = db.get(ParticipantSession, p.sid)
        assert sess.current_page == data["index"] + 1
    # a token used on one page cannot be replayed onto another page
    _, data, csrf = p.page()
    assert p.submit(data, csrf, {}, token="tok-consent-1").status_code == 409
    # replayed event batches are logged once
    evs = [{"id": "evt-00000001", "kind": "play", "slot": None, "t": 0.0, "ms": 5}]
    for _ in range(3):
        assert p.post(data["events_url"], {"events": evs}, csrf).status_code == 200
    with store.Session() as db:
        assert db.query(Event).filter_by(session_id=p.sid, client_id="evt-00000001").count() == 1


def test_expired_reservation_is_released_and_cannot_restart(study_dir, db_url):
    import datetime as dt
    app = make_app(study_dir, db_url)
    store = store_of(app)
    a = h.Participant(app.test_client(), "pexpire01")
    a.enter()
    a.consent()                  # the plan is reserved when the participant starts
    with store.Session.begin() as db:
        sess = db.get(ParticipantSession, a.sid)
        plan = db.get(Plan, sess.plan_id)
        plan.reserved_until = dt.datetime(2000, 1, 1)
        plan_id = plan.id
    b = h.Participant(app.test_client(), "pexpire02")
    b.enter()
    b.consent()
    with store.Session() as db:
        assert db.get(ParticipantSession, b.sid).plan_id == plan_id
        assert db.get(ParticipantSession, a.sid).status == "expired"
    r = h.Participant(app.test_client(), "pexpire01").enter()    # the timed-out outcome's page and code
    assert r.status_code == 410
    assert "expired" in r.get_data(as_text=True)
    assert 'id="failure-code">FAIL5678<' in r.get_data(as_text=True)
    assert a.client.get(f"/s/{a.sid}/").status_code == 410


def test_study_full(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    for i in range(6):
        p = h.Participant(app.test_client(), f"pfull{i:04d}")
        assert p.enter().status_code == 302
        assert p.consent().status_code == 200
    r = h.Participant(app.test_client(), "pfull9999").enter()
    assert r.status_code == 503
    assert "All places" in r.get_data(as_text=True)


def test_draft_autosave_survives_a_server_restart(study_dir, db_url):
    app = make_app(study_dir, db_url)
    p = h.Participant(app.test_client(), "pdraft001")
    p.enter()
    data, csrf, _ = walk_to(app, p, "mushra", np.random.default_rng(0))
    draft = {"fields": {"rating-0": "42", "rating-1": "7"}, "touched": [0, 1]}
    assert p.post(data["draft_url"], {"draft": draft}, csrf).status_code == 200
    assert p.post(data["draft_url"], {"draft": "x"}, csrf).status_code == 422
    # only the last path segment is the page index; the session id before it is random
    # and may itself start with the same digit
    stale_url = data["draft_url"].rsplit("/", 1)[0] + f"/{data['index'] + 1}"
    assert stale_url != data["draft_url"]
    assert p.post(stale_url, {"draft": draft}, csrf).status_code == 409
    ended = [{"id": "evt-ended-00", "kind": "ended", "slot": 0}]
    assert p.post(data["events_url"], {"events": ended}, csrf).status_code == 200
    cookie = p.client.get_cookie("study_gesture-test")
    # a new server process on the same database and secret
    app2 = make_app(study_dir, db_url, INIT_DB=True)
    c2 = app2.test_client()
    c2.set_cookie(cookie.key, cookie.value)
    r = c2.get(f"/s/{p.sid}/")
    restored = json.loads(h.PAGE_DATA_RE.search(r.get_data(as_text=True)).group(1))
    assert restored["index"] == data["index"]
    assert restored["draft"] == draft
    assert restored["ended"] == [0]
    # and re-entry from Prolific in a fresh browser resumes on the same page with the draft
    q = h.Participant(app2.test_client(), "pdraft001")
    q.enter()
    assert q.page()[1]["draft"] == draft


def test_database_with_other_plans_is_refused(study_dir, db_url):
    import copy

    from study_app.definition import load_study
    from study_app.design import build_plans
    from study_app.storage import init_db, make_engine
    make_app(study_dir, db_url)                      # stores the plans of study.yaml
    study = load_study(study_dir / "study.yaml")
    plans = build_plans(study)
    init_db(make_engine(db_url), study, plans)       # same plans again: fine (restarts)
    other = copy.deepcopy(plans)
    other["plans"] = other["plans"][::-1]
    with pytest.raises(StudyStateError, match="different session plans"):
        init_db(make_engine(db_url), study, other)


def test_submit_reports_what_it_did_as_a_submit_status(tmp_path, sqlite_url):
    h.make_study(tmp_path, sessions=1)
    app = make_app(tmp_path, sqlite_url)
    store = store_of(app)
    p, q = h.Participant(app.test_client(), "pstatus01"), h.Participant(app.test_client(), "pstatus02")
    p.enter()
    q.enter()

    def evaluate(pages, played):
        return Submission(data={"agree": True, "honeypot": False}, outcome=Outcome())

    status, answer, sess = store.submit(p.sid, 0, "tok-status-1", evaluate)
    assert status is SubmitStatus.STORED
    assert (answer.page_index, sess.current_page) == (0, 1)
    assert store.submit(p.sid, 0, "tok-status-1", evaluate)[0] is SubmitStatus.DUPLICATE
    assert store.submit(p.sid, 0, "tok-status-2", evaluate)[0] is SubmitStatus.CONFLICT
    assert store.submit(p.sid, 5, "tok-status-3", evaluate)[0] is SubmitStatus.AHEAD
    assert store.submit("no-such-session", 0, "tok-status-4", evaluate) == (SubmitStatus.MISSING, None, None)
    assert store.submit(q.sid, 0, "tok-status-5", evaluate)[0] is SubmitStatus.FULL     # the one plan is p's


def _statements(store):
    """A list that collects every SQL statement the store's engine sends from now on."""
    from sqlalchemy import event
    seen: list[str] = []
    event.listen(store.engine, "before_cursor_execute", lambda conn, cur, stmt, *a: seen.append(stmt))
    return seen


def test_plan_pages_are_read_once_per_process_and_a_first_view_is_one_transaction(study_dir, db_url):
    app = make_app(study_dir, db_url)
    store = store_of(app)
    assert store.fixed_pages            # no adaptive block
    rng = np.random.default_rng(0)
    p = h.Participant(app.test_client(), "pcache001")
    p.enter()
    walk_to(app, p, "pairwise", rng)    # the plan's pages are read here once
    seen = _statements(store)
    for _ in range(3):
        _, data, _ = p.page()           # reloads
        assert p.get(data["videos"][0]).status_code == 200
    assert not [s for s in seen if "plans.pages" in s]
    # a reload writes nothing: a read without the write lock (SQLite: a plain BEGIN, no BEGIN IMMEDIATE)
    assert not [s for s in seen if "INSERT INTO page_views" in s or s.startswith("BEGIN IMMEDIATE")]
    # a new page is written in one transaction, without a read before it
    del seen[:]
    _, data, csrf = p.page()
    pages = h.plan_pages(app, p.sid)
    assert p.submit(data, csrf, h.make_answer(h.study_of(app), pages[data["index"]], rng)).status_code == 200
    del seen[:]
    p.page()
    assert sum(1 for s in seen if s.startswith("SELECT sessions.")) == 1
    assert sum(1 for s in seen if "INSERT INTO page_views" in s) == 1


def test_plans_topped_up_while_the_server_runs_are_handed_out(tmp_path):
    from study_fixtures import export_rows

    from study_app.operations import topup
    h.make_study(tmp_path, sessions=1)
    url = f"sqlite:///{tmp_path / 'study.db'}"
    app = make_app(tmp_path, url)
    first, _ = h.run_participant(app, app.test_client(), "pfirst001", np.random.default_rng(0))  # the only plan
    assert h.Participant(app.test_client(), "plate0001").enter().status_code == 503      # full
    other = make_app(tmp_path, url)                                # the CLI's store, another process
    [key] = topup(store_of(other), h.study_of(other), 1)
    p, _ = h.run_participant(app, app.test_client(), "plate0002", np.random.default_rng(1))
    with store_of(app).Session() as db:
        plan = db.get(Plan, db.get(ParticipantSession, p.sid).plan_id)
        assert plan.key == key and plan.status == "used"
        answered = {a.page_id for a in db.query(Answer).filter_by(session_id=p.sid)}
    assert answered == {page["page"] for page in plan.pages if page["type"] != "finish"} - {None}
    assert {r["participant"] for r in export_rows(app)} == {first.pid, p.pid}
