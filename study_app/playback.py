"""Was a page's media really played? The server's own evidence, not the browser's word.

The browser reports ``play`` and ``ended`` events, and answers are locked until every video ended; a script
can send those events without playing anything. The server therefore keeps its own record: the media
route notes which slots of a page the session requested (``media_requests``), and the time on the page
(first view to answer, measured by the server) is compared with the clips' durations. A page is
**implausible** when a slot was never requested, or (with ``require_full_playback``) when the time on the
page is shorter than ``playback_min_fraction`` (default 1) of its longest clip, or when the bytes the
server sent for a slot (:mod:`study_app.served`) do not cover its whole file. Such pages are flagged in the export
(``playback_implausible``), never refused: the researcher decides (``evalsuite analyze`` can exclude on it).

Durations come from the manifest's ``duration_s`` column when present, otherwise from the file itself
(the ``mvhd`` box of MP4/MOV/M4V files, the header of WAV files), read once per file and kept in memory.
A clip of another format has no known duration: only the request check applies to it.
"""
from __future__ import annotations

import os
import pathlib
import struct
from dataclasses import dataclass

__all__ = ["PlaybackCheck", "check_playback", "media_seconds", "probe_seconds"]

_CACHE: dict[tuple[str, int, int], float | None] = {}


@dataclass(frozen=True)
class PlaybackCheck:
    implausible: bool
    not_requested: tuple[int, ...] = ()      # slots the session never fetched
    min_ms: int | None = None                 # the least plausible time on the page (None: durations unknown)
    reasons: tuple[str, ...] = ()            # why it is implausible, one plain sentence each


def check_playback(n_slots: int, requested: set[int], seconds: list[float | None], rt_ms: int,
                   min_fraction: float, full_playback: bool,
                   served: dict[int, tuple[int, int]] | None = None) -> PlaybackCheck:
    """Judge one answered page with ``n_slots`` media slots (see the module docstring).

    ``served`` maps a slot to (distinct bytes sent, file length); None skips the byte check (no record).
    """
    missing = tuple(k for k in range(n_slots) if k not in requested)
    reasons = [f"unwatched: slot {k} never fetched" for k in missing]
    if served is not None:
        for k in range(n_slots):
            got, total = served.get(k, (0, 0))
            if k not in missing and (total == 0 or got < total):
                reasons.append(f"unwatched: bytes {got:,}/{total:,} served")
        if full_playback and len(reasons) > len(missing):
            # the answer was unlocked by "ended" events for every video, which the bytes contradict
            reasons.append("playback events inconsistent with served bytes")
    known = [s for s in seconds if s is not None]
    min_ms = int(1000 * min_fraction * max(known)) if known and full_playback and min_fraction > 0 else None
    if min_ms is not None and rt_ms < min_ms:
        reasons.append(f"answered {rt_ms / 1000:.1f} s after the page for {max(known):.1f} s of video")
    return PlaybackCheck(implausible=bool(reasons), not_requested=missing, min_ms=min_ms, reasons=tuple(reasons))


def media_seconds(study, file: str) -> float | None:
    """Duration of a stimulus in seconds: the manifest's ``duration_s``, else probed from the file."""
    stim = study.manifest.by_file().get(file)
    if stim is not None and stim.duration_s is not None:
        return stim.duration_s
    return probe_seconds(study.manifest.root / file)


def probe_seconds(path) -> float | None:
    """Duration of an MP4/MOV or WAV file from its header (cached per path, size and time), or None."""
    path = pathlib.Path(path)
    try:
        st = path.stat()
    except OSError:
        return None
    key = (os.fspath(path), st.st_size, st.st_mtime_ns)
    if key not in _CACHE:
        if len(_CACHE) > 10_000:
            _CACHE.clear()
        try:
            with open(path, "rb") as fh:
                head = fh.read(12)
                fh.seek(0)
                if head[:4] == b"RIFF" and head[8:12] == b"WAVE":
                    _CACHE[key] = _wav_seconds(fh)
                else:
                    _CACHE[key] = _mp4_seconds(fh, st.st_size)
        except (OSError, struct.error, ValueError):
            _CACHE[key] = None
    return _CACHE[key]


def _boxes(fh, start: int, end: int):
    """(type, payload start, payload end) of the ISO BMFF boxes between ``start`` and ``end``."""
    pos = start
    for _ in range(10_000):
        if pos + 8 > end:
            return
        fh.seek(pos)
        size, kind = struct.unpack(">I4s", fh.read(8))
        header = 8
        if size == 1:
            size = struct.unpack(">Q", fh.read(8))[0]
            header = 16
        elif size == 0:
            size = end - pos
        if size < header:
            return
        yield kind, pos + header, min(pos + size, end)
        pos += size


def _mp4_seconds(fh, file_size: int) -> float | None:
    for kind, start, end in _boxes(fh, 0, file_size):
        if kind != b"moov":
            continue
        for sub, s, _e in _boxes(fh, start, end):
            if sub != b"mvhd":
                continue
            fh.seek(s)
            version = fh.read(1)[0]
            fh.read(3)
            if version == 1:
                _c, _m, scale, duration = struct.unpack(">QQIQ", fh.read(28))
            else:
                _c, _m, scale, duration = struct.unpack(">IIII", fh.read(16))
            return duration / scale if scale else None
    return None


def _wav_seconds(fh) -> float | None:
    fh.seek(12)
    byte_rate = None
    for _ in range(1000):
        chunk = fh.read(8)
        if len(chunk) < 8:
            return None
        kind, size = struct.unpack("<4sI", chunk)
        if kind == b"fmt ":
            fmt = fh.read(size)
            byte_rate = struct.unpack("<I", fmt[8:12])[0]
            if size % 2:
                fh.read(1)
        elif kind == b"data":
            return size / byte_rate if byte_rate else None
        else:
            fh.seek(size + (size % 2), 1)
    return None
