"""Admin authentication: the admin token from start-up, given in the login form (a flag in the signed
session cookie) or as ``Authorization: Bearer <token>`` (scripts). There is no default credential."""
from __future__ import annotations

import hashlib
import hmac
import ipaddress
import math
import secrets
import threading
import time
from collections.abc import Callable
from functools import wraps
from typing import Any

from flask import abort, current_app, redirect, request, session, url_for

__all__ = ["check_token", "admin_authorised", "admin_required", "admin_logins", "LoginThrottle", "address_group",
           "start_admin_session", "end_admin_session", "TrustedProxies", "parse_networks"]


def check_token(given: str, expected: str) -> bool:
    """Constant-time comparison of a given token with the expected one."""
    return hmac.compare_digest(given.encode(), expected.encode())


class LoginThrottle:
    """Failed admin logins per client address group (:func:`address_group`). Up to ``limit`` failures within
    ``window`` seconds cost nothing; after that each further try must wait ``2 ** (failures - limit)`` seconds
    (at most ``max_delay``) after the last failure (HTTP 429 with Retry-After until then). A delay, not a
    lock: the right token from the same address is accepted once the short delay has passed, while guessing
    stays bounded to one try per ``max_delay`` seconds. Kept in memory per server process (with gunicorn,
    per worker)."""

    def __init__(self, limit: int = 10, window: float = 900.0, max_delay: float = 30.0,
                 clock: Callable[[], float] = time.monotonic):
        self.limit, self.window, self.max_delay, self.clock = limit, window, max_delay, clock
        self._failures: dict[str, list[float]] = {}
        self._lock = threading.Lock()

    def _recent(self, address: str, now: float) -> list[float]:
        times = [t for t in self._failures.get(address, []) if now - t < self.window]
        if times:
            self._failures[address] = times
        else:
            self._failures.pop(address, None)
        return times

    def retry_after(self, address: str) -> int:
        """Seconds until ``address`` may try again (0: now)."""
        now = self.clock()
        with self._lock:
            times = self._recent(address, now)
            if len(times) < self.limit:
                return 0
            delay = min(self.max_delay, 2.0 ** (len(times) - self.limit))
            wait = times[-1] + delay - now
            return 0 if wait <= 0 else max(1, math.ceil(wait))

    def failed(self, address: str) -> None:
        now = self.clock()
        with self._lock:
            self._failures.setdefault(address, []).append(now)
            self._recent(address, now)

    def succeeded(self, address: str) -> None:
        with self._lock:
            self._failures.pop(address, None)


def address_group(address: str | None) -> str:
    """The unit the per-address limits count: an IPv4 address itself, an IPv6 address's /64 network (one
    household or machine usually holds a whole /64, so counting single IPv6 addresses limits nothing)."""
    try:
        ip = ipaddress.ip_address(address or "")
    except ValueError:
        return address or "unknown"
    if isinstance(ip, ipaddress.IPv6Address):
        if ip.ipv4_mapped is not None:
            return str(ip.ipv4_mapped)
        return str(ipaddress.IPv6Network((ip, 64), strict=False))
    return str(ip)


def _admin_mac(nonce: str) -> str:
    """The admin cookie's proof, keyed by the admin token: a changed token invalidates every cookie."""
    key = current_app.config["ADMIN_TOKEN"].encode()
    return hmac.new(key, f"admin-login|{nonce}".encode(), hashlib.sha256).hexdigest()


def start_admin_session() -> None:
    """Mark this browser's signed session as logged in as admin (a random id and its token-keyed proof)."""
    nonce = secrets.token_hex(16)
    session["admin"] = {"nonce": nonce, "mac": _admin_mac(nonce)}


def _session_nonce() -> str | None:
    value = session.get("admin")
    if not isinstance(value, dict):
        return None
    nonce, mac = value.get("nonce"), value.get("mac")
    if not isinstance(nonce, str) or not isinstance(mac, str) or len(nonce) != 32:
        return None
    return nonce if check_token(mac, _admin_mac(nonce)) else None


def end_admin_session() -> None:
    """Log out: the cookie's id is stored as logged out, so a copy of the cookie no longer works."""
    from study_app.context import get_store
    from study_app.storage import AdminLogout

    nonce = _session_nonce()
    session.pop("admin", None)
    if nonce is not None:
        with get_store().Session.begin() as db:
            if db.get(AdminLogout, nonce) is None:
                db.add(AdminLogout(nonce=nonce))


def _session_is_admin() -> bool:
    from study_app.context import get_store
    from study_app.storage import AdminLogout

    nonce = _session_nonce()
    if nonce is None:
        return False
    with get_store().ReadSession() as db:
        return db.get(AdminLogout, nonce) is None


def admin_logins() -> LoginThrottle:
    """This app's record of failed admin logins (form or bearer token), by client address."""
    throttle = current_app.extensions.setdefault("evalsuite_admin_logins", LoginThrottle())
    assert isinstance(throttle, LoginThrottle)
    return throttle


def admin_authorised() -> bool:
    token = current_app.config["ADMIN_TOKEN"]
    header = request.headers.get("Authorization", "")
    if header.startswith("Bearer "):
        address, logins = address_group(request.remote_addr), admin_logins()
        if logins.retry_after(address):
            abort(429)
        ok = check_token(header[7:].strip(), token)
        if ok:
            logins.succeeded(address)
        else:
            logins.failed(address)
        return ok
    return _session_is_admin()


def admin_required(view: Callable[..., Any]) -> Callable[..., Any]:
    @wraps(view)
    def wrapped(*args: Any, **kwargs: Any) -> Any:
        if not admin_authorised():
            # scripts, downloads and the admin page's own JSON polling get 403, not the login form
            if (request.headers.get("Authorization") or request.path.startswith("/admin/export")
                    or request.path.endswith(".json")):
                abort(403)
            return redirect(url_for("admin.login"))
        return view(*args, **kwargs)
    return wrapped


def parse_networks(value, field: str) -> list[ipaddress.IPv4Network | ipaddress.IPv6Network]:
    """Proxy addresses or networks (``10.0.0.5``, ``10.0.0.0/24``, ``::1``) from a list or a comma-separated
    string; a :class:`~study_app.errors.StudyStateError` naming ``field`` for anything else."""
    from study_app.errors import StudyStateError

    items = value.split(",") if isinstance(value, str) else value
    if not isinstance(items, (list, tuple)):
        raise StudyStateError("expected a list of proxy addresses or networks", field=field)
    out = []
    for item in items:
        try:
            out.append(ipaddress.ip_network(str(item).strip(), strict=False))
        except ValueError:
            raise StudyStateError(f"expected an IP address or network such as 127.0.0.1 or 10.0.0.0/24, got "
                                  f"{item!r}", field=field) from None
    return out


class TrustedProxies:
    """WSGI middleware: ``X-Forwarded-For`` (``x_for`` hops, werkzeug's ProxyFix) is believed only on requests
    whose peer address is one of ``networks``; from anyone else the X-Forwarded-* headers are removed, so a
    client cannot choose the address the per-address limits count."""

    HEADERS = ("HTTP_X_FORWARDED_FOR", "HTTP_X_FORWARDED_PROTO", "HTTP_X_FORWARDED_HOST", "HTTP_X_FORWARDED_PORT",
               "HTTP_X_FORWARDED_PREFIX")

    def __init__(self, app: Callable[..., Any], x_for: int, networks: list):
        from werkzeug.middleware.proxy_fix import ProxyFix

        self.app, self.networks = app, networks
        self.fixed = ProxyFix(app, x_for=x_for)

    def trusted(self, peer: str | None) -> bool:
        try:
            ip = ipaddress.ip_address(peer or "")
        except ValueError:
            return False
        return any(ip.version == n.version and ip in n for n in self.networks)

    def __call__(self, environ: dict, start_response: Callable[..., Any]) -> Any:
        if self.trusted(environ.get("REMOTE_ADDR")):
            return self.fixed(environ, start_response)
        for key in self.HEADERS:
            environ.pop(key, None)
        return self.app(environ, start_response)
