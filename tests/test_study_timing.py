"""Per-request timing (study_app.timing, EVALSUITE_TIMING_LOG): off by default; when set, one line per request
with its kind and its time split into CPU, write-queue wait, commit, SQL and pool, and a summary per kind."""
from __future__ import annotations

import json

import study_helpers as h
from study_fixtures import make_app

from study_app import timing


def test_timing_log_is_off_by_default(study_dir, sqlite_url, tmp_path, monkeypatch):
    monkeypatch.delenv(timing.ENV, raising=False)
    app = make_app(study_dir, sqlite_url)
    assert not isinstance(app.wsgi_app, timing.TimingMiddleware)


def test_every_request_is_logged_with_its_parts(study_dir, sqlite_url, tmp_path, monkeypatch):
    log = tmp_path / "timing.log"
    monkeypatch.setenv(timing.ENV, str(log))
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "ptime0001")
    p.enter()
    _, data, csrf = p.page()
    assert p.submit(data, csrf, {"agree": True, "website": ""}).status_code == 200
    rows = [json.loads(line) for line in log.read_text().splitlines()]
    assert [(r["m"], r["kind"], r["status"]) for r in rows] == [
        ("GET", "enter", 302), ("GET", "page", 200), ("POST", "answer", 200)]
    answer = rows[-1]
    assert answer["commit"] > 0 and answer["held"] > 0 and answer["sql"] > 0
    assert answer["wall"] >= answer["lock"] + answer["commit"] + answer["sql"]
    summary = timing.summarise(str(log))
    assert set(summary) == {"enter", "page", "answer"}
    assert summary["answer"]["n"] == 1 and summary["answer"]["p99"] == answer["wall"]
    assert summary["answer"]["slow_commit"] == answer["commit"]
