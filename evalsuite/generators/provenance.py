"""Provenance of generated motion: package versions, the model folder's hash, the inputs' hashes."""
from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import pathlib
import platform
from collections.abc import Sequence
from typing import Any

from evalsuite._version import __version__
from evalsuite.errors import InputError
from evalsuite.generators.contract import GenerationRequest
from evalsuite.hashing import file_sha256

__all__ = ["package_versions", "model_sha256", "describe_inputs", "PACKAGES"]

# The packages whose versions can change generated numbers.
PACKAGES = ("numpy", "scipy", "torch", "python_speech_features", "praat-parselmouth", "tokenizers", "safetensors")


@functools.lru_cache(maxsize=1)
def package_versions() -> dict[str, str]:
    """``{"python": ..., "evalsuite": ..., package: version}`` for the installed packages of :data:`PACKAGES`."""
    out = {"python": platform.python_version(), "evalsuite": __version__}
    for name in PACKAGES:
        try:
            out[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            continue
    return out


def model_sha256(path: pathlib.Path) -> str:
    """sha256 over a model folder's files (relative path and content, sorted), or of a single file."""
    if path.is_file():
        return file_sha256(path)
    if not path.is_dir():
        raise InputError("no such model folder or file", path=path, field="--model")
    h = hashlib.sha256()
    for f in sorted(p for p in path.rglob("*") if p.is_file()):
        h.update(f.relative_to(path).as_posix().encode() + b"\0" + bytes.fromhex(file_sha256(f)))
    return h.hexdigest()


@functools.lru_cache(maxsize=4096)
def _audio_hash(path: str, mtime_ns: int, size: int) -> str:
    return file_sha256(path)


def describe_inputs(requests: Sequence[GenerationRequest]) -> list[dict[str, Any]]:
    """Per request: segment, duration, fps, the audio's sha256 and the transcript's words (what a generator
    may read), so that the cache key changes when any input changes."""
    rows = []
    for r in requests:
        audio = None
        if r.audio is not None and pathlib.Path(r.audio).is_file():
            st = pathlib.Path(r.audio).stat()
            audio = _audio_hash(str(r.audio), st.st_mtime_ns, st.st_size)
        words = [[w.text, round(w.start, 6), round(w.end, 6)] for w in r.transcript.words] if r.transcript else None
        motion = None
        if r.segment is not None and r.segment.motion is not None and pathlib.Path(r.segment.motion).is_file():
            st = pathlib.Path(r.segment.motion).stat()
            motion = _audio_hash(str(r.segment.motion), st.st_mtime_ns, st.st_size)
        rows.append({"segment": r.segment_id, "duration": round(r.duration, 6), "fps": r.fps, "audio_sha256": audio,
                     "transcript": words, "speaker": r.speaker, "motion_sha256": motion})
    return rows
