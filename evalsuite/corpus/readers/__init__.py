"""Corpus readers: ``load_corpus(path, layout=None)`` for the layouts users have on disk.

Each layout is one function registered by name (:func:`~evalsuite.corpus.readers.base.register_layout`):
``genea2020``, ``genea2022``, ``genea2023`` (also the synthetic speaker's output), ``beat``, ``beat2``,
``zeggs`` and ``folder``. A new layout is one new function with a ``detect`` and a ``read``; see docs/corpus.md. An
installed package adds one with an entry point in the group ``evalsuite.corpus_layouts``; :data:`LAYOUTS`
is the :class:`~evalsuite.registry.Registry`.
"""
from __future__ import annotations

import os
import pathlib

from evalsuite.corpus.readers import genea, takes  # noqa: F401  (registers the built-in layouts)
from evalsuite.corpus.readers.base import (
    LAYOUTS,
    MISMATCH_POLICIES,
    CorpusBuilder,
    ReadOptions,
    current_mismatch_policy,
    mismatch_policy,
    register_layout,
)
from evalsuite.corpus.readers.headers import motion_info, wav_info
from evalsuite.corpus.types import Corpus
from evalsuite.errors import InputError

__all__ = ["load_corpus", "detect_layout", "register_layout", "LAYOUTS", "ReadOptions", "CorpusBuilder",
           "MISMATCH_POLICIES", "mismatch_policy", "wav_info", "motion_info"]


def _known() -> str:
    return "; ".join(f"{name}: {lay.description}" for name, lay in LAYOUTS.items())


def detect_layout(path: str | os.PathLike[str]) -> str:
    """The layout of a corpus folder: the one specific layout whose ``detect`` accepts it, else ``folder``.
    InputError when several match (ambiguous) or none does."""
    root = pathlib.Path(path)
    if not root.is_dir():
        raise InputError("no such corpus folder" if not root.exists() else "expected a corpus folder", path=root)
    hits = [name for name, lay in LAYOUTS.items() if name != "folder" and lay.detect(root)]
    if len(hits) == 1:
        return hits[0]
    if len(hits) > 1:
        raise InputError(f"the folder looks like several layouts ({', '.join(hits)}); name one with "
                         "load_corpus(..., layout=NAME) or `evalsuite corpus info|split --layout NAME`", path=root)
    if "folder" in LAYOUTS and LAYOUTS["folder"].detect(root):
        return "folder"
    raise InputError(f"unknown corpus layout: no layout recognises this folder. Known layouts: {_known()}",
                     path=root)


def load_corpus(path: str | os.PathLike[str], layout: str | None = None, *, on_mismatch: str | None = None,
                tolerance: float = 0.5, tolerance_rel: float = 0.02, motion_fps: float | None = None) -> Corpus:
    """Read a corpus folder into a :class:`~evalsuite.corpus.types.Corpus` (files by path; headers only).

    Args:
        layout: a registered layout name; detected when None (:func:`detect_layout`).
        on_mismatch: a segment whose audio and motion durations differ by more than
            ``max(tolerance, tolerance_rel * the longer)`` seconds: ``'error'`` (InputError naming both files
            and durations), ``'warn'`` (kept, warned, recorded) or ``'skip'`` (left out, recorded). Records are
            in ``corpus.meta['mismatches']`` and ``['skipped']``; missing parts in ``['missing']`` (counts)
            and each ``segment.meta['missing']``. None: the policy of the enclosing
            :func:`~evalsuite.corpus.readers.base.mismatch_policy` (a command's ``--on-mismatch``), else
            ``'error'``.
        motion_fps: frame rate of motion files that store none (``.npy``, ``.csv``).
    """
    root = pathlib.Path(path)
    name = detect_layout(root) if layout is None else layout
    reader = LAYOUTS.get(name)
    if not root.is_dir():
        raise InputError("no such corpus folder", path=root)
    policy, option = current_mismatch_policy()
    builder = CorpusBuilder(root, name, ReadOptions(on_mismatch or policy, tolerance, tolerance_rel, motion_fps,
                                                    option))
    reader.read(root, builder)
    if not builder.segments and not builder.meta["skipped"]:
        raise InputError(f"no segments found for layout {name!r} ({reader.description})", path=root)
    return builder.build()
