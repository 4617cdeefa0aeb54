""":func:`extract`: run a recipe by name through the cache, then apply the frame-rate and length rules of
:mod:`evalsuite.features.base`."""
from __future__ import annotations

import logging
import os
import pathlib
from typing import Any

import numpy as np

from evalsuite.corpus.types import Transcript
from evalsuite.errors import InputError
from evalsuite.features.base import (
    Audio,
    AudioInput,
    check_transcript,
    fit_length,
    get_recipe,
    load_audio,
    resample_frames,
)
from evalsuite.features.cache import cache_key, cache_load, cache_store, default_cache_dir

__all__ = ["extract"]

log = logging.getLogger(__name__)


def extract(name: str, audio: AudioInput | Audio | None, *, fps: float | None = None, n_frames: int | None = None,
            transcript: Transcript | None = None, cache: bool = True,
            cache_dir: str | os.PathLike[str] | None = None, dtype: Any = np.float32,
            **params: Any) -> np.ndarray:
    """Features of ``audio`` (a WAV path or ``(samples (N, C), rate)``) by recipe ``name``: float32
    ``(T, D)`` (``(T, 61, 30)`` for ``aud2repr2pose_demo_windows``).

    ``fps``: the frame rate wanted (``None``: the recipe's native rate, or its default for text recipes);
    frame ``t`` belongs to time ``t / fps``. ``n_frames``: crop or edge-pad to exactly that many frames.
    ``transcript``: the words with times, for text recipes. ``params``: recipe options (see each recipe).
    ``cache``/``cache_dir``: the content-hash cache (default folder:
    :func:`evalsuite.features.cache.default_cache_dir`; entries keep the recipe's full float64 precision).
    ``dtype``: float32 by default; ``np.float64`` for comparisons with reference arrays."""
    recipe = get_recipe(name)
    check_transcript(recipe, transcript)
    unknown = sorted(set(params) - set(recipe.params))
    if unknown:
        known = ", ".join(sorted(recipe.params)) or "none"
        raise InputError(f"recipe {name!r} has no option {', '.join(unknown)} (its options: {known})",
                         field=unknown[0])
    if n_frames is not None and (isinstance(n_frames, bool) or not isinstance(n_frames, (int, np.integer))
                                 or n_frames < 0):
        raise InputError(f"n_frames must be a non-negative integer, got {n_frames!r}", field="n_frames")
    if fps is not None and (isinstance(fps, bool) or not isinstance(fps, (int, float, np.number))
                            or not np.isfinite(fps) or fps <= 0):
        raise InputError(f"the frame rate must be a positive number, got {fps!r}", field="fps")
    if fps is not None and recipe.native_fps is not None and not recipe.resamplable \
            and abs(fps - recipe.native_fps) > 1e-9:
        raise InputError(f"recipe {name!r} gives {recipe.native_fps:g} fps only, not {fps:g}", field="fps")
    loaded: Audio | None = None
    if audio is not None:
        loaded = load_audio(audio)
    elif recipe.needs_audio:
        raise InputError(f"recipe {name!r} computes speech features: give audio", field="audio")
    elif n_frames is None and transcript is None:
        raise InputError("give audio, a transcript or n_frames to know how many frames to compute")

    compute_fps = None
    if recipe.native_fps is None:
        compute_fps = float(fps if fps is not None else (recipe.default_fps or 20.0))

    data: np.ndarray | None = None
    key = None
    folder = pathlib.Path(cache_dir) if cache_dir is not None else default_cache_dir()
    if cache:
        digest = loaded.digest() if loaded is not None else f"frames:{n_frames}"
        # recipes computed at the rate asked also compute exactly n_frames: both are part of the key
        frames = n_frames if recipe.native_fps is None else None
        key = cache_key(digest, recipe.name, recipe.version, recipe.key_params(params), transcript, compute_fps,
                        frames)
        data = cache_load(folder, key)
    if data is None:
        opts = {**recipe.params, **params}
        data = np.asarray(recipe.compute(loaded, transcript, compute_fps, n_frames, opts), dtype=np.float64)
        if cache and key is not None:
            cache_store(folder, key, data)

    if recipe.native_fps is not None and fps is not None and abs(fps - recipe.native_fps) > 1e-9 * fps:
        log.info("%s: resampled from %.6g to %.6g fps by linear interpolation in time", name, recipe.native_fps, fps)
        data = resample_frames(data, recipe.native_fps, float(fps))
    if n_frames is not None:
        data = fit_length(data, n_frames)
    return np.ascontiguousarray(data, dtype=dtype)
