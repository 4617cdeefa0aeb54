"""Which files the GENEA Leaderboard's script scores, and how it reads them.

* Ground truth: every ``<video_id>.npz`` of a folder, or a BEAT2 language folder (``smplxflame_30/`` files of
  the ``test`` split of ``train_test_split.csv``; its ``wave16k/`` and ``sem/`` are then the default speech and
  semantic folders).
* Predictions: the folder's ``.npz`` files grouped by the first five ``_``-separated tokens of the name
  (``2_scott_0_103_103_3`` -> ``2_scott_0_103_103``); a name with fewer tokens is skipped. Within a recording
  the files are in **text order** (``sorted`` paths: ``_10`` before ``_2``), and ``--sampling fixed`` takes the
  first of them, ``all`` every one (the script's ``choose_item``).
* Reading: ``poses`` with NaN read as 0 (the script's ``np.nan_to_num``), betas of the ground truth.
"""
from __future__ import annotations

import os
import pathlib
from dataclasses import dataclass

import numpy as np

from evalsuite.errors import InputError
from evalsuite.leaderboard.meanvel import split_ids
from evalsuite.leaderboard.submission import video_id_of
from evalsuite.motion.smplx import SmplxData, read_smplx

__all__ = ["SAMPLING", "FGD_PAIRINGS", "GroundTruth", "list_ground_truth", "group_predictions", "choose",
           "sample_groups", "read_recording", "LENGTH_WARNING"]

SAMPLING = ("fixed", "all")
FGD_PAIRINGS = ("published", "corrected")
LENGTH_WARNING = 0.2   # the script prints "Frame count mismatch" beyond 20 % of the ground truth's frames
FPS = 30.0


@dataclass(frozen=True)
class GroundTruth:
    """The ground-truth recordings (video id -> file) and the speech/semantic folders found beside them."""

    files: dict[str, pathlib.Path]
    audio_dir: pathlib.Path | None = None
    sem_dir: pathlib.Path | None = None


def list_ground_truth(gt_dir: str | os.PathLike[str]) -> GroundTruth:
    """The ground truth of a folder of ``<video_id>.npz`` or of a BEAT2 language folder (its test split)."""
    root = pathlib.Path(gt_dir)
    if not root.is_dir():
        raise InputError("no such ground-truth folder; expected a folder of <video_id>.npz or a BEAT2 language "
                         "folder (beat_english_v2.0.0/)", path=root)
    folder, wanted, audio, sem = root, None, None, None
    if (root / "smplxflame_30").is_dir():
        folder = root / "smplxflame_30"
        if (root / "train_test_split.csv").is_file():
            wanted = split_ids(root / "train_test_split.csv", "test")
        audio = root / "wave16k" if (root / "wave16k").is_dir() else None
        sem = root / "sem" if (root / "sem").is_dir() else None
    files = {p.stem: p for p in sorted(folder.glob("*.npz")) if wanted is None or p.stem in wanted}
    if not files:
        raise InputError("no ground-truth .npz files" + (" of the test split" if wanted is not None else ""),
                         path=folder)
    return GroundTruth(files, audio, sem)


def group_predictions(folder: str | os.PathLike[str]) -> tuple[dict[str, list[pathlib.Path]], list[str]]:
    """``(groups, skipped)``: video id -> the folder's ``.npz`` files of that recording in text order, and the
    names skipped for having fewer than five ``_`` tokens."""
    root = pathlib.Path(folder)
    if not root.is_dir():
        raise InputError("no such folder of predictions", path=root)
    groups: dict[str, list[pathlib.Path]] = {}
    skipped: list[str] = []
    for path in root.glob("*.npz"):
        vid = video_id_of(path.stem)
        if vid is None:
            skipped.append(path.name)
            continue
        groups.setdefault(vid, []).append(path)
    for vid in groups:
        groups[vid] = sorted(groups[vid], key=os.fspath)
    return dict(sorted(groups.items())), sorted(skipped)


def choose(paths: list[pathlib.Path], sampling: str) -> list[pathlib.Path]:
    """The samples a metric uses: ``fixed`` the first in text order, ``all`` every one (in text order)."""
    if sampling not in SAMPLING:
        raise InputError(f"unknown sampling {sampling!r}; expected one of {', '.join(SAMPLING)}", field="sampling")
    return list(paths[:1]) if sampling == "fixed" else list(paths)


def sample_groups(groups: dict[str, list[pathlib.Path]]) -> dict[str, list[pathlib.Path]]:
    """The files ``sample_div`` uses: names of at least six ``_`` tokens (``<video_id>_<k>``), by recording."""
    out: dict[str, list[pathlib.Path]] = {}
    for vid, paths in groups.items():
        kept = [p for p in paths if len(p.stem.split("_")) >= 6]
        if kept:
            out[vid] = kept
    return out


def read_recording(path: pathlib.Path) -> SmplxData:
    """An SMPL-X file with NaN poses read as 0; the Leaderboard's metrics assume 30 fps."""
    data = read_smplx(path, nan="zero")
    if data.stored.get("pose_width", 165) != 165:
        raise InputError(f"poses are {data.stored['pose_width']} wide; the GENEA Leaderboard's script needs all 55 "
                         "SMPL-X joints, (T, 165)", path=path, field="poses")
    if data.fps != FPS:
        raise InputError(f"mocap_frame_rate is {data.fps:g}; the GENEA Leaderboard's metrics assume {FPS:g} fps "
                         "(BEAT2's smplxflame_30)", path=path, field="mocap_frame_rate")
    return data


def length_warning(video_id: str, gt_frames: int, pred: pathlib.Path, pred_frames: int) -> str | None:
    """The script's "Frame count mismatch" warning (beyond 20 %); it then scores the first min(T_gt, T_pred)."""
    if abs(gt_frames - pred_frames) > gt_frames * LENGTH_WARNING:
        return (f"{pred.name}: {pred_frames} frames against {gt_frames} of the ground truth {video_id} (more than "
                f"{LENGTH_WARNING:.0%} apart); FGD, beat alignment, SRGR and div use the first "
                f"{min(gt_frames, pred_frames)}")
    return None


def betas_of(data: SmplxData) -> np.ndarray:
    """The ground truth's betas, used for the positions of the ground truth and of every prediction."""
    return np.asarray(data.betas, dtype=np.float64)
