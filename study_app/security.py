"""Admin authentication: the admin token from start-up, given in the login form (a flag in the signed
session cookie) or as ``Authorization: Bearer <token>`` (scripts). There is no default credential."""
from __future__ import annotations

import hmac
import threading
import time
from collections.abc import Callable
from functools import wraps
from typing import Any

from flask import abort, current_app, redirect, request, session, url_for

__all__ = ["check_token", "admin_authorised", "admin_required", "admin_logins", "LoginThrottle"]


def check_token(given: str, expected: str) -> bool:
    """Constant-time comparison of a given token with the expected one."""
    return hmac.compare_digest(given.encode(), expected.encode())


class LoginThrottle:
    """Failed admin logins per client address: after ``limit`` failures within ``window`` seconds the address
    is refused (HTTP 429) until the oldest of them is ``window`` seconds old. Kept in memory per server
    process (with gunicorn, per worker: the limit then applies per worker, still bounding guessing)."""

    def __init__(self, limit: int = 10, window: float = 900.0):
        self.limit, self.window = limit, window
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
        now = time.monotonic()
        with self._lock:
            times = self._recent(address, now)
            if len(times) < self.limit:
                return 0
            return max(1, int(times[-self.limit] + self.window - now) + 1)

    def failed(self, address: str) -> None:
        now = time.monotonic()
        with self._lock:
            self._failures.setdefault(address, []).append(now)
            self._recent(address, now)

    def succeeded(self, address: str) -> None:
        with self._lock:
            self._failures.pop(address, None)


def admin_logins() -> LoginThrottle:
    """This app's record of failed admin logins (form or bearer token), by client address."""
    throttle = current_app.extensions.setdefault("evalsuite_admin_logins", LoginThrottle())
    assert isinstance(throttle, LoginThrottle)
    return throttle


def admin_authorised() -> bool:
    token = current_app.config["ADMIN_TOKEN"]
    header = request.headers.get("Authorization", "")
    if header.startswith("Bearer "):
        address, logins = request.remote_addr or "unknown", admin_logins()
        if logins.retry_after(address):
            abort(429)
        ok = check_token(header[7:].strip(), token)
        if ok:
            logins.succeeded(address)
        else:
            logins.failed(address)
        return ok
    return session.get("admin") is True


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
