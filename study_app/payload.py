"""Checks of what a participant's browser sends: every problem is a :class:`PayloadError` (HTTP 422 with
its message), never a KeyError from deep inside."""
from __future__ import annotations

from collections.abc import Iterable
from typing import Any

__all__ = ["PayloadError", "require_dict", "only_keys", "int_in", "parse_json_object", "MAX_JSON_DEPTH"]

MAX_JSON_DEPTH = 16   # answers, drafts and event lists are shallow; deeper input is not ours


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


def _no_constant(name: str) -> Any:
    raise PayloadError(f"{name} is not a number JSON allows (NaN and Infinity are refused)")


def _depth(value: Any) -> int:
    """Nesting depth of parsed JSON, without recursion; a NUL character in any string or key is a
    :class:`PayloadError` (PostgreSQL's text cannot hold one: it would fail as a server error)."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, str) and "\x00" in item:
            raise PayloadError("a NUL character (\\u0000) in a string; expected text without it")
        if isinstance(item, (dict, list)):
            deepest = max(deepest, depth)
            stack.extend((v, depth + 1) for v in (item.values() if isinstance(item, dict) else item))
            if isinstance(item, dict):
                stack.extend((k, depth) for k in item)
    return deepest


def parse_json_object(raw: bytes) -> dict:
    """The request body as a JSON object: strict JSON (no NaN/Infinity), nested at most
    :data:`MAX_JSON_DEPTH` levels, no NUL character in a string; anything else is a :class:`PayloadError`, never a RecursionError."""
    import json

    try:
        value = json.loads(raw, parse_constant=_no_constant)
    except RecursionError:
        raise PayloadError(f"JSON nested too deeply (at most {MAX_JSON_DEPTH} levels)") from None
    except (ValueError, UnicodeDecodeError) as exc:
        if isinstance(exc, PayloadError):
            raise
        raise PayloadError(f"expected a JSON object ({exc})") from None
    if not isinstance(value, dict):
        raise PayloadError("expected a JSON object")
    if _depth(value) > MAX_JSON_DEPTH:
        raise PayloadError(f"JSON nested too deeply (at most {MAX_JSON_DEPTH} levels)")
    return value


def int_in(value: Any, lo: int, hi: int, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise PayloadError(f"{what}: expected an integer in {lo}..{hi}")
    return value
