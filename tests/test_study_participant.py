"""The participant blueprint (study_app.participant): entry from Prolific, MTurk or anonymously, re-entry
and resuming, sessions that belong to one browser, and page data that never names a condition or a file."""
from __future__ import annotations

import json

import numpy as np
import pytest
import study_helpers as h
from study_fixtures import make_app

from study_app.context import store_of, study_of
from study_app.storage import ParticipantSession


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
    # finished participants cannot start over: the same attempt's link shows their code and return link again
    done, _ = h.run_participant(app, app.test_client(), "preent002", rng)
    r = h.Participant(app.test_client(), "preent002").enter()
    assert r.status_code == 200
    assert 'id="completion-code">DONE1234<' in r.get_data(as_text=True)
    assert "submissions/complete?cc=DONE1234" in r.get_data(as_text=True)
    # the participant id alone (another attempt's SESSION_ID) shows no code
    pid = h.valid_pid("preent002")
    r = app.test_client().get(f"/start/gesture-test?PROLIFIC_PID={pid}&STUDY_ID={h.PROLIFIC_STUDY}&SESSION_ID=x1")
    assert r.status_code == 409
    assert "already completed" in r.get_data(as_text=True)
    assert "DONE1234" not in r.get_data(as_text=True)
    # failed participants neither: theirs is the attention-check outcome's code
    h.run_participant(app, app.test_client(), "preent003", rng, fail_checks=2)
    r = h.Participant(app.test_client(), "preent003").enter()
    assert r.status_code == 200
    assert 'id="failure-code">FAIL5678<' in r.get_data(as_text=True)
    assert "attention checks" in r.get_data(as_text=True)
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


def test_answer_responses_are_exactly_the_documented_json(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "pbytes001")
    p.enter()
    _, data, csrf = p.page()
    body = {"token": "tok-bytes-01", "answer": {"agree": True, "website": ""}, "events": []}
    nxt = f"/s/{p.sid}/"
    stored = p.post(data["answer_url"], body, csrf)
    assert (stored.status_code, stored.data) == (
        200, b'{"next":"%s","session_status":"active","status":"stored"}\n' % nxt.encode())
    again = p.post(data["answer_url"], body, csrf)
    assert (again.status_code, again.data) == (
        200, b'{"next":"%s","session_status":"active","status":"duplicate"}\n' % nxt.encode())
    other = p.post(data["answer_url"], {**body, "token": "tok-bytes-02"}, csrf)
    assert (other.status_code, other.data) == (
        409, b'{"current_page":1,"error":"this page was already answered in another tab or window; the answer '
        b'given there is kept","next":"%s","session_status":"active","stale":true}\n' % nxt.encode())
    late_draft = p.post(data["draft_url"], {"draft": {"fields": {}}}, csrf)     # a stale tab's autosave
    assert (late_draft.status_code, late_draft.get_json()) == (
        409, {"error": "not the current page", "stale": True, "next": nxt})
