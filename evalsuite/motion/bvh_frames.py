"""The frame data of a BVH file: a vectorised reader for well-formed data, and a line-by-line reader that
says exactly where data is wrong (line, column, frame, channel)."""
from __future__ import annotations

import io
import math
import re
import warnings

import numpy as np

from evalsuite.errors import BVHError
from evalsuite.motion.skeleton import Skeleton

__all__ = ["frames_fast", "frames_slow", "NUMBER_RE"]

# What BVH numbers are: plain decimal or exponent notation in ASCII (Python's float() also takes
# "nan", "1_0", non-ASCII digits; BVH does not).
NUMBER_RE = re.compile(r"^[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?$", re.ASCII)
# Bytes that a frame line may contain (ASCII digits, signs, point, exponent, whitespace): anything else
# sends the data to the line-by-line reader, which names the bad token.
_FRAME_BYTES = np.zeros(256, dtype=bool)
_FRAME_BYTES[np.frombuffer(b"0123456789+-.eE \t\r\n\v\f", dtype=np.uint8)] = True


def frames_slow(lines: list[str], first_line: int, n_frames: int, skeleton: Skeleton, path: str) -> np.ndarray:
    """Line-by-line parse that reports exactly where the frame data is wrong."""
    n_ch = skeleton.n_channels
    names = skeleton.channel_names()
    out = np.empty((n_frames, n_ch), dtype=np.float64)
    frame = 0
    for offset_, line in enumerate(lines):
        number = first_line + offset_
        fields = line.split()
        if not fields:
            continue
        if frame >= n_frames:
            raise BVHError(f"more frame lines than 'Frames: {n_frames}' declares; expected {n_frames} frames",
                           path=path, line=number)
        if len(fields) != n_ch:
            raise BVHError(f"frame {frame} has {len(fields)} values; expected {n_ch} "
                           f"(one per channel of the hierarchy)", path=path, line=number)
        for col, tok in enumerate(fields):
            if not NUMBER_RE.match(tok):
                column = line.index(tok, sum(len(f) for f in fields[:col])) + 1
                what = "a finite number" if tok.lower().lstrip("+-") in ("nan", "inf", "infinity") else "a number"
                raise BVHError(f"expected {what}, found {tok[:60]!r} (column {column}; BVH numbers are plain decimal "
                               "or exponent notation)", path=path, line=number,
                               field=f"frame {frame}, channel '{names[col]}'")
            value = float(tok)
            if not math.isfinite(value):
                raise BVHError(f"expected a finite number, found {tok[:60]!r}", path=path, line=number,
                               field=f"frame {frame}, channel '{names[col]}'")
            out[frame, col] = value
        frame += 1
    if frame != n_frames:
        raise BVHError(f"the file is truncated or 'Frames:' is wrong: 'Frames: {n_frames}' but {frame} frame lines "
                       "found", path=path, line=first_line + len(lines) - 1 if lines else first_line)
    return out


def frames_fast(body: bytes, n_frames: int, n_ch: int) -> np.ndarray | None:
    """Vectorised parse; ``None`` when anything looks off (the slow path then explains).

    First pandas' C tokenizer with a single-space separator (what most writers emit; it
    checks the value count of every line), then numpy's whitespace-agnostic reader with a
    line count, for files with tabs or runs of spaces.
    """
    if n_frames == 0 or n_ch == 0:
        return None
    import pandas as pd

    stripped = body.strip()
    if stripped.count(b"\n") + 1 != n_frames:
        return None
    if not _FRAME_BYTES[np.frombuffer(stripped, dtype=np.uint8)].all():
        return None  # letters, quotes, '_' or non-ASCII: not BVH numbers, the slow path says where
    try:
        frame = pd.read_csv(io.BytesIO(stripped), sep=" ", header=None, engine="c", dtype=np.float64,
                            na_filter=True, skip_blank_lines=False)
        arr = frame.to_numpy()
        if arr.shape[1] == n_ch + 1 and np.isnan(arr[:, -1]).all():
            arr = arr[:, :-1]  # trailing space at the end of every line
        if arr.shape == (n_frames, n_ch) and np.isfinite(arr).all():
            # Column-major as pandas builds it: no copy, and FK reads whole channel columns.
            return np.asarray(arr)
    except (ValueError, pd.errors.ParserError):
        pass
    if not _every_line_has(stripped, n_ch):
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # older numpy warns when it stops at a bad token
            flat = np.fromstring(stripped.decode("latin-1"), dtype=np.float64, sep=" ")
    except ValueError:  # newer numpy raises instead
        return None
    if flat.size != n_frames * n_ch or not np.isfinite(flat).all():
        return None
    return flat.reshape(n_frames, n_ch)


def _every_line_has(data: bytes, n_tokens: int) -> bool:
    """Whether every line holds exactly ``n_tokens`` whitespace-separated tokens (vectorised).

    A right total alone could hide a line with one value too many next to one with one too
    few, which would silently shift channels between frames.
    """
    arr = np.frombuffer(data, dtype=np.uint8)
    space = (arr == 32) | ((arr >= 9) & (arr <= 13))  # space, \t, \n, \v, \f, \r
    token_starts = np.flatnonzero(~space & np.concatenate(([True], space[:-1])))
    line_ends = np.append(np.flatnonzero(arr == 10), len(arr))
    per_line = np.diff(np.concatenate(([0], np.searchsorted(token_starts, line_ends))))
    return bool(np.all(per_line == n_tokens))
