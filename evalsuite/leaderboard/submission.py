"""Check a GENEA Leaderboard submission folder against the ground truth before it is sent.

A submission is a folder of SMPL-X ``.npz`` files, one or more samples per test recording, named
``<video_id>_<k>.npz``; the organisers' ``exp_eval_metrics.py`` groups files by the first five ``_``-separated
tokens of the name (``2_scott_0_103_103``). :func:`validate_submission` reads every file with numpy (raw
problems are reported as they are, before any reader would mend them) and returns a
:class:`SubmissionReport`: per file, what is wrong and what was expected, each an error or a warning.

Lengths: the organisers' script only prints a warning when a prediction's frame count differs from the
ground truth's by more than 20 % (:data:`LEADERBOARD_LENGTH_TOLERANCE`) and then scores the first
``min(T_gt, T_pred)`` frames. The Leaderboard asks for motion "equally long" as the speech, so here a
difference of more than ``max(1, length_tolerance * T_gt)`` frames (default 2 %,
:data:`DEFAULT_LENGTH_TOLERANCE`) is an error, and a difference beyond 20 % is also reported as the warning
their script prints.
"""
from __future__ import annotations

import csv
import pathlib
import re
import zipfile
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from tqdm import tqdm

from evalsuite.corpus.readers.headers import motion_info
from evalsuite.errors import InputError

__all__ = ["Problem", "SubmissionReport", "validate_submission", "read_truth", "video_id_of", "LEADERBOARD_LENGTH_TOLERANCE",
           "DEFAULT_LENGTH_TOLERANCE", "POSE_WIDTH", "DEFAULT_FPS"]

LEADERBOARD_LENGTH_TOLERANCE = 0.2  # exp_eval_metrics.py: |T_gt - T_pred| > 0.2 * T_gt prints a warning
DEFAULT_LENGTH_TOLERANCE = 0.02
POSE_WIDTH = 165  # 55 SMPL-X joints x axis-angle
DEFAULT_FPS = 30.0  # BEAT2 smplxflame_30; the organisers' scripts assume it
_OPTIONAL = ("betas", "expressions", "mocap_frame_rate", "model", "gender")
_NUMBER = re.compile(r"^\d+$")


@dataclass(frozen=True)
class Problem:
    """One finding: ``file`` (relative to the submission folder, or ``"(submission)"``), ``severity``
    (``"error"`` or ``"warning"``), a stable ``code``, ``message`` (what is wrong) and ``expected``."""

    file: str
    severity: str
    code: str
    message: str
    expected: str

    def as_dict(self) -> dict[str, str]:
        return {"file": self.file, "severity": self.severity, "code": self.code, "message": self.message,
                "expected": self.expected}


@dataclass
class SubmissionReport:
    """What :func:`validate_submission` found; ``ok`` when there is no error (warnings allowed)."""

    submission: str
    against: str
    files: int = 0
    recordings: int = 0
    samples: dict[str, int] = field(default_factory=dict)
    tolerances: dict[str, Any] = field(default_factory=dict)
    problems: list[Problem] = field(default_factory=list)

    def add(self, file: str, severity: str, code: str, message: str, expected: str) -> None:
        self.problems.append(Problem(file, severity, code, message, expected))

    @property
    def errors(self) -> list[Problem]:
        return [p for p in self.problems if p.severity == "error"]

    @property
    def warnings(self) -> list[Problem]:
        return [p for p in self.problems if p.severity == "warning"]

    @property
    def ok(self) -> bool:
        return not self.errors

    def as_dict(self) -> dict[str, Any]:
        return {"submission": self.submission, "against": self.against, "ok": self.ok, "files": self.files,
                "recordings": self.recordings, "samples_per_recording": self.samples,
                "tolerances": self.tolerances, "errors": len(self.errors), "warnings": len(self.warnings),
                "problems": [p.as_dict() for p in self.problems]}


def video_id_of(stem: str) -> str | None:
    """The recording a file belongs to: its first five ``_``-separated tokens, as the organisers group files
    (``2_scott_0_103_103_3`` -> ``2_scott_0_103_103``); None for a name with fewer than five tokens."""
    parts = stem.split("_")
    return "_".join(parts[:5]) if len(parts) >= 5 else None


@dataclass(frozen=True)
class _Truth:
    frames: int
    fps: float


def _test_ids(table: pathlib.Path) -> set[str] | None:
    """The ``test`` recordings of BEAT2's ``train_test_split.csv`` (columns ``id``, ``type``)."""
    with open(table, newline="", encoding="utf-8-sig") as fh:
        rows = list(csv.DictReader(fh))
    if not rows or "id" not in rows[0] or "type" not in rows[0]:
        raise InputError("expected the columns id and type (BEAT2's train_test_split.csv)", path=table, line=1)
    return {r["id"].strip() for r in rows if (r.get("type") or "").strip().lower() == "test"}


def read_truth(gt_dir: pathlib.Path) -> dict[str, _Truth]:
    """Frames and fps of each ground-truth recording, from the file headers: a folder of ``<video_id>.npz``, or a
    BEAT2 language folder (its ``smplxflame_30/`` files of the ``test`` split of ``train_test_split.csv``)."""
    if not gt_dir.is_dir():
        raise InputError("no such ground-truth folder; expected a folder of <video_id>.npz (the test set) or a "
                         "BEAT2 language folder", path=gt_dir)
    folder, wanted = gt_dir, None
    if (gt_dir / "smplxflame_30").is_dir():
        folder = gt_dir / "smplxflame_30"
        if (gt_dir / "train_test_split.csv").is_file():
            wanted = _test_ids(gt_dir / "train_test_split.csv")
    out: dict[str, _Truth] = {}
    for path in sorted(folder.glob("*.npz")):
        if wanted is not None and path.stem not in wanted:
            continue
        info = motion_info(path, DEFAULT_FPS)
        if info.frames is None:
            raise InputError("no 'poses' array; expected a BEAT2 SMPL-X ground-truth file", path=path)
        out[path.stem] = _Truth(int(info.frames), float(info.fps or DEFAULT_FPS))
    if not out:
        raise InputError("no ground-truth .npz files" + (" of the test split" if wanted is not None else ""),
                         path=folder)
    return out


def _load(path: pathlib.Path, name: str, report: SubmissionReport) -> dict[str, np.ndarray] | None:
    """Every array of one ``.npz`` (no pickles); None, with the error reported, when it cannot be read."""
    try:
        with np.load(path, allow_pickle=False) as npz:
            keys = list(npz.files)
            out: dict[str, np.ndarray] = {}
            for key in keys:
                try:
                    out[key] = npz[key]
                except ValueError as exc:  # an object array (a pickle)
                    sev = "error" if key in ("poses", "trans") else "warning"
                    report.add(name, sev, "unreadable_key", f"the array {key!r} cannot be read without pickle "
                               f"({exc})", "plain numeric or string arrays (np.savez of numpy arrays)")
            return out
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        report.add(name, "error", "unreadable", f"cannot read the file as .npz ({type(exc).__name__}: {exc})",
                   "a NumPy .npz archive written with np.savez")
        return None


def _first_bad(a: np.ndarray, mask: np.ndarray, width: int) -> str:
    frame, col = (int(i) for i in np.argwhere(mask)[0][:2]) if a.ndim == 2 else (int(np.argwhere(mask)[0][0]), 0)
    return f"first at frame {frame}, column {col} = joint {col // 3} from 0" if width == POSE_WIDTH else \
        f"first at frame {frame}"


def _check_array(name: str, key: str, a: np.ndarray, width: int, report: SubmissionReport) -> bool:
    """Shape ``(T, width)``, a float dtype, finite values; False when the shape or dtype is wrong."""
    unit = "55 joints x axis-angle in radians" if key == "poses" else "root translation in metres"
    if a.ndim != 2 or a.shape[1] != width:
        hint = " (flatten the joints: poses.reshape(T, 165))" if a.ndim == 3 and a.shape[1:] == (55, 3) else \
            " (156 = SMPL-X without jaw and eyes: add 9 zero columns after joint 21)" if a.shape[-1:] == (156,) \
            else ""
        report.add(name, "error", "shape", f"{key} has shape {a.shape}{hint}", f"(T, {width}): {unit}")
        return False
    if a.dtype.kind != "f" or a.dtype.itemsize < 4:
        report.add(name, "error", "dtype", f"{key} has dtype {a.dtype}", "float32 or float64")
        return False
    nan, inf = np.isnan(a), np.isinf(a)
    if nan.any():
        report.add(name, "error", "nan", f"{key} has {int(nan.sum())} NaN values ({_first_bad(a, nan, width)}); "
                   "the organisers' loader silently replaces NaN poses by 0 (the rest pose)", "finite numbers only")
    if inf.any():
        report.add(name, "error", "inf", f"{key} has {int(inf.sum())} infinite values ({_first_bad(a, inf, width)})",
                   "finite numbers only")
    return True


def _check_file(path: pathlib.Path, name: str, truth: _Truth | None, length_tolerance: float,
                report: SubmissionReport) -> None:
    data = _load(path, name, report)
    if data is None:
        return
    missing = [k for k in ("poses", "trans") if k not in data]
    if missing:
        report.add(name, "error", "keys", f"no {' and no '.join(repr(k) for k in missing)} array (keys: "
                   f"{', '.join(sorted(data)) or 'none'})", "poses (T, 165) and trans (T, 3), as BEAT2's "
                   "smplxflame_30 files")
    absent = [k for k in _OPTIONAL if k not in data]
    if absent:
        report.add(name, "warning", "optional_keys", f"no {', '.join(absent)}",
                   "the keys of BEAT2's files: betas (300,), expressions (T, 100), mocap_frame_rate 30, "
                   "model 'smplx2020', gender 'neutral'")
    fps = DEFAULT_FPS if truth is None else truth.fps
    if "mocap_frame_rate" in data:
        rate = data["mocap_frame_rate"]
        value = float(rate) if rate.size == 1 and rate.dtype.kind in "fiu" else None
        if value is None or abs(value - fps) > 1e-6:
            report.add(name, "error", "fps", f"mocap_frame_rate is {rate!r}" if value is None else
                       f"mocap_frame_rate is {value:g}", f"{fps:g} (the ground truth's frame rate)")
    poses = data.get("poses")
    if poses is None or not _check_array(name, "poses", poses, POSE_WIDTH, report):
        return
    frames = len(poses)
    if "trans" in data and _check_array(name, "trans", data["trans"], 3, report) and len(data["trans"]) != frames:
        report.add(name, "error", "trans_length", f"trans has {len(data['trans'])} frames but poses {frames}",
                   "one translation per pose frame")
    if frames == 0:
        report.add(name, "error", "empty", "poses has no frames", "as many frames as the ground truth")
        return
    if truth is None:
        return
    diff = abs(frames - truth.frames)
    allowed = max(1, int(length_tolerance * truth.frames))
    if diff > allowed:
        report.add(name, "error", "length", f"{frames} frames ({frames / fps:.2f} s) but the ground truth has "
                   f"{truth.frames} ({truth.frames / fps:.2f} s): {diff} frames apart",
                   f"{truth.frames} frames, within {allowed} ({100 * length_tolerance:g} % of the ground truth, "
                   "at least 1)")
    if diff > LEADERBOARD_LENGTH_TOLERANCE * truth.frames:
        report.add(name, "warning", "length_leaderboard", "more than 20 % longer or shorter than the ground truth: "
                   "the organisers' script prints 'Frame count mismatch' and scores only the first "
                   f"{min(frames, truth.frames)} frames", f"{truth.frames} frames")


def _check_samples(groups: dict[str, list[str]], report: SubmissionReport) -> None:
    counts = Counter(len(files) for files in groups.values())
    if len(counts) > 1:
        common = max(counts, key=lambda n: (counts[n], n))  # the most frequent; the larger on a tie
        for vid, files in sorted(groups.items()):
            if len(files) != common:
                report.add(f"{vid}_*.npz", "error", "sample_count", f"{len(files)} samples "
                           f"({', '.join(files)})", f"{common} samples, as most recordings have (the same number "
                           "for every recording)")
    if groups and max(counts) < 2:
        report.add("(submission)", "warning", "single_sample", "one sample per recording: sample_div (diversity "
                   "across samples) cannot be computed", "at least 2 samples per recording (the Leaderboard asks "
                   "stochastic systems for 5, named <video_id>_<k>.npz)")
    for vid, files in sorted(groups.items()):
        if len(files) > 1 and f"{vid}.npz" in files:
            report.add(f"{vid}.npz", "warning", "sample_name", "a file without a sample suffix beside other samples: "
                       "the organisers' sample_div skips names of fewer than six '_' tokens",
                       f"{vid}_<k>.npz for every sample")
        suffixes = [f[len(vid) + 1:-4].split("_")[-1] for f in files if f != f"{vid}.npz"]
        numbers = [s for s in suffixes if _NUMBER.match(s)]
        if len({len(s) for s in numbers}) > 1:
            first = sorted(files)[0]
            report.add(f"{vid}_*.npz", "warning", "sample_order", f"sample numbers of different widths: files are "
                       f"taken in text order ({', '.join(sorted(files))}), so _10 comes before _2 and 'fixed' "
                       f"sampling uses {first}", "numbers of one width (e.g. _1.._5, or _01.._10)")


def validate_submission(submission: str | pathlib.Path, against: str | pathlib.Path, *,
                        length_tolerance: float = DEFAULT_LENGTH_TOLERANCE, progress: bool = False
                        ) -> SubmissionReport:
    """Check every file of ``submission`` against the ground truth ``against`` (see the module docstring).

    Args:
        submission: the folder of ``<video_id>_<k>.npz`` files.
        against: a folder of ``<video_id>.npz`` ground truth, or a BEAT2 language folder (its test split).
        length_tolerance: the largest frame-count difference that is not an error, as a share of the ground
            truth's frames (at least 1 frame).
        progress: show a progress bar over the files.
    """
    sub, gt = pathlib.Path(submission), pathlib.Path(against)
    if not sub.is_dir():
        raise InputError("no such submission folder; expected a folder of <video_id>_<k>.npz files", path=sub)
    if not length_tolerance >= 0:
        raise InputError(f"expected a share >= 0, got {length_tolerance}", field="--length-tolerance")
    truth = read_truth(gt)
    report = SubmissionReport(str(sub), str(gt), tolerances={
        "length_error_share": length_tolerance, "length_error_min_frames": 1,
        "leaderboard_warning_share": LEADERBOARD_LENGTH_TOLERANCE})
    entries = sorted(sub.iterdir())
    npz = [p for p in entries if p.is_file() and p.suffix == ".npz"]
    for p in entries:
        if p.name.startswith("."):
            continue
        if p.is_dir():
            report.add(p.name + "/", "warning", "ignored", "a sub-folder: the organisers read only the submission "
                       "folder's own .npz files", "every .npz directly in the folder")
        elif p.suffix != ".npz":
            report.add(p.name, "warning", "ignored", "not an .npz file: ignored by the organisers' scripts",
                       "<video_id>_<k>.npz files only")
    if not npz:
        report.add("(submission)", "error", "no_files", "no .npz files", "one <video_id>_<k>.npz per recording "
                   f"and sample ({len(truth)} recordings)")
    groups: dict[str, list[str]] = {}
    for p in npz:
        vid = video_id_of(p.stem)
        if vid is None:
            report.add(p.name, "error", "name", "the name has fewer than five '_'-separated tokens, so it names no "
                       "recording (the organisers skip it)", "<video_id>_<k>.npz, e.g. 2_scott_0_103_103_1.npz")
        elif vid not in truth:
            near = sorted(truth)[:3]
            report.add(p.name, "error", "unknown_recording", f"{vid} is not a recording of the ground truth",
                       f"one of the {len(truth)} test recordings (e.g. {', '.join(near)})")
        else:
            groups.setdefault(vid, []).append(p.name)
    for vid in sorted(set(truth) - set(groups)):
        report.add(f"{vid}_*.npz", "error", "missing_recording", f"no file for {vid} (the organisers' script stops "
                   "at a missing prediction)", f"{vid}_1.npz .. {vid}_<k>.npz")
    _check_samples(groups, report)
    report.files, report.recordings = len(npz), len(groups)
    report.samples = {vid: len(files) for vid, files in sorted(groups.items())}
    for p in tqdm(npz, desc="checking files", unit="file", disable=not progress):
        vid = video_id_of(p.stem)
        _check_file(p, p.name, truth.get(vid) if vid else None, length_tolerance, report)
    report.problems.sort(key=lambda q: (q.file != "(submission)", q.file, q.severity != "error"))
    return report
