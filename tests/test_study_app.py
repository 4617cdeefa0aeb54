"""Study server through Flask's test client, on SQLite and on a real throwaway PostgreSQL."""
from __future__ import annotations

import csv
import io
import itertools
import json
import re
import threading

import numpy as np
import pytest
import study_helpers as h

from study_app import create_app
from study_app.context import store_of, study_of
from study_app.errors import StudyStateError
from study_app.pages import Outcome
from study_app.storage import Answer, Event, ParticipantSession, Plan
from study_app.submission import Submission
from study_app.testing import create_database, throwaway_postgres

_counter = itertools.count()


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("studyapp")
    h.make_study(folder)
    return folder


@pytest.fixture(scope="module")
def pg_server():
    with throwaway_postgres() as url:
        yield url


@pytest.fixture(params=["sqlite", pytest.param("postgresql", marks=pytest.mark.postgres)])
def db_url(request, tmp_path):
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'study.db'}"
    return create_database(request.getfixturevalue("pg_server"), f"t{next(_counter)}")


@pytest.fixture()
def sqlite_url(tmp_path):
    return f"sqlite:///{tmp_path / 'study.db'}"


def make_app(study_dir, url, study_file="study.yaml", **extra):
    return create_app({"STUDY": str(study_dir / study_file), "DATABASE_URL": url,
                       "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN,
                       "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(study_dir / "inst"),
                       **extra})


def export_rows(app):
    r = app.test_client().get("/admin/export/results.csv",
                              headers={"Authorization": f"Bearer {h.ADMIN}"})
    assert r.status_code == 200
    return list(csv.DictReader(io.StringIO(r.get_data(as_text=True))))


# --------------------------------------------------------------------------- full sessions

def test_full_sessions_export_equals_answers(study_dir, db_url):
    app = make_app(study_dir, db_url)
    rng = np.random.default_rng(1)
    done, r = h.run_participant(app, app.test_client(), "pfinish01", rng)
    html = r.get_data(as_text=True)
    assert "DONE1234" in html
    assert "https://app.prolific.com/submissions/complete?cc=DONE1234" in html
    failed, r = h.run_participant(app, app.test_client(), "pfail0001", rng, fail_checks=2)
    assert "FAIL5678" in r.get_data(as_text=True)
    assert "cc=FAIL5678" in r.get_data(as_text=True)
    partial, _ = h.run_participant(app, app.test_client(), "ppartial1", rng, stop_after=6)
    rows = export_rows(app)
    keys = h.as_keys(rows)
    assert len(keys) == len(set(keys))                                  # no duplicated judgement
    assert set(keys) == h.expected_rows(app, [done, failed, partial])     # exactly the answers given
    status = {r["participant"]: r["session_status"] for r in rows}
    pid = h.valid_pid
    assert status == {pid("pfinish01"): "finished", pid("pfail0001"): "failed", pid("ppartial1"): "incomplete"}
    checks = [r for r in rows if r["is_attention_check"] == "1"]
    assert {(r["participant"], r["attention_passed"]) for r in checks} == {
        (pid("pfinish01"), "1"), (pid("pfail0001"), "0")}
    assert all(r["is_training"] == "1" for r in rows if r["page"].startswith("training"))
    for r in rows:
        assert int(r["rt_ms"]) >= 0
        assert r["shown_at"] <= r["answered_at"]
        assert r["shown_at"].endswith("Z")
        assert r["study"] == "gesture-test"
        assert r["platform"] == "prolific"
    # raw JSON has the questionnaire and the interaction log
    raw = json.loads(app.test_client().get("/admin/export/raw.json",
                                           headers={"Authorization": f"Bearer {h.ADMIN}"}).data)
    assert any(a["data"].get("responses", {}).get("gender") == "other" for a in raw["answers"])
    assert {e["kind"] for e in raw["events"]} == {"ended"}
    # the CLI export reads the same database
    from click.testing import CliRunner

    from evalsuite.cli import main
    out = study_dir / f"cli-{next(_counter)}.csv"
    res = CliRunner().invoke(main, ["study", "export", str(study_dir / "study.yaml"), "--db", db_url,
                                    "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert h.as_keys(csv.DictReader(out.open())) == keys


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


# ------------------------------------------------------------------------------- security

def test_csrf_is_required_on_every_post(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    client = app.test_client()
    p = h.Participant(client, "pcsrf0001")
    p.enter()
    _, data, csrf = p.page()
    good = {"token": "tok-csrf-0001", "answer": {"agree": True}, "events": []}
    for headers in ({}, {"X-CSRFToken": "forged"}, {"X-CSRFToken": csrf[:-2] + "xx"}):
        for url, body in ((data["answer_url"], good), (data["draft_url"], {"draft": {}}),
                          (data["events_url"], {"events": []})):
            r = client.post(url, json=body, headers=headers)
            assert r.status_code == 400
            assert "CSRF" in r.get_data(as_text=True)
    # a token from another browser's session does not work either
    other = h.Participant(app.test_client(), "pcsrf0002")
    other.enter()
    _, _, other_csrf = other.page()
    assert client.post(data["answer_url"], json=good, headers={"X-CSRFToken": other_csrf}).status_code == 400
    assert client.post("/admin/login", data={"token": h.ADMIN}).status_code == 400
    assert client.post(data["answer_url"], json=good, headers={"X-CSRFToken": csrf}).status_code == 200


def test_participant_cannot_reach_another_session(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    alice, bob = h.Participant(app.test_client(), "palice001"), h.Participant(app.test_client(), "pbob00001")
    alice.enter()
    bob.enter()
    _, data, csrf = alice.page()
    _, _, bob_csrf = bob.page()
    for url in (f"/s/{alice.sid}/", f"/s/{alice.sid}/media/0/0"):
        assert bob.client.get(url).status_code == 403
    for url, body in ((data["answer_url"], {"token": "tok-bob-0001", "answer": {"agree": True}}),
                      (data["draft_url"], {"draft": {}}), (data["events_url"], {"events": []})):
        assert bob.client.post(url, json=body, headers={"X-CSRFToken": bob_csrf}).status_code == 403
    assert app.test_client().get(f"/s/{alice.sid}/").status_code == 403     # no cookie at all
    assert bob.client.get("/s/not-a-session/").status_code == 403
    assert alice.client.get(f"/s/{alice.sid}/").status_code == 200
    assert bob.client.get("/admin/export/results.csv").status_code == 403


def test_stimulus_serving_is_limited_to_the_plan(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "ptrav0001")
    p.enter()
    data, csrf, _ = _walk_to(app, p, "pairwise", np.random.default_rng(0))   # the first video page
    ok = p.client.get(data["videos"][0], headers={"Range": "bytes=0-99"})
    assert ok.status_code == 206
    assert ok.mimetype == "video/mp4"
    assert len(ok.data) == 100
    first = sorted((study_dir / "stim").glob("*.mp4"))[0].name
    bad = [f"/s/{p.sid}/media/{data['index']}/9", f"/s/{p.sid}/media/{data['index'] + 1}/0",
           f"/s/{p.sid}/media/-1/0", f"/s/{p.sid}/media/../../../etc/passwd",
           f"/s/{p.sid}/media/{data['index']}/..%2f..%2fstudy.yaml",
           f"/s/{p.sid}/media/%2e%2e/%2e%2e/study.yaml", f"/s/{p.sid}/media/{first}",
           "/static/../study.yaml", "/static/..%2f..%2fapp.py", "/static/%2e%2e/app.py",
           f"/stim/{first}", "/stim/manifest.csv", "/study.yaml"]
    for url in bad:
        r = p.client.get(url)
        assert r.status_code in (403, 404), url
        assert b"condition" not in r.data
        assert b"file,segment" not in r.data


def test_condition_names_and_file_names_never_reach_the_participant(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    study = study_of(app)
    secrets_ = set(study.conditions) | {s.file for s in study.manifest.stimuli} | {
        s.file.rsplit(".", 1)[0] for s in study.manifest.stimuli}
    rng = np.random.default_rng(5)
    p, _ = h.run_participant(app, app.test_client(), "pleak0001", rng)
    q, _ = h.run_participant(app, app.test_client(), "pleak0002", rng, fail_checks=2)
    responses = p.responses + q.responses
    urls = p.urls + q.urls
    for page in range(len(h.plan_pages(app, p.sid))):
        for slot in range(8):
            urls.append(f"/s/{p.sid}/media/{page}/{slot}")
    for static in ("study.js", "finish.js", "study.css"):
        responses.append(p.client.get(f"/static/{static}"))
    assert len(responses) > 40
    for r in responses:
        text = r.get_data(as_text=True) if r.mimetype != "video/mp4" else ""
        blob = (text + json.dumps(dict(r.headers))).lower()
        for s in secrets_:
            assert s.lower() not in blob, (s, r.request.path)
    for u in urls:
        for s in secrets_:
            assert s.lower() not in u.lower()


def test_security_headers_and_cookie_flags(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url, SESSION_COOKIE_SECURE=True)
    client = app.test_client()
    r = client.get(h.prolific_url("pcookie01"))
    cookie = r.headers["Set-Cookie"]
    assert "Secure" in cookie
    assert "HttpOnly" in cookie
    assert "SameSite=Lax" in cookie
    assert "frame-ancestors 'none'" in r.headers["Content-Security-Policy"]
    assert r.headers["X-Content-Type-Options"] == "nosniff"


def test_no_default_credentials(study_dir, sqlite_url):
    base = {"STUDY": str(study_dir / "study.yaml"), "DATABASE_URL": sqlite_url}
    for missing in ({"SECRET_KEY": h.SECRET}, {"ADMIN_TOKEN": h.ADMIN},
                    {"SECRET_KEY": h.SECRET, "ADMIN_TOKEN": "short"}):
        with pytest.raises(StudyStateError):
            create_app({**base, **missing})


def test_admin_needs_the_token(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    client = app.test_client()
    assert client.get("/admin/").status_code == 302
    assert client.get("/admin/export/results.csv").status_code == 403
    assert client.get("/admin/export/raw.json", headers={"Authorization": "Bearer wrong-token-123"}).status_code == 403
    login = client.get("/admin/login").get_data(as_text=True)
    csrf = re.search(r'name="csrf_token" value="([^"]+)"', login).group(1)
    assert client.post("/admin/login", data={"token": "wrong", "csrf_token": csrf}).status_code == 403
    assert client.post("/admin/login", data={"token": h.ADMIN, "csrf_token": csrf}).status_code == 302
    h.run_participant(app, app.test_client(), "padmin001", np.random.default_rng(2), fail_checks=1)
    page = client.get("/admin/").get_data(as_text=True)
    assert h.valid_pid("padmin001") in page
    assert "SYSALPHA vs SYSBETA" in page
    assert "plan-0000" in page
    assert client.get("/admin/export/results.csv").status_code == 200


# ------------------------------------------------------------------------- participants

def test_reentry_resumes_or_is_refused_but_never_restarts(study_dir, db_url):
    app = make_app(study_dir, db_url)
    rng = np.random.default_rng(3)
    p, _ = h.run_participant(app, app.test_client(), "preent001", rng, stop_after=4)
    # same Prolific ID from another browser: same session, same page
    again = h.Participant(app.test_client(), "preent001")
    assert again.enter().status_code == 302
    assert again.sid == p.sid
    _, data, _ = again.page()
    assert data["index"] == 4
    # finished participants cannot start over
    done, _ = h.run_participant(app, app.test_client(), "preent002", rng)
    r = h.Participant(app.test_client(), "preent002").enter()
    assert r.status_code == 409
    assert "already completed" in r.get_data(as_text=True)
    # failed participants neither
    h.run_participant(app, app.test_client(), "preent003", rng, fail_checks=2)
    r = h.Participant(app.test_client(), "preent003").enter()
    assert r.status_code == 409
    assert "cannot take part" in r.get_data(as_text=True)
    with store_of(app).Session() as db:
        assert db.query(ParticipantSession).filter_by(participant=h.valid_pid("preent001")).count() == 1


def test_resume_disabled_refuses_reentry(study_dir, sqlite_url):
    text = h.STUDY_YAML.format(sessions=6).replace("min_width: 800", "min_width: 800\nresume: false").replace(
        "id: gesture-test", "id: gesture-noresume")
    (study_dir / "noresume.yaml").write_text(text)
    from study_app.definition import load_study
    from study_app.design import build_plans, default_plans_path, write_plans
    st = load_study(study_dir / "noresume.yaml")
    write_plans(build_plans(st), default_plans_path(st))
    app = make_app(study_dir, sqlite_url, study_file="noresume.yaml")
    first = h.Participant(app.test_client(), "pnores001", "gesture-noresume")
    assert first.enter().status_code == 302
    # opening the link again before starting (consent) is not a restart
    assert h.Participant(app.test_client(), "pnores001", "gesture-noresume").enter().status_code == 302
    assert first.consent().status_code == 200
    r = h.Participant(app.test_client(), "pnores001", "gesture-noresume").enter()
    assert r.status_code == 409
    assert "already started" in r.get_data(as_text=True)


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
    r = h.Participant(app.test_client(), "pexpire01").enter()
    assert r.status_code == 409
    assert "expired" in r.get_data(as_text=True)
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


@pytest.mark.parametrize("url,code,text", [
    ("/start/gesture-test", 400, "lacks a valid PROLIFIC_PID"),
    ("/start/gesture-test?PROLIFIC_PID=a%20b&STUDY_ID=x&SESSION_ID=y", 400, "PROLIFIC_PID"),
    (f"/start/gesture-test?PROLIFIC_PID={'a' * 24}&STUDY_ID={'b' * 24}", 400, "SESSION_ID"),
    ("/start/gesture-test?PROLIFIC_PID=abc&STUDY_ID=x&SESSION_ID=y", 400, "PROLIFIC_PID"),
    (f"/start/gesture-test?PROLIFIC_PID={'g' * 24}&STUDY_ID={'b' * 24}&SESSION_ID=y", 400, "PROLIFIC_PID"),
    (f"/start/gesture-test?PROLIFIC_PID={'a' * 24}&STUDY_ID=x&SESSION_ID=y", 400, "STUDY_ID"),
    ("/start/other-study?PROLIFIC_PID=abc&STUDY_ID=x&SESSION_ID=y", 404, ""),
    ("/start/gesture-test?PROLIFIC_PID=" + "a" * 65 + "&STUDY_ID=x&SESSION_ID=y", 400, "PROLIFIC_PID"),
])
def test_entry_parameters_are_validated(study_dir, sqlite_url, url, code, text):
    app = make_app(study_dir, sqlite_url)
    r = app.test_client().get(url)
    assert r.status_code == code
    assert text in r.get_data(as_text=True)


def test_mobile_devices_are_refused(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    ua = "Mozilla/5.0 (iPhone; CPU iPhone OS 17_0 like Mac OS X) Mobile/15E148"
    r = app.test_client().get(h.prolific_url("pmobile01"), headers={"User-Agent": ua})
    assert r.status_code == 403
    assert "computer" in r.get_data(as_text=True)


def _app_for_platform(study_dir, sqlite_url, platform: str, study_id: str):
    """The test study entered through another platform, with its plans built."""
    from study_app.definition import load_study
    from study_app.design import build_plans, default_plans_path, write_plans

    text = h.STUDY_YAML.format(sessions=3).replace("platform: prolific", f"platform: {platform}").replace(
        "id: gesture-test", f"id: {study_id}")
    (study_dir / f"{platform}.yaml").write_text(text)
    st = load_study(study_dir / f"{platform}.yaml")
    write_plans(build_plans(st), default_plans_path(st))
    return make_app(study_dir, sqlite_url, study_file=f"{platform}.yaml")


def test_mturk_entry_preview_and_submit_form(study_dir, sqlite_url):
    app = _app_for_platform(study_dir, sqlite_url, "mturk", "gesture-mturk")
    client = app.test_client()
    r = client.get("/start/gesture-mturk?assignmentId=ASSIGNMENT_ID_NOT_AVAILABLE&hitId=H1")
    assert r.status_code == 200
    assert 'id="preview"' in r.get_data(as_text=True)
    bad = client.get("/start/gesture-mturk?workerId=A1W2&assignmentId=A1&hitId=H1&turkSubmitTo=https://evil.example")
    assert bad.status_code == 400
    assert "turkSubmitTo" in bad.get_data(as_text=True)
    for bad_worker in ("W1", "a1w2", "A1-W2"):
        r = client.get(f"/start/gesture-mturk?workerId={bad_worker}&assignmentId=A1&hitId=H1"
                       "&turkSubmitTo=https%3A%2F%2Fworkersandbox.mturk.com")
        assert r.status_code == 400
        assert "workerId" in r.get_data(as_text=True)
    r = client.get("/start/gesture-mturk?workerId=A1W2&assignmentId=A1&hitId=H1"
                   "&turkSubmitTo=https%3A%2F%2Fworkersandbox.mturk.com")
    assert r.status_code == 302
    # usable inside MTurk's iframe, also where third-party cookies are blocked
    cookie = r.headers["Set-Cookie"]
    assert all(a in cookie for a in ("SameSite=None", "Secure", "Partitioned", "HttpOnly")), cookie
    sid = r.headers["Location"].split("/s/")[1].strip("/")
    p = h.Participant(client, "W1")
    p.sid = sid
    rng = np.random.default_rng(0)
    while True:
        r, data, csrf = p.page()
        if data is None:
            break
        pages = h.plan_pages(app, sid)
        assert p.submit(data, csrf, h.make_answer(study_of(app), pages[data["index"]], rng)).status_code == 200
    html = r.get_data(as_text=True)
    assert 'action="https://workersandbox.mturk.com/mturk/externalSubmit"' in html
    assert 'name="assignmentId" value="A1"' in html


def test_anonymous_participants_resume_by_cookie(study_dir, sqlite_url):
    app = _app_for_platform(study_dir, sqlite_url, "anonymous", "gesture-anon")
    client = app.test_client()
    first = client.get("/start/gesture-anon").headers["Location"]
    assert client.get("/start/gesture-anon").headers["Location"] == first
    other = app.test_client().get("/start/gesture-anon").headers["Location"]
    assert other != first


# ----------------------------------------------------------------------- answers and drafts

def test_videos_must_be_played_before_answering(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "pplay0001")
    p.enter()
    rng = np.random.default_rng(0)
    data, csrf, spec = _walk_to(app, p, "pairwise", rng)              # the first video page
    answer = h.make_answer(study_of(app), spec, rng)
    r = p.submit(data, csrf, answer, played=False)
    assert r.status_code == 422
    assert "play every video to the end" in r.get_json()["error"]
    only_one = [{"id": "evt-only-one", "kind": "ended", "slot": 0, "t": 1.0, "ms": 1}]
    assert p.submit(data, csrf, answer, events=only_one).status_code == 422
    # the second video's end arrives through the periodic event log: now the answer is accepted
    # (a refused answer stores nothing, not even its events: the browser sends them again)
    logged = [{"id": "evt-first01", "kind": "ended", "slot": 0}, {"id": "evt-second1", "kind": "ended", "slot": 1}]
    assert p.post(data["events_url"], {"events": logged}, csrf).status_code == 200
    assert p.submit(data, csrf, answer, events=[]).status_code == 200


BAD_PAYLOADS = [
    ("not json", None, "expected a JSON object"),
    ("extra field", {"token": "tok-000001", "answer": {}, "admin": 1}, "unexpected field"),
    ("no token", {"answer": {}}, "token"),
    ("short token", {"token": "abc", "answer": {}}, "token"),
    ("token chars", {"token": "tok/../../x", "answer": {}}, "token"),
    ("answer not object", {"token": "tok-000001", "answer": [1]}, "expected an object"),
    ("rt negative", {"token": "tok-000001", "answer": {}, "client_rt_ms": -5}, "client_rt_ms"),
    ("events not list", {"token": "tok-000001", "answer": {"agree": True}, "events": "x"}, "events"),
    ("event kind", {"token": "tok-000001", "answer": {"agree": True}, "events": [{"id": "evt-000001", "kind": "hack"}]}, "kind"),
    ("event slot", {"token": "tok-000001", "answer": {"agree": True}, "events": [{"id": "evt-000001", "kind": "play", "slot": 7}]}, "slot"),
]


@pytest.mark.parametrize("desc,body,fragment", BAD_PAYLOADS, ids=[b[0] for b in BAD_PAYLOADS])
def test_answer_payloads_are_validated(study_dir, sqlite_url, desc, body, fragment):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "pvalid001")
    p.enter()
    _, data, csrf = p.page()
    if body is None:
        r = p.client.post(data["answer_url"], data="x", content_type="application/json",
                          headers={"X-CSRFToken": csrf})
    else:
        r = p.post(data["answer_url"], body, csrf)
    assert r.status_code == 422
    assert fragment in r.get_json()["error"]


def _walk_to(app, p, page_type, rng):
    while True:
        _, data, csrf = p.page()
        pages = h.plan_pages(app, p.sid)     # reserved with the first answer
        if data["type"] == page_type and not pages[data["index"]].get("check"):
            return data, csrf, pages[data["index"]]
        p.submit(data, csrf, h.make_answer(study_of(app), pages[data["index"]], rng))


@pytest.mark.parametrize("page_type,answer,fragment", [
    ("consent", {"agree": False}, "must agree"),
    ("consent", {"agree": True, "extra": 1}, "unexpected field"),
    ("questionnaire", {"age": 12, "gender": "male"}, "answer.age: expected a number in 18..99"),
    ("questionnaire", {"age": "old", "gender": "male"}, "answer.age: expected a number"),
    ("questionnaire", {"age": 30, "gender": "robot"}, "answer.gender: expected one of the options"),
    ("questionnaire", {"gender": "male"}, "answer.age: this question needs an answer"),
    ("questionnaire", {"age": 30, "gender": "male", "comments": "x" * 1001}, "at most 1000"),
    ("pairwise", {"choices": {"human_likeness": "up"}}, "expected one of left, equal, right"),
    ("pairwise", {"choices": {}}, "answer.choices.human_likeness"),
    ("pairwise", {"choices": {"human_likeness": "left", "other": "left"}}, "unexpected field"),
    ("pairwise", {"choices": {"human_likeness": "left"}, "reasons": ["bogus"]}, "reason ids"),
    ("pairwise", {"choices": {"human_likeness": "right"}, "reasons": []}, "at least one reason"),
    ("pairwise", {"choices": {"human_likeness": "left"}}, "at least one reason"),
    ("mushra", {"ratings": [1, 2]}, "expected a list of 3 ratings"),
    ("mushra", {"ratings": [1, 2, 101]}, "answer.ratings[2]: expected an integer in 0..100"),
    ("mushra", {"ratings": [1, 2, True]}, "answer.ratings[2]"),
    ("likert", {"ratings": {"natural": 6, "fits": 1}}, "answer.ratings.natural: expected an integer in 1..5"),
    ("likert", {"ratings": {"natural": 2}}, "answer.ratings.fits"),
])
def test_answers_are_validated_per_page_type(study_dir, sqlite_url, page_type, answer, fragment):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "ptype0001")
    p.enter()
    data, csrf, spec = _walk_to(app, p, page_type, np.random.default_rng(0))
    r = p.submit(data, csrf, answer)
    assert r.status_code == 422 and fragment in r.get_json()["error"], r.get_json()
    assert p.page()[1]["index"] == data["index"]          # nothing was stored


def test_required_reasons_are_not_asked_for_an_equal_judgement(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    assert study_of(app).page("hl").cfg["reasons_required"]
    p = h.Participant(app.test_client(), "preason01")
    p.enter()
    data, csrf, spec = _walk_to(app, p, "pairwise", np.random.default_rng(0))
    assert spec["block"] == "hl"
    assert data["reasons_required"] is True
    r = p.submit(data, csrf, {"choices": {"human_likeness": "equal"}, "reasons": []})
    assert r.status_code == 200, r.get_json()
    assert p.page()[1]["index"] == data["index"] + 1


def test_draft_autosave_survives_a_server_restart(study_dir, db_url):
    app = make_app(study_dir, db_url)
    p = h.Participant(app.test_client(), "pdraft001")
    p.enter()
    data, csrf, _ = _walk_to(app, p, "mushra", np.random.default_rng(0))
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


def test_consent_from_a_too_narrow_window_is_refused(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "pnarrow01")
    p.enter()
    _, data, csrf = p.page()
    body = {"token": "tok-narrow-01", "answer": {"agree": True, "website": ""}, "width": 640}
    r = p.post(data["answer_url"], body, csrf)
    assert r.status_code == 422
    assert "at least 800 pixels" in r.get_json()["error"]
    body["width"], body["token"] = 1280, "tok-narrow-02"
    assert p.post(data["answer_url"], body, csrf).status_code == 200


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
