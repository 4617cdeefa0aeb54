"""Score condition folders as the GENEA Leaderboard does: :func:`score_leaderboard` (one DataFrame) and
:func:`evaluate_leaderboard` (with per-sequence values and warnings), behind ``evalsuite score --preset
genea-leaderboard``.

Per recording r (ground truth g, T_g frames, betas of g) and each sample p used (``--sampling``), t = min(T_g, T_p):
``fid_g``, ``fid_k`` and ``var_k`` take g and p at full length; ``fgd``, ``bc_*``, ``div`` and ``srgr`` take the
first t frames. FGD: the first sample's latents go to one side and g's (cut to that t) to the other; with
``--fgd-pairing published`` the later samples join the ground truth's side (the script calls
``update(gt, pred)`` then ``update_pred`` for samples 2..k), with ``corrected`` the predictions' side.
"""
from __future__ import annotations

import dataclasses
import os
import pathlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from evalsuite.errors import InputError
from evalsuite.leaderboard import beats as bc
from evalsuite.leaderboard import metrics as lm
from evalsuite.leaderboard.bootstrap import Pieces, leaderboard_bootstrap, pooled_gaussian, recording_bootstrap
from evalsuite.leaderboard.files import (
    FGD_PAIRINGS,
    SAMPLING,
    GroundTruth,
    betas_of,
    choose,
    group_predictions,
    length_warning,
    list_ground_truth,
    read_recording,
    sample_groups,
)
from evalsuite.motion.smplx import SmplxData
from evalsuite.motion.smplx_body import model_missing_message, optional_model_path, smplx_positions

__all__ = ["METRICS", "LeaderboardOptions", "LeaderboardResult", "evaluate_leaderboard", "score_leaderboard"]

METRICS = ("fgd", "fid_g", "fid_k", "var_k", "sample_div", "bc_a2m", "bc_m2a", "div", "srgr")
_INFO = {"fgd": ("", "lower"), "fid_g": ("", "lower"), "fid_k": ("", "lower"), "var_k": ("rad^2", "closer to natural"),
         "sample_div": ("rad^2", "higher"), "bc_a2m": ("", "closer to natural"), "bc_m2a": ("", "closer to natural"),
         "div": ("m", "closer to natural"), "srgr": ("", "higher")}


@dataclass
class LeaderboardOptions:
    """The choices of a run (defaults: the Leaderboard's)."""

    sampling: str = "fixed"
    fgd_pairing: str = "published"
    audio_dir: str | os.PathLike[str] | None = None
    sem_dir: str | os.PathLike[str] | None = None
    mean_vel: str | os.PathLike[str] | np.ndarray | None = None
    fgd_model: str | os.PathLike[str] | None = None
    smplx_model: str | os.PathLike[str] | None = None
    metrics: Sequence[str] | None = None
    bootstrap: int = 0
    seed: int = 0
    progress: bool = False
    published_threshold_frame: bool = True


@dataclass
class LeaderboardResult:
    summary: pd.DataFrame
    per_sequence: pd.DataFrame
    issues: list[str] = field(default_factory=list)
    settings: dict[str, Any] = field(default_factory=dict)


def _samples_column(metric: str, sampling: str) -> str:
    if metric == "sample_div":
        return "all"
    if sampling == "fixed":
        return "first"
    return "all" if metric in ("fgd", "fid_g", "fid_k") else "each"


def _wanted(options: LeaderboardOptions, gt: GroundTruth, model: pathlib.Path | None, issues: list[str]
            ) -> tuple[set[str], pathlib.Path | None, pathlib.Path | None]:
    """The metrics to compute, the speech and the semantic folder; a metric asked for by name whose input is
    missing is an error, otherwise it is left out with a warning."""
    if options.sampling not in SAMPLING:
        raise InputError(f"unknown sampling {options.sampling!r}; expected {' or '.join(SAMPLING)}", field="sampling")
    if options.fgd_pairing not in FGD_PAIRINGS:
        raise InputError(f"unknown FGD pairing {options.fgd_pairing!r}; expected {' or '.join(FGD_PAIRINGS)}",
                         field="fgd-pairing")
    asked = list(options.metrics) if options.metrics else list(METRICS)
    unknown = [m for m in asked if m not in METRICS]
    if unknown:
        raise InputError(f"unknown Leaderboard metric {unknown[0]!r}; expected some of {', '.join(METRICS)}",
                         field="metrics")
    audio = pathlib.Path(options.audio_dir) if options.audio_dir is not None else gt.audio_dir
    sem = pathlib.Path(options.sem_dir) if options.sem_dir is not None else gt.sem_dir
    need = {"fgd": [("--fgd MODEL (evalsuite fgd import-emage)", options.fgd_model is not None)],
            "div": [("--smplx-model", model is not None)],
            "srgr": [("--smplx-model", model is not None), ("--sem DIR", sem is not None)],
            "bc_a2m": [("--smplx-model", model is not None), ("--audio DIR", audio is not None),
                       ("--bc-mean-vel FILE", options.mean_vel is not None)]}
    need["bc_m2a"] = need["bc_a2m"]
    out = set()
    for m in asked:
        lacking = [opt for opt, ok in need.get(m, []) if not ok]
        if not lacking:
            out.add(m)
            continue
        text = model_missing_message(m) if lacking == ["--smplx-model"] else f"{m} needs {' and '.join(lacking)}"
        if options.metrics:
            raise InputError(text, field=m)
        if m != "bc_m2a" or "bc_a2m" not in asked:
            issues.append(f"{m} left out: {text}")
    if out & {"bc_a2m", "bc_m2a"}:
        out |= {"bc_a2m", "bc_m2a"}   # computed together; reported as asked
    return out, audio, sem


def _encoder(path: str | os.PathLike[str]) -> Callable[[np.ndarray], np.ndarray]:
    try:
        from evalsuite.learned.emage_aeskconv import aeskconv_latents, axis_angle_to_rot6d, load_emage_model
    except ImportError as exc:
        raise InputError(f"fgd needs the learned extra ({exc}): pip install 'evalsuite[learned]'", field="fgd") from None
    model, _ = load_emage_model(path)
    return lambda poses: aeskconv_latents(model, axis_angle_to_rot6d(poses))


def _positions(poses: np.ndarray, betas: np.ndarray, model: pathlib.Path | None) -> np.ndarray:
    return smplx_positions(SmplxData(poses, np.zeros((len(poses), 3)), betas), model, mode="leaderboard", betas=betas)


def _condition(name: str, folder: pathlib.Path, gt: GroundTruth, gt_data: Mapping[str, SmplxData], wanted: set[str],
               ctx: dict[str, Any], options: LeaderboardOptions, issues: list[str], rows: list[dict]
               ) -> tuple[dict[str, float], list[Pieces], dict[str, list[np.ndarray]], int]:
    groups, skipped = group_predictions(folder)
    if skipped:
        issues.append(f"{name}: {len(skipped)} file(s) with fewer than five '_' tokens skipped (the organisers' "
                      f"script skips them), e.g. {skipped[0]}")
    missing = [v for v in gt.files if v not in groups]
    if missing:
        raise InputError(f"no prediction for {len(missing)} ground-truth recording(s), e.g. {missing[0]} (expected "
                         f"{missing[0]}_<k>.npz); the Leaderboard scores a complete submission only", path=folder)
    extra = [v for v in groups if v not in gt.files]
    if extra:
        raise InputError(f"predictions for {len(extra)} recording(s) not in the ground truth, e.g. {extra[0]} (the "
                         "organisers' script stops when the video ids differ)", path=folder)
    enc, model, mean_vel = ctx.get("encoder"), ctx.get("model"), ctx.get("mean_vel")
    keep_frames = options.bootstrap > 0
    # Memory stays flat in the number of recordings: FD_g/FD_k pool per-recording sufficient statistics
    # (bootstrap.Pieces) instead of every frame, and each recording's files are read when it is scored.
    side_a: list[np.ndarray] = []
    side_b: list[np.ndarray] = []
    n_used = 0
    sgroups = sample_groups(groups) if "sample_div" in wanted else {}
    sd_error: InputError | None = None if sgroups or "sample_div" not in wanted else InputError(
        "sample_div: no recordings with samples named <video_id>_<k>")
    pieces: list[Pieces] = []
    frames: dict[str, list[np.ndarray]] = {"fd_g_gt": [], "fd_g_pred": [], "fd_k_gt": [], "fd_k_pred": []}
    bar = tqdm(gt.files, desc=f"leaderboard {name}", unit="recording", disable=not options.progress)
    for vid in bar:
        g_data = gt_data[vid]
        g = g_data.poses
        betas = betas_of(g_data)
        piece = Pieces(vid)
        piece.add_fd("fid_g", g, None)
        piece.add_fd("fid_k", np.diff(g, axis=0), None)
        g_pos = _positions(g, betas, model) if wanted & {"srgr"} else None
        wave = bc.load_wave(ctx["audio"] / f"{vid}.wav") if "bc_a2m" in wanted else None
        weights_rows = lm.read_sem(ctx["sem"] / f"{vid}.txt") if "srgr" in wanted else None
        onsets: dict[int, np.ndarray] = {}
        for i, path in enumerate(choose(groups[vid], options.sampling)):
            p = read_recording(path).poses
            warn = length_warning(vid, len(g), path, len(p))
            if warn:
                issues.append(f"{name}: {warn}")
            t = min(len(g), len(p))
            n_used += 1
            piece.add_fd("fid_g", None, p)
            piece.add_fd("fid_k", None, np.diff(p, axis=0))
            vk = float(np.var(p, axis=0).mean())
            piece.var_k.append(vk)
            rows.append({"condition": name, "sequence": vid, "sample": path.stem, "metric": "var_k", "value": vk})
            if keep_frames:
                frames["fd_g_gt"].append(g[:t])
                frames["fd_g_pred"].append(p[:t])
                if t > 1:
                    frames["fd_k_gt"].append(np.diff(g[:t], axis=0))
                    frames["fd_k_pred"].append(np.diff(p[:t], axis=0))
            if enc is not None:
                lat_p = enc(p[:t])
                if i == 0:
                    lat_g = enc(g[:t])
                    side_a.append(lat_g)
                    piece.add_fd("fgd", lat_g, None)
                    side_b.append(lat_p)
                    piece.add_fd("fgd", None, lat_p)
                elif options.fgd_pairing == "published":
                    side_a.append(lat_p)
                    piece.add_fd("fgd", lat_p, None)
                else:
                    side_b.append(lat_p)
                    piece.add_fd("fgd", None, lat_p)
            if not wanted & {"div", "srgr", "bc_a2m"}:
                continue
            pos = _positions(p[:t], betas, model)
            values: dict[str, float] = {}
            if "div" in wanted:
                s, n = lm.l1_div_terms(pos)
                piece.div = (piece.div[0] + s, piece.div[1] + n)
                values["div"] = s / n
            if "srgr" in wanted and g_pos is not None and weights_rows is not None:
                rate = lm.srgr_rate(pos, g_pos[:t], lm.semantic_weights(weights_rows, t))
                piece.srgr = (piece.srgr[0] + rate * t, piece.srgr[1] + t)
                values["srgr"] = rate
            if "bc_a2m" in wanted and wave is not None and mean_vel is not None:
                src = str(ctx["audio"] / f"{vid}.wav")
                if t not in onsets:   # samples of the same length share the speech's cut
                    onsets[t] = bc.sequence_onsets(wave, t, source=src)
                a2m, m2a, w = bc.sequence_bc(pos, wave, mean_vel, published_threshold_frame=options.
                                             published_threshold_frame, source=src, onsets=onsets[t])
                piece.bc = (piece.bc[0] + a2m * w, piece.bc[1] + m2a * w, piece.bc[2] + w)
                values.update(bc_a2m=a2m, bc_m2a=m2a)
            rows.extend({"condition": name, "sequence": vid, "sample": path.stem, "metric": m, "value": v}
                        for m, v in values.items())
        if vid in sgroups and sd_error is None:
            try:
                piece.sample_div = lm.sample_div({vid: [read_recording(f).poses for f in sgroups[vid]]})
            except InputError as exc:
                sd_error = exc
        pieces.append(piece)
    out: dict[str, float] = {m: lm.frechet_published(*pooled_gaussian(pieces, m, 0), *pooled_gaussian(pieces, m, 1))
                             for m in ("fid_g", "fid_k")}
    out["var_k"] = float(np.mean([v for pc in pieces for v in pc.var_k]))   # lm.var_k: the mean over samples
    if enc is not None:
        out["fgd"] = lm.frechet_fgd(np.concatenate(side_a), np.concatenate(side_b))
        frames["fgd_a"], frames["fgd_b"] = side_a, side_b
    if "sample_div" in wanted:   # lm.sample_div: the mean of the recordings' values
        if sd_error is None:
            out["sample_div"] = float(np.mean([pc.sample_div for pc in pieces if pc.sample_div is not None]))
        else:
            for pc in pieces:
                pc.sample_div = None
            if options.metrics:
                raise sd_error
            issues.append(f"{name}: sample_div left out: {sd_error}")
    if "div" in wanted:
        out["div"] = sum(pc.div[0] for pc in pieces) / sum(pc.div[1] for pc in pieces)
    if "srgr" in wanted:
        out["srgr"] = sum(pc.srgr[0] for pc in pieces) / sum(pc.srgr[1] for pc in pieces)
    if "bc_a2m" in wanted:
        w = sum(pc.bc[2] for pc in pieces)
        out["bc_a2m"] = sum(pc.bc[0] for pc in pieces) / w
        out["bc_m2a"] = sum(pc.bc[1] for pc in pieces) / w
    return {m: v for m, v in out.items() if m in wanted}, pieces, frames, n_used


def evaluate_leaderboard(gt_dir: str | os.PathLike[str], conditions: Mapping[str, str | os.PathLike[str]]
                         | Sequence[str | os.PathLike[str]], options: LeaderboardOptions | None = None,
                         **kwargs: Any) -> LeaderboardResult:
    """Score each condition folder against ``gt_dir`` with the Leaderboard's metrics (see the module docstring).

    ``conditions``: name -> folder, or folders (named by their folder name). Keyword arguments set fields of
    :class:`LeaderboardOptions`.
    """
    options = LeaderboardOptions(**kwargs) if options is None else dataclasses.replace(options, **kwargs)
    named = dict(conditions) if isinstance(conditions, Mapping) else {pathlib.Path(c).name: c for c in conditions}
    if not named:
        raise InputError("no condition folders to score")
    gt = list_ground_truth(gt_dir)
    issues: list[str] = []
    model = optional_model_path(options.smplx_model)
    wanted, audio, sem = _wanted(options, gt, model, issues)
    report = wanted & set(options.metrics or METRICS)
    ctx: dict[str, Any] = {"model": model, "audio": audio, "sem": sem}
    if "fgd" in wanted and options.fgd_model is not None:
        ctx["encoder"] = _encoder(options.fgd_model)
    if "bc_a2m" in wanted and options.mean_vel is not None:
        mv = options.mean_vel
        ctx["mean_vel"] = mv if isinstance(mv, np.ndarray) else bc.read_mean_velocity(mv)
    gt_data = _Recordings(gt.files)
    summary: list[dict[str, Any]] = []
    rows: list[dict] = []
    convention = f"genea-leaderboard (sampling={options.sampling}, fgd_pairing={options.fgd_pairing})"
    for name, folder in named.items():
        values, pieces, frames, n_samples = _condition(name, pathlib.Path(folder), gt, gt_data, wanted, ctx, options,
                                                       issues, rows)
        values = {m: v for m, v in values.items() if m in report}
        cis = recording_bootstrap(pieces, values, options.bootstrap, options.seed) if options.bootstrap else {}
        lb = leaderboard_bootstrap(frames, options.bootstrap, options.seed) if options.bootstrap else {}
        for m in METRICS:
            if m not in values:
                continue
            unit, better = _INFO[m]
            lo, hi, sd = cis.get(m, (np.nan, np.nan, np.nan))
            lb_mean, lb_lo, lb_hi = lb.get(m, (np.nan, np.nan, np.nan))
            summary.append({"condition": name, "metric": m, "value": values[m], "unit": unit, "ci_low": lo,
                            "ci_high": hi, "std": np.nan, "n": len(pieces), "better": better, "convention": convention,
                            "samples": _samples_column(m, options.sampling), "n_samples": n_samples,
                            "ci_method": "bootstrap over recordings" if options.bootstrap else "", "boot_std": sd,
                            "lb_boot_mean": lb_mean, "lb_ci_low": lb_lo, "lb_ci_high": lb_hi})
    settings = {"preset": "genea-leaderboard", "sampling": options.sampling, "fgd_pairing": options.fgd_pairing,
                "ground_truth": os.fspath(gt_dir), "recordings": len(gt.files), "audio_dir": _str(ctx["audio"]),
                "sem_dir": _str(ctx["sem"]), "bootstrap": options.bootstrap, "seed": options.seed,
                "published_threshold_frame": options.published_threshold_frame, "metrics": sorted(report)}
    return LeaderboardResult(pd.DataFrame(summary), pd.DataFrame(rows, columns=["condition", "sequence", "sample",
                                                                                "metric", "value"]), issues, settings)


def score_leaderboard(gt_dir: str | os.PathLike[str], conditions: Mapping[str, str | os.PathLike[str]]
                      | Sequence[str | os.PathLike[str]], **kwargs: Any) -> pd.DataFrame:
    """The summary DataFrame of :func:`evaluate_leaderboard` (rows ``condition, metric, value, ...``)."""
    return evaluate_leaderboard(gt_dir, conditions, **kwargs).summary


class _Recordings(Mapping[str, SmplxData]):
    """The ground truth's recordings, read when asked for (not all held at once)."""

    def __init__(self, files: Mapping[str, pathlib.Path]):
        self.files = files

    def __getitem__(self, video_id: str) -> SmplxData:
        return read_recording(self.files[video_id])

    def __iter__(self):
        return iter(self.files)

    def __len__(self) -> int:
        return len(self.files)


def _str(path: pathlib.Path | None) -> str | None:
    return os.fspath(path) if path is not None else None
