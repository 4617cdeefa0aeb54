"""``evalsuite score --preset genea-leaderboard``: run :func:`evalsuite.leaderboard.score.evaluate_leaderboard`
and write the tables evalsuite writes for every score run (summary.csv, per_sequence.csv, results.json,
summary.md, summary.tex)."""
from __future__ import annotations

import json
import math
import os
import pathlib
from typing import Any

import click

from evalsuite._version import __version__
from evalsuite.leaderboard.score import METRICS, LeaderboardOptions, LeaderboardResult, evaluate_leaderboard
from evalsuite.metrics.report import format_table, latex_table, markdown_table, summary_frame

__all__ = ["PRESETS", "write_leaderboard_outputs", "run_preset"]

PRESETS = ("genea-leaderboard",)


def _clean(x: Any) -> Any:
    if isinstance(x, float) and not math.isfinite(x):
        return None
    if isinstance(x, dict):
        return {k: _clean(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_clean(v) for v in x]
    return x


def write_leaderboard_outputs(result: LeaderboardResult, out_dir: str | os.PathLike[str]) -> dict[str, pathlib.Path]:
    """Write the run's tables and JSON under ``out_dir``; returns ``{kind: path}``."""
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    frame = summary_frame(result.summary.to_dict("records"))
    paths = {"summary_csv": out / "summary.csv", "per_sequence_csv": out / "per_sequence.csv",
             "json": out / "results.json", "markdown": out / "summary.md", "latex": out / "summary.tex"}
    frame.to_csv(paths["summary_csv"], index=False)
    result.per_sequence.to_csv(paths["per_sequence_csv"], index=False)
    payload = {"provenance": {"evalsuite_version": __version__, **result.settings},
               "summary": _clean(frame.to_dict("records")), "issues": result.issues}
    paths["json"].write_text(json.dumps(payload, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    paths["markdown"].write_text(markdown_table(frame), encoding="utf-8")
    paths["latex"].write_text(latex_table(frame), encoding="utf-8")
    return paths


def _metric_names(metrics: tuple[str, ...]) -> list[str] | None:
    names = [m.strip() for item in metrics for m in item.split(",") if m.strip()]
    return names or None


def run_preset(preset: str, reference: str, conditions: tuple[str, ...], out_dir: pathlib.Path, *,
               metrics: tuple[str, ...], audio_dir: pathlib.Path | None, sem_dir: pathlib.Path | None,
               mean_vel: pathlib.Path | None, sampling: str, fgd_pairing: str, fgd_model: pathlib.Path | None,
               bootstrap: int, seed: int, quiet: bool) -> LeaderboardResult:
    """The ``score`` command's work under a preset (``-r`` the ground truth, each condition ``[NAME=]FOLDER``)."""
    if preset not in PRESETS:
        raise click.BadParameter(f"unknown preset {preset!r}; expected {', '.join(PRESETS)}")
    gt = reference.split("=", 1)[1] if "=" in reference and not os.path.exists(reference) else reference
    named: dict[str, str] = {}
    for c in conditions:
        name, folder = c.split("=", 1) if "=" in c and not os.path.exists(c) else (pathlib.Path(c).name, c)
        named[name] = folder
    options = LeaderboardOptions(sampling=sampling, fgd_pairing=fgd_pairing, audio_dir=audio_dir, sem_dir=sem_dir,
                                 mean_vel=mean_vel, fgd_model=fgd_model, metrics=_metric_names(metrics),
                                 bootstrap=bootstrap, seed=seed, progress=not quiet)
    result = evaluate_leaderboard(gt, named, options)
    paths = write_leaderboard_outputs(result, out_dir)
    for issue in result.issues:
        click.secho(f"warning: {issue}", fg="yellow", err=True)
    if not quiet:
        frame = summary_frame(result.summary.to_dict("records"))
        click.echo(format_table(frame) if len(frame) else "nothing scored")
        click.echo(f"\nWrote {paths['summary_csv']} (and per_sequence.csv, results.json, summary.md, summary.tex) "
                   f"to {out_dir}; metrics of the preset: {', '.join(METRICS)}")
    return result

