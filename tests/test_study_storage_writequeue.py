"""The SQLite write queue (study_app.storage.writequeue) and the lock-free page view: a writing transaction
holds an exclusive flock on ``<db>-writers`` until it ends, a killed holder frees it, a thread never waits
for itself, a repeated page view takes no lock at all, and a page's first view commits without the fsync
that every answer keeps (synchronous=FULL; on PostgreSQL synchronous_commit)."""
from __future__ import annotations

import fcntl
import os
import sqlite3
import subprocess
import sys
import textwrap
import threading
import time

import pytest
import study_helpers as h
from sqlalchemy import event, text
from study_fixtures import make_app

from study_app.context import store_of
from study_app.storage import make_engine
from study_app.testing import create_database


def _queue_is_held(db_path) -> bool:
    fd = os.open(f"{db_path}-writers", os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def test_a_writing_transaction_holds_the_queue_until_it_ends(tmp_path):
    db = tmp_path / "q.db"
    engine = make_engine(f"sqlite:///{db}")
    with engine.begin() as conn:
        conn.exec_driver_sql("CREATE TABLE t (x INTEGER)")
    assert not _queue_is_held(db)
    with engine.begin() as conn:
        conn.execute(text("INSERT INTO t VALUES (1)"))
        assert _queue_is_held(db)                      # other writers wait in the kernel meanwhile
    assert not _queue_is_held(db)                      # released by COMMIT
    try:
        with engine.begin() as conn:
            conn.execute(text("INSERT INTO t VALUES (2)"))
            raise RuntimeError("abandon")
    except RuntimeError:
        pass
    assert not _queue_is_held(db)                      # and by ROLLBACK
    with engine.execution_options(evalsuite_readonly=True).connect() as conn:
        conn.execute(text("SELECT count(*) FROM t")).scalar()
        assert not _queue_is_held(db)                  # readers never queue
    # a second writer waits for the first one's commit, then goes on at once
    order = []
    with engine.begin() as conn:
        conn.execute(text("INSERT INTO t VALUES (3)"))

        def second():
            with engine.begin() as c2:
                order.append("second in")
                c2.execute(text("INSERT INTO t VALUES (4)"))
        t = threading.Thread(target=second)
        t.start()
        time.sleep(0.3)
        order.append("first commits")
    t.join(10)
    assert order == ["first commits", "second in"]
    # one thread holding the queue does not wait for itself through a second connection
    with engine.connect() as a, engine.connect() as b:
        a.begin()
        a.execute(text("INSERT INTO t VALUES (5)"))
        assert b.connection.dbapi_connection.lock_writes(wait=True) is True
        a.rollback()


def test_a_killed_holder_releases_the_queue(tmp_path):
    db = tmp_path / "k.db"
    engine = make_engine(f"sqlite:///{db}")
    with engine.begin() as conn:
        conn.exec_driver_sql("CREATE TABLE t (x INTEGER)")
    script = textwrap.dedent(f"""
        import sys, time
        from sqlalchemy import text
        from study_app.storage import make_engine
        conn = make_engine("sqlite:///{db}").connect()
        conn.begin()
        conn.execute(text("INSERT INTO t VALUES (1)"))
        print("holding", flush=True)
        time.sleep(60)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "holding"
        assert _queue_is_held(db)
        proc.kill()
        proc.wait(10)
        t0 = time.perf_counter()
        with engine.begin() as conn:
            conn.execute(text("INSERT INTO t VALUES (2)"))
        assert time.perf_counter() - t0 < 5
    finally:
        proc.kill()
        proc.wait(10)
    with engine.connect() as conn:
        assert conn.execute(text("SELECT x FROM t")).scalars().all() == [2]


def test_a_repeated_page_view_takes_no_lock(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    p = h.Participant(app.test_client(), "pview0001")
    p.enter()
    assert p.page()[0].status_code == 200               # first view: its record is written
    holder = sqlite3.connect(sqlite_url.removeprefix("sqlite:///"), isolation_level=None)
    holder.execute("BEGIN IMMEDIATE")                   # another writer holds SQLite's write lock
    done = []
    t = threading.Thread(target=lambda: done.append(store_of(app).view_current_page(p.sid)))
    try:
        t.start()
        t.join(5)
        assert done and done[0][0].id == p.sid          # the same page again: read without waiting
    finally:
        holder.execute("ROLLBACK")
        holder.close()
        t.join(60)


def test_a_first_page_view_skips_the_fsync_and_answers_keep_it(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    store = store_of(app)
    begins = []        # (synchronous at each write transaction's BEGIN IMMEDIATE: 1 NORMAL, 2 FULL)

    @event.listens_for(store.engine, "before_cursor_execute")
    def _seen(conn, cursor, statement, *args):
        if statement.startswith("BEGIN IMMEDIATE"):
            begins.append(conn.connection.dbapi_connection.execute("PRAGMA synchronous").fetchone()[0])

    p = h.Participant(app.test_client(), "pview0002")
    p.enter()
    begins.clear()
    _, data, csrf = p.page()                            # first view of the consent page
    assert begins == [1]
    begins.clear()
    assert p.submit(data, csrf, {"agree": True, "website": ""}).get_json()["status"] == "stored"
    assert begins and set(begins) == {2}                # the answer is fsynced before it is acknowledged
    begins.clear()
    p.page()                                            # the next page's first view
    p.page()                                            # and again: nothing to write, no transaction
    assert begins == [1]


@pytest.mark.postgres
def test_postgres_first_view_commits_without_waiting_for_the_flush_and_answers_wait(pg_server):
    from study_app.storage.store import Store
    # (the throwaway server runs with synchronous_commit off; these connections with PostgreSQL's default)
    store = Store(make_engine(create_database(pg_server, "relaxed") + "?options=-csynchronous_commit%3Don"))
    with store.RelaxedSession.begin() as db:
        assert db.execute(text("SHOW synchronous_commit")).scalar() == "off"
    for _ in range(3):           # the same pooled connection again: the setting did not outlive its transaction
        with store.Session.begin() as db:
            assert db.execute(text("SHOW synchronous_commit")).scalar() == "on"
