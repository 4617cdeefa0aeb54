"""CPU and SQL statements per request of the study server, in one process (no network, no gunicorn).

N participants walk the load-test study of ``benchmarks/study_load.py`` (consent, 3 pairwise, 2 MUSHRA pages)
one after another through the app's WSGI interface (Flask's test client), with the media server set to nginx-signed
(the page signs the video URLs, nginx would serve them without the app; ``--media-server nginx``: the app
authorises each video and nginx would send it). For each request kind (entry, page, answer, media
authorisation) it prints the process CPU time per request (``time.process_time``) and the SQL statements per
request (SQLAlchemy ``before_cursor_execute`` events), and "per answer": an answer with its page and its video
authorisations, on SQLite (WAL, synchronous=FULL) and on PostgreSQL.

    python benchmarks/study_request_cost.py                        # SQLite and a throwaway PostgreSQL
    python benchmarks/study_request_cost.py --databases sqlite --participants 50
    python benchmarks/study_request_cost.py --database-url postgresql://user@host/db
    python benchmarks/study_request_cost.py --baseline HEAD~3      # and the ratio to an earlier commit

``--baseline REF`` measures that commit first (a temporary git worktree, in a child process) and prints each
figure's ratio to it, so that both are measured under the same load; the load average is printed beside them.
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import secrets
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

# the code measured: this checkout, or a --baseline worktree (set by the parent run)
ROOT = os.environ.get("EVALSUITE_BENCH_ROOT") or os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
sys.path.insert(0, os.path.join(ROOT, "benchmarks"))

KINDS = ("entry", "page", "answer", "media")
PROLIFIC_STUDY = "5e" * 12


def walk(app, pid, rng, cost):
    """One participant through the whole study; adds (CPU seconds, statements) per request to ``cost``."""
    from study_load import choose_answer, page_form, playback_events

    client = app.test_client()
    counter = app.extensions["evalsuite_sql_counter"]

    def timed(kind, call, *args, **kw):
        counter[0] = 0
        t0 = time.process_time()
        r = call(*args, **kw)
        cost[kind].append((time.process_time() - t0, counter[0]))
        return r

    r = timed("entry", client.get, f"/start/load-test?PROLIFIC_PID={pid}&STUDY_ID={PROLIFIC_STUDY}&SESSION_ID=s{pid}")
    assert r.status_code == 302, r.status_code
    sid = r.headers["Location"].split("/s/")[1].strip("/")
    answers = 0
    while True:
        form = page_form(timed("page", client.get, f"/s/{sid}/").get_data(as_text=True))
        if form is None:
            return answers
        data, csrf = form
        for video in data["videos"]:
            if "?md5=" in video:
                continue                      # a signed URL (nginx-signed): nginx sends it, the app is not asked
            v = timed("media", client.get, video)
            assert v.status_code == 200, v.status_code
        body = {"token": secrets.token_hex(12), "answer": choose_answer(rng, data), "events": playback_events(data)}
        a = timed("answer", client.post, data["answer_url"], json=body, headers={"X-CSRFToken": csrf})
        assert a.status_code == 200 and a.get_json()["status"] == "stored", (a.status_code, a.get_data()[:300])
        answers += 1


def measure(study, url, participants, secret, media_server="nginx-signed"):
    """{kind: (requests, CPU ms per request, statements per request)} for ``participants`` walks."""
    from sqlalchemy import event

    from study_app import create_app
    from study_app.context import store_of

    app = create_app({"STUDY": study, "DATABASE_URL": url, "SECRET_KEY": secret, "ADMIN_TOKEN": secret,
                      "SESSION_COOKIE_SECURE": False, "MEDIA_SERVER": media_server,
                      "MEDIA_LINKS": os.path.join(os.path.dirname(study), "links"), "MEDIA_LINK_SECRET": secret,
                      "MEDIA_ACCESS_LOG": os.path.join(os.path.dirname(study), "media.log"),
                      "INSTANCE_PATH": os.path.join(os.path.dirname(study), "inst")})
    counter = [0]
    app.extensions["evalsuite_sql_counter"] = counter

    def count(*_args):
        counter[0] += 1

    event.listen(store_of(app).engine, "before_cursor_execute", count)
    rng = np.random.default_rng(0)
    walk(app, secrets.token_hex(12), rng, collections.defaultdict(list))   # imports, template caches
    cost: dict[str, list] = collections.defaultdict(list)
    for i in range(participants):
        walk(app, f"{i:08x}{secrets.token_hex(8)}", rng, cost)
    store_of(app).engine.dispose()
    out = {}
    for kind in KINDS:
        rows = cost.get(kind, [])
        if rows:
            cpu = sum(c for c, _ in rows) / len(rows)
            sql = sum(s for _, s in rows) / len(rows)
            out[kind] = (len(rows), 1000 * cpu, sql)
    return out


def report(name, figures, base=None):
    """Print one database's figures, with the ratio to ``base`` (the --baseline run's) where given."""
    print(f"{name}")
    print(f"  {'request':<8} {'count':>6} {'CPU ms':>8} {'SQL stmts':>10}" + ("   CPU / baseline" if base else ""))
    if "page" in figures and "answer" in figures:
        figures = {**figures, "answer+page": (figures["answer"][0], figures["answer"][1] + figures["page"][1],
                                              figures["answer"][2] + figures["page"][2])}
        n, media = figures["answer"][0], figures.get("media", (0, 0.0, 0.0))   # + its video authorisations
        figures["per answer"] = (n, figures["answer+page"][1] + media[0] * media[1] / n,
                                 figures["answer+page"][2] + media[0] * media[2] / n)
    for kind, (n, cpu, sql) in figures.items():
        ratio = ""
        if base and kind in base:
            ratio = f"   {cpu / base[kind][1]:.2f}x (baseline {base[kind][1]:.2f} ms, {base[kind][2]:.1f} stmts)"
        print(f"  {kind:<8} {n:>6} {cpu:>8.2f} {sql:>10.1f}{ratio}")
    return figures


def run_baseline(ref, argv):
    """The same measurement of git ref ``ref`` (a temporary worktree, in a child process): {database: figures}."""
    wt = tempfile.mkdtemp(prefix="study-cost-baseline-")
    subprocess.run(["git", "-C", ROOT, "worktree", "add", "--detach", wt, ref], check=True, capture_output=True)
    try:
        env = {**os.environ, "EVALSUITE_BENCH_ROOT": wt, "PYTHONPATH": wt}
        out = subprocess.run([sys.executable, os.path.abspath(__file__), *argv, "--json"], env=env, check=True,
                             capture_output=True, text=True).stdout
        return json.loads(out.strip().splitlines()[-1])
    finally:
        subprocess.run(["git", "-C", ROOT, "worktree", "remove", "--force", wt], capture_output=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--participants", type=int, default=30, help="participants walking the study per database")
    ap.add_argument("--databases", default="sqlite,postgresql",
                    help="comma-separated databases to measure, of sqlite, postgresql (a throwaway cluster)")
    ap.add_argument("--database-url", default=None,
                    help="measure this (empty) database instead of a throwaway PostgreSQL cluster")
    ap.add_argument("--baseline", default=None,
                    help="also measure this git ref (e.g. HEAD~3) in a temporary worktree first and print each "
                         "figure's ratio to it")
    ap.add_argument("--media-server", default="nginx-signed", choices=("nginx", "nginx-signed"),
                    help="nginx: the app authorises each video (X-Accel-Redirect); nginx-signed (the default): the "
                         "page signs the video URLs and nginx serves them without the app (a --baseline run: nginx)")
    ap.add_argument("--json", action="store_true", help="print the figures as one JSON line only (for --baseline)")
    args = ap.parse_args()
    base: dict = {}
    if args.baseline:
        argv = ["--participants", str(args.participants), "--databases", args.databases]
        if args.database_url:
            argv += ["--database-url", args.database_url]
        print(f"measuring the baseline {args.baseline} first ...", flush=True)
        base = run_baseline(args.baseline, argv)
    from study_load import STUDY

    from study_app.definition import load_study
    from study_app.design import build_plans, default_plans_path, write_plans
    from study_app.samples import make_sample_stimuli
    from study_app.testing import create_database, throwaway_postgres

    tmp = tempfile.mkdtemp(prefix="study-cost-")
    try:
        make_sample_stimuli(os.path.join(tmp, "stim"), ["SYSA", "SYSB", "SYSC"], ["seg01", "seg02", "seg03"],
                            seconds=0.5)
        study = os.path.join(tmp, "study.yaml")
        with open(study, "w") as fh:
            fh.write(STUDY.format(sessions=args.participants + 5))
        st = load_study(study)
        write_plans(build_plans(st), default_plans_path(st))
        secret = secrets.token_hex(16)
        out: dict = {}
        say = (lambda *a, **k: None) if args.json else print
        say(f"{args.participants} participants, 6 answers each, one after another through the WSGI app; "
            f"{os.cpu_count()} CPUs, load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        dbs = [d.strip() for d in args.databases.split(",") if d.strip()]
        if "sqlite" in dbs:
            out["sqlite"] = measure(study, f"sqlite:///{tmp}/cost.db", args.participants, secret, args.media_server)
        if args.database_url:
            out["postgresql"] = measure(study, args.database_url, args.participants, secret, args.media_server)
        elif "postgresql" in dbs:
            with throwaway_postgres(fsync=True) as server:
                out["postgresql"] = measure(study, create_database(server, "cost"), args.participants, secret, args.media_server)
        if args.json:
            print(json.dumps(out))
            return
        names = {"sqlite": "SQLite (WAL, synchronous=FULL)",
                 "postgresql": "PostgreSQL " + (args.database_url.split("@")[-1] if args.database_url
                                                else "(throwaway cluster, fsync on)")}
        for db, figures in out.items():
            baseline = base.get(db)
            if baseline and "page" in baseline and "answer" in baseline:
                baseline["answer+page"] = (baseline["answer"][0], baseline["answer"][1] + baseline["page"][1],
                                           baseline["answer"][2] + baseline["page"][2])
            report(names[db] + (f", against {args.baseline}" if baseline else ""), figures, baseline)
        print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
