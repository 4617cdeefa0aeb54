"""The feature-recipe registry, the audio a recipe reads, and the frame-rate and length rules.

A recipe is one :class:`Recipe` instance registered with :func:`register_recipe` (the built-in recipes
register themselves when :mod:`evalsuite.features` is imported; an installed package adds one with an entry
point in the group ``evalsuite.feature_recipes``). :data:`RECIPES` is the
:class:`~evalsuite.registry.Registry`. :func:`extract` runs one by name.

Rules every recipe follows (documented in ``docs/features.md``):

* **Output**: float32 ``(T, D)`` (the Aud2Repr2Pose windows: ``(T, 61, 30)``); frame ``t`` belongs to time
  ``t / fps`` (each recipe's docstring says whether its analysis window starts or is centred there).
* **Frame rate**: a recipe has a fixed ``native_fps`` or computes at any rate (``native_fps is None``, the
  text recipes). A fixed-rate recipe asked for another ``fps`` is **resampled by linear interpolation in
  time**: output frame ``t`` is the native track read at position ``t * native_fps / fps`` (beyond the last
  native frame: the last frame), and ``floor(T_native * fps / native_fps)`` frames cover the same duration.
  Asked for a rate that divides the native one (Ferstl's 100 -> 20 fps), this picks native frames
  ``[0::k]`` exactly.
* **Length**: with ``n_frames`` the output is cropped, or padded by repeating its last frame, to exactly
  that many frames (so features line up with motion frames).
"""
from __future__ import annotations

import hashlib
import json
import os
import pathlib
import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Union

import numpy as np

from evalsuite.audio import read_wav
from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError
from evalsuite.registry import Registry

__all__ = ["RECIPES", "Audio", "AudioInput", "Recipe", "register_recipe", "get_recipe", "list_recipes", "load_audio",
           "resample_frames", "fit_length"]

AudioInput = Union[str, "os.PathLike[str]", tuple]  # noqa: UP007  (a runtime alias: Python 3.10 cannot | a string)


@dataclass(frozen=True)
class Audio:
    """Speech audio as a recipe sees it.

    ``samples`` is ``(N, C)`` exactly as ``scipy.io.wavfile.read`` gives it for a file (int16 stays int16:
    the reference code computes on that scale) or as the caller passed it; ``path`` is the file when there
    is one (Praat-based recipes read it)."""

    samples: np.ndarray
    rate: int
    path: pathlib.Path | None = None

    @property
    def duration(self) -> float:
        return len(self.samples) / float(self.rate)

    def float_samples(self) -> np.ndarray:
        """``(N, C)`` float64 in [-1, 1): integers scaled by ``2 ** (bits - 1)`` as :func:`read_wav` does."""
        x = self.samples
        if x.dtype == np.uint8:
            return (x.astype(np.float64) - 128.0) / 128.0
        if x.dtype.kind == "i":
            return x.astype(np.float64) / float(np.iinfo(x.dtype).max + 1)
        return x.astype(np.float64)

    def mono(self) -> np.ndarray:
        """``(N,)`` float64 in [-1, 1): channels averaged in floating point."""
        return self.float_samples().mean(axis=1)

    def digest(self) -> str:
        """sha256 of the audio content: the file's bytes, or the array's dtype, shape, rate and bytes."""
        h = hashlib.sha256()
        if self.path is not None:
            with open(self.path, "rb") as fh:
                for block in iter(lambda: fh.read(1 << 20), b""):
                    h.update(block)
            return "file:" + h.hexdigest()
        x = np.ascontiguousarray(self.samples)
        h.update(f"{x.dtype.str}|{x.shape}|{self.rate}|".encode())
        h.update(x.tobytes())
        return "array:" + h.hexdigest()


def load_audio(audio: AudioInput | Audio) -> Audio:
    """A path to a WAV file, or ``(samples, rate)`` with samples ``(N,)`` or ``(N, C)`` -> :class:`Audio`."""
    if isinstance(audio, Audio):
        return audio
    if isinstance(audio, tuple):
        if len(audio) != 2:
            raise InputError(f"audio must be a WAV path or (samples, rate), got a tuple of {len(audio)} items")
        samples, rate = audio
        x = np.asarray(samples)
        if x.ndim == 1:
            x = x[:, None]
        if x.ndim != 2 or x.shape[0] == 0 or x.shape[1] == 0:
            raise InputError(f"audio samples must have shape (N,) or (N, C) with N, C >= 1, got {np.shape(samples)}")
        if x.dtype.kind not in "iuf":
            raise InputError(f"audio samples must be integers or floats, got {x.dtype}")
        if x.dtype.kind == "f" and not np.isfinite(x).all():
            raise InputError("audio samples must be finite (found NaN or infinity)")
        if isinstance(rate, bool) or not isinstance(rate, (int, np.integer)) or rate <= 0:
            raise InputError(f"the sample rate must be a positive integer, got {rate!r}")
        return Audio(x, int(rate))
    path = pathlib.Path(os.fspath(audio))
    try:
        samples, rate = read_wav(path, raw=True)
    except (UnboundLocalError, IndexError, struct.error) as exc:   # scipy on some truncated headers
        raise InputError(f"not a readable WAV file ({type(exc).__name__}: {exc})", path=path) from None
    return Audio(samples, rate, path)


@dataclass
class Recipe:
    """One way of computing features, by name.

    ``compute(audio, transcript, fps, n_frames, options)`` returns the native-rate array (``fps`` is given
    only to recipes with ``native_fps is None``, which compute at any rate; ``resamplable=False`` refuses
    any other rate); ``dim`` is the feature dimension (or
    the shape of one frame). ``reproduces`` cites what it reproduces, ``quirks`` lists the reference code's
    quirks it keeps (or where it may differ), ``extra`` names the optional extra it needs (``None``: the
    core install). ``version`` goes into the cache key: bump it when the numbers change."""

    name: str
    native_fps: float | None
    dim: int | tuple[int, ...]
    reproduces: str
    quirks: str
    compute: Callable[..., np.ndarray]
    extra: str | None = None
    version: int = 1
    needs_audio: bool = True
    needs_transcript: bool = False
    default_fps: float | None = None
    resamplable: bool = True
    params: dict[str, Any] = field(default_factory=dict)

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, "native_fps": self.native_fps, "dim": self.dim, "reproduces": self.reproduces,
                "quirks": self.quirks, "extra": self.extra, "version": self.version,
                "needs_audio": self.needs_audio, "needs_transcript": self.needs_transcript}

    def key_params(self, params: dict[str, Any]) -> str:
        return json.dumps({**self.params, **params}, sort_keys=True, default=str)


RECIPES: Registry[Recipe] = Registry("feature recipe", "evalsuite.feature_recipes", base=Recipe,
                                     name_of=lambda r: r.name, field="recipe")


def register_recipe(recipe: Recipe, *, replace: bool = False) -> Recipe:
    """Add a recipe; its name must be new (``replace=True`` swaps an existing one)."""
    return RECIPES.register(recipe.name, recipe, replace=replace)


def get_recipe(name: str) -> Recipe:
    return RECIPES.get(name)


def list_recipes() -> list[Recipe]:
    """The registered recipes (installed plug-ins included), sorted by name."""
    recipes = RECIPES.loaded()
    return [recipes[n] for n in sorted(recipes)]


def resample_frames(x: np.ndarray, native_fps: float, fps: float) -> np.ndarray:
    """The documented rule: linear interpolation in time from ``native_fps`` to ``fps`` along axis 0."""
    if fps <= 0 or not np.isfinite(fps):
        raise InputError(f"the frame rate must be a positive number, got {fps!r}", field="fps")
    if abs(fps - native_fps) <= 1e-9 * native_fps or len(x) == 0:
        return x
    n_out = max(int(np.floor(len(x) * fps / native_fps + 1e-9)), 1)
    pos = np.arange(n_out) * (native_fps / fps)
    pos = np.minimum(pos, len(x) - 1)
    lo = np.floor(pos).astype(np.int64)
    hi = np.minimum(lo + 1, len(x) - 1)
    w = (pos - lo).reshape((-1,) + (1,) * (x.ndim - 1))
    xf = x.astype(np.float64)
    return (1.0 - w) * xf[lo] + w * xf[hi]


def fit_length(x: np.ndarray, n_frames: int) -> np.ndarray:
    """Crop to ``n_frames``, or pad by repeating the last frame (zeros if there is none)."""
    if isinstance(n_frames, bool) or int(n_frames) != n_frames or n_frames < 0:
        raise InputError(f"n_frames must be a non-negative integer, got {n_frames!r}", field="n_frames")
    n = int(n_frames)
    if len(x) >= n:
        return x[:n]
    if len(x) == 0:
        return np.zeros((n,) + x.shape[1:], dtype=x.dtype)
    pad = np.repeat(x[-1:], n - len(x), axis=0)
    return np.concatenate([x, pad], axis=0)


def check_transcript(recipe: Recipe, transcript: Transcript | None) -> None:
    if recipe.needs_transcript and transcript is None:
        raise InputError(f"recipe {recipe.name!r} computes text features: give a transcript", field="transcript")
