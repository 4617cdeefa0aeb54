"""A per-joint mean velocity file for the Leaderboard's beat alignment, computed from a training split.

The Leaderboard divides each joint's speed by EMAGE's ``mean_vel_smplxflame_30.npy`` before it looks for motion
beats. EMAGE made that file from every recording of BEAT2's ``smplxflame_30/`` folder: full SMPL-X joint
positions (global orientation, translation, jaw, eyes and expressions applied, each file's own betas), speed by
central differences at 30 fps, the mean over every frame of every file, per joint (55,). This module does the
same for the recordings of one split of ``train_test_split.csv`` (or every file), with the user's SMPL-X model.
"""
from __future__ import annotations

import csv
import os
import pathlib

import numpy as np
from tqdm import tqdm

from evalsuite.errors import InputError
from evalsuite.leaderboard.beats import FPS, mean_velocity
from evalsuite.motion.smplx import read_smplx
from evalsuite.motion.smplx_body import smplx_positions

__all__ = ["split_ids", "mean_velocity_of_split"]


def split_ids(table: str | os.PathLike[str], split: str) -> set[str]:
    """The recordings whose ``type`` is ``split`` in BEAT2's ``train_test_split.csv`` (columns ``id``, ``type``)."""
    with open(table, newline="", encoding="utf-8-sig") as fh:
        rows = list(csv.DictReader(fh))
    if not rows or "id" not in rows[0] or "type" not in rows[0]:
        raise InputError("expected the columns id and type (BEAT2's train_test_split.csv)", path=table, line=1)
    return {r["id"].strip() for r in rows if (r.get("type") or "").strip().lower() == split.lower()}


def mean_velocity_of_split(beat2_dir: str | os.PathLike[str], model_path: str | os.PathLike[str] | None = None,
                           split: str | None = "train", progress: bool = False) -> np.ndarray:
    """Per-joint mean speed (55,) in m/s of the ``split`` recordings of a BEAT2 language folder (``None``: every
    file of ``smplxflame_30/``, as EMAGE did), from full positions with the SMPL-X model ``model_path`` (or
    ``EVALSUITE_SMPLX_MODEL``). Save it with ``np.save`` and pass it as ``--bc-mean-vel``."""
    root = pathlib.Path(beat2_dir)
    folder = root / "smplxflame_30"
    if not folder.is_dir():
        raise InputError("not a BEAT2 language folder: no smplxflame_30/", path=root)
    files = sorted(folder.glob("*.npz"))
    if split is not None:
        wanted = split_ids(root / "train_test_split.csv", split)
        files = [f for f in files if f.stem in wanted]
    if not files:
        raise InputError(f"no recordings of the {split!r} split in smplxflame_30/", path=root)
    positions = (smplx_positions(read_smplx(f, nan="zero"), model_path, mode="full")
                 for f in tqdm(files, desc="mean velocity", unit="file", disable=not progress))
    return mean_velocity(positions, FPS)
