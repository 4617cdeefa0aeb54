"""Where operators get their motion from, and fitting a motion to a request.

An operator (``mismatched``, ``mean_pose``, the degradations, ``smoothed`` …) applies to a *source*
condition named by its option ``of``: ``natural`` (the default: the corpus segment's own motion) or a folder
of motion files keyed by segment id (``<segment>.bvh|.npz|…``, or ``<segment>_<k>.*`` for sample k), such as
another generator's output or a released challenge submission.
"""
from __future__ import annotations

import pathlib
from typing import Any

import numpy as np

from evalsuite.generators.contract import GenerationRequest, GeneratorError
from evalsuite.motion import Motion
from evalsuite.motion.io import list_motion_files, load_motion
from evalsuite.motion.ops import resample

__all__ = ["OF_OPTION", "source_path", "source_motion", "fit_to_request", "folder_files"]

OF_OPTION = {"of": "the source condition: 'natural' (default: the corpus's motion) or a folder of motion files "
                   "named by segment id"}

_FOLDERS: dict[str, dict[str, pathlib.Path]] = {}


def folder_files(folder: str | pathlib.Path) -> dict[str, pathlib.Path]:
    """Motion files of a folder by stem (listed once per process)."""
    key = str(pathlib.Path(folder).resolve())
    if key not in _FOLDERS:
        path = pathlib.Path(folder)
        if not path.is_dir():
            raise GeneratorError(f"no such folder {folder}", field="of")
        _FOLDERS[key] = list_motion_files(path)
    return _FOLDERS[key]


def source_path(of: Any, req: GenerationRequest) -> pathlib.Path:
    """The source condition's motion file of the request's segment (sample ``req.sample`` where a folder has
    several samples per segment)."""
    if of in (None, "", "natural"):
        if req.segment is None or req.segment.motion is None:
            raise GeneratorError(f"segment {req.segment_id!r} has no natural motion (give --corpus with motion, "
                                 "or a source folder with the option 'of')")
        return pathlib.Path(req.segment.motion)
    files = folder_files(of)
    for stem in (f"{req.segment_id}_{req.sample}", req.segment_id):
        if stem in files:
            return files[stem]
    raise GeneratorError(f"no motion file for segment {req.segment_id!r} in {of} "
                         f"(expected {req.segment_id}.bvh/.npz or {req.segment_id}_{req.sample}.*)", field="of")


def source_motion(of: Any, req: GenerationRequest) -> Motion:
    """The motion of :func:`source_path`."""
    return load_motion(source_path(of, req))


def fit_to_request(motion: Motion, req: GenerationRequest) -> Motion:
    """Resampled to ``req.fps`` and cropped to ``req.n_frames`` (a shorter motion holds its last frame),
    so operators hand the runner exactly what was asked for."""
    m = resample(motion, req.fps)
    n = req.n_frames
    if m.n_frames == n:
        return m
    idx = np.minimum(np.arange(n), m.n_frames - 1)
    return m.with_values(m.values[idx]) if m.is_hierarchical else m.with_positions(m.positions()[idx])
