"""Abuse of the study server that the hardening review found (issue 11): event floods, plan exhaustion,
forged playback. Each test failed on the code before its fix."""
from __future__ import annotations

import dataclasses
import json
import re
import secrets

import pytest
import study_helpers as h
from sqlalchemy import event as sa_event

from study_app import create_app
from study_app.context import store_of, study_of
from study_app.errors import StudyStateError
from study_app.storage import Event


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("abuse")
    h.make_study(folder)
    return folder


@pytest.fixture()
def app(study_dir, tmp_path):
    return create_app({"STUDY": str(study_dir / "study.yaml"), "DATABASE_URL": f"sqlite:///{tmp_path / 'a.db'}",
                       "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                       "INSTANCE_PATH": str(tmp_path / "inst")})


def _pid(n: int) -> str:
    """A well-formed Prolific id (24 hex characters)."""
    return f"{n:024x}"


def _entered(app, n=1):
    p = h.Participant(app.test_client(), _pid(n))
    assert p.enter().status_code == 302
    return p


def _events(n, kind="seeked"):
    return [{"id": secrets.token_hex(8), "kind": kind, "slot": None, "t": None, "ms": 1, "detail": ""}
            for _ in range(n)]


def _count_events(app, sid, page=None):
    with store_of(app).Session() as db:
        q = db.query(Event).filter_by(session_id=sid)
        if page is not None:
            q = q.filter_by(page_index=page)
        return q.count()


# --------------------------------------------------------------------------------------- event caps

def test_events_are_capped_per_page_with_a_clear_413(app):
    cap = store_of(app).rules.events_per_page
    p = _entered(app)
    _, data, csrf = p.page()
    first = _events(cap - 100)
    assert p.post(data["events_url"], {"events": first}, csrf).status_code == 200
    r = p.post(data["events_url"], {"events": _events(300)}, csrf)
    assert r.status_code == 413
    body = r.get_json()
    assert "of this page is full (at most 1000 events per page" in body["error"]
    assert (body["logged"], body["dropped"]) == (100, 200)
    assert _count_events(app, p.sid) == cap
    r = p.post(data["events_url"], {"events": _events(5)}, csrf)
    assert r.status_code == 413
    assert r.get_json()["logged"] == 0
    assert _count_events(app, p.sid) == cap
    # a replayed batch is not new: nothing to refuse
    assert p.post(data["events_url"], {"events": first[:50]}, csrf).status_code == 200
    # playback events are counted apart: a flood of others never keeps out the record of a played video
    r = p.post(data["events_url"], {"events": _events(3, "ended")}, csrf)
    assert r.status_code == 200
    assert _count_events(app, p.sid) == cap + 3
    # the answer is still taken (never blocked by the log), its extra events are not stored
    r = p.submit(data, csrf, {"agree": True, "website": ""}, events=_events(10, "visible"))
    assert r.status_code == 200
    assert r.get_json()["events_dropped"] == 10
    assert _count_events(app, p.sid) == cap + 3


def test_events_are_capped_per_session(app):
    store = store_of(app)
    store.rules = dataclasses.replace(store.rules, events_per_page=50, events_per_session=80)
    rng = __import__("numpy").random.default_rng(0)
    p = _entered(app, 2)
    _, data, csrf = p.page()
    assert p.post(data["events_url"], {"events": _events(50)}, csrf).status_code == 200
    spec = h.plan_pages(app, p.sid)[data["index"]]
    assert p.submit(data, csrf, h.make_answer(study_of(app), spec, rng)).status_code == 200
    _, data, csrf = p.page()
    r = p.post(data["events_url"], {"events": _events(45)}, csrf)
    assert r.status_code == 413
    assert "of this session is full (at most 80 events per session" in r.get_json()["error"]
    assert _count_events(app, p.sid) == 80
    assert _count_events(app, p.sid, data["index"]) == 30


def _selects_of_event_rows(app, fn):
    """Run ``fn`` and return the SQL statements that read rows (not aggregates: counts, or the admin's per-slot
    maxima of 'does not play' reports) of the events table."""
    engine = store_of(app).engine
    seen = []

    def hook(conn, cursor, statement, params, context, executemany):
        s = statement.lower()
        if re.search(r"\bfrom events\b", s) and not re.search(r"\b(count|max|min|sum)\(", s):
            seen.append(statement)

    sa_event.listen(engine, "before_cursor_execute", hook)
    try:
        fn()
    finally:
        sa_event.remove(engine, "before_cursor_execute", hook)
    return seen


def test_admin_page_and_results_export_do_not_load_the_interaction_log(app):
    rng = __import__("numpy").random.default_rng(1)
    p, _ = h.run_participant(app, app.test_client(), _pid(3), rng)
    admin = app.test_client()
    auth = {"Authorization": f"Bearer {h.ADMIN}"}
    assert _selects_of_event_rows(app, lambda: admin.get("/admin/", headers=auth)) == []
    assert _selects_of_event_rows(app, lambda: admin.get("/admin/export/results.csv", headers=auth)) == []
    # the raw JSON still has the whole log (streamed in batches), and is valid JSON
    raw = json.loads(admin.get("/admin/export/raw.json", headers=auth).get_data(as_text=True))
    assert len(raw["events"]) == _count_events(app, p.sid) > 0
    assert {e["kind"] for e in raw["events"]} == {"ended"}


# --------------------------------------------------------------------------------- plan exhaustion

def _free_plans(app):
    from study_app.storage import Plan
    with store_of(app).Session() as db:
        return db.query(Plan).filter_by(status="free").count()


def _from(app, address):
    client = app.test_client()
    client.environ_base["REMOTE_ADDR"] = address
    return client


def test_visitors_who_never_start_hold_no_plan(app):
    n_plans = _free_plans(app)
    for i in range(20):            # cookie-less requests with made-up (well-formed) ids, each from its own address
        r = _from(app, f"10.0.0.{i}").get(h.prolific_url(_pid(1000 + i)))
        assert r.status_code == 302
    assert _free_plans(app) == n_plans
    # a real participant still gets a place, reserved when they give consent
    p = _entered(app, 5)
    assert _free_plans(app) == n_plans
    assert p.consent().status_code == 200
    assert _free_plans(app) == n_plans - 1
    # ... and resumes from the same browser, or with the same Prolific SESSION_ID from another one
    assert p.enter().status_code == 302
    again = h.Participant(app.test_client(), _pid(5))
    assert again.enter().status_code == 302
    assert again.sid == p.sid
    _, data, _ = again.page()
    assert data["index"] == 1


def test_a_window_too_narrow_reserves_nothing(app):
    n_plans = _free_plans(app)
    p = _entered(app, 6)
    _, data, csrf = p.page()
    r = p.post(data["answer_url"], {"token": "tok-narrow-01", "answer": {"agree": True, "website": ""},
                                    "width": 500}, csrf)
    assert r.status_code == 422
    assert "800 pixels" in r.get_json()["error"]
    assert _free_plans(app) == n_plans


def test_when_every_plan_is_taken_consent_says_study_full(app):
    n_plans = _free_plans(app)
    waiting = _entered(app, 7)                  # reads the consent page while the others take every place
    for i in range(n_plans):
        p = _entered(app, 100 + i)
        assert p.consent().status_code == 200
    _, data, csrf = waiting.page()
    assert data is None                          # the page itself says so now
    r = waiting.client.post(f"/s/{waiting.sid}/answer/0", json={"token": "tok-full-0001", "answer": {
        "agree": True, "website": ""}}, headers={"X-CSRFToken": _csrf_of(waiting)})
    assert r.status_code == 409
    assert "All places" in r.get_json()["error"]
    r = waiting.client.get(r.get_json()["next"])
    assert r.status_code == 503
    assert "All places" in r.get_data(as_text=True)
    # a newcomer is told at once
    r = h.Participant(app.test_client(), _pid(999)).enter()
    assert r.status_code == 503


def _csrf_of(p):
    m = re.search(r'name="csrf_token" value="([^"]+)"', p.client.get("/admin/login").get_data(as_text=True))
    assert m is not None
    return m.group(1)


def test_new_sessions_per_client_address_are_limited(app):
    study = study_of(app)
    limit = study.new_sessions_per_address
    assert limit == 10                                   # the documented default
    for i in range(limit):
        assert _from(app, "192.0.2.7").get(h.prolific_url(_pid(200 + i))).status_code == 302
    r = _from(app, "192.0.2.7").get(h.prolific_url(_pid(300)))
    assert r.status_code == 429
    assert "Too many" in r.get_data(as_text=True)
    assert 0 < int(r.headers["Retry-After"]) <= 3600
    # nothing was created for the refused one, other addresses are not affected, and resuming is not a new session
    from study_app.storage import ParticipantSession
    with store_of(app).Session() as db:
        assert db.query(ParticipantSession).filter_by(participant=_pid(300)).count() == 0
    assert _from(app, "192.0.2.8").get(h.prolific_url(_pid(300))).status_code == 302
    assert _from(app, "192.0.2.7").get(h.prolific_url(_pid(200))).status_code == 302


def test_the_limit_is_configured_in_the_study(tmp_path):
    from study_app.definition import load_study
    from study_app.errors import StudyDefinitionError

    text = h.STUDY_YAML.format(sessions=4).replace("min_width: 800", "min_width: 800\nnew_sessions_per_address: 2\n"
                                                   "new_sessions_window_minutes: 5")
    path = h.make_study(tmp_path, yaml_text=text)
    app = create_app({"STUDY": str(path), "DATABASE_URL": f"sqlite:///{tmp_path / 'l.db'}", "SECRET_KEY": h.SECRET,
                      "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "i")})
    assert [_from(app, "192.0.2.9").get(h.prolific_url(_pid(i))).status_code for i in range(3)] == [302, 302, 429]
    for change, message in (("new_sessions_per_address: -1", "new_sessions_per_address"),
                            ("prolific_study_id: st1", "24 hexadecimal")):    # an id no link could match
        (tmp_path / "bad.yaml").write_text(text.replace("new_sessions_per_address: 2", change))
        with pytest.raises(StudyDefinitionError, match=message):
            load_study(tmp_path / "bad.yaml")


# ------------------------------------------------------------------------------- forged playback

def _walk(app, pid, rng, fetch: bool, dwell: float = 0.0):
    """A scripted participant: posts 'ended' for every video; fetches them (``fetch``) and stays ``dwell``
    seconds on pages with media, or not."""
    import time
    study = study_of(app)
    p = _entered(app, pid)
    while True:
        r, data, csrf = p.page()
        if data is None:
            return p, r
        spec = h.plan_pages(app, p.sid)[data["index"]]
        if fetch:
            for url in data["videos"]:
                assert p.client.get(url).status_code == 200
        if data["videos"] and dwell:
            time.sleep(dwell)
        assert p.submit(data, csrf, h.make_answer(study, spec, rng)).status_code == 200


def test_forged_playback_is_flagged_in_the_export_and_excluded_by_analyze(tmp_path):
    import csv
    import io

    from click.testing import CliRunner

    from evalsuite.cli import main
    from study_app.playback import probe_seconds

    text = h.STUDY_YAML.format(sessions=4).replace("min_width: 800", "min_width: 800\nplayback_min_fraction: 0.6")
    path = h.make_study(tmp_path, yaml_text=text)
    app = create_app({"STUDY": str(path), "DATABASE_URL": f"sqlite:///{tmp_path / 'p.db'}", "SECRET_KEY": h.SECRET,
                      "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "i")})
    study = study_of(app)
    clip = study.manifest.stimuli[0].file
    assert probe_seconds(study.manifest.root / clip) == pytest.approx(1.0, abs=0.05)    # 1 s sample clips
    rng = __import__("numpy").random.default_rng(7)
    bot, r = _walk(app, 11, rng, fetch=False)                # never requests a video, answers at once
    assert "DONE1234" in r.get_data(as_text=True)              # the browser's word was taken: it finished
    # (a minimum well above a loaded machine's request times, so answering at once is always too soon)
    hasty, _ = _walk(app, 12, rng, fetch=True)               # fetches every video but answers at once
    honest, _ = _walk(app, 13, rng, fetch=True, dwell=0.7)   # fetches and stays >= 0.6 x the 1 s clips

    auth = {"Authorization": f"Bearer {h.ADMIN}"}
    export = app.test_client().get("/admin/export/results.csv", headers=auth).get_data(as_text=True)
    rows = list(csv.DictReader(io.StringIO(export)))
    flags = {}
    for row in rows:
        flags.setdefault(row["session"], set()).add(row["playback_implausible"])
    assert flags == {bot.sid: {"1"}, hasty.sid: {"1"}, honest.sid: {"0"}}
    raw = json.loads(app.test_client().get("/admin/export/raw.json", headers=auth).get_data(as_text=True))
    bot_pages = [a["playback"] for a in raw["answers"] if a["session"] == bot.sid and a["playback"]]
    assert bot_pages and all(pb["implausible"] and pb["not_requested"] for pb in bot_pages)
    hasty_pages = {a["page"]: a["playback"] for a in raw["answers"] if a["session"] == hasty.sid and a["playback"]}
    # 0.6 x the 1 s clips; the headphone check: 0.6 x one trial's 4 s sound
    assert all(pb["not_requested"] == [] and pb["min_ms"] == (2400 if page == "headphones" else 600)
               for page, pb in hasty_pages.items())

    results = tmp_path / "results.csv"
    results.write_text(export)
    out = tmp_path / "analysis"
    res = CliRunner().invoke(main, ["analyze", str(results), "-o", str(out), "--no-figures", "--bootstrap", "0",
                                    "--no-mushra-screening"])
    assert res.exit_code == 0, res.output
    import pandas as pd
    excl = pd.read_csv(out / "exclusions.csv", keep_default_na=False)
    assert set(excl.loc[excl["reason"] == "implausible_playback", "session"]) == {bot.sid, hasty.sid}
    report = (out / "report.html").read_text()
    assert "implausible_playback" in report
    assert "exclude at &gt;= 1 flagged pages (2 sessions flagged)" in report
    assert "2 sessions have pages with implausible playback" in report
    # the rule can be switched off: then nobody is excluded for it
    res = CliRunner().invoke(main, ["analyze", str(results), "-o", str(tmp_path / "a2"), "--no-figures",
                                    "--bootstrap", "0", "--no-mushra-screening", "--implausible-playback", "off"])
    assert res.exit_code == 0, res.output
    excl = pd.read_csv(tmp_path / "a2" / "exclusions.csv", keep_default_na=False)
    assert "implausible_playback" not in set(excl["reason"])
    assert "the rule is off" in (tmp_path / "a2" / "report.html").read_text()


def test_playback_judgement_rules():
    from study_app.playback import check_playback

    ok = check_playback(2, {0, 1}, [4.0, 6.0], rt_ms=3000, min_fraction=0.5, full_playback=True)
    assert (ok.implausible, ok.min_ms) == (False, 3000)
    assert check_playback(2, {0, 1}, [4.0, 6.0], rt_ms=2999, min_fraction=0.5, full_playback=True).implausible
    missing = check_playback(2, {1}, [4.0, 6.0], rt_ms=60_000, min_fraction=0.5, full_playback=True)
    assert (missing.implausible, missing.not_requested) == (True, (0,))
    # without full playback only the request is checked; unknown durations likewise
    assert not check_playback(2, {0, 1}, [4.0, 6.0], rt_ms=10, min_fraction=0.5, full_playback=False).implausible
    assert not check_playback(2, {0, 1}, [None, None], rt_ms=10, min_fraction=0.5, full_playback=True).implausible


def test_wav_and_manifest_durations(tmp_path):
    import wave

    from study_app.playback import probe_seconds

    with wave.open(str(tmp_path / "t.wav"), "wb") as w:
        w.setnchannels(2)
        w.setsampwidth(2)
        w.setframerate(8000)
        w.writeframes(b"\0\0\0\0" * 12000)
    assert probe_seconds(tmp_path / "t.wav") == pytest.approx(1.5)
    (tmp_path / "junk.mp4").write_bytes(b"\0\0\0\x08free" + secrets.token_bytes(100))
    assert probe_seconds(tmp_path / "junk.mp4") is None
    assert probe_seconds(tmp_path / "missing.mp4") is None


def test_concurrent_consents_share_out_the_last_plans_exactly(tmp_path):
    import threading

    from study_app.storage import Answer, ParticipantSession, Plan

    path = h.make_study(tmp_path, sessions=2)
    app = create_app({"STUDY": str(path), "DATABASE_URL": f"sqlite:///{tmp_path / 'c.db'}", "SECRET_KEY": h.SECRET,
                      "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "i")})
    people = [_entered(app, 400 + i) for i in range(6)]
    pages = [p.page() for p in people]
    codes: list[int] = []
    barrier = threading.Barrier(len(people))

    def consent(p, page):
        _, data, csrf = page
        barrier.wait()
        codes.append(p.submit(data, csrf, {"agree": True, "website": ""}).status_code)

    threads = [threading.Thread(target=consent, args=(p, pg)) for p, pg in zip(people, pages)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(codes) == [200, 200, 409, 409, 409, 409]
    with store_of(app).Session() as db:
        plans = db.query(Plan).all()
        assert {p.status for p in plans} == {"reserved"}
        holders = {p.session_id for p in plans}
        assert len(holders) == 2
        assert {a.session_id for a in db.query(Answer).all()} == holders      # answer and plan together
        assert {s.id for s in db.query(ParticipantSession).filter(ParticipantSession.plan_id.isnot(None))} == holders


@pytest.mark.postgres
def test_media_requests_and_plan_reservation_on_postgresql(study_dir, tmp_path):
    from study_app.storage import MediaRequest, Plan
    from study_app.testing import create_database, throwaway_postgres

    with throwaway_postgres() as server:
        app = create_app({"STUDY": str(study_dir / "study.yaml"), "DATABASE_URL": create_database(server, "abuse"),
                          "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                          "INSTANCE_PATH": str(tmp_path / "inst")})
        rng = __import__("numpy").random.default_rng(3)
        p = _entered(app, 21)
        store = store_of(app)
        with store.Session() as db:
            assert db.query(Plan).filter_by(status="reserved").count() == 0
        while True:
            _, data, csrf = p.page()
            if data["videos"] and data["type"] != "headphone_check":     # its sounds are sent once only
                break
            spec = h.plan_pages(app, p.sid)[data["index"]]
            assert p.submit(data, csrf, h.make_answer(study_of(app), spec, rng)).status_code == 200
        for url in data["videos"] * 2:                        # twice: recorded once
            assert p.client.get(url).status_code == 200
        store.media_log.recorded.clear()                      # as in another server process
        assert p.client.get(data["videos"][0]).status_code == 200
        with store.Session() as db:
            assert db.query(Plan).filter_by(status="reserved").count() == 1
            assert db.query(MediaRequest).filter_by(session_id=p.sid).count() == len(data["videos"])
        store.engine.dispose()


def test_behind_a_trusted_proxy_the_limit_counts_forwarded_addresses(study_dir, tmp_path):
    def app_with(proxies, name):
        return create_app({"STUDY": str(study_dir / "study.yaml"), "DATABASE_URL": f"sqlite:///{tmp_path / name}",
                           "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False,
                           "INSTANCE_PATH": str(tmp_path / "inst"), "TRUSTED_PROXIES": proxies})

    def enter(app, n, forwarded):
        return app.test_client().get(h.prolific_url(_pid(n)), headers={"X-Forwarded-For": forwarded}).status_code

    trusting = app_with(1, "t.db")
    assert [enter(trusting, 500 + i, f"198.51.100.{i}") for i in range(12)] == [302] * 12
    untrusting = app_with(0, "u.db")                 # every client seems to be the proxy itself
    assert [enter(untrusting, 600 + i, f"198.51.100.{i}") for i in range(11)] == [302] * 10 + [429]
    with pytest.raises(StudyStateError, match="TRUSTED_PROXIES"):
        app_with(-1, "x.db")


def test_a_video_request_does_not_wait_for_the_sqlite_write_lock(app):
    import time

    from study_app.storage import MediaRequest

    store = store_of(app)
    p = _entered(app, 31)
    blocker = store.engine.raw_connection()
    cur = blocker.dbapi_connection.cursor()
    cur.execute("BEGIN IMMEDIATE")                    # another writer holds the lock (e.g. an answer's fsync)
    try:
        start = time.perf_counter()
        store.record_media_request(p.sid, 0, 0)
        assert time.perf_counter() - start < 1.0      # queued, not waiting (the busy timeout is 60 s)
    finally:
        cur.execute("ROLLBACK")
        blocker.close()
    store.dump(study_of(app).id)                       # exports write this process's queue first
    with store.Session() as db:
        assert db.query(MediaRequest).filter_by(session_id=p.sid, page_index=0, slot=0).count() == 1
    store.record_media_request(p.sid, 0, 1)            # uncontended: written at once
    with store.Session() as db:
        assert db.query(MediaRequest).filter_by(session_id=p.sid).count() == 2
