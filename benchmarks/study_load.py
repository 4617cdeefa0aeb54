"""Load test of the study server as deployed: nginx in front of gunicorn, many participants at once, no
answer lost or duplicated.

Starts the app under gunicorn (deploy/gunicorn.conf.py; several worker processes, loopback only) behind
Debian's nginx with the shipped site file (deploy/nginx/evalsuite.conf.template; videos served by nginx from
the page's signed URLs without an application request, EVALSUITE_MEDIA_SERVER=nginx-signed, or with
--media-server nginx after the app authorised each), on SQLite and on a throwaway PostgreSQL cluster, and
lets N simulated participants (threads, each with its own cookie jar, like separate browsers) complete the
study: they arrive spread over --ramp seconds, enter from Prolific, GET every page and its videos, think
(uniform --think-min..--think-max seconds, watching and deciding) and POST every answer with its interaction
log, retrying with the same submit token on any connection error or 5xx exactly as the browser code does.
Like a browser, each keeps its connection to nginx open between requests (--no-keepalive: a new connection
per request).

Reports p50/p95/p99 latency of entries, page views, answers and videos, checks them against the targets
(300 participants: answer and page p99 < 300 ms, video p95 < 100 ms; 1,000: every request p99 < 1 s) and
proves that the export holds exactly what the clients sent: every acknowledged answer once, with the same
content, and nothing else. The "+ SIGKILL" run of each case SIGKILLs the whole gunicorn process group once
half of the answers are acknowledged (nginx stays up and answers 502 meanwhile), restarts it on the same
database, lets the clients retry, and checks again that every acknowledged answer is stored; its latencies
include the restart and are not held to the targets.

    python benchmarks/study_load.py                          # every case: SQLite 300, PostgreSQL 300 and 1000
    python benchmarks/study_load.py --cases sqlite-300        # one case (with its SIGKILL run)
    python benchmarks/study_load.py --cases sqlite-300 --participants 100 --no-kill

Bounded: every request has a timeout, clients give up after --deadline seconds, servers listen on 127.0.0.1
only, everything lives in a temporary folder that is removed.
"""
from __future__ import annotations

import argparse
import collections
import concurrent.futures as cf
import contextlib
import csv
import http.client
import http.cookiejar
import io
import json
import os
import re
import resource
import secrets
import shutil
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

TIMING_ENV = "EVALSUITE_TIMING_LOG"
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


class Client:
    """One participant's browser: own cookies, same-token retries, latency records."""

    def __init__(self, base, pid, rng, deadline, stats, think=(0.0, 0.0), arrive=0.0, keepalive=True):
        self.base, self.pid, self.rng, self.deadline, self.stats = base, pid, rng, deadline, stats
        self.think, self.arrive = think, arrive
        self.jar = http.cookiejar.CookieJar()
        # A browser keeps its connection to the site open between requests (HTTP/1.1 keep-alive); without
        # keepalive every request opens a new connection (urllib's Connection: close), to compare.
        self.keepalive = keepalive
        self.conn = None
        self.opener = None if keepalive else urllib.request.build_opener(
            urllib.request.HTTPCookieProcessor(self.jar), _NoRedirect())
        self.acked = []        # (sid, page index, token, answer, status)
        self.sid = None
        self.retries = 0
        self.retry_reasons = collections.Counter()       # "<kind> <status or exception>" -> count

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
                if self.keepalive:
                    code, payload, location = self.send_kept(req)
                else:
                    with self.opener.open(req, timeout=30) as resp:
                        payload = resp.read()
                        code = resp.status
                        location = resp.headers.get("Location")
            except urllib.error.HTTPError as exc:
                code, payload, location = exc.code, exc.read(), exc.headers.get("Location")
            except (urllib.error.URLError, ConnectionError, OSError, http.client.HTTPException) as exc:
                code, payload, location = None, b"", None
                failure = type(getattr(exc, "reason", exc)).__name__
            if code is not None and code < 500:
                self.stats[kind].append(time.perf_counter() - t0)
                return code, payload, location
            self.retries += 1
            self.retry_reasons[f"{kind} {code if code is not None else failure}"] += 1
            if time.time() > self.deadline:
                raise TimeoutError(f"{self.pid}: server unreachable for too long")
            time.sleep(backoff)
            backoff = min(backoff * 2, 2.0)

    def send_kept(self, req):
        """``req`` over this browser's one kept-open connection (opened again after the server closed it or
        failed), with the cookie jar's cookies; ``(status, body, Location)``."""
        if self.conn is None:
            self.conn = http.client.HTTPConnection(req.host, timeout=30)
        self.jar.add_cookie_header(req)
        try:
            self.conn.request(req.get_method(), req.selector, body=req.data,
                              headers={**req.headers, **req.unredirected_hdrs})
            resp = self.conn.getresponse()
            payload = resp.read()
        except BaseException:
            self.conn.close()
            self.conn = None
            raise
        self.jar.extract_cookies(resp, req)
        if resp.will_close:
            self.conn.close()
            self.conn = None
        return resp.status, payload, resp.getheader("Location")

    def run(self):
        try:
            return self.participate()
        finally:
            if self.conn is not None:
                self.conn.close()

    def participate(self):
        time.sleep(self.arrive)                  # participants arrive spread over the ramp
        code, _, loc = self.request("enter", f"/start/load-test?PROLIFIC_PID={self.pid}"
                                    f"&STUDY_ID={'5e' * 12}&SESSION_ID=s{self.pid}")
        assert code == 302, code
        self.sid = loc.split("/s/")[1].strip("/")
        while True:
            code, html, _ = self.request("page", f"/s/{self.sid}/")
            form = page_form(html.decode())
            if form is None:
                return self
            data, csrf = form
            for video in data["videos"]:         # the browser loads every video of the page
                code, body, _ = self.request("video", video)
                assert code == 200 and body, code
            answer = self.answer(data)
            if self.think[1] > 0:
                time.sleep(float(self.rng.uniform(*self.think)))      # watching and deciding
            token = secrets.token_hex(12)
            code, payload, _ = self.request("answer", data["answer_url"],
                                            {"token": token, "answer": answer, "events": playback_events(data)},
                                            {"X-CSRFToken": csrf})
            if code == 409:
                continue   # a retry after a crash found the page already answered by this token
            assert code == 200, (code, payload[:300])
            self.acked.append((self.sid, data["index"], token, answer, json.loads(payload)["status"]))

    def answer(self, data):
        return choose_answer(self.rng, data)


def page_form(html: str):
    """``(page data, CSRF token)`` of a study page, or None on the finish page."""
    m = PAGE_DATA_RE.search(html)
    if m is None:
        assert "LOADDONE" in html, html[:500]
        return None
    return json.loads(m.group(1)), CSRF_RE.search(html).group(1)


def choose_answer(rng, data):
    """A participant's random answer to the page ``data``."""
    t = data["type"]
    if t == "consent":
        return {"agree": True, "website": ""}
    if t == "pairwise":
        return {"choices": {"human_likeness": ["left", "equal", "right"][int(rng.integers(3))]}, "reasons": []}
    if t == "mushra":
        return {"ratings": [int(v) for v in rng.integers(0, 101, len(data["videos"]))]}
    return {}


def playback_events(data):
    """A play and an ended event for every video of the page (as the player reports them)."""
    return [{"id": secrets.token_hex(8), "kind": k, "slot": s, "t": 0.0, "ms": 1}
            for s in range(len(data["videos"])) for k in ("play", "ended")]


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


def run_load(name, study, stim, db_url, participants, args, kill_after=None):
    from study_app.definition import load_study
    from study_app.design import build_plans
    from study_app.media_frontend import Gunicorn, Nginx
    from study_app.storage import init_db, make_engine
    st = load_study(study)
    init_db(make_engine(db_url), st, build_plans(st))     # like `evalsuite study build --db`
    media_log = os.path.join(os.path.dirname(study), f"media-{secrets.token_hex(4)}.log")
    env = {"EVALSUITE_STUDY": study, "EVALSUITE_DATABASE_URL": db_url, "EVALSUITE_SECRET_KEY": SECRET,
           "EVALSUITE_ADMIN_TOKEN": ADMIN, "EVALSUITE_TRUSTED_PROXIES": "1",
           "EVALSUITE_MEDIA_SERVER": args.media_server, "EVALSUITE_MEDIA_ACCESS_LOG": media_log,
           "EVALSUITE_MEDIA_LINKS": media_log + ".links", "EVALSUITE_MEDIA_LINK_SECRET": SECRET + "-links"}
    timing_log = os.path.join(os.path.dirname(study), f"timing-{secrets.token_hex(4)}.log") if args.timing else None
    if timing_log:
        env[TIMING_ENV] = timing_log
    if args.no_write_queue:
        env["EVALSUITE_SQLITE_WRITE_QUEUE"] = "0"
    server = Gunicorn(env, args.workers, args.threads)
    nginx = Nginx(f"127.0.0.1:{server.port}", stim, media_log, workers=args.nginx_workers,
                  links=media_log + ".links", link_secret=SECRET + "-links")
    server.start()
    nginx.start()
    warm_up(nginx.url, 4 * args.workers)
    settle([server.proc.pid, nginx.proc.pid])
    stats = collections.defaultdict(list)
    deadline = time.time() + args.deadline
    arrivals = np.random.default_rng(12345).uniform(0, args.ramp, participants)
    clients = [Client(nginx.url, f"{name[:2].encode().hex()}{i:020x}", np.random.default_rng(i), deadline, stats,
                      (args.think_min, args.think_max), float(arrivals[i]), not args.no_keepalive)
               for i in range(participants)]
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
    cpu0 = group_cpu([server.proc.pid, nginx.proc.pid]), resource.getrusage(resource.RUSAGE_SELF), comm_cpu("postgres")
    if kill_after is not None:
        threading.Thread(target=killer, daemon=True).start()
    errors = []
    try:
        with cf.ThreadPoolExecutor(max_workers=participants) as pool:
            futures = [pool.submit(c.run) for c in clients]
            for f in cf.as_completed(futures):
                if f.exception() is not None:
                    errors.append(repr(f.exception()))
        wall = time.perf_counter() - t0
        # CPU seconds of gunicorn and nginx during the run (a crash run counts only the restarted server)
        # and of the simulated browsers in this process
        server_cpu = group_cpu([server.proc.pid, nginx.proc.pid]) - (0.0 if crash else cpu0[0])
        self_cpu = resource.getrusage(resource.RUSAGE_SELF)
        client_cpu = (self_cpu.ru_utime + self_cpu.ru_stime) - (cpu0[1].ru_utime + cpu0[1].ru_stime)
        db_cpu = comm_cpu("postgres") - cpu0[2] if db_url.startswith("postgresql") else 0.0
        raw, rows = fetch_export(nginx.url)
        seen = nginx_times(nginx.access_log)
    finally:
        server.stop()
        nginx.stop()
    check = verify(clients, raw, rows)
    finished = sum(1 for s in raw["sessions"] if s["status"] == "finished")
    lat = {f"{kind}_p{q}": pct(stats[kind], q) for kind in ("enter", "page", "answer", "video") for q in (50, 95, 99)}
    lat.update({f"nginx_{kind}_p{q}": pct(seen[kind], q) for kind in ("enter", "page", "answer") for q in (50, 99)})
    lat.update({f"upstream_{kind}_p{q}": pct(seen["upstream_" + kind], q) for kind in ("enter", "page", "answer")
                for q in (50, 99)})
    if timing_log:
        from study_app.timing import summarise
        lat["timing"] = summarise(timing_log)
    return {"name": name, "participants": participants, "wall_s": wall, "finished": finished, "errors": errors,
            "crash": crash, "retries": sum(c.retries for c in clients), "server_cpu_s": server_cpu,
            "retry_reasons": sum((c.retry_reasons for c in clients), collections.Counter()),
            "client_cpu_s": client_cpu, "db_cpu_s": db_cpu,
            "answers_per_s": check["acknowledged"] / wall, **lat, **check}


def nginx_times(path):
    """Seconds nginx took per entry, page view and answer (its access log: first byte read to last byte
    sent), i.e. the server's side of the latency without the simulated browsers' own waiting for a CPU."""
    seen = collections.defaultdict(list)
    with open(path) as fh:
        for line in fh:
            parts = line.split()
            if len(parts) != 5 or parts[2] == "502":
                continue
            seconds, method, uri = float(parts[0]), parts[3], parts[4]
            kind = ("enter" if uri.startswith("/start/") else "answer" if method == "POST" and "/answer/" in uri
                    else "page" if method == "GET" and re.fullmatch(r"/s/[^/]+/", uri) else None)
            if kind:
                seen[kind].append(seconds)
                if parts[1] != "-":           # gunicorn's time as nginx saw it: queue + app
                    seen["upstream_" + kind].append(sum(float(x) for x in parts[1].split(",")))
    return seen


def comm_cpu(prefix):
    """CPU seconds (user + system) used so far by the processes whose command name starts with ``prefix`` (Linux
    /proc): PostgreSQL's postmaster and backends (every one on the machine; the benchmark's own cluster is the
    only busy one). The live ones count their own time; a postmaster also counts the time of the backends that
    have exited (its reaped children: the pool closes its overflow connections)."""
    ticks, procs = os.sysconf("SC_CLK_TCK"), {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as fh:
                head, rest = fh.read().rsplit(")", 1)
        except OSError:
            continue
        if head.split("(", 1)[1].startswith(prefix):
            fields = rest.split()
            procs[int(entry)] = (int(fields[1]), int(fields[11]) + int(fields[12]), int(fields[13]) + int(fields[14]))
    total = sum(own + (reaped if parent not in procs else 0) for parent, own, reaped in procs.values())
    return total / ticks


def group_cpu(groups):
    """CPU seconds (user + system) used so far by the live processes of these process groups (Linux /proc)."""
    ticks, total = os.sysconf("SC_CLK_TCK"), 0
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as fh:
                fields = fh.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) in groups:
            total += int(fields[11]) + int(fields[12])
    return total / ticks


def warm_up(base, n):
    """A few requests first, so that every gunicorn worker has booted before the clock starts."""
    for _ in range(n):
        with contextlib.suppress(urllib.error.HTTPError):
            urllib.request.urlopen(base + "/", timeout=30).read()
        time.sleep(0.1)


def settle(groups, timeout=120.0):
    """Wait until these process groups use no CPU (under 10 ms in 0.5 s): every gunicorn worker has imported the
    app. Workers boot in parallel and the first one up answers the warm-up, so without this the others' imports
    would be counted in the run's CPU and compete with its first requests."""
    end = time.time() + timeout
    before = group_cpu(groups)
    while time.time() < end:
        time.sleep(0.5)
        now = group_cpu(groups)
        if now - before < 0.01:
            return
        before = now


def targets(r, case):
    """The issue's targets for a run of ``case`` without a crash, also with fewer --participants: (what,
    measured ms, limit ms)."""
    if case == "pg-1000":
        return [(f"{k} p99", r[f"{k}_p99"], 1000.0) for k in ("enter", "page", "answer", "video")]
    return [("answer p99", r["answer_p99"], 300.0), ("page p99", r["page_p99"], 300.0),
            ("video p95", r["video_p95"], 100.0)]


def report(r, case):
    print(f"\n== {r['name']} ==")
    print(f"participants finished: {r['finished']}   wall time: {r['wall_s']:.1f} s   "
          f"answers/s: {r['answers_per_s']:.0f}   client retries: {r['retries']}")
    if r["retries"]:
        print("client retries by request and answer: " + ", ".join(f"{k}: {n}" for k, n in r["retry_reasons"].most_common()))
    print(f"CPU: gunicorn + nginx {r['server_cpu_s']:.1f} s ({1000 * r['server_cpu_s'] / max(r['acknowledged'], 1):.0f} ms "
          f"per answer with its page and videos, {r['server_cpu_s'] / r['wall_s']:.2f} cores on average), simulated "
          f"browsers {r['client_cpu_s']:.1f} s" + (f", PostgreSQL {r['db_cpu_s']:.1f} s "
                                                  f"({1000 * r['db_cpu_s'] / max(r['acknowledged'], 1):.0f} ms per answer)"
                                                  if r["db_cpu_s"] else "")
          + f"; load average now {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for kind, label in (("enter", "entry (Prolific link)"), ("page", "page view"), ("answer", "answer POST"),
                        ("video", "video GET (nginx)")):
        print(f"{label:22s} p50 {r[kind + '_p50']:6.0f} ms   p95 {r[kind + '_p95']:6.0f} ms   "
              f"p99 {r[kind + '_p99']:6.0f} ms" + (f"   (nginx's own time p50 {r['nginx_' + kind + '_p50']:.0f} ms, "
                                                 f"p99 {r['nginx_' + kind + '_p99']:.0f} ms)" if kind != "video" else ""))
    if "timing" in r:
        print("app timing (EVALSUITE_TIMING_LOG; ms; the parts are means over each kind's slowest 1 %):")
        for kind, t in sorted(r["timing"].items()):
            up = (f", nginx upstream p50 {r['upstream_' + kind + '_p50']:.0f} p99 {r['upstream_' + kind + '_p99']:.0f}"
                  if "upstream_" + kind + "_p50" in r else "")
            print(f"  {kind:7s} n {t['n']:5.0f}  in app p50 {t['p50']:5.0f} p99 {t['p99']:5.0f}{up};  slowest: "
                  + " ".join(f"{k} {t['slow_' + k]:.0f}" for k in ("wall", "cpu", "lock", "commit", "sql", "pool", "other"))
                  + f";  write queue held p50 {t['held_p50']:.0f} p99 {t['held_p99']:.0f}")
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
    print("OK: zero lost, changed or duplicated answers" if ok else "FAILED: answers lost, changed or duplicated")
    if not r["crash"]:
        for what, got, limit in targets(r, case):
            met = got < limit
            ok &= met
            print(f"target {what} < {limit:.0f} ms: {got:.0f} ms {'met' if met else 'NOT MET'}")
    return ok


CASES = {"sqlite-300": ("sqlite", 300), "pg-300": ("postgresql", 300), "pg-1000": ("postgresql", 1000)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default=",".join(CASES),
                    help=f"comma-separated cases to run, of {', '.join(CASES)} (each with its SIGKILL run)")
    ap.add_argument("--participants", type=int, default=None,
                    help="participants per case instead of the case's own number (a reduced run, held to the case's targets)")
    ap.add_argument("--workers", type=int, default=4, help="gunicorn worker processes")
    ap.add_argument("--threads", type=int, default=8, help="threads per gunicorn worker")
    ap.add_argument("--nginx-workers", type=int, default=2, help="nginx worker processes")
    ap.add_argument("--deadline", type=float, default=900, help="seconds before clients give up")
    ap.add_argument("--kill-after", type=float, default=0.5,
                    help="crash run: SIGKILL once this share of the answers is acknowledged")
    ap.add_argument("--no-kill", action="store_true", help="skip the SIGKILL runs")
    ap.add_argument("--media-server", default="nginx-signed", choices=("nginx", "nginx-signed"),
                    help="nginx-signed (the default): nginx serves the page's signed video URLs without the app; "
                         "nginx: the app authorises each video (X-Accel-Redirect)")
    ap.add_argument("--think-min", type=float, default=2.0, help="shortest think time per page, seconds")
    ap.add_argument("--think-max", type=float, default=10.0, help="longest think time per page, seconds")
    ap.add_argument("--timing", action="store_true",
                    help="log every request's time inside the app split into CPU, write-lock wait, commit, SQL, pool "
                         "wait and the rest (study_app.timing; EVALSUITE_TIMING_LOG) and print the breakdown")
    ap.add_argument("--no-write-queue", action="store_true",
                    help="SQLite writers poll in SQLite's busy handler instead of waiting in the write queue "
                         "(study_app.storage.writequeue), to compare")
    ap.add_argument("--no-keepalive", action="store_true",
                    help="a new connection for every request (urllib's Connection: close) instead of each simulated "
                         "browser keeping its connection to nginx open, as browsers do")
    ap.add_argument("--ramp", type=float, default=30.0,
                    help="participants arrive uniformly spread over this many seconds")
    args = ap.parse_args()
    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    unknown = [c for c in cases if c not in CASES]
    if unknown:
        ap.error(f"unknown case(s) {', '.join(unknown)}; expected some of {', '.join(CASES)}")

    from study_app.samples import make_sample_stimuli
    from study_app.testing import create_database, throwaway_postgres

    tmp = tempfile.mkdtemp(prefix="study-load-")
    ok = True
    try:
        stim = os.path.join(tmp, "stim")
        make_sample_stimuli(stim, ["SYSA", "SYSB", "SYSC"], ["seg01", "seg02", "seg03"], seconds=0.5)
        most = max(args.participants or CASES[c][1] for c in cases)
        study = os.path.join(tmp, "study.yaml")
        with open(study, "w") as fh:
            fh.write(STUDY.format(sessions=most))
        from study_app.definition import load_study
        from study_app.design import build_plans, default_plans_path, write_plans
        st = load_study(study)
        write_plans(build_plans(st), default_plans_path(st))
        print(f"6 answers per participant (consent, 3 pairwise, 2 MUSHRA pages); nginx ({args.nginx_workers} "
              f"workers) in front of gunicorn {args.workers} workers x {args.threads} threads on 127.0.0.1; "
              f"{os.cpu_count()} CPUs; think time uniform {args.think_min:g}-{args.think_max:g} s; arrivals over "
              f"{args.ramp:g} s; {'a new connection per request' if args.no_keepalive else 'kept-open connections'}; "
              f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        for case in cases:
            kind, n = CASES[case]
            n = args.participants or n
            runs = [(None, "")] + ([] if args.no_kill else [(args.kill_after, ", SIGKILL mid-run + restart")])
            if kind == "sqlite":
                for k, (kill, label) in enumerate(runs):
                    ok &= report(run_load(f"SQLite (WAL, synchronous=FULL), {n} participants{label}", study, stim,
                                          f"sqlite:///{tmp}/{case}-{k}.db", n, args, kill_after=kill), case)
            else:
                with throwaway_postgres(fsync=True, max_connections=300) as server:
                    for k, (kill, label) in enumerate(runs):
                        ok &= report(run_load(f"PostgreSQL (fsync on), {n} participants{label}", study, stim,
                                              create_database(server, f"load{k}"), n, args, kill_after=kill),
                                      case)
            print(f"load average after {case}: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
