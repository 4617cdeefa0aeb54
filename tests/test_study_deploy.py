"""The deployment (docs/deploy.md): Debian's nginx with the shipped site file (deploy/nginx) in front of gunicorn,
media sent by nginx after the app authorised it (X-Accel-Redirect) with an exact playback record, slow
clients that cannot stall a new participant's entry, and a PostgreSQL backup restored into a fresh cluster."""
from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
import requests
import study_helpers as h
from deploy_helpers import ADMIN, SECRET, WebParticipant, admin_get, app_env, make_study

from study_app.app import create_app
from study_app.media_frontend import Gunicorn, Nginx
from study_app.media_nginx import parse_line
from study_app.storage import Store, make_engine
from study_app.testing import create_database, postgres_bindir, throwaway_postgres


def _served(db_url: str, study_id: str = "deploy-test") -> dict:
    store = Store(make_engine(db_url))
    return store.dump(study_id)["media_served"]


def test_nginx_serves_the_study_and_records_the_bytes_each_client_received(tmp_path):
    db = f"sqlite:///{tmp_path / 'study.db'}"
    study = make_study(tmp_path, db)
    log = tmp_path / "media.log"
    app = Gunicorn(app_env(study, db, EVALSUITE_MEDIA_SERVER="nginx", EVALSUITE_MEDIA_ACCESS_LOG=str(log)),
                   workers=2, threads=4)
    nginx = Nginx(f"127.0.0.1:{app.port}", tmp_path / "stim", log)
    try:
        app.start()
        nginx.start()
        p = WebParticipant(nginx.url, "5f0c" * 6)
        p.enter()
        p.consent()
        received: dict[tuple[int, int], list[tuple[int, int]]] = {}
        lengths: dict[tuple[int, int], int] = {}
        html, data, csrf = p.page()
        assert data is not None and csrf is not None and data["type"] == "pairwise"
        first_page = data["index"]
        # slot 0 in two overlapping ranges, slot 1 only its first 1,000 bytes
        a = p.video(data["videos"][0], 0, 999)
        assert a.status_code == 206 and len(a.content) == 1000
        assert a.headers["Content-Type"] == "video/mp4"
        assert a.headers["Cache-Control"] == "private, no-store"
        for header in ("Last-Modified", "ETag", "X-Accel-Redirect", "Content-Disposition"):
            assert header not in a.headers, header                    # blinding: nothing of the file
        total0 = int(a.headers["Content-Range"].split("/")[1])
        b = p.video(data["videos"][0], 500)
        assert b.status_code == 206 and len(b.content) == total0 - 500
        whole = requests.get(nginx.url + data["videos"][0], cookies=p.http.cookies, timeout=30)
        assert whole.content == a.content + b.content[500:]           # one file, byte for byte
        received[(first_page, 0)] = [(0, 999), (500, total0 - 1), (0, total0 - 1)]
        lengths[(first_page, 0)] = total0
        c = p.video(data["videos"][1], 0, 999)
        received[(first_page, 1)] = [(0, 999)]
        lengths[(first_page, 1)] = int(c.headers["Content-Range"].split("/")[1])
        # the internal location and the stimulus folder are not reachable from outside
        name = sorted((tmp_path / "stim").glob("*.mp4"))[0].name
        for url in (f"/_evalsuite_media/{name}", f"/stim/{name}", "/stim/manifest.csv"):
            assert requests.get(nginx.url + url, timeout=10).status_code == 404, url
        # someone else's session gets nothing
        assert requests.get(nginx.url + data["videos"][0], timeout=10).status_code in (403, 404)
        p.answer(data, csrf, {"choices": {"human_likeness": "left"}, "reasons": []})
        while True:
            html, data, csrf = p.page()
            if data is None:
                break
            for slot, url in enumerate(data["videos"]):
                r = p.video(url)
                assert r.status_code == 200
                received[(data["index"], slot)] = [(0, len(r.content) - 1)]
                lengths[(data["index"], slot)] = len(r.content)
            p.answer(data, csrf, {"choices": {"human_likeness": "right"}, "reasons": []})
        assert "DEPLOYDONE" in html
        # nginx sent every video (one log line per response with a body), not the app
        assert sum(parse_line(x) is not None for x in log.read_text().splitlines()) == 4 + sum(len(r) for k, r in received.items() if k[0] != first_page)
        raw = admin_get(nginx.url, "/admin/export/raw.json").json()
        served = _served(db)
        for (index, slot), ranges in received.items():
            covered = len(set().union(*(range(f, t + 1) for f, t in ranges)))
            assert served[(p.sid, index)][slot] == (covered, lengths[(index, slot)]), (index, slot)
        first = next(x for x in raw["answers"] if x["page_index"] == first_page)
        assert f"unwatched: bytes 1,000/{lengths[(first_page, 1)]:,} served" in first["playback"]["reasons"]
        assert not any("unwatched" in r for x in raw["answers"] if x["page_index"] != first_page
                       for r in (x.get("playback") or {}).get("reasons", []))
    finally:
        app.stop()
        nginx.stop()



class SlowClient(threading.Thread):
    """A participant's browser on a very slow line: asks for a large video and reads 1 KiB per 50 ms."""

    def __init__(self, base: str, pid: str):
        super().__init__(daemon=True)
        p = WebParticipant(base, pid)
        p.enter()
        p.consent()
        _, data, _ = p.page()
        assert data is not None
        self.port, self.url = int(base.rsplit(":", 1)[1]), data["videos"][0]
        self.cookie = "; ".join(f"{c.name}={c.value}" for c in p.http.cookies)
        self.started, self.stop, self.received = threading.Event(), threading.Event(), 0

    def run(self) -> None:
        with socket.socket() as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
            s.connect(("127.0.0.1", self.port))
            s.sendall(f"GET {self.url} HTTP/1.1\r\nHost: localhost\r\nCookie: {self.cookie}\r\n"
                      "Connection: close\r\n\r\n".encode())
            while not self.stop.is_set():
                chunk = s.recv(1024)
                if not chunk:
                    return
                self.received += len(chunk)
                self.started.set()
                time.sleep(0.05)


def _entry_seconds(base: str, pid: str, timeout: float) -> float:
    """A new participant's entry: the Prolific link and the first page, in seconds (``timeout`` if stalled)."""
    t0 = time.perf_counter()
    try:
        p = WebParticipant(base, pid)
        p.enter(timeout=timeout)
        assert p.http.get(f"{base}/s/{p.sid}/", timeout=timeout).status_code == 200
    except requests.exceptions.Timeout:
        return timeout
    return time.perf_counter() - t0


def test_slow_clients_downloading_large_videos_cannot_stall_a_new_participants_entry(tmp_path):
    db = f"sqlite:///{tmp_path / 'study.db'}"
    study = make_study(tmp_path, db, sessions=60, pad_bytes=8 << 20)      # 8 MiB clips
    # Without nginx the app sends the files itself: two slow downloads hold gunicorn's only two threads
    # and the next participant waits (the "57 s entry stall").
    app = Gunicorn(app_env(study, db, EVALSUITE_MEDIA_SERVER="app"), workers=1, threads=2).start()
    slow = [SlowClient(app.url, f"{i:024x}") for i in range(2)]
    try:
        for c in slow:
            c.start()
            assert c.started.wait(10)
        assert _entry_seconds(app.url, "a" * 24, timeout=3) >= 2.5
    finally:
        for c in slow:
            c.stop.set()
        app.kill()
    # Behind nginx the app only authorises the request: six slow downloads, and thirty entries stay fast.
    log = tmp_path / "media.log"
    app = Gunicorn(app_env(study, db, EVALSUITE_MEDIA_SERVER="nginx", EVALSUITE_MEDIA_ACCESS_LOG=str(log)),
                   workers=1, threads=2)
    nginx = Nginx(f"127.0.0.1:{app.port}", tmp_path / "stim", log)
    try:
        app.start()
        nginx.start()
        slow = [SlowClient(nginx.url, f"{i + 100:024x}") for i in range(6)]
        for c in slow:
            c.start()
            assert c.started.wait(10)
        times = [_entry_seconds(nginx.url, f"{i + 200:024x}", timeout=10) for i in range(30)]
        assert all(c.is_alive() and c.received < 8 << 20 for c in slow)      # still downloading
        assert float(np.percentile(times, 99)) < 0.5, sorted(times)[-5:]
    finally:
        for c in slow:
            c.stop.set()
        app.stop()
        nginx.stop()


@pytest.mark.postgres
def test_a_pg_dump_restored_into_a_fresh_cluster_exports_the_same_study(tmp_path):
    bindir = postgres_bindir()
    assert bindir is not None
    dump = tmp_path / "study.dump"
    with throwaway_postgres() as server:
        url = create_database(server, "study")
        study = make_study(tmp_path, url)
        app = create_app({"STUDY": str(study), "DATABASE_URL": url, "SECRET_KEY": SECRET, "ADMIN_TOKEN": ADMIN,
                          "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "inst")})
        for k in range(3):
            p = h.Participant(app.test_client(), f"{k:024x}", study_id="deploy-test")
            p.enter()
            for _ in range(k + 1):                  # one, two or all three answers
                _, data, csrf = p.page()
                if data is None:
                    break
                for url_ in data["videos"]:
                    p.get(url_)
                answer = {"agree": True, "website": ""} if data["type"] == "consent" else \
                    {"choices": {"human_likeness": "left"}, "reasons": []}
                assert p.submit(data, csrf, answer).status_code == 200
        before = [_export(app, path) for path in ("raw.json", "results.csv")]
        # the backup recipe of docs/deploy.md: pg_dump's custom format
        subprocess.run([os.path.join(bindir, "pg_dump"), "-Fc", "-f", str(dump), _dsn(url)], check=True)
    with throwaway_postgres() as fresh:
        url = create_database(fresh, "restored")
        subprocess.run([os.path.join(bindir, "pg_restore"), "--no-owner", "-d", _dsn(url), str(dump)], check=True)
        restored = create_app({"STUDY": str(study), "DATABASE_URL": url, "SECRET_KEY": SECRET, "ADMIN_TOKEN": ADMIN,
                               "SESSION_COOKIE_SECURE": False, "INIT_DB": False,
                               "INSTANCE_PATH": str(tmp_path / "inst2")})
        after = [_export(restored, path) for path in ("raw.json", "results.csv")]
    assert len(before[0]["answers"]) == 6 and before[1].count("\n") > 1
    assert after == before


def _export(app, name: str):
    r = app.test_client().get(f"/admin/export/{name}", headers={"Authorization": f"Bearer {ADMIN}"})
    assert r.status_code == 200
    return r.get_json() if name.endswith(".json") else r.get_data(as_text=True)


def _dsn(url: str) -> str:
    return url.replace("postgresql+psycopg://", "postgresql://")


def test_container_files_use_the_tested_nginx_site_and_gunicorn_settings():
    """docker-compose.yml and the Dockerfile cannot run here (no docker): they must at least reuse the files
    the tests above run, and give nginx every name the site file needs."""
    import yaml

    from study_app.media_frontend import GUNICORN_CONF, SITE_NAMES, SITE_TEMPLATE
    root = SITE_TEMPLATE.parents[2]
    compose = yaml.safe_load((root / "docker-compose.yml").read_text())["services"]
    nginx = compose["nginx"]
    assert "./deploy/nginx/evalsuite.conf.template:/etc/nginx/templates/evalsuite.conf.template:ro" in nginx["volumes"]
    assert set(SITE_NAMES) <= set(nginx["environment"])
    assert "${" + "NGINX_LISTEN}" in SITE_TEMPLATE.read_text()
    log = nginx["environment"]["EVALSUITE_MEDIA_ACCESS_LOG"]
    dockerfile = (root / "Dockerfile").read_text()
    assert f"EVALSUITE_MEDIA_ACCESS_LOG={log}" in dockerfile
    # signed video URLs: the app's links folder is nginx's, on a volume both mount at the same place, and the
    # stimuli the links point at are at the same path in both containers
    assert re.search(r"^\s*EVALSUITE_MEDIA_SERVER=nginx-signed\b", dockerfile, re.M)
    links = nginx["environment"]["EVALSUITE_MEDIA_LINKS"]
    assert f"EVALSUITE_MEDIA_LINKS={links} " in dockerfile
    shared = set(compose["app"]["volumes"]) & set(nginx["volumes"])
    assert any(not v.startswith(".") and links.startswith(v.split(":")[1] + "/") for v in shared), shared
    stim = nginx["environment"]["EVALSUITE_STIMULI"]
    assert any(v.split(":")[1] in (stim, os.path.dirname(stim)) for v in compose["app"]["volumes"])
    # the link secret: the same compose variable in both, required, never a literal (nor a default) in the files
    secret = "${EVALSUITE_MEDIA_LINK_SECRET:?"
    for service in (compose["app"], nginx):
        assert str(service["environment"]["EVALSUITE_MEDIA_LINK_SECRET"]).startswith(secret), service
    instructions = [line for line in dockerfile.splitlines() if not line.lstrip().startswith("#")]
    assert not any("LINK_SECRET" in line for line in instructions)
    assert "LINK_SECRET:-" not in (root / "docker-compose.yml").read_text()
    assert "${" + "EVALSUITE_MEDIA_LINK_SECRET}" in SITE_TEMPLATE.read_text()     # filled in by the image's envsubst
    assert f'"-c", "/opt/evalsuite/src/deploy/{GUNICORN_CONF.name}"' in dockerfile
    assert nginx["environment"]["EVALSUITE_APP"] == "app:8000" and "EVALSUITE_BIND=0.0.0.0:8000" in dockerfile
    unit = (root / "deploy" / "systemd" / "evalsuite-study.service").read_text()
    assert f"-c /opt/evalsuite/src/deploy/{GUNICORN_CONF.name}" in unit


def test_a_gunicorn_worker_imports_the_app_without_the_analysis_stack():
    # Every worker imports the app at its start and again after a crash: pandas, scipy.stats, matplotlib and
    # evalsuite.analysis (seconds of CPU each time) are imported only where a study uses them.
    code = ("import sys, study_app.app\n"
            "print(' '.join(m for m in ('pandas', 'scipy.stats', 'scipy.optimize', 'matplotlib', 'torch',"
            " 'evalsuite.analysis') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""
