"""Checks of what a participant's browser sends: every problem is a :class:`PayloadError` (HTTP 422 with
its message), never a KeyError from deep inside."""
from __future__ import annotations

from collections.abc import Iterable
from typing import Any

__all__ = ["PayloadError", "require_dict", "only_keys", "int_in"]


class PayloadError(ValueError):
    pass


def require_dict(value: Any, what: str) -> dict:
    if not isinstance(value, dict):
        raise PayloadError(f"{what}: expected an object")
    return value


def only_keys(obj: dict, allowed: Iterable[str], what: str) -> None:
    extra = sorted(set(obj) - set(allowed))
    if extra:
        raise PayloadError(f"{what}: unexpected field {extra[0]!r}")


def int_in(value: Any, lo: int, hi: int, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise PayloadError(f"{what}: expected an integer in {lo}..{hi}")
    return value
