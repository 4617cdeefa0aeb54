"""Media sent by nginx (study_app.media_nginx, the MEDIA_SERVER switch of study_app.media) and the app's own
media_served rows through the media log's queued writer (study_app.media_log)."""
from __future__ import annotations

import os
import sqlite3
import time

import pytest
import study_helpers as h
from deploy_helpers import ADMIN, SECRET, make_study

from study_app.app import create_app
from study_app.context import store_of
from study_app.errors import StudyStateError
from study_app.media_nginx import ACCEL_PREFIX, ingest, parse_line

SID = "AbCdEfGhIjKlMnOpQrStUvWx"


def _app(tmp_path, **extra):
    db = tmp_path / "study.db"
    study = tmp_path / "study.yaml"
    if not study.exists():
        make_study(tmp_path, f"sqlite:///{db}")
    return create_app({"STUDY": str(study), "DATABASE_URL": f"sqlite:///{db}", "SECRET_KEY": SECRET,
                       "ADMIN_TOKEN": ADMIN, "SESSION_COOKIE_SECURE": False,
                       "INSTANCE_PATH": str(tmp_path / "inst"), **extra})


def _on_video_page(app):
    p = h.Participant(app.test_client(), "ab" * 12, study_id="deploy-test")
    p.enter()
    _, data, csrf = p.page()
    assert p.submit(data, csrf, {"agree": True, "website": ""}).status_code == 200
    _, data, _ = p.page()
    assert data["type"] == "pairwise"
    return p, data


def test_parse_line_gives_the_exact_range_nginx_sent():
    uri = f"/s/{SID}/media/3/1"
    assert parse_line(f'1700000000.123 206 1000 {uri} "bytes 0-999/5000" 1000\n')[:7] == \
        (SID, 3, 1, 0, 999, 5000, 206)
    # a client that left after 300 bytes of its range: only those are recorded
    assert parse_line(f'1700000000.5 206 300 {uri} "bytes 4000-4999/5000" 1000')[3:6] == (4000, 4299, 5000)
    assert parse_line(f'1700000000.5 200 5000 {uri} "-" 5000')[3:7] == (0, 4999, 5000, 200)
    assert parse_line(f'1700000000.5 200 1234 {uri}?x=1 "-" 5000')[3:6] == (0, 1233, 5000)
    row = parse_line(f'1700000000.5 200 5000 {uri} "-" 5000')
    assert row is not None and row[7].year == 2023
    for line in (f'1700000000.5 200 0 {uri} "-" 5000',            # HEAD or nothing sent
                 f'1700000000.5 304 0 {uri} "-" -',
                 f'1700000000.5 206 100 {uri} "-" 100',             # a multipart answer (max_ranges 1 forbids)
                 f'1700000000.5 404 153 {uri} "-" 153',
                 '1700000000.5 200 5000 /static/study.js "-" 5000',
                 "garbage"):
        assert parse_line(line) is None, line


def test_media_server_setting_is_checked(tmp_path):
    with pytest.raises(StudyStateError, match="MEDIA_SERVER"):
        _app(tmp_path, MEDIA_SERVER="apache")
    with pytest.raises(StudyStateError, match="MEDIA_ACCESS_LOG"):
        _app(tmp_path, MEDIA_SERVER="nginx")
    assert _app(tmp_path).config["MEDIA_SERVER"] == "app"          # the default needs no front server


def test_nginx_mode_redirects_and_reads_nginx_log_into_the_playback_record(tmp_path):
    log = tmp_path / "media.log"
    app = _app(tmp_path, MEDIA_SERVER="nginx", MEDIA_ACCESS_LOG=str(log))
    store = store_of(app)
    p, data = _on_video_page(app)
    r = p.get(data["videos"][0], headers={"Range": "bytes=0-99"})
    assert r.status_code == 200 and r.data == b""
    target = r.headers["X-Accel-Redirect"]
    assert target.startswith(ACCEL_PREFIX) and (tmp_path / "stim" / target[len(ACCEL_PREFIX):]).is_file()
    assert r.mimetype == "video/mp4" and "Last-Modified" not in r.headers
    index = data["index"]
    assert store.dump("deploy-test")["media_served"] == {}          # the app sent nothing itself
    assert store.dump("deploy-test")["media_requests"][(p.sid, index)] == {0}
    uri = f"/s/{p.sid}/media/{index}"
    log.write_text(f'1.0 206 100 {uri}/0 "bytes 0-99/900" 100\n'
                   f'1.1 200 900 /s/{SID}/media/{index}/0 "-" 900\n'       # no such session: skipped
                   f'1.2 206 800 {uri}/0 "bytes 100-899/900" 800\n'
                   f'1.3 206 50 {uri}/1 "bytes 0-49/700"')                  # nginx is still writing this line
    assert store.dump("deploy-test")["media_served"] == {(p.sid, index): {0: (900, 900)}}
    assert store.dump("deploy-test")["media_served"] == {(p.sid, index): {0: (900, 900)}}   # read once
    with open(log, "a") as fh:
        fh.write(" 50\n")
    assert store.dump("deploy-test")["media_served"][(p.sid, index)] == {0: (900, 900), 1: (50, 700)}
    # the log rotated: a new file is read from its start
    os.rename(log, tmp_path / "media.log.1")
    log.write_text(f'2.0 206 100 {uri}/1 "bytes 600-699/700" 100\n')
    assert store.dump("deploy-test")["media_served"][(p.sid, index)][1] == (150, 700)
    assert ingest(store.media_log, str(log)) == 0


def test_app_sent_media_is_recorded_without_waiting_for_the_write_lock(tmp_path):
    app = _app(tmp_path)
    store = store_of(app)
    p, data = _on_video_page(app)
    p.get(data["videos"][1], headers={"Range": "bytes=0-9"})        # this slot's request is recorded
    holder = sqlite3.connect(tmp_path / "study.db", timeout=0)
    holder.execute("BEGIN IMMEDIATE")                               # another writer holds SQLite's lock
    try:
        t0 = time.perf_counter()
        r = p.get(data["videos"][1], headers={"Range": "bytes=10-99"})
        assert r.status_code == 206 and len(r.data) == 90
        assert time.perf_counter() - t0 < 1.0                       # not the 60 s busy timeout
    finally:
        holder.rollback()
        holder.close()
    store.media_log.flush()
    assert store.dump("deploy-test")["media_served"][(p.sid, data["index"])][1][0] == 100
