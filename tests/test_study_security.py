"""Security of the study server (study_app.security's admin token, study_app.app's CSRF protection, headers
and required settings): no default credentials, no POST without a CSRF token, the admin pages only with the
token."""
from __future__ import annotations

import re

import numpy as np
import pytest
import study_helpers as h
from study_fixtures import make_app, walk_to

from study_app import create_app
from study_app.context import study_of
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


# ---------------------------------------------------------------------------------- admin sessions (issue 38)

def _login(client, token=h.ADMIN):
    login = client.get("/admin/login").get_data(as_text=True)
    csrf = re.search(r'name="csrf_token" value="([^"]+)"', login).group(1)
    return client.post("/admin/login", data={"token": token, "csrf_token": csrf})


def _csrf_of_admin_page(client):
    return re.search(r'name="csrf_token" value="([^"]+)"', client.get("/admin/").get_data(as_text=True)).group(1)


def test_logout_invalidates_a_copy_of_the_admin_cookie(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    client = app.test_client()
    assert _login(client).status_code == 302
    cookie = client.get_cookie(app.config["SESSION_COOKIE_NAME"]).value
    copy = app.test_client()
    copy.set_cookie(app.config["SESSION_COOKIE_NAME"], cookie)
    assert copy.get("/admin/status.json").status_code == 200
    assert client.post("/admin/logout", data={"csrf_token": _csrf_of_admin_page(client)}).status_code == 302
    assert client.get("/admin/status.json").status_code == 403
    assert copy.get("/admin/status.json").status_code == 403       # the stolen or kept copy is dead too
    assert _login(client).status_code == 302                        # a new login works
    assert client.get("/admin/status.json").status_code == 200


def test_a_changed_admin_token_invalidates_existing_admin_cookies(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    client = app.test_client()
    assert _login(client).status_code == 302
    assert client.get("/admin/status.json").status_code == 200
    app.config["ADMIN_TOKEN"] = "a-new-admin-token-987654"        # as a restart with a new token does
    assert client.get("/admin/status.json").status_code == 403
    assert _login(client, "a-new-admin-token-987654").status_code == 302
    assert client.get("/admin/status.json").status_code == 200


def test_wrong_tokens_delay_but_never_lock_out_the_right_token():
    from study_app.security import LoginThrottle

    now = [1000.0]
    throttle = LoginThrottle(limit=10, window=900, max_delay=30, clock=lambda: now[0])
    for _ in range(10):
        assert throttle.retry_after("198.51.100.7") == 0
        throttle.failed("198.51.100.7")
    assert throttle.retry_after("198.51.100.7") == 1                 # 2 ** 0 s after the last failure
    now[0] += 1
    assert throttle.retry_after("198.51.100.7") == 0
    for _ in range(20):                                              # a guesser is held to one try per 30 s
        now[0] += throttle.retry_after("198.51.100.7")
        throttle.failed("198.51.100.7")
    assert throttle.retry_after("198.51.100.7") == 30
    now[0] += 30                                                     # not 15 minutes: the admin gets in
    assert throttle.retry_after("198.51.100.7") == 0


def test_the_right_token_is_accepted_after_wrong_ones_from_the_same_address(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    client = app.test_client()
    for _ in range(10):
        assert _login(client, "wrong-token-000000").status_code == 403
    assert _login(client).status_code == 429                          # right away: wait a second
    logins = app.extensions["evalsuite_admin_logins"]
    logins.clock = lambda: __import__("time").monotonic() + 2        # two seconds later
    assert _login(client).status_code == 302
    assert client.get("/admin/status.json").status_code == 200


def test_ipv6_addresses_are_grouped_by_their_64_network():
    from study_app.security import address_group

    assert address_group("2001:db8:1:2:aaaa::1") == address_group("2001:db8:1:2:ffff:ffff:ffff:ffff")
    assert address_group("2001:db8:1:2::1") != address_group("2001:db8:1:3::1")
    assert address_group("198.51.100.7") == "198.51.100.7"
    assert address_group("::ffff:198.51.100.7") == "198.51.100.7"


def test_new_sessions_per_address_count_an_ipv6_64_as_one_address(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url)
    limit = study_of(app).new_sessions_per_address
    codes = []
    for i in range(limit + 1):
        client = app.test_client()
        client.environ_base["REMOTE_ADDR"] = f"2001:db8:5:6:{i:x}::1"     # one /64, a new address each time
        codes.append(client.get(h.prolific_url(f"{700 + i:024x}")).status_code)
    assert codes == [302] * limit + [429]


def test_x_forwarded_for_is_believed_only_from_the_configured_proxies(study_dir, sqlite_url):
    app = make_app(study_dir, sqlite_url, TRUSTED_PROXIES=1, TRUSTED_PROXY_ADDRESSES="10.9.0.1, 10.8.0.0/24")
    limit = study_of(app).new_sessions_per_address

    def enter(n, peer, forwarded):
        client = app.test_client()
        client.environ_base["REMOTE_ADDR"] = peer
        return client.get(h.prolific_url(f"{n:024x}"), headers={"X-Forwarded-For": forwarded}).status_code

    # through the proxy: each forwarded address is a client of its own
    assert [enter(900 + i, "10.8.0.3", f"198.51.100.{i}") for i in range(limit + 2)] == [302] * (limit + 2)
    # straight from a client that makes up the header: its own address counts, whatever it claims
    assert [enter(950 + i, "203.0.113.9", f"198.51.100.{100 + i}") for i in range(limit + 1)] == \
        [302] * limit + [429]
    with pytest.raises(StudyStateError, match="TRUSTED_PROXY_ADDRESSES"):
        make_app(study_dir, sqlite_url, TRUSTED_PROXIES=1, TRUSTED_PROXY_ADDRESSES="proxy.example")


def test_unhashable_reasons_and_nul_characters_are_422_not_500(study_dir, db_url):
    app = make_app(study_dir, db_url)
    p = h.Participant(app.test_client(), "pnul00001")
    p.enter()
    data, csrf, _ = walk_to(app, p, "pairwise", np.random.default_rng(4))
    r = p.submit(data, csrf, {"choices": {"human_likeness": "left"}, "reasons": [{}]})
    assert r.status_code == 422
    assert "reasons" in r.get_json()["error"]
    ev = [{"id": "nul0000001", "kind": "seeked", "slot": 0, "t": 1.0, "ms": 1, "detail": "a\x00b"}]
    r = p.post(data["events_url"], {"events": ev}, csrf)
    assert r.status_code == 422
    assert "NUL" in r.get_json()["error"]
    r = p.submit(data, csrf, {"choices": {"human_likeness": "left"}, "reasons": ["smooth\x00"]})
    assert r.status_code == 422
    assert p.post(data["draft_url"], {"draft": {"k\x00": 1}}, csrf).status_code == 422
    assert p.submit(data, csrf, {"choices": {"human_likeness": "left"}, "reasons": ["smooth"]}).status_code == 200
