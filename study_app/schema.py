"""Validation helpers for study definitions: every failure names the file, the field path and what was
expected (:class:`~study_app.errors.StudyDefinitionError`)."""
from __future__ import annotations

from typing import NoReturn

from evalsuite.errors import did_you_mean
from study_app.errors import StudyDefinitionError
from study_app.model import ID_RE

__all__ = ["Checker", "describe", "load_text_items"]


class Checker:
    """Small helpers that raise errors naming file and field path."""

    def __init__(self, path):
        self.path = path

    def fail(self, field_path: str, message: str) -> NoReturn:
        raise StudyDefinitionError(message, path=self.path, field=field_path)

    def get(self, obj: dict, key: str, where: str, types, *, required=False, default=None,
            expected: str = ""):
        fp = f"{where}.{key}" if where else key
        if key not in obj or obj[key] is None:
            if required:
                self.fail(fp, f"missing; expected {expected or _type_name(types)}")
            return default
        value = obj[key]
        # bool is an int subclass: reject True where a number is expected.
        if isinstance(value, bool) and bool not in _as_tuple(types):
            self.fail(fp, f"expected {expected or _type_name(types)}, got {value!r}")
        if not isinstance(value, types):
            self.fail(fp, f"expected {expected or _type_name(types)}, got {describe(value)}")
        return value

    def ident(self, obj, key, where, *, required=True, default=None):
        value = self.get(obj, key, where, str, required=required, default=default,
                         expected="an id of letters, digits, '_', '-', '.' (at most 64)")
        if value is not None and not ID_RE.match(value):
            self.fail(f"{where}.{key}" if where else key,
                      f"expected an id of letters, digits, '_', '-', '.' (at most 64), got {value[:60]!r}")
        return value

    def int_range(self, obj, key, where, lo, hi, *, required=False, default=None):
        value = self.get(obj, key, where, int, required=required, default=default,
                         expected=f"an integer in {lo}..{hi}")
        if value is not None and not lo <= value <= hi:
            self.fail(f"{where}.{key}" if where else key,
                      f"expected an integer in {lo}..{hi}, got {value}")
        return value

    def str_list(self, obj, key, where, *, required=False, default=None, min_len=0):
        fp = f"{where}.{key}" if where else key
        value = self.get(obj, key, where, list, required=required, default=default,
                         expected="a list of strings")
        if value is None:
            return value
        for i, v in enumerate(value):
            if not isinstance(v, str) or not v.strip():
                self.fail(f"{fp}[{i}]", f"expected a non-empty string, got {describe(v)}")
        if len(value) < min_len:
            self.fail(fp, f"expected at least {min_len} entries, got {len(value)}")
        first: dict[str, int] = {}
        for i, v in enumerate(value):
            j = first.setdefault(v.strip(), i)
            if j != i:
                self.fail(fp, f"expected distinct {key} ({v[:60]!r} is entry {j} and entry {i})")
        return value

    def unknown_keys(self, obj: dict, allowed, where: str):
        odd = [k for k in obj if not isinstance(k, str)]
        if odd:
            self.fail(f"{where}" if where else "", f"expected field names as text, found {describe(odd[0])}")
        extra = sorted(set(obj) - set(allowed))
        if extra:
            self.fail(f"{where}.{extra[0]}" if where else extra[0],
                      f"unknown field{did_you_mean(extra[0], allowed) or '; see docs/study_app.md for the fields'}")


def _as_tuple(types):
    return types if isinstance(types, tuple) else (types,)


def _type_name(types) -> str:
    names = {str: "a string", int: "an integer", float: "a number", bool: "true or false",
             list: "a list", dict: "a mapping"}
    return " or ".join(names.get(t, t.__name__) for t in _as_tuple(types))


def describe(value) -> str:
    return f"{type(value).__name__} {value!r}"[:80]


def load_text_items(chk, page, key, where, *, required, extra=()):
    items = chk.get(page, key, where, list, required=required, default=[],
                    expected="a list of {id, text}")
    if required and not items:
        chk.fail(f"{where}.{key}", "expected at least one entry")
    out, ids = [], set()
    for j, it in enumerate(items):
        iw = f"{where}.{key}[{j}]"
        if not isinstance(it, dict):
            chk.fail(iw, f"expected a mapping with id and text, got {describe(it)}")
        chk.unknown_keys(it, ("id", "text") + extra, iw)
        iid = chk.ident(it, "id", iw)
        if iid in ids:
            chk.fail(f"{iw}.id", f"duplicate id {iid!r}")
        ids.add(iid)
        entry = {"id": iid, "text": chk.get(it, "text", iw, str, required=True)}
        for e in extra:
            entry[e] = chk.get(it, e, iw, str, default="")
        out.append(entry)
    return out
