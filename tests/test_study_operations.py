"""Operations on a running study (study_app.operations, the admin page's forms and ``evalsuite study ...``):
release, top-up, exclusion, pilot mode, GDPR deletion, pseudonymised and review exports, and the Prolific API
client (study_app.prolific_api) against a fake Prolific on loopback."""
from __future__ import annotations

import csv
import io
import json
import logging
import re
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import numpy as np
import pytest
import study_helpers as h
from click.testing import CliRunner
from sqlalchemy import inspect, text
from study_fixtures import export_rows, make_app

from study_app.cli import study as study_cli
from study_app.context import store_of
from study_app.prolific_api import ProlificClient, ProlificError
from study_app.storage import ParticipantSession, Plan, SessionMark

AUTH = {"Authorization": f"Bearer {h.ADMIN}"}


def _admin(app):
    client = app.test_client()
    page = client.get("/admin/login").get_data(as_text=True)
    csrf = re.search(r'name="csrf_token" value="([^"]+)"', page).group(1)
    assert client.post("/admin/login", data={"token": h.ADMIN, "csrf_token": csrf}).status_code == 302
    return client


def _op(client, name, **form):
    csrf = re.search(r'name="csrf_token" value="([^"]+)"', client.get("/admin/").get_data(as_text=True)).group(1)
    r = client.post(f"/admin/op/{name}", data={"csrf_token": csrf, **form})
    assert r.status_code == 302
    return client.get("/admin/").get_data(as_text=True)


def _cli(*args, ok=True):
    r = CliRunner().invoke(study_cli, [str(a) for a in args])
    assert (r.exit_code == 0) == ok, r.output
    return r.output


def _started(app, name):
    p = h.Participant(app.test_client(), name)
    p.enter()
    p.consent()
    return p


def test_release_a_reserved_plan_from_the_admin_page_and_the_cli(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    a, b = _started(app, "prel0001"), _started(app, "prel0002")
    store = store_of(app)
    with store.Session() as db:
        key_a = db.get(Plan, db.get(ParticipantSession, a.sid).plan_id).key
        key_b = db.get(Plan, db.get(ParticipantSession, b.sid).plan_id).key
    page = _op(_admin(app), "release", plan=key_a)
    assert f"plan {key_a} released" in page
    _cli("release", study_dir / "study.yaml", key_b, "--db", sqlite_url)
    with store.Session() as db:
        for sid, key in ((a.sid, key_a), (b.sid, key_b)):
            assert db.query(Plan).filter_by(key=key).one().status == "free"
            assert (db.get(ParticipantSession, sid).status, db.get(ParticipantSession, sid).end_reason) == \
                ("expired", "released")
    assert "not reserved" in _cli("release", study_dir / "study.yaml", key_b, "--db", sqlite_url, ok=False)
    assert "no plan" in _op(_admin(app), "release", plan="plan-9999")


def test_topup_adds_plans_to_a_running_study(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    store = store_of(app)
    with store.Session() as db:
        before = db.query(Plan).count()
    assert "2 plans added" in _op(_admin(app), "topup", n="2")
    out = _cli("topup", study_dir / "study.yaml", "3", "--db", sqlite_url)
    assert "topup2-plan-0000" in out
    with store.Session() as db:
        keys = [p.key for p in db.query(Plan).order_by(Plan.position)]
    assert len(keys) == before + 5 and keys[-5:] == ["topup1-plan-0000", "topup1-plan-0001", "topup2-plan-0000",
                                                      "topup2-plan-0001", "topup2-plan-0002"]
    # the server starts again on the same database (no rebuild), and the added plans are handed out
    app = make_app(study_dir, sqlite_url)
    with store_of(app).Session.begin() as db:
        for p in db.query(Plan).filter(~Plan.key.startswith("topup")):
            p.status = "used"
    p = _started(app, "ptopup01")
    with store_of(app).Session() as db:
        assert db.get(Plan, db.get(ParticipantSession, p.sid).plan_id).key == "topup1-plan-0000"
    h.run_participant(app, app.test_client(), "ptopup02", np.random.default_rng(0))


def test_excluded_and_pilot_sessions_stay_out_of_the_export(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    rng = np.random.default_rng(5)
    kept, _ = h.run_participant(app, app.test_client(), "pkept001", rng)
    dropped, _ = h.run_participant(app, app.test_client(), "pdrop001", rng)
    _cli("pilot", study_dir / "study.yaml", "on", "--db", sqlite_url)
    assert "pilot mode on" in _cli("pilot", study_dir / "study.yaml", "status", "--db", sqlite_url)
    pilot, _ = h.run_participant(app, app.test_client(), "ppilot01", rng)
    page = _op(_admin(app), "pilot", on="0")
    assert 'id="pilot-mode">off<' in page
    assert "reason" in _op(_admin(app), "exclude", session=dropped.pid, reason="")
    _op(_admin(app), "exclude", session=dropped.pid, reason="watched without sound")
    with store_of(app).Session() as db:
        assert db.get(SessionMark, dropped.sid).reason == "watched without sound"
        assert db.get(SessionMark, pilot.sid).pilot
    assert {r["participant"] for r in export_rows(app)} == {kept.pid}
    client = app.test_client()
    rows = csv.DictReader(io.StringIO(client.get("/admin/export/results.csv?pilot=1&excluded=1",
                                                 headers=AUTH).get_data(as_text=True)))
    assert {r["participant"] for r in rows} == {kept.pid, dropped.pid, pilot.pid}
    raw = json.loads(client.get("/admin/export/raw.json", headers=AUTH).get_data(as_text=True))
    assert {s["participant"] for s in raw["sessions"]} == {kept.pid}
    assert {e["session"] for e in raw["events"]} == {kept.sid}
    # the CLI: exclusion taken back, pilot kept on request
    _cli("exclude", study_dir / "study.yaml", dropped.sid, "--undo", "--db", sqlite_url)
    out = study_dir / "ops-results.csv"
    _cli("export", study_dir / "study.yaml", "--db", sqlite_url, "-o", out, "--include-pilot")
    rows = list(csv.DictReader(io.StringIO(out.read_text())))
    assert {r["participant"] for r in rows} == {kept.pid, dropped.pid, pilot.pid}


def _rows_naming(engine, values):
    """Every (table, row) of the database holding one of ``values`` in any column."""
    found = []
    with engine.connect() as conn:
        for table in inspect(engine).get_table_names():
            for row in conn.execute(text(f'SELECT * FROM "{table}"')):
                if any(v in str(cell) for cell in row for v in values):
                    found.append((table, row))
    return found


def test_forget_deletes_every_row_of_one_participant(study_dir, db_url, caplog):
    app = make_app(study_dir, db_url)
    rng = np.random.default_rng(7)
    gone, _ = h.run_participant(app, app.test_client(), "pforget01", rng, fail_checks=0)
    other, _ = h.run_participant(app, app.test_client(), "pforget02", rng)
    _op(_admin(app), "exclude", session=gone.sid, reason="asked to be deleted")
    gone.client.get(f"/s/{gone.sid}/")
    engine = store_of(app).engine
    assert _rows_naming(engine, [gone.sid, gone.pid])
    assert "type the participant id a second time" in _op(_admin(app), "forget", participant=gone.pid, confirm="x")
    with caplog.at_level(logging.WARNING, logger="study_app.operations"):
        page = _op(_admin(app), "forget", participant=gone.pid, confirm=gone.pid)
    assert "participant forgotten" in page
    assert _rows_naming(engine, [gone.sid, gone.pid]) == []
    assert _rows_naming(engine, [other.sid, other.pid])              # the others' data stays
    line = [r.getMessage() for r in caplog.records if "forgotten on request" in r.getMessage()]
    assert len(line) == 1 and gone.pid not in line[0]
    # and from the CLI
    _cli("forget", study_dir / "study.yaml", other.pid, "--yes", "--db", db_url)
    assert _rows_naming(engine, [other.sid, other.pid]) == []
    assert "no session or participant" in _cli("forget", study_dir / "study.yaml", other.pid, "--yes", "--db",
                                               db_url, ok=False)


def test_pseudonymised_export_holds_no_raw_id(study_dir, sqlite_url, tmp_path):
    app = make_app(study_dir, sqlite_url)
    rng = np.random.default_rng(9)
    ps = [h.run_participant(app, app.test_client(), f"ppseudo{i}", rng)[0] for i in range(2)]
    raw_ids = [p.pid for p in ps] + [f"se{p.pid}" for p in ps]
    out, raw = tmp_path / "r.csv", tmp_path / "raw.json"
    _cli("export", study_dir / "study.yaml", "--db", sqlite_url, "-o", out, "--raw", raw, "--pseudonymise",
         "--key", "a-research-secret-123")
    texts = [out.read_text(), raw.read_text()]
    client = app.test_client()
    texts += [client.get(u, headers=AUTH).get_data(as_text=True)
              for u in ("/admin/export/results.csv?pseudonymise=1", "/admin/export/raw.json?pseudonymise=1")]
    for t in texts:
        assert not any(i in t for i in raw_ids)
    rows = list(csv.DictReader(io.StringIO(texts[0])))
    assert len({r["participant"] for r in rows}) == 2 and all(r["participant"].startswith("p-") for r in rows)
    again = tmp_path / "r2.csv"          # the same key gives the same pseudonyms
    _cli("export", study_dir / "study.yaml", "--db", sqlite_url, "-o", again, "--pseudonymise",
         "--key", "a-research-secret-123")
    assert again.read_text() == texts[0]


def test_review_export_lists_outcome_action_and_reason(study_dir, sqlite_url, tmp_path):
    app = make_app(study_dir, sqlite_url)
    rng = np.random.default_rng(11)
    done, _ = h.run_participant(app, app.test_client(), "preview01", rng)
    failed, _ = h.run_participant(app, app.test_client(), "preview02", rng, fail_checks=2)
    nocons = h.Participant(app.test_client(), "preview03")
    nocons.enter()
    _, data, csrf = nocons.page()
    nocons.submit(data, csrf, {"agree": False})
    excluded, _ = h.run_participant(app, app.test_client(), "preview04", rng)
    _op(_admin(app), "exclude", session=excluded.pid, reason="same answer everywhere")
    out = tmp_path / "review.csv"
    _cli("review-export", study_dir / "study.yaml", "--db", sqlite_url, "-o", out)
    rows = {r["participant_id"]: r for r in csv.DictReader(io.StringIO(out.read_text()))}
    assert list(next(iter(rows.values()))) == ["participant_id", "submission_id", "outcome", "code", "action", "reason"]
    assert rows[done.pid] == {"participant_id": done.pid, "submission_id": f"se{done.pid}", "outcome": "completed",
                              "code": "DONE1234", "action": "AUTOMATICALLY_APPROVE", "reason": "completed the study"}
    assert (rows[failed.pid]["outcome"], rows[failed.pid]["action"], rows[failed.pid]["reason"]) == \
        ("attention_checks", "MANUALLY_REVIEW", "failed 2 attention checks")
    assert (rows[nocons.pid]["outcome"], rows[nocons.pid]["action"]) == ("no_consent", "REQUEST_RETURN")
    assert rows[excluded.pid]["reason"] == "excluded: same answer everywhere"
    web = app.test_client().get("/admin/export/review.csv?excluded=1", headers=AUTH).get_data(as_text=True)
    assert web == out.read_text()


def test_admin_counters_refresh_with_answers_and_plans(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    client = app.test_client()
    before = client.get("/admin/status.json", headers=AUTH).get_json()
    h.run_participant(app, app.test_client(), "pcount01", np.random.default_rng(1))
    after = client.get("/admin/status.json", headers=AUTH).get_json()
    assert before["answers"] == 0 and after["answers"] > 0
    assert after["plans"]["used"] == before["plans"].get("used", 0) + 1
    page = client.get("/admin/", headers=AUTH).get_data(as_text=True)
    assert 'data-key="answers"' in page and 'id="plan-counts"' in page


# ------------------------------------------------------------------------------- Prolific API, faked

class _FakeProlific(BaseHTTPRequestHandler):
    calls: list = []

    def do_POST(self):
        body = json.loads(self.rfile.read(int(self.headers["Content-Length"])) or b"{}")
        self.calls.append((self.path, self.headers["Authorization"], body))
        if "bad" in self.path:
            self.send_response(400)
            self.end_headers()
            self.wfile.write(b'{"error": "no such submission"}')
            return
        answer = {"id": "bulk0001"} if self.path.endswith("bonus-payments/") else {"status": "ok"}
        self.send_response(200)
        self.send_header("Content-Type", "application/json")
        self.end_headers()
        self.wfile.write(json.dumps(answer).encode())

    def log_message(self, *args):
        pass


@pytest.fixture()
def fake_prolific():
    _FakeProlific.calls = []
    server = ThreadingHTTPServer(("127.0.0.1", 0), _FakeProlific)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_port}/api/v1", _FakeProlific.calls
    server.shutdown()
    server.server_close()


def test_prolific_client_calls_against_a_fake_server(fake_prolific):
    url, calls = fake_prolific
    client = ProlificClient("tok-123", url)
    client.approve("sub001")
    client.reject("sub002", "x" * 120, "FAILED_CHECK")
    client.request_return("sub003", ["did not consent"])
    client.bonus("5e0000000000000000000001", {"pid001": 0.5, "pid002": 1})
    assert [(p, b) for p, _, b in calls] == [
        ("/api/v1/submissions/sub001/transition/", {"action": "APPROVE"}),
        ("/api/v1/submissions/sub002/transition/", {"action": "REJECT", "message": "x" * 120,
                                                    "rejection_category": "FAILED_CHECK"}),
        ("/api/v1/submissions/sub003/request-return/", {"request_return_reasons": ["did not consent"]}),
        ("/api/v1/submissions/bonus-payments/", {"study_id": "5e0000000000000000000001",
                                                 "csv_bonuses": "pid001,0.50\npid002,1.00\n"}),
        ("/api/v1/bulk-bonus-payments/bulk0001/pay/", {})]
    assert {a for _, a, _ in calls} == {"Token tok-123"}
    with pytest.raises(ProlificError, match="answered 400 to POST /submissions/bad1/transition/"):
        client.approve("bad1")
    with pytest.raises(ProlificError, match="at least 100 characters"):
        client.reject("sub002", "too short")
    with pytest.raises(ProlificError, match="no Prolific API token"):
        ProlificClient("")


def test_prolific_review_carries_out_the_review_export(study_dir, sqlite_url, fake_prolific):
    url, calls = fake_prolific
    app = make_app(study_dir, sqlite_url)
    rng = np.random.default_rng(13)
    h.run_participant(app, app.test_client(), "pprol001", rng)
    nocons = h.Participant(app.test_client(), "pprol002")
    nocons.enter()
    _, data, csrf = nocons.page()
    nocons.submit(data, csrf, {"agree": False})
    dry = _cli("prolific-review", study_dir / "study.yaml", "--db", sqlite_url)
    assert "request return" in dry and calls == []
    _cli("prolific-review", study_dir / "study.yaml", "--db", sqlite_url, "--apply", "--token", "tok-9",
         "--base-url", url)
    assert [(p, b) for p, _, b in calls] == [(f"/api/v1/submissions/se{nocons.pid}/request-return/",
                                              {"request_return_reasons": ["did not consent"]})]


def test_every_study_command_and_option_explains_itself():
    import click

    out = _cli("--help")
    for name in ("release", "topup", "exclude", "pilot", "forget", "review-export", "prolific-review"):
        assert name in out
        assert "Usage" in _cli(name, "--help")
    for name, cmd in study_cli.commands.items():
        assert cmd.help, name
        assert [p.name for p in cmd.params if isinstance(p, click.Option) and not p.help] == [], name
    assert "--pseudonymise" in _cli("export", "--help")
