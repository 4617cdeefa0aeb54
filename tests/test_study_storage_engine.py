"""study_app.storage.engine: PostgreSQL's pool pings a connection only after it sat idle, and replaces a dead one."""
from __future__ import annotations

import itertools

import pytest
from sqlalchemy.exc import OperationalError

from study_app.storage import engine as engine_module
from study_app.testing import create_database

pytestmark = pytest.mark.postgres
_names = (f"eng{i}" for i in itertools.count())


def _backend_pid(engine) -> int:
    with engine.connect() as conn:
        return conn.exec_driver_sql("SELECT pg_backend_pid()").scalar()


def _terminate(url: str, pid: int) -> None:
    other = engine_module.make_engine(url)
    with other.connect() as conn:
        assert conn.exec_driver_sql(f"SELECT pg_terminate_backend({int(pid)})").scalar()
    other.dispose()


@pytest.fixture()
def killed(pg_server):
    """An engine whose one pooled connection's server process was just terminated, and that process's id."""
    url = create_database(pg_server, next(_names))
    eng = engine_module.make_engine(url)
    first = _backend_pid(eng)
    _terminate(url, first)
    yield eng, first
    eng.dispose()


def test_a_connection_idle_too_long_is_pinged_and_a_dead_one_replaced(killed, monkeypatch):
    eng, first = killed
    monkeypatch.setattr(engine_module, "PING_AFTER_IDLE_S", 0.0)     # every pooled connection counts as idle
    assert _backend_pid(eng) != first   # the ping found it dead: a fresh connection, no error


def test_a_connection_back_in_the_pool_a_moment_ago_is_not_pinged(killed, monkeypatch):
    eng, first = killed
    monkeypatch.setattr(engine_module, "PING_AFTER_IDLE_S", 3600.0)
    with pytest.raises(OperationalError):         # no round trip before use: its statement fails instead
        _backend_pid(eng)
    assert _backend_pid(eng) != first             # and the pool replaced it for the next request
