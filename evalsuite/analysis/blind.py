"""Double-blind analysis: condition names replaced by stable codes until ``--reveal``.

Gesticulator's authors ran their tests on obfuscated condition names and only looked at
which was which afterwards. ``evalsuite analyze --blind`` does the same: before any
statistic is computed, every condition name is replaced by a code (``B01``, ``B02``, ...),
so tables, figures, the HTML report and console messages only ever show codes.

- Codes are *stable*: a random salt is drawn on the first ``--blind`` run and stored in
  ``OUT_DIR/.evalsuite-blind``; every later run into that folder reuses it (and stays
  blind even without ``--blind``), so codes do not change while the analysis is refined.
- The permutation is seeded by the salt, so it reveals nothing about the real names
  (not even their alphabetical order).
- ``--reveal`` analyses with the real names, writes ``blind_key.csv`` (code -> condition)
  so earlier blinded outputs can be read, and removes the marker.
- A mismatched stimulus ``X:mismatched`` is coded as ``<code of X>:mismatched`` (and an
  audio-mismatched one ``X:audio_mismatched`` as ``<code of X>:audio_mismatched``) so the
  matched/mismatched analyses still pair them.
"""
from __future__ import annotations

import hashlib
import json
import pathlib
import secrets

import numpy as np
import pandas as pd

from evalsuite.analysis.pairwise import AUDIO_MISMATCH_SUFFIX
from evalsuite.errors import InputError

MARKER = ".evalsuite-blind"
CONDITION_COLUMNS = ("condition", "condition_a", "condition_b")


def all_conditions(df: pd.DataFrame):
    """Every non-empty condition name in a results table."""
    names = set()
    for col in CONDITION_COLUMNS:
        if col in df.columns:
            names |= set(df[col])
    names.discard("")
    return names


def blind_codes(conditions, salt: str, mismatch_suffix: str = ":mismatched") -> dict:
    """``{name: code}`` for ``conditions``: a salt-seeded permutation of the base names
    numbered ``B01, B02, ...``; ``X + mismatch_suffix`` maps to ``code(X) + mismatch_suffix``, and
    ``X:audio_mismatched`` to ``code(X):audio_mismatched``."""
    names = set(conditions)
    suffixes = [s for s in (mismatch_suffix, AUDIO_MISMATCH_SUFFIX) if s]

    def parent(n: str) -> tuple[str, str] | None:
        return next(((n[: -len(s)], s) for s in suffixes if n.endswith(s) and n[: -len(s)] in names), None)

    base = sorted(n for n in names if parent(n) is None)
    seed = int.from_bytes(hashlib.sha256(salt.encode()).digest()[:8], "little")
    perm = np.random.default_rng(seed).permutation(len(base))
    width = max(2, len(str(len(base))))
    codes = {base[i]: f"B{k + 1:0{width}d}" for k, i in enumerate(perm)}
    for n in names - set(base):
        x, s = parent(n) or (n, "")
        codes[n] = codes[x] + s
    return codes


def apply_codes(df: pd.DataFrame, codes: dict) -> pd.DataFrame:
    """Copy of ``df`` with condition names replaced by their codes."""
    out = df.copy()
    for col in CONDITION_COLUMNS:
        if col in out.columns:
            out[col] = out[col].map(lambda v: codes.get(v, v))
    out.attrs.update(df.attrs)
    return out


def resolve(out_dir: pathlib.Path, blind: bool, reveal: bool):
    """Decide the blinding state for a run into ``out_dir``.

    Returns ``(salt or None, reveal_salt or None)``: a salt when this run is blind; the
    stored salt when ``--reveal`` should write the key. Creates the marker on ``--blind``.
    """
    if blind and reveal:
        raise InputError("--blind and --reveal exclude each other: --reveal ends a blinded analysis")
    marker = pathlib.Path(out_dir) / MARKER
    stored = None
    if marker.is_file():
        try:
            stored = json.loads(marker.read_text())["salt"]
        except (ValueError, KeyError, TypeError) as exc:
            raise InputError(f"unreadable blinding marker ({exc}); delete it to start over",
                             path=marker) from exc
    if reveal:
        return None, stored
    if blind or stored:
        if stored is None:
            stored = secrets.token_hex(16)
            marker.parent.mkdir(parents=True, exist_ok=True)
            marker.write_text(json.dumps({"salt": stored}))
        return stored, None
    return None, None


def finish_reveal(out_dir: pathlib.Path, salt: str, conditions, mismatch_suffix: str) -> pathlib.Path:
    """Write ``blind_key.csv`` (code, condition) and remove the marker; returns the key path."""
    codes = blind_codes(conditions, salt, mismatch_suffix)
    key = pd.DataFrame(sorted(((c, n) for n, c in codes.items())), columns=["code", "condition"])
    path = pathlib.Path(out_dir) / "blind_key.csv"
    key.to_csv(path, index=False)
    (pathlib.Path(out_dir) / MARKER).unlink(missing_ok=True)
    return path
