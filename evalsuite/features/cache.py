"""The on-disk feature cache, keyed by content.

An entry is ``<cache_dir>/<key[:2]>/<key>.npz`` where ``key`` is the sha256 of the audio content (the
WAV file's bytes, or an array's dtype, shape, rate and bytes), the recipe's name and version, its
parameters and the transcript's words and times. The entry holds the array, the key and the sha256 of the
array's bytes; an entry that cannot be read, or whose key or checksum does not match, is recomputed and
overwritten, never trusted. Entries are written to a temporary file and renamed, so a crash never leaves a
half-written entry under the final name.

Default folder: ``$EVALSUITE_CACHE_DIR``, else ``$XDG_CACHE_HOME/evalsuite/features``, else
``~/.cache/evalsuite/features``.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import pathlib
import tempfile
import zipfile

import numpy as np

from evalsuite.corpus.types import Transcript

__all__ = ["default_cache_dir", "cache_key", "cache_load", "cache_store", "transcript_digest"]

log = logging.getLogger(__name__)


def default_cache_dir() -> pathlib.Path:
    env = os.environ.get("EVALSUITE_CACHE_DIR")
    if env:
        return pathlib.Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return pathlib.Path(base) / "evalsuite" / "features"


def transcript_digest(transcript: Transcript | None) -> str:
    if transcript is None:
        return "none"
    words = [[w.text, repr(float(w.start)), repr(float(w.end)), bool(w.estimated)] for w in transcript.words]
    return hashlib.sha256(json.dumps(words).encode()).hexdigest()


def cache_key(audio_digest: str, recipe: str, version: int, params: str, transcript: Transcript | None,
              fps: float | None = None, n_frames: int | None = None) -> str:
    payload = json.dumps({"audio": audio_digest, "recipe": recipe, "version": version, "params": params,
                          "transcript": transcript_digest(transcript), "fps": fps, "n_frames": n_frames},
                         sort_keys=True)
    return hashlib.sha256(payload.encode()).hexdigest()


def _entry(cache_dir: pathlib.Path, key: str) -> pathlib.Path:
    return pathlib.Path(cache_dir) / key[:2] / f"{key}.npz"


def _checksum(x: np.ndarray) -> str:
    x = np.ascontiguousarray(x)
    return hashlib.sha256(f"{x.dtype.str}|{x.shape}|".encode() + x.tobytes()).hexdigest()


def cache_load(cache_dir: pathlib.Path, key: str) -> np.ndarray | None:
    """The cached array, or ``None`` when absent or not trustworthy (logged at INFO)."""
    path = _entry(cache_dir, key)
    if not path.is_file():
        return None
    try:
        with np.load(path, allow_pickle=False) as z:
            data = np.array(z["data"])
            stored_key = str(z["key"])
            checksum = str(z["sha256"])
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        log.info("feature cache entry %s is unreadable (%s): recomputing", path, exc)
        return None
    if stored_key != key or checksum != _checksum(data):
        log.info("feature cache entry %s does not match its key or checksum: recomputing", path)
        return None
    return data


def cache_store(cache_dir: pathlib.Path, key: str, data: np.ndarray) -> None:
    """Write an entry atomically; a cache folder that cannot be written is skipped with a warning."""
    path = _entry(cache_dir, key)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, data=data, key=np.array(key), sha256=np.array(_checksum(data)))
            os.replace(tmp, path)
        except BaseException:
            if os.path.exists(tmp):
                os.unlink(tmp)
            raise
    except OSError as exc:
        log.warning("cannot write the feature cache entry %s (%s); continuing without it", path, exc)
