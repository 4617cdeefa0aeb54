"""``evalsuite score``: score condition folders against natural motion."""
from __future__ import annotations

import pathlib

import click

from evalsuite.errors import InputError


def _fgd_rows(result, model_path, fps, resample, bootstrap, seed, progress, raw):
    """Rows from the learned FGD scorer (``evalsuite.learned.fgd.score_fgd``), imported only when asked."""
    try:
        from evalsuite.learned.fgd import score_fgd
    except ModuleNotFoundError as exc:
        raise InputError(f"--fgd needs the learned extra (module {exc.name!r} is missing): "
                         "pip install 'evalsuite[learned]'", field="fgd") from None
    from evalsuite.metrics.scoring import _load

    plan = result["plan"]
    motions = {}
    for cond in plan.conditions:
        motions[cond] = {}
        for s, info in result["files"][cond].items():
            motions[cond][s] = _load(info["path"], fps, resample)
    reference = motions.pop(plan.reference)
    rows = score_fgd(model_path, reference, motions, raw=raw, n_bootstrap=bootstrap, seed=seed, progress=progress)
    out = []
    for r in rows:
        r = dict(r)
        for key in ("ci_low", "ci_high"):
            r.setdefault(key, float("nan"))
        r.setdefault("better", "lower")
        r.setdefault("convention", result["convention"].name)
        out.append(r)
    return out


@click.command()
@click.option("-r", "--reference", required=True, metavar="[NAME=]FOLDER",
              help="Folder of natural motion (BVH, .npy, .npz or .csv); files are paired by name.")
@click.argument("conditions", nargs=-1, metavar="[NAME=]FOLDER...")
@click.option("-o", "--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=pathlib.Path),
              help="Folder for the tables, JSON and figures.")
@click.option("--joints", default=None, help="Joint preset (e.g. genea2020_upper, genea2023) or comma-separated "
              "joint names; default: every joint of the natural motion.")
@click.option("-m", "--metrics", multiple=True, help="Metric families (kinematics, histograms, errors, distribution, "
              "cca, beats) or metric names, comma-separated or repeated; default: all (beats with --audio).")
@click.option("--convention", type=click.Choice(["default", "genea2020", "genea2022", "aud2repr2pose"]),
              default="default", show_default=True, help="Scaling and binning conventions (see docs/metrics.md).")
@click.option("--audio", "audio_dir", type=click.Path(path_type=pathlib.Path), default=None,
              help="Folder of <sequence>.wav speech audio for beat alignment.")
@click.option("--sigma", type=float, default=0.1, show_default=True, help="Beat alignment sigma in seconds.")
@click.option("--fps", type=float, default=None, help="Frame rate of .npy/.csv files (they store none).")
@click.option("--resample", type=float, default=None, metavar="FPS",
              help="Resample every file to FPS first (needed when conditions differ in frame rate).")
@click.option("--speed-bins", default=None, metavar="MAX:WIDTH", help="Speed histogram range and bin width.")
@click.option("--acceleration-bins", default=None, metavar="MAX:WIDTH", help="Acceleration histogram range/width.")
@click.option("--groups", default="wrists,forearms", show_default=True,
              help="Joint groups for histograms (presets or NAME:J1;J2 with ';' between joints), comma-separated; "
              "all joints pooled is always included.")
@click.option("--bootstrap", type=click.IntRange(min=0), default=0, show_default=True,
              help="Bootstrap resamples over sequences for 95% confidence intervals (0: none).")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the bootstrap.")
@click.option("--jobs", type=click.IntRange(min=1), default=1, show_default=True, help="Local worker processes.")
@click.option("--dask", "dask_address", default=None, metavar="ADDRESS",
              help="Run the per-file work on an existing dask.distributed scheduler (e.g. tcp://127.0.0.1:8786).")
@click.option("--strict", is_flag=True, help="Fail (exit 1) on any unreadable file or missing pair instead of "
              "reporting it and scoring the rest.")
@click.option("--no-figures", is_flag=True, help="Skip the matplotlib figures.")
@click.option("--fgd", "fgd_model", type=click.Path(path_type=pathlib.Path), default=None, metavar="MODEL",
              help="Also compute FGD with this trained feature extractor (needs the learned extra).")
@click.option("--fgd-raw", is_flag=True, help="With --fgd, also the raw-space FD of whole windows (slow: one "
              "eigendecomposition of window x pose dimensions per condition).")
@click.option("--quiet", is_flag=True, help="No progress bar and no table on the terminal.")
def score(reference, conditions, out_dir, joints, metrics, convention, audio_dir, sigma, fps, resample, speed_bins,
          acceleration_bins, groups, bootstrap, seed, jobs, dask_address, strict, no_figures, fgd_model, fgd_raw, quiet):
    """Score generated motion (CONDITIONS) against natural motion (--reference).

    Every folder holds one file per sequence; files are paired with the natural ones by name
    (stem). Condition names are the folder names, or give NAME=FOLDER. Writes summary.csv
    (long form: condition, metric, value, unit, ci_low, ci_high, ...), per_sequence.csv,
    per_joint.csv, histograms.csv, results.json (with provenance and file hashes),
    summary.md, summary.tex and figures/ (PNG and SVG).

    Example: evalsuite score -r natural=data/NA data/SysA data/SysB -j genea2020_upper -o scores
    """
    from evalsuite.metrics.figures import write_figures
    from evalsuite.metrics.report import format_table, summary_frame, write_outputs
    from evalsuite.metrics.scoring import score_folders

    group_list = [g.replace(";", ",") for g in groups.split(",") if g.strip()] if groups else []
    result = score_folders(reference, conditions, joints=joints, metrics=list(metrics) or None,
                           convention=convention, audio_dir=audio_dir, fps=fps, resample=resample,
                           speed_bins=speed_bins, acceleration_bins=acceleration_bins, groups=group_list,
                           sigma=sigma, bootstrap=bootstrap, seed=seed, jobs=jobs, dask_address=dask_address,
                           strict=strict, progress=not quiet, figures=not no_figures)
    if fgd_model is not None:
        result["summary"].extend(_fgd_rows(result, fgd_model, fps, resample, bootstrap, seed, not quiet, fgd_raw))
    paths = write_outputs(result, out_dir)
    figures = [] if no_figures else write_figures(result, out_dir / "figures")
    for issue in result["issues"]:
        click.secho(f"warning: {issue}", fg="yellow", err=True)
    if not quiet:
        click.echo(format_table(summary_frame(result["summary"])))
        click.echo(f"\nWrote {paths['summary_csv']} (and per_sequence.csv, per_joint.csv, histograms.csv, "
                   f"results.json, summary.md, summary.tex){'' if no_figures else f', {len(figures)} figure files'}"
                   f" to {out_dir}")
    # The other conditions' results are written above; a condition with nothing scored is still a
    # failure the caller (often a script) must notice.
    scored = {row["condition"] for row in result["summary"]}
    unscored = [c for c in result["plan"].conditions if c not in scored]
    if unscored:
        raise click.ClickException(f"nothing could be scored for condition(s) {', '.join(unscored)} (see the "
                                   f"warnings above); the other results are in {out_dir}")
