"""Admin authentication: the admin token from start-up, given in the login form (a flag in the signed
session cookie) or as ``Authorization: Bearer <token>`` (scripts). There is no default credential."""
from __future__ import annotations

import hmac
from collections.abc import Callable
from functools import wraps
from typing import Any

from flask import abort, current_app, redirect, request, session, url_for

__all__ = ["check_token", "admin_authorised", "admin_required"]


def check_token(given: str, expected: str) -> bool:
    """Constant-time comparison of a given token with the expected one."""
    return hmac.compare_digest(given.encode(), expected.encode())


def admin_authorised() -> bool:
    token = current_app.config["ADMIN_TOKEN"]
    header = request.headers.get("Authorization", "")
    if header.startswith("Bearer "):
        return check_token(header[7:].strip(), token)
    return session.get("admin") is True


def admin_required(view: Callable[..., Any]) -> Callable[..., Any]:
    @wraps(view)
    def wrapped(*args: Any, **kwargs: Any) -> Any:
        if not admin_authorised():
            if request.headers.get("Authorization") or request.path.startswith("/admin/export"):
                abort(403)
            return redirect(url_for("admin.login"))
        return view(*args, **kwargs)
    return wrapped
