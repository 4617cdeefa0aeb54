"""Parsing a study definition's text (YAML or JSON) into plain data, within limits.

Refused with a :class:`~study_app.errors.StudyDefinitionError` naming the file, the line or the field path:
YAML or JSON syntax errors; a key given twice in one mapping (the YAML and JSON readers would keep the last
one silently); more than :data:`MAX_ALIASES` YAML aliases; nesting deeper than :data:`MAX_NESTING`; NaN and
infinities; whole numbers beyond :data:`MAX_INT`; lists longer than :data:`MAX_LIST_ITEMS` and strings longer
than :data:`MAX_STRING_CHARS`. A file over :data:`MAX_FILE_BYTES` is refused before it is read. The limits
lie far above real definitions (a few kilobytes, a few dozen list entries) and keep loading under a second.
"""
from __future__ import annotations

import json
import math
import pathlib

import yaml

from study_app.errors import StudyDefinitionError

__all__ = ["parse_definition", "MAX_FILE_BYTES", "MAX_LIST_ITEMS", "MAX_STRING_CHARS", "MAX_INT"]

MAX_FILE_BYTES = 200_000    # PyYAML's safe loader reads about 200 kB a second
MAX_NESTING = 50            # definitions are a few levels deep; far deeper input is not a definition
MAX_ALIASES = 50            # YAML aliases per file (a "billion laughs" file has 81; definitions need few)
MAX_LIST_ITEMS = 1_000      # pages, questions, options, conditions, segments, ...
MAX_STRING_CHARS = 20_000   # a consent text of some 3,000 words
MAX_INT = 10**15            # any count or seed; larger ones overflow a float


class _DefinitionLoader(yaml.SafeLoader):
    """PyYAML's safe loader that refuses more than :data:`MAX_ALIASES` aliases and a key twice in a mapping."""

    aliases = 0

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            self.aliases += 1
            if self.aliases > MAX_ALIASES:
                raise yaml.YAMLError(f"more than {MAX_ALIASES} aliases; a study definition needs few")
        return super().compose_node(parent, index)

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen: dict[object, int] = {}
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=True)
                line = key_node.start_mark.line + 1
                try:
                    first = seen.get(key)
                except TypeError:      # an unhashable key: PyYAML says so itself
                    continue
                if first is not None:
                    raise _DuplicateKey(f"key {str(key)[:60]!r} given twice (lines {first} and {line}); expected "
                                        "each key once", line)
                seen[key] = line
        return super().construct_mapping(node, deep=deep)


class _DuplicateKey(Exception):
    def __init__(self, message: str, line: int | None = None):
        super().__init__(message)
        self.line = line


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a number a study definition can use")


def _json_object(pairs: list[tuple[str, object]]) -> dict:
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise _DuplicateKey(f"key {key[:60]!r} given twice in one object; expected each key once")
        out[key] = value
    return out


def parse_definition(path: pathlib.Path, text: str) -> object:
    """JSON (``.json``) or YAML, with errors that name the file and line, checked by :func:`check_values`."""
    kind = "JSON" if path.suffix.lower() == ".json" else "YAML"
    try:
        if kind == "JSON":
            data = json.loads(text, parse_constant=_no_constant, object_pairs_hook=_json_object)
        else:
            data = yaml.load(text, Loader=_DefinitionLoader)  # a SafeLoader subclass
    except RecursionError:
        raise StudyDefinitionError(f"nested too deeply (at most {MAX_NESTING} levels)", path=path) from None
    except _DuplicateKey as exc:
        raise StudyDefinitionError(str(exc), path=path, line=exc.line) from None
    except json.JSONDecodeError as exc:
        raise StudyDefinitionError(f"invalid JSON: {exc.msg}", path=path, line=exc.lineno) from None
    except ValueError as exc:   # a NaN constant, or an integer of more than 4300 digits
        raise StudyDefinitionError(f"invalid {kind}: {str(exc)[:200]}", path=path) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise StudyDefinitionError(f"invalid YAML: {getattr(exc, 'problem', None) or exc}", path=path,
                                   line=mark.line + 1 if mark else None) from None
    check_values(path, data)
    return data


def check_values(path: pathlib.Path, data: object) -> None:
    """Bounded depth, list lengths, string lengths and numbers everywhere (YAML's .nan / .inf are numbers to
    it; a 400-digit integer is one to both readers)."""
    stack: list[tuple[object, str, int]] = [(data, "", 1)]
    seen: set[int] = set()   # YAML aliases share objects: visit each once (no "billion laughs" walk)
    while stack:
        item, where, depth = stack.pop()
        field = where or None
        if isinstance(item, (dict, list)):
            if id(item) in seen:
                continue
            seen.add(id(item))
        if depth > MAX_NESTING:
            raise StudyDefinitionError(f"nested too deeply (at most {MAX_NESTING} levels)", path=path, field=field)
        if isinstance(item, float) and not math.isfinite(item):
            raise StudyDefinitionError(f"expected a finite number, got {item}", path=path, field=field)
        if isinstance(item, int) and not isinstance(item, bool) and abs(item) > MAX_INT:
            raise StudyDefinitionError(f"a number of {len(str(abs(item)))} digits; expected at most {len(str(MAX_INT)) - 1} "
                                       "(no count or seed of a study is larger)", path=path, field=field)
        if isinstance(item, str) and len(item) > MAX_STRING_CHARS:
            raise StudyDefinitionError(f"a text of {len(item):,} characters; expected at most {MAX_STRING_CHARS:,}",
                                       path=path, field=field)
        if isinstance(item, list) and len(item) > MAX_LIST_ITEMS:
            raise StudyDefinitionError(f"a list of {len(item):,} entries; expected at most {MAX_LIST_ITEMS:,}",
                                       path=path, field=field)
        if isinstance(item, dict):
            stack.extend((v, f"{where}.{k}" if where else str(k), depth + 1) for k, v in item.items())
        elif isinstance(item, list):
            stack.extend((v, f"{where}[{i}]", depth + 1) for i, v in enumerate(item))
