"""Durations from file headers, without loading samples or frames: WAV (RIFF ``fmt``/``data`` chunks) and
BVH (``Frames:`` x ``Frame Time:``); evalsuite ``.npz``/``.npy`` positions from the array header."""
from __future__ import annotations

import os
import pathlib
import struct
import zipfile
from dataclasses import dataclass
from typing import Any

import numpy as np

from evalsuite.errors import InputError

__all__ = ["AudioInfo", "MotionInfo", "wav_info", "motion_info"]


@dataclass(frozen=True)
class AudioInfo:
    rate: int
    channels: int
    duration: float


@dataclass(frozen=True)
class MotionInfo:
    fps: float | None
    frames: int | None
    duration: float | None


def wav_info(path: str | os.PathLike[str]) -> AudioInfo:
    """Sample rate, channels and duration from a WAV header (PCM, float and extensible formats)."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError("no such audio file", path=path)
    with open(path, "rb") as fh:
        head = fh.read(12)
        if len(head) < 12 or head[:4] not in (b"RIFF", b"RF64") or head[8:12] != b"WAVE":
            raise InputError("not a WAV file: expected a RIFF/WAVE header", path=path)
        fmt: tuple[int, int, int] | None = None
        size = path.stat().st_size
        while True:
            chunk = fh.read(8)
            if len(chunk) < 8:
                raise InputError("the WAV file has no 'data' chunk", path=path)
            cid, clen = chunk[:4], struct.unpack("<I", chunk[4:])[0]
            if cid == b"fmt ":
                body = fh.read(clen)
                if len(body) < 16:
                    raise InputError("the WAV 'fmt ' chunk is too short", path=path)
                _, channels, rate, _, block = struct.unpack("<HHIIH", body[:14])
                fmt = (channels, rate, block)
                if clen % 2:
                    fh.seek(1, 1)
            elif cid == b"data":
                if fmt is None:
                    raise InputError("the WAV 'data' chunk comes before its 'fmt ' chunk", path=path)
                channels, rate, block = fmt
                if rate <= 0 or block <= 0 or channels <= 0:
                    raise InputError(f"the WAV header gives rate {rate}, {channels} channels, block size {block}",
                                     path=path)
                available = size - fh.tell()
                n_bytes = min(clen, available) if clen != 0xFFFFFFFF else available
                return AudioInfo(int(rate), int(channels), (n_bytes // block) / float(rate))
            else:
                fh.seek(clen + (clen % 2), 1)


def _bvh_info(path: pathlib.Path) -> MotionInfo:
    frames: int | None = None
    with open(path, "rb") as fh:
        for n, raw in enumerate(fh, start=1):
            line = raw.decode("utf-8", "replace").strip()
            low = line.lower()
            if low.startswith("frames:"):
                try:
                    frames = int(line.split(":", 1)[1])
                except ValueError:
                    raise InputError(f"expected 'Frames: <count>', found {line!r}", path=path, line=n) from None
            elif low.startswith("frame time:"):
                try:
                    ft = float(line.split(":", 1)[1])
                except ValueError:
                    raise InputError(f"expected 'Frame Time: <seconds>', found {line!r}", path=path,
                                     line=n) from None
                if frames is None or not ft > 0:
                    raise InputError(f"expected 'Frames: N' before a positive 'Frame Time', found {line!r}",
                                     path=path, line=n)
                fps = 1.0 / ft
                if abs(fps - round(fps)) < 0.01:  # 0.03333 as written for 30 fps
                    fps = float(round(fps))
                return MotionInfo(fps, frames, frames / fps)
    raise InputError("no 'Frames:' and 'Frame Time:' lines; expected a BVH file with a MOTION section", path=path)


def _npy_shape(fh: Any) -> tuple[int, ...]:
    """The shape in a ``.npy`` header (public numpy readers; versions 1 and 2, version 3 is 2 in UTF-8)."""
    major, _ = np.lib.format.read_magic(fh)
    read = np.lib.format.read_array_header_1_0 if major == 1 else np.lib.format.read_array_header_2_0
    shape, _, _ = read(fh)
    return tuple(int(n) for n in shape)


def motion_info(path: str | os.PathLike[str], fps: float | None = None) -> MotionInfo:
    """Frame rate, frames and duration of a motion file from its header. ``.npy``/``.csv`` files store no
    rate: ``fps`` supplies it (else the duration is unknown, None)."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError("no such motion file", path=path)
    suffix = path.suffix.lower()
    try:
        if suffix == ".bvh":
            return _bvh_info(path)
        if suffix == ".npy":
            with open(path, "rb") as fh:
                frames = _npy_shape(fh)[0]
        elif suffix == ".npz":
            with zipfile.ZipFile(path) as zf:
                names = zf.namelist()
                # evalsuite's positions/fps; BEAT2's SMPL-X poses/mocap_frame_rate; else a single array
                key = next((k for k in ("positions.npy", "poses.npy") if k in names),
                           names[0] if len(names) == 1 else None)
                if key is None:
                    return MotionInfo(fps, None, None)
                with zf.open(key) as fh:
                    frames = _npy_shape(fh)[0]
                rate_key = next((k for k in ("fps.npy", "mocap_frame_rate.npy") if k in names), None)
                if rate_key is not None:  # the file's own rate wins over a default for files without one
                    with zf.open(rate_key) as fh:
                        fps = float(np.lib.format.read_array(fh))
        elif suffix == ".csv":
            with open(path, "rb") as fh:
                frames = max(0, sum(1 for line in fh if line.strip()) - 1)
        else:
            raise InputError(f"unknown motion file type {path.suffix!r}", path=path)
    except InputError:
        raise
    except (ValueError, OSError, zipfile.BadZipFile, IndexError) as exc:
        raise InputError(f"cannot read the motion file's header ({exc})", path=path) from None
    return MotionInfo(fps, frames, frames / fps if fps else None)
