"""Security of the study server (study_app.security's admin token, study_app.app's CSRF protection, headers
and required settings): no default credentials, no POST without a CSRF token, the admin pages only with the
token."""
from __future__ import annotations

import re

import numpy as np
import pytest
import study_helpers as h
from study_fixtures import make_app

from study_app import create_app
from study_app.errors import StudyStateError


def test_csrf_is_required_on_every_post(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    client = app.test_client()
    p = h.Participant(client, "pcsrf0001")
    p.enter()
    _, data, csrf = p.page()
    good = {"token": "tok-csrf-0001", "answer": {"agree": True}, "events": []}
    for headers in ({}, {"X-CSRFToken": "forged"}, {"X-CSRFToken": csrf[:-2] + "xx"}):
        for url, body in ((data["answer_url"], good), (data["draft_url"], {"draft": {}}),
                          (data["events_url"], {"events": []})):
            r = client.post(url, json=body, headers=headers)
            assert r.status_code == 400
            assert "CSRF" in r.get_data(as_text=True)
    # a token from another browser's session does not work either
    other = h.Participant(app.test_client(), "pcsrf0002")
    other.enter()
    _, _, other_csrf = other.page()
    assert client.post(data["answer_url"], json=good, headers={"X-CSRFToken": other_csrf}).status_code == 400
    assert client.post("/admin/login", data={"token": h.ADMIN}).status_code == 400
    assert client.post(data["answer_url"], json=good, headers={"X-CSRFToken": csrf}).status_code == 200


def test_security_headers_and_cookie_flags(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url, SESSION_COOKIE_SECURE=True)
    client = app.test_client()
    r = client.get(h.prolific_url("pcookie01"))
    cookie = r.headers["Set-Cookie"]
    assert "Secure" in cookie
    assert "HttpOnly" in cookie
    assert "SameSite=Lax" in cookie
    assert "frame-ancestors 'none'" in r.headers["Content-Security-Policy"]
    assert r.headers["X-Content-Type-Options"] == "nosniff"


def test_no_default_credentials(study_dir, sqlite_url):
    base = {"STUDY": str(study_dir / "study.yaml"), "DATABASE_URL": sqlite_url}
    for missing in ({"SECRET_KEY": h.SECRET}, {"ADMIN_TOKEN": h.ADMIN},
                    {"SECRET_KEY": h.SECRET, "ADMIN_TOKEN": "short"}):
        with pytest.raises(StudyStateError):
            create_app({**base, **missing})


def test_admin_needs_the_token(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    client = app.test_client()
    assert client.get("/admin/").status_code == 302
    assert client.get("/admin/export/results.csv").status_code == 403
    assert client.get("/admin/export/raw.json", headers={"Authorization": "Bearer wrong-token-123"}).status_code == 403
    login = client.get("/admin/login").get_data(as_text=True)
    csrf = re.search(r'name="csrf_token" value="([^"]+)"', login).group(1)
    assert client.post("/admin/login", data={"token": "wrong", "csrf_token": csrf}).status_code == 403
    assert client.post("/admin/login", data={"token": h.ADMIN, "csrf_token": csrf}).status_code == 302
    h.run_participant(app, app.test_client(), "padmin001", np.random.default_rng(2), fail_checks=1)
    page = client.get("/admin/").get_data(as_text=True)
    assert h.valid_pid("padmin001") in page
    assert "SYSALPHA vs SYSBETA" in page
    assert "plan-0000" in page
    assert client.get("/admin/export/results.csv").status_code == 200
