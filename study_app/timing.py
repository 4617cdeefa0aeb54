"""Per-request timing of the study server, off by default (a diagnosis tool for load tests).

Set ``EVALSUITE_TIMING_LOG`` to a file path and every request appends one JSON line to it (each process
opens it in append mode)::

    {"m": "POST", "kind": "answer", "status": 200, "at": ..., "wall": ..., "cpu": ..., "lock": ...,
     "commit": ..., "sql": ..., "pool": ..., "held": ...}

all times in milliseconds: ``wall`` the request's time inside the app (the WSGI call, which runs the view and
builds the body), ``cpu`` the CPU time of the request's thread, ``lock`` the wait to open write transactions
(on SQLite the write queue, :mod:`study_app.storage.writequeue`, and ``BEGIN IMMEDIATE`` with the busy
handler's sleeps), ``commit`` the time in COMMIT (the fsync, and on SQLite an automatic WAL checkpoint),
``sql`` the other statements, ``pool`` waiting for a connection from the pool, and ``held`` how long the
request held the write queue (not a part of ``wall``'s split). What is left, ``wall - cpu - lock - commit -
sql - pool``, is waiting for the interpreter lock (other threads of the worker) and for the CPU. The time a
request waits before a gunicorn thread takes it is nginx's ``$upstream_response_time`` minus ``wall``
(``benchmarks/study_load.py --timing`` prints both).
"""
from __future__ import annotations

import json
import os
import re
import threading
import time

__all__ = ["ENV", "enabled", "instrument_engine", "TimingMiddleware", "summarise"]

ENV = "EVALSUITE_TIMING_LOG"
_local = threading.local()
KINDS = (("enter", re.compile(r"^/start/")), ("answer", re.compile(r"^/s/[^/]+/answer/")),
         ("video", re.compile(r"^/s/[^/]+/media/")), ("page", re.compile(r"^/s/[^/]+/$")))
FIELDS = ("lock", "commit", "sql", "pool")
EXTRA = ("held",)       # not a part of the wall time: how long the request held the write queue


def enabled() -> bool:
    return bool(os.environ.get(ENV))


def add(field: str, seconds: float) -> None:
    acc = getattr(_local, "acc", None)
    if acc is not None:
        acc[field] += seconds


def instrument_engine(engine) -> None:
    """Count the engine's time per request: opening write transactions, commits, statements, pool waits."""
    from sqlalchemy import event

    @event.listens_for(engine, "before_cursor_execute")
    def _before(conn, cursor, statement, parameters, context, executemany):
        conn.info["evalsuite_t0"] = time.perf_counter()

    @event.listens_for(engine, "after_cursor_execute")
    def _after(conn, cursor, statement, parameters, context, executemany):
        t0 = conn.info.pop("evalsuite_t0", None)
        if t0 is not None:
            # BEGIN IMMEDIATE is the wait for SQLite's write lock: "lock", not "sql"
            add("lock" if statement.startswith("BEGIN IMMEDIATE") else "sql", time.perf_counter() - t0)

    dialect = engine.dialect
    original_commit = dialect.do_commit
    dialect.do_commit = lambda dbapi_conn: timed("commit", original_commit, dbapi_conn)

    pool = engine.pool
    original_connect = pool.connect

    def timed_connect(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return original_connect(*args, **kwargs)
        finally:
            add("pool", time.perf_counter() - t0)

    pool.connect = timed_connect


def timed(field: str, fn, *args):
    """Call ``fn(*args)`` and add its time to this request's ``field``."""
    t0 = time.perf_counter()
    try:
        return fn(*args)
    finally:
        add(field, time.perf_counter() - t0)


def kind_of(path: str) -> str:
    return next((k for k, rx in KINDS if rx.match(path)), "other")


class TimingMiddleware:
    """WSGI middleware writing one line per request to ``path`` (see the module's docstring)."""

    def __init__(self, app, path: str):
        self.app, self.path, self._lock = app, path, threading.Lock()

    def __call__(self, environ, start_response):
        t0, c0 = time.perf_counter(), time.thread_time()
        _local.acc = dict.fromkeys(FIELDS + EXTRA, 0.0)
        status = []

        def start(s, headers, exc_info=None):
            status.append(int(s.split()[0]))
            return start_response(s, headers, exc_info)

        try:
            return self.app(environ, start)        # Flask runs the view here; the body is already built
        finally:
            acc, _local.acc = _local.acc, None
            line = {"m": environ.get("REQUEST_METHOD"), "kind": kind_of(environ.get("PATH_INFO", "")),
                    "status": status[0] if status else 0, "at": time.time(),
                    "wall": 1000 * (time.perf_counter() - t0), "cpu": 1000 * (time.thread_time() - c0),
                    **{k: 1000 * v for k, v in acc.items()}}
            with self._lock, open(self.path, "a") as fh:
                fh.write(json.dumps(line) + "\n")


def summarise(path: str) -> dict[str, dict[str, float]]:
    """kind -> {n, wall p50/p99, and each part's mean over the slowest 1 % of that kind's requests}."""
    import numpy as np
    rows: dict[str, list[dict]] = {}
    with open(path) as fh:
        for line in fh:
            r = json.loads(line)
            rows.setdefault(r["kind"], []).append(r)
    out = {}
    for kind, rs in rows.items():
        walls = np.array([r["wall"] for r in rs])
        slow = [r for r in rs if r["wall"] >= np.percentile(walls, 99)]
        parts = {k: float(np.mean([r[k] for r in slow])) for k in ("wall", "cpu", *FIELDS)}
        parts["other"] = parts["wall"] - sum(parts[k] for k in ("cpu", *FIELDS))
        held = np.array([r.get("held", 0.0) for r in rs])
        out[kind] = {"n": len(rs), "p50": float(np.percentile(walls, 50)), "p99": float(np.percentile(walls, 99)),
                     "held_p50": float(np.percentile(held, 50)), "held_p99": float(np.percentile(held, 99)),
                     **{f"slow_{k}": v for k, v in parts.items()}}
    return out
