"""BVH reading (writing: :mod:`evalsuite.motion.bvh_writer`).

The reader accepts what real exporters write: any whitespace (spaces, tabs, CRLF), numbers
such as ``+1.5``, ``1e-3``, ``-0``, ``.0083333``, joint names with ``:``, ``-``, ``.``,
several ``ROOT`` blocks, channel lists of any length and order on any joint, and
``End Site`` blocks. Anything else raises :class:`~evalsuite.errors.BVHError` naming the
file, the line and what was expected; no other exception type escapes for bad input.

The frame data is parsed with one vectorised call; only if that fast path finds an
inconsistency does a line-by-line pass run to report exactly where the file is wrong.
"""
from __future__ import annotations

import difflib
import math
import os
import re

import numpy as np

from evalsuite.errors import BVHError
from evalsuite.motion.bvh_frames import NUMBER_RE, frames_fast, frames_slow
from evalsuite.motion.skeleton import Skeleton, canonical_channel

__all__ = ["parse_bvh", "read_bvh_file", "format_bvh", "write_bvh"]

_FRAMES_RE = re.compile(r"^\s*Frames\s*:\s*(\S*)\s*$", re.IGNORECASE)
COUNT_RE = re.compile(r"^\d+$", re.ASCII)
# Limits far beyond real files, so that a damaged or hostile file fails fast with a clear message.
MAX_DEPTH = 256            # joints nested inside each other
MAX_JOINTS = 10_000
MAX_LINE_CHARS = 1_000_000
MAX_FPS = 100_000.0
_FRAME_TIME_RE = re.compile(r"^\s*Frame\s+Time\s*:\s*(\S*)\s*$", re.IGNORECASE)


class _Tokens:
    """Whitespace tokens of the HIERARCHY part, each with its 1-based line number."""

    def __init__(self, lines: list[str], path: str):
        self.path = path
        self.items: list[tuple[str, int]] = []
        for number, line in enumerate(lines, 1):
            for tok in line.replace("{", " { ").replace("}", " } ").split():
                self.items.append((tok, number))
        self.pos = 0
        self.last_line = len(lines)

    def error(self, message: str, line: int | None = None) -> BVHError:
        return BVHError(message, path=self.path, line=line if line is not None else self.line())

    def line(self) -> int:
        if self.pos < len(self.items):
            return self.items[self.pos][1]
        return self.last_line

    def peek(self) -> str | None:
        return self.items[self.pos][0] if self.pos < len(self.items) else None

    def next(self, expected: str) -> tuple[str, int]:
        if self.pos >= len(self.items):
            raise self.error(f"unexpected end of the hierarchy; expected {expected}")
        item = self.items[self.pos]
        self.pos += 1
        return item

    def expect(self, word: str) -> int:
        tok, line = self.next(repr(word))
        if tok.lower() != word.lower():
            raise self.error(f"expected {word!r}, found {tok[:60]!r}", line)
        return line

    def number(self, what: str) -> float:
        tok, line = self.next(what)
        if not NUMBER_RE.match(tok):
            raise self.error(f"expected a number for {what}, found {tok[:60]!r}", line)
        value = float(tok)
        if not math.isfinite(value):
            raise self.error(f"expected a finite number for {what}, found {tok[:60]!r}", line)
        return value


def _parse_hierarchy(tokens: _Tokens) -> Skeleton:
    tokens.expect("HIERARCHY")
    names: list[str] = []
    parents: list[int] = []
    offsets: list[tuple[float, float, float]] = []
    channels: list[tuple[str, ...]] = []
    end_parents: list[int] = []
    end_offsets: list[tuple[float, float, float]] = []
    name_lines: dict[str, int] = {}
    depths: list[int] = []

    def offset_values(owner: str) -> tuple[float, float, float]:
        x, y, z = (tokens.number(f"OFFSET {axis} of {owner}") for axis in "xyz")
        return x, y, z

    def joint(parent: int, keyword_line: int) -> None:
        # The name is every token up to '{' on the keyword's line (names rarely hold spaces).
        parts = []
        while tokens.peek() is not None and tokens.peek() != "{" and tokens.items[tokens.pos][1] == keyword_line:
            parts.append(tokens.next("a joint name")[0])
        if not parts:
            raise tokens.error("expected a joint name after ROOT/JOINT", keyword_line)
        name = " ".join(parts)
        if name in name_lines:
            raise tokens.error(f"duplicate joint name {name!r} (first defined on line {name_lines[name]}); "
                               "expected unique joint names", keyword_line)
        name_lines[name] = keyword_line
        tokens.expect("{")
        index = len(names)
        depth = 0 if parent < 0 else depths[parent] + 1
        if depth > MAX_DEPTH:
            raise tokens.error(f"joint {name!r} is nested {depth} levels deep; real skeletons are far shallower "
                               f"(limit {MAX_DEPTH})", keyword_line)
        if index >= MAX_JOINTS:
            raise tokens.error(f"more than {MAX_JOINTS:,} joints; real skeletons have far fewer", keyword_line)
        depths.append(depth)
        names.append(name)
        parents.append(parent)
        offsets.append((0.0, 0.0, 0.0))
        channels.append(())
        seen_offset = seen_channels = False
        while True:
            tok, line = tokens.next(f"'}}' closing joint {name!r}")
            word = tok.upper()
            if word == "OFFSET":
                if seen_offset:
                    raise tokens.error(f"joint {name!r} has a second OFFSET", line)
                offsets[index] = offset_values(f"joint {name!r}")
                seen_offset = True
            elif word == "CHANNELS":
                if seen_channels:
                    raise tokens.error(f"joint {name!r} has a second CHANNELS line", line)
                count_tok, count_line = tokens.next("the channel count")
                if not COUNT_RE.match(count_tok):
                    raise tokens.error(f"expected a whole channel count after CHANNELS, found {count_tok[:60]!r}",
                                       count_line)
                chans = []
                for _ in range(int(count_tok)):
                    ch_tok, ch_line = tokens.next(f"{count_tok} channel names for joint {name!r}")
                    canon = canonical_channel(ch_tok)
                    if canon is None:
                        raise tokens.error(
                            f"unknown channel {ch_tok[:60]!r} for joint {name!r}; expected one of Xposition, "
                            "Yposition, Zposition, Xrotation, Yrotation, Zrotation"
                            + (" (fewer channel names than CHANNELS says?)" if ch_tok.upper() in
                               ("JOINT", "END", "OFFSET", "}") else ""), ch_line)
                    if canon in chans and canon.endswith("position"):
                        raise tokens.error(f"channel {canon} listed twice for joint {name!r}", ch_line)
                    chans.append(canon)
                channels[index] = tuple(chans)
                seen_channels = True
            elif word == "JOINT":
                joint(index, line)
            elif word == "END":
                tokens.expect("Site")
                tokens.expect("{")
                tokens.expect("OFFSET")
                end_offsets.append(offset_values(f"the End Site of {name!r}"))
                end_parents.append(index)
                tokens.expect("}")
            elif tok == "}":
                if not seen_offset:
                    raise tokens.error(f"joint {name!r} has no OFFSET; expected 'OFFSET x y z'", line)
                return
            else:
                raise tokens.error(f"expected OFFSET, CHANNELS, JOINT, End Site or '}}' in joint {name!r}, "
                                   f"found {tok[:60]!r}{_did_you_mean(tok, JOINT_KEYWORDS)}", line)

    while (peeked := tokens.peek()) is not None and peeked.upper() == "ROOT":
        _, line = tokens.next("ROOT")
        joint(-1, line)
    if not names:
        tok = tokens.peek()
        raise tokens.error("expected ROOT after HIERARCHY"
                           + (f", found {tok[:60]!r}{_did_you_mean(tok, ('ROOT',))}" if tok else ""))
    if (tok := tokens.peek()) is not None:
        # Refused, not skipped (some readers skip lines up to MOTION): a misspelt second ROOT would lose a skeleton.
        raise tokens.error(f"expected MOTION or another ROOT after the hierarchy, found {tok[:60]!r}"
                           f"{_did_you_mean(tok, ('MOTION', 'ROOT'))}")
    return Skeleton(names, np.asarray(parents, dtype=np.int64), np.asarray(offsets, dtype=np.float64), channels,
                    np.asarray(end_parents, dtype=np.int64), np.asarray(end_offsets, dtype=np.float64).reshape(-1, 3))


JOINT_KEYWORDS = ("OFFSET", "CHANNELS", "JOINT", "End Site")


def _did_you_mean(token: str, keywords: tuple[str, ...]) -> str:
    """``" (did you mean 'OFFSET'?)"`` for a misspelt keyword (case ignored), else ``""``."""
    close = difflib.get_close_matches(token.upper(), [k.upper() for k in keywords], n=1, cutoff=0.6)
    return f" (did you mean {next(k for k in keywords if k.upper() == close[0])!r}?)" if close else ""


def _read_text(path: str, data: bytes) -> str:
    nul = data.find(b"\x00")
    if nul >= 0:
        raise BVHError(f"binary data (NUL byte at byte {nul}); expected a text BVH file", path=path)
    return data.decode("utf-8", errors="replace")


def _check_line_lengths(data: bytes, path: str) -> None:
    """Refuse lines no BVH has (a damaged or hostile file), before any per-line work."""
    if len(data) <= MAX_LINE_CHARS:
        return
    ends = np.flatnonzero(np.frombuffer(data, dtype=np.uint8) == 10)
    bounds = np.concatenate(([-1], ends, [len(data)]))
    lengths = np.diff(bounds) - 1
    longest = int(np.argmax(lengths))
    if lengths[longest] > MAX_LINE_CHARS:
        raise BVHError(f"line of {int(lengths[longest]):,} characters; BVH lines are far shorter (limit "
                       f"{MAX_LINE_CHARS:,})", path=path, line=longest + 1)


def parse_bvh(data: bytes | str, path: str = "<string>") -> tuple[Skeleton, np.ndarray, float]:
    """Parse BVH content. Returns ``(skeleton, values (T, C), frame_time)``."""
    path = os.fspath(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]  # a UTF-8 byte-order mark some editors write
    _check_line_lengths(data, path)
    match = re.search(rb"^[ \t]*MOTION[ \t]*\r?$", data, flags=re.MULTILINE | re.IGNORECASE)
    if match is None:
        header_lines = _read_text(path, data).splitlines()
        tokens = _Tokens(header_lines, path)
        _parse_hierarchy(tokens)  # reports a broken hierarchy precisely, if that is the problem
        raise BVHError("no MOTION section; expected 'MOTION' after the hierarchy", path=path,
                       line=len(header_lines))
    header = _read_text(path, data[: match.start()] or b" ")
    header_lines = header.splitlines()
    skeleton = _parse_hierarchy(_Tokens(header_lines, path))
    motion_line = data.count(b"\n", 0, match.start()) + 1

    rest = data[match.end():]
    if rest.startswith(b"\n"):
        rest = rest[1:]  # the rest of the MOTION line itself
    # Frames: and Frame Time: come next, each on its own line (blank lines tolerated).
    pos = 0
    line_no = motion_line
    found = {}
    for key, regex, what in (("frames", _FRAMES_RE, "'Frames: N'"), ("time", _FRAME_TIME_RE, "'Frame Time: t'")):
        while True:
            nl = rest.find(b"\n", pos)
            if nl < 0:
                nl = len(rest)
            line = rest[pos:nl].decode("utf-8", errors="replace")
            line_no += 1
            pos = nl + 1
            if line.strip():
                break
            if nl >= len(rest):
                raise BVHError(f"unexpected end of file; expected {what}", path=path, line=line_no)
        m = regex.match(line)
        if not m:
            raise BVHError(f"expected {what}, found {line.strip()[:60]!r}", path=path, line=line_no)
        found[key] = (m.group(1), line_no)
    frames_tok, frames_line = found["frames"]
    if not COUNT_RE.match(frames_tok):
        raise BVHError(f"expected a whole number of frames, found {frames_tok!r}", path=path, line=frames_line,
                       field="Frames")
    n_frames = int(frames_tok)
    if n_frames == 0:
        raise BVHError("expected at least 1 frame; 'Frames: 0' holds no motion", path=path, line=frames_line,
                       field="Frames")
    time_tok, time_line = found["time"]
    frame_time = float(time_tok) if NUMBER_RE.match(time_tok) else float("nan")
    if not (math.isfinite(frame_time) and frame_time >= 1.0 / MAX_FPS):
        raise BVHError(f"expected a positive frame time in seconds (at most {MAX_FPS:g} frames per second), "
                       f"found {time_tok!r}", path=path, line=time_line, field="Frame Time")

    body = rest[pos:]
    # Check the declared count against the data before allocating for it.
    available = body.count(b"\n") + (0 if body.endswith(b"\n") else 1)
    if n_frames and skeleton.n_channels and n_frames > available:
        raise BVHError(f"'Frames: {n_frames}' but the file has only {available} lines of frame data; "
                       "the file is truncated or 'Frames:' is wrong", path=path, line=frames_line, field="Frames")
    nul = body.find(b"\x00")
    if nul >= 0:
        raise BVHError("binary data (NUL byte) in the frame data; expected text", path=path,
                       line=time_line + 1 + body.count(b"\n", 0, nul))
    if skeleton.n_channels == 0:
        # No channels: frame lines are empty, so only stray content can be wrong.
        if body.strip():
            bad = len(body[: body.index(body.strip()[:1])].split(b"\n"))
            raise BVHError("frame data found but the hierarchy has no channels", path=path, line=time_line + bad)
        return skeleton, np.zeros((n_frames, 0)), frame_time
    values = frames_fast(body, n_frames, skeleton.n_channels)
    if values is None:
        lines = body.decode("utf-8", errors="replace").split("\n")
        values = frames_slow(lines, time_line + 1, n_frames, skeleton, path)
    return skeleton, values, frame_time


def read_bvh_file(path: str | os.PathLike[str]) -> tuple[Skeleton, np.ndarray, float]:
    """Read a BVH file: ``(skeleton, values, frame_time)``. Raises BVHError for bad input."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise BVHError(f"cannot read the file: {exc.strerror or exc}", path=path) from None
    if not data.strip():
        raise BVHError("the file is empty; expected a BVH file starting with HIERARCHY", path=path)
    return parse_bvh(data, path)


# Writing lives in evalsuite.motion.bvh_writer; re-exported here (bvh.format_bvh, bvh.write_bvh).
from evalsuite.motion.bvh_writer import format_bvh as format_bvh  # noqa: E402
from evalsuite.motion.bvh_writer import write_bvh as write_bvh  # noqa: E402
