"""Fixtures and helpers of the study-server tests that drive the app through Flask's test client, on SQLite
and on a real throwaway PostgreSQL (registered for every test module by ``tests/conftest.py``)."""
from __future__ import annotations

import csv
import io
import itertools

import pytest
import study_helpers as h

from study_app import create_app
from study_app.context import study_of
from study_app.testing import create_database, throwaway_postgres

_counter = itertools.count()


@pytest.fixture(scope="module")
def study_dir(tmp_path_factory):
    folder = tmp_path_factory.mktemp("studyapp")
    h.make_study(folder)
    return folder


@pytest.fixture(scope="session")
def pg_server():
    with throwaway_postgres() as url:
        yield url


@pytest.fixture(params=["sqlite", pytest.param("postgresql", marks=pytest.mark.postgres)])
def db_url(request, tmp_path):
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'study.db'}"
    return create_database(request.getfixturevalue("pg_server"), f"t{next(_counter)}")


@pytest.fixture()
def sqlite_url(tmp_path):
    return f"sqlite:///{tmp_path / 'study.db'}"


def make_app(study_dir, url, study_file="study.yaml", **extra):
    return create_app({"STUDY": str(study_dir / study_file), "DATABASE_URL": url,
                       "SECRET_KEY": h.SECRET, "ADMIN_TOKEN": h.ADMIN,
                       "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(study_dir / "inst"),
                       **extra})


def export_rows(app):
    r = app.test_client().get("/admin/export/results.csv",
                              headers={"Authorization": f"Bearer {h.ADMIN}"})
    assert r.status_code == 200
    return list(csv.DictReader(io.StringIO(r.get_data(as_text=True))))


def walk_to(app, p, page_type, rng):
    while True:
        _, data, csrf = p.page()
        pages = h.plan_pages(app, p.sid)     # reserved with the first answer
        if data["type"] == page_type and not pages[data["index"]].get("check"):
            return data, csrf, pages[data["index"]]
        p.submit(data, csrf, h.make_answer(study_of(app), pages[data["index"]], rng))
