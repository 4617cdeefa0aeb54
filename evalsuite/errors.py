"""Exception types for bad input.

Every reader in evalsuite raises :class:`InputError` (a ``ValueError``) or one of its
subclasses for malformed input, never an ``IndexError``/``KeyError`` from deep inside a
parser. The message names the file, the line (when there is one), the field and what
was expected, so the CLI can print it without a traceback.
"""
from __future__ import annotations

import difflib
import os
from collections.abc import Iterable


class InputError(ValueError):
    """Malformed or unusable input (file, CSV, config, HTTP payload).

    Attributes ``path``, ``line`` (1-based) and ``field`` are ``None`` when unknown.
    """

    def __init__(self, message: str, *, path=None, line: int | None = None, field: str | None = None):
        self.path = os.fspath(path) if path is not None else None
        self.line = line
        self.field = field
        self.reason = message
        where = ""
        if self.path is not None:
            where = self.path
            if line is not None:
                where += f":{line}"
            where += ": "
        elif line is not None:
            where = f"line {line}: "
        if field:
            where += f"{field}: "
        super().__init__(where + message)


def did_you_mean(name: object, known: Iterable[str]) -> str:
    """``". Did you mean 'a' or 'b'?"`` with the (at most three) known names closest to ``name``, or ``""``."""
    close = difflib.get_close_matches(str(name), list(known), n=3, cutoff=0.6)
    return f". Did you mean {' or '.join(repr(c) for c in close)}?" if close else ""


class BVHError(InputError):
    """A BVH file that cannot be read: the one error type the BVH reader lets escape."""


class MotionError(InputError):
    """Motion data that does not fit the operation asked for (unknown joint, bad fps, ...)."""


class UnknownNameError(InputError, KeyError):
    """A name that no registry knows (metric family, page kind, generator, layout, ...).

    Also a ``KeyError``, so a registry behaves as a mapping; the message lists the known names and the
    closest ones ("did you mean ...")."""

    __str__ = InputError.__str__


class PluginError(InputError):
    """An installed plug-in (entry point) that cannot be imported or does not fit its extension point."""
