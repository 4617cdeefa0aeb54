"""Stimulus files of equal size: a file's size must not tell a participant which condition it shows.

A still clip (``mean_pose``) compresses to a few kilobytes, a noisy attention check to a hundred times more;
anyone who opens the browser's network panel sees the sizes. Two remedies, used by ``render stimuli``
(config key ``equal_size``):

* ``cbr``: constant-bitrate H.264 (:data:`CBR_PARAMS`: x264's ``nal-hrd=cbr`` fills a clip that needs fewer
  bits with filler data), so clips of one length come out about equally large; then ``pad`` evens out what is
  left (a clip too complex for the bitrate overshoots it);
* ``pad``: every file of a group (the stimuli and attention checks of one segment, which is what one study page
  shows) is brought to the same size by a trailing top-level ``free`` box (ISO/IEC 14496-12 4.1: a box whose
  contents are ignored; players and browsers skip it). The box starts with :data:`MARKER`, so padding is
  replaced, not stacked, when the group's largest file changes.
"""
from __future__ import annotations

import os
import pathlib
import struct
from collections.abc import Iterable

__all__ = ["cbr_params", "content_size", "pad_to", "pad_group", "MARKER"]

MARKER = b"evalsuite-padding\x00"
_HEADER = 8


def cbr_params(bitrate: str) -> list[str]:
    """ffmpeg output options for constant-bitrate x264 at ``bitrate`` (e.g. ``"400k"``)."""
    return ["-b:v", bitrate, "-minrate", bitrate, "-maxrate", bitrate, "-bufsize", bitrate,
            "-x264-params", "nal-hrd=cbr:force-cfr=1"]


def _boxes(path: pathlib.Path) -> list[tuple[int, bytes, int]]:
    """Top-level boxes of an MP4 file: ``(offset, type, size)``."""
    out = []
    total = path.stat().st_size
    with open(path, "rb") as fh:
        offset = 0
        while offset + _HEADER <= total:
            fh.seek(offset)
            size, kind = struct.unpack(">I4s", fh.read(_HEADER))
            if size == 1:
                size = struct.unpack(">Q", fh.read(8))[0]
            elif size == 0:
                size = total - offset
            if size < _HEADER or offset + size > total:
                raise ValueError(f"{path}: not an MP4 file (bad box at byte {offset})")
            out.append((offset, kind, size))
            offset += size
    return out


def content_size(path) -> int:
    """The file's size without padding this module added."""
    path = pathlib.Path(path)
    boxes = _boxes(path)
    if boxes and boxes[-1][1] == b"free":
        offset, _, size = boxes[-1]
        with open(path, "rb") as fh:
            fh.seek(offset + _HEADER)
            if fh.read(len(MARKER)) == MARKER:
                return offset
    return path.stat().st_size


def pad_to(path, size: int) -> bool:
    """Make ``path`` exactly ``size`` bytes with a trailing padding box (replacing padding it had); returns
    whether the file changed. ``size`` must leave room for the box: at least the content plus 26 bytes."""
    path = pathlib.Path(path)
    content = content_size(path)
    box = size - content
    if box < _HEADER + len(MARKER):
        raise ValueError(f"{path}: cannot pad {content} bytes to {size}; the padding box needs "
                         f"{_HEADER + len(MARKER)} bytes")
    if path.stat().st_size == size:
        return False
    with open(path, "r+b") as fh:
        fh.truncate(content)
        fh.seek(content)
        fh.write(struct.pack(">I4s", box, b"free") + MARKER)
        fh.write(bytes(box - _HEADER - len(MARKER)))
        fh.flush()
        os.fsync(fh.fileno())
    return True


def pad_group(paths: Iterable) -> int:
    """Pad every file of ``paths`` to the size of the largest (without padding) plus one padding box; returns
    the common size."""
    paths = [pathlib.Path(p) for p in paths]
    target = max(content_size(p) for p in paths) + _HEADER + len(MARKER)
    for p in paths:
        pad_to(p, target)
    return target
