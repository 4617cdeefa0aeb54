"""Load test of the study server: many participants at once, no answer lost or duplicated.

Starts the app under gunicorn (several worker processes, loopback only) on SQLite and on a
throwaway PostgreSQL cluster, and lets N simulated participants (threads, each with its own
cookie jar, like separate browsers) complete the study concurrently: enter from Prolific,
GET every page and its videos, POST every answer with its interaction log, retrying with the same submit
token on any connection error or 5xx exactly as the browser code does.

Reports p50/p99 latency of page views and answer submissions and proves that the export
holds exactly what the clients sent: every acknowledged answer once, with the same content,
and nothing else. A third run SIGKILLs the whole gunicorn process group in the middle of the
run, restarts it on the same database, lets the clients retry, and checks again that every
answer acknowledged before (and after) the crash is stored.

    python benchmarks/study_load.py                 # 300 participants, 4 workers
    python benchmarks/study_load.py --participants 100 --skip-postgres

Bounded: every request has a timeout, clients give up after --deadline seconds, servers
listen on 127.0.0.1 only, everything lives in a temporary folder that is removed.
"""
from __future__ import annotations

import argparse
import collections
import concurrent.futures as cf
import csv
import http.client
import http.cookiejar
import io
import json
import os
import re
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

ADMIN = "bench-admin-token-" + secrets.token_hex(8)
SECRET = "bench-secret-" + secrets.token_hex(16)
PAGE_DATA_RE = re.compile(r'<script id="page-data" type="application/json">(.*?)</script>', re.S)
CSRF_RE = re.compile(r'name="csrf_token" id="csrf_token" value="([^"]+)"')

STUDY = """\
id: load-test
title: Load test
stimuli: stim/manifest.csv
platform: prolific
completion_code: LOADDONE
sessions: {sessions}
reservation_minutes: 100
new_sessions_per_address: 0      # every simulated participant connects from 127.0.0.1
pages:
  - {{type: consent, id: consent, text: Consent text.}}
  - type: pairwise
    id: hl
    conditions: [SYSA, SYSB, SYSC]
    questions: [{{id: human_likeness, text: "Which one is more human-like?"}}]
    pages: 3
    muted: true
  - type: mushra
    id: ratings
    conditions: [SYSA, SYSB]
    reference: SYSC
    question: {{id: rating, text: "How human-like?"}}
    pages: 2
    muted: true
  - {{type: finish, id: finish, text: Thanks.}}
"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Gunicorn:
    def __init__(self, study, db_url, workers, threads):
        self.port = free_port()
        self.env = dict(os.environ, EVALSUITE_STUDY=study, EVALSUITE_DATABASE_URL=db_url,
                        EVALSUITE_SECRET_KEY=SECRET, EVALSUITE_ADMIN_TOKEN=ADMIN,
                        EVALSUITE_INSECURE_COOKIES="1", PYTHONPATH=ROOT)
        self.args = [sys.executable, "-m", "gunicorn", "-w", str(workers), "--threads", str(threads),
                     "-k", "gthread", "-b", f"127.0.0.1:{self.port}", "--timeout", "60",
                     "--log-level", "warning", "study_app.app:create_app_from_env()"]
        self.proc = None

    def start(self):
        self.proc = subprocess.Popen(self.args, env=self.env, start_new_session=True,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        deadline = time.time() + 60
        while time.time() < deadline:
            try:
                urllib.request.urlopen(f"{self.url}/", timeout=2)
                return self
            except (urllib.error.URLError, ConnectionError, OSError):
                if self.proc.poll() is not None:
                    raise RuntimeError("gunicorn exited: " + self.proc.stderr.read().decode()[-2000:]) from None
                time.sleep(0.2)
        raise RuntimeError("gunicorn did not start")

    @property
    def url(self):
        return f"http://127.0.0.1:{self.port}"

    def kill(self):
        """SIGKILL the master and every worker at once (a crash, no graceful shutdown)."""
        os.killpg(self.proc.pid, signal.SIGKILL)
        self.proc.wait(10)

    def stop(self):
        if self.proc and self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)


class Client:
    """One participant's browser: own cookies, same-token retries, latency records."""

    def __init__(self, base, pid, rng, deadline, stats, think=0.0):
        self.base, self.pid, self.rng, self.deadline, self.stats = base, pid, rng, deadline, stats
        self.think = think
        self.jar = http.cookiejar.CookieJar()
        self.opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor(self.jar),
                                                  _NoRedirect())
        self.acked = []        # (sid, page index, token, answer, status)
        self.sid = None
        self.retries = 0

    def request(self, kind, url, body=None, headers=None):
        """Send until the server answers (not 5xx) or the deadline passes."""
        data = json.dumps(body).encode() if body is not None else None
        hdrs = {"Content-Type": "application/json", **(headers or {})} if body is not None else {}
        backoff = 0.1
        while True:
            t0 = time.perf_counter()
            try:
                req = urllib.request.Request(self.base + url, data=data, headers=hdrs,
                                             method="POST" if body is not None else "GET")
                with self.opener.open(req, timeout=30) as resp:
                    payload = resp.read()
                    code = resp.status
                    location = resp.headers.get("Location")
            except urllib.error.HTTPError as exc:
                code, payload, location = exc.code, exc.read(), exc.headers.get("Location")
            except (urllib.error.URLError, ConnectionError, OSError, http.client.HTTPException):
                code, payload, location = None, b"", None
            if code is not None and code < 500:
                self.stats[kind].append(time.perf_counter() - t0)
                return code, payload, location
            self.retries += 1
            if time.time() > self.deadline:
                raise TimeoutError(f"{self.pid}: server unreachable for too long")
            time.sleep(backoff)
            backoff = min(backoff * 2, 2.0)

    def run(self):
        code, _, loc = self.request("enter", f"/start/load-test?PROLIFIC_PID={self.pid}"
                                    f"&STUDY_ID={'5e' * 12}&SESSION_ID=s{self.pid}")
        assert code == 302, code
        self.sid = loc.split("/s/")[1].strip("/")
        while True:
            code, html, _ = self.request("page", f"/s/{self.sid}/")
            html = html.decode()
            m = PAGE_DATA_RE.search(html)
            if m is None:
                assert "LOADDONE" in html, html[:500]
                return self
            data = json.loads(m.group(1))
            csrf = CSRF_RE.search(html).group(1)
            for video in data["videos"]:         # the browser loads every video of the page
                code, body, _ = self.request("video", video)
                assert code == 200 and body, code
            answer = self.answer(data)
            if self.think:
                time.sleep(float(self.rng.exponential(self.think)))   # watching and deciding
            token = secrets.token_hex(12)
            events = [{"id": secrets.token_hex(8), "kind": k, "slot": s, "t": 0.0, "ms": 1}
                      for s in range(len(data["videos"])) for k in ("play", "ended")]
            code, payload, _ = self.request("answer", data["answer_url"],
                                            {"token": token, "answer": answer, "events": events},
                                            {"X-CSRFToken": csrf})
            if code == 409:
                continue   # a retry after a crash found the page already answered by this token
            assert code == 200, (code, payload[:300])
            self.acked.append((self.sid, data["index"], token, answer, json.loads(payload)["status"]))

    def answer(self, data):
        t = data["type"]
        if t == "consent":
            return {"agree": True, "website": ""}
        if t == "pairwise":
            return {"choices": {"human_likeness": ["left", "equal", "right"][int(self.rng.integers(3))]},
                    "reasons": []}
        if t == "mushra":
            return {"ratings": [int(v) for v in self.rng.integers(0, 101, len(data["videos"]))]}
        return {}


class _NoRedirect(urllib.request.HTTPRedirectHandler):
    def redirect_request(self, *args, **kwargs):
        return None


def fetch_export(base):
    def get(path):
        req = urllib.request.Request(base + path, headers={"Authorization": f"Bearer {ADMIN}"})
        return urllib.request.urlopen(req, timeout=120).read().decode()
    return json.loads(get("/admin/export/raw.json")), list(csv.DictReader(io.StringIO(get("/admin/export/results.csv"))))


def verify(clients, raw, rows):
    """Compare what clients sent (and saw acknowledged) with what the server exports."""
    acked = {}
    for c in clients:
        for sid, index, token, answer, _status in c.acked:
            acked[(sid, index)] = (token, answer)
    stored = collections.Counter((a["session"], a["page_index"]) for a in raw["answers"])
    by_key = {(a["session"], a["page_index"]): a for a in raw["answers"]}
    lost = [k for k in acked if k not in by_key]
    mismatched = []
    for k, (token, answer) in acked.items():
        a = by_key.get(k)
        if a is None:
            continue
        data = {key: a["data"][key] for key in answer if key in a["data"]}
        if a["submit_token"] != token or data != answer and not (answer.get("agree") and a["data"].get("agree")):
            mismatched.append(k)
    duplicated = [k for k, n in stored.items() if n > 1]
    unexpected = [k for k in by_key if k not in acked]
    judgement_keys = [(r["session"], r["page"], r["question"], r["condition"], r["condition_a"],
                       r["condition_b"], r["position_a"]) for r in rows]
    expected_rows = sum(1 if "choices" in ans else len(ans["ratings"]) if "ratings" in ans else 0
                        for _, ans in acked.values())
    return {"acknowledged": len(acked), "stored": len(raw["answers"]), "lost": len(lost),
            "changed": len(mismatched), "duplicated": len(duplicated), "unexpected": len(unexpected),
            "csv_rows": len(rows), "csv_rows_expected": expected_rows,
            "csv_duplicate_rows": len(judgement_keys) - len(set(judgement_keys)),
            "duplicate_acks": sum(1 for c in clients for *_, s in c.acked if s == "duplicate")}


def pct(values, q):
    return float(np.percentile(np.asarray(values) * 1000, q)) if values else float("nan")


def run_load(name, study, db_url, args, kill_after=None):
    from study_app.definition import load_study
    from study_app.design import build_plans
    from study_app.storage import init_db, make_engine
    st = load_study(study)
    init_db(make_engine(db_url), st, build_plans(st))     # like `evalsuite study build --db`
    server = Gunicorn(study, db_url, args.workers, args.threads).start()
    stats = collections.defaultdict(list)
    deadline = time.time() + args.deadline
    clients = [Client(server.url, f"{name[:2].encode().hex()}{i:020x}", np.random.default_rng(i), deadline, stats,
                      args.think) for i in range(args.participants)]
    crash = {}

    def killer():
        # Crash in the middle of the run: once this share of all answers is acknowledged.
        total = 6 * len(clients)
        while sum(len(c.acked) for c in clients) < kill_after * total and time.time() < deadline:
            time.sleep(0.05)
        acked_before = sum(len(c.acked) for c in clients)
        server.kill()
        crash["killed_at_acked"] = acked_before
        time.sleep(1.0)
        server.start()
        crash["restarted"] = True

    t0 = time.perf_counter()
    if kill_after is not None:
        threading.Thread(target=killer, daemon=True).start()
    errors = []
    with cf.ThreadPoolExecutor(max_workers=args.participants) as pool:
        futures = [pool.submit(c.run) for c in clients]
        for f in cf.as_completed(futures):
            if f.exception() is not None:
                errors.append(repr(f.exception()))
    wall = time.perf_counter() - t0
    raw, rows = fetch_export(server.url)
    server.stop()
    check = verify(clients, raw, rows)
    finished = sum(1 for s in raw["sessions"] if s["status"] == "finished")
    return {"name": name, "wall_s": wall, "finished": finished, "errors": errors, "crash": crash,
            "retries": sum(c.retries for c in clients),
            "answers_per_s": check["acknowledged"] / wall,
            "page_p50": pct(stats["page"], 50), "page_p99": pct(stats["page"], 99),
            "answer_p50": pct(stats["answer"], 50), "answer_p99": pct(stats["answer"], 99),
            "video_p50": pct(stats["video"], 50), "video_p99": pct(stats["video"], 99),
            **check}


def report(r):
    print(f"\n== {r['name']} ==")
    print(f"participants finished: {r['finished']}   wall time: {r['wall_s']:.1f} s   "
          f"answers/s: {r['answers_per_s']:.0f}   client retries: {r['retries']}")
    print(f"page view latency  p50 {r['page_p50']:.0f} ms   p99 {r['page_p99']:.0f} ms")
    print(f"answer POST latency p50 {r['answer_p50']:.0f} ms   p99 {r['answer_p99']:.0f} ms")
    print(f"video GET latency  p50 {r['video_p50']:.0f} ms   p99 {r['video_p99']:.0f} ms")
    print(f"answers acknowledged {r['acknowledged']}, stored {r['stored']}: lost {r['lost']}, "
          f"changed {r['changed']}, duplicated {r['duplicated']}, stored without ack {r['unexpected']}")
    print(f"results.csv rows {r['csv_rows']} (expected {r['csv_rows_expected']}), "
          f"duplicate judgement rows {r['csv_duplicate_rows']}")
    if r["crash"]:
        print(f"SIGKILL of all gunicorn processes after {r['crash']['killed_at_acked']} of "
              f"{r['acknowledged']} answers were acknowledged, restarted: {r['crash'].get('restarted', False)}; retries acknowledged as "
              f"'duplicate' (stored before the crash, ack lost): {r['duplicate_acks']}")
    if r["errors"]:
        print(f"client errors: {len(r['errors'])}: {r['errors'][:3]}")
    ok = (r["lost"] == r["changed"] == r["duplicated"] == r["unexpected"] == r["csv_duplicate_rows"] == 0
          and r["csv_rows"] == r["csv_rows_expected"] and not r["errors"])
    print("OK: zero lost or duplicated answers" if ok else "FAILED")
    return ok


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--participants", type=int, default=300)
    ap.add_argument("--workers", type=int, default=4)
    ap.add_argument("--threads", type=int, default=8)
    ap.add_argument("--deadline", type=float, default=600, help="seconds before clients give up")
    ap.add_argument("--kill-after", type=float, default=0.5,
                    help="crash run: SIGKILL once this share of the answers is acknowledged")
    ap.add_argument("--think", type=float, default=0.0,
                    help="mean think time per page in seconds (0: every client as fast as it can)")
    ap.add_argument("--skip-postgres", action="store_true")
    args = ap.parse_args()

    from study_app.samples import make_sample_stimuli
    from study_app.testing import create_database, throwaway_postgres

    tmp = tempfile.mkdtemp(prefix="study-load-")
    ok = True
    try:
        make_sample_stimuli(os.path.join(tmp, "stim"), ["SYSA", "SYSB", "SYSC"],
                            ["seg01", "seg02", "seg03"], seconds=0.5)
        study = os.path.join(tmp, "study.yaml")
        with open(study, "w") as fh:
            fh.write(STUDY.format(sessions=args.participants))
        from study_app.definition import load_study
        from study_app.design import build_plans, default_plans_path, write_plans
        st = load_study(study)
        write_plans(build_plans(st), default_plans_path(st))
        print(f"{args.participants} concurrent participants x 6 answers (consent, 3 pairwise, 2 MUSHRA pages); gunicorn "
              f"{args.workers} workers x {args.threads} threads on 127.0.0.1; {os.cpu_count()} CPUs; "
              f"think time {args.think:g} s")
        ok &= report(run_load("SQLite (WAL, synchronous=FULL)", study,
                              f"sqlite:///{tmp}/load.db", args))
        ok &= report(run_load("SQLite, SIGKILL mid-run + restart", study,
                              f"sqlite:///{tmp}/crash.db", args, kill_after=args.kill_after))
        if not args.skip_postgres:
            with throwaway_postgres(fsync=True, max_connections=300) as server:
                ok &= report(run_load("PostgreSQL (fsync on)", study, create_database(server, "load"), args))
                ok &= report(run_load("PostgreSQL, SIGKILL mid-run + restart", study,
                                      create_database(server, "crash"), args, kill_after=args.kill_after))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
