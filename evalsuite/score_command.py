"""``evalsuite score``: score condition folders against natural motion.

The command sits above both :mod:`evalsuite.metrics` (the engine and its metric families) and
:mod:`evalsuite.learned` (the FGD family, added for a run with ``--fgd MODEL``), so neither package
imports the other upwards.
"""
from __future__ import annotations

import pathlib

import click

from evalsuite.corpus.cli import on_mismatch_option
from evalsuite.errors import InputError
from evalsuite.motion.smplx_option import smplx_model_option


def _fgd_family(model_path, raw: bool, n: int | None = None, infinity: bool = False):
    """The FGD metric family for this run (needs the learned extra: torch)."""
    try:
        from evalsuite.learned.family import FGDFamily
    except ImportError as exc:
        raise InputError(f"--fgd needs the learned extra ({exc}): pip install 'evalsuite[learned]'",
                         field="fgd") from None
    return FGDFamily(model_path, raw=raw, n=n, infinity=infinity)


@click.command()
@click.option("-r", "--reference", required=True, metavar="[NAME=]FOLDER",
              help="Folder of natural motion (BVH, .npy, .npz or .csv); files are paired by name.")
@click.argument("conditions", nargs=-1, metavar="[NAME=]FOLDER...")
@click.option("-o", "--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=pathlib.Path),
              help="Folder for the tables, JSON and figures.")
@click.option("--joints", default=None, help="Joint preset (e.g. genea2020_upper, genea2023) or comma-separated "
              "joint names; default: every joint of the natural motion.")
@click.option("-m", "--metrics", multiple=True, help="Metric families (kinematics, histograms, errors, distribution, gac, "
              "cca, beats, coupling) or metric names, comma-separated or repeated; default: all (beats with --audio, "
              "beats and coupling with --corpus).")
@click.option("--convention", type=click.Choice(["default", "genea2020", "genea2022", "aud2repr2pose"]),
              default="default", show_default=True, help="Scaling and binning conventions (see docs/metrics.md).")
@click.option("--audio", "audio_dir", type=click.Path(path_type=pathlib.Path), default=None,
              help="Folder of <sequence>.wav speech audio for beat alignment.")
@click.option("--corpus", "corpus_dir", type=click.Path(path_type=pathlib.Path), default=None, metavar="DIR",
              help="Corpus whose segments the files belong to (matched by name = segment id): adds the speech-"
              "gesture coupling metrics (and its speech for beat alignment).")
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
              help="Bootstrap resamples over sequences for 95% confidence intervals (0: none). Cost: mostly FD_g "
              "and FD_k, about 2.5 ms per resample, condition and distance at 249 pose dimensions (83 joints) on one "
              "core, growing with the cube of the dimensions; the resamples run on --jobs threads (1000 resamples of "
              "9 conditions x 40 segments with 83 joints: about 40 s on 2 cores). A progress bar shows the resamples left.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the bootstrap.")
@click.option("--jobs", type=click.IntRange(min=1), default=1, show_default=True,
              help="Local worker processes (and threads for the bootstrap).")
@click.option("--dask", "dask_address", default=None, metavar="ADDRESS",
              help="Run the per-file work on an existing dask.distributed scheduler (e.g. tcp://127.0.0.1:8786).")
@click.option("--strict", is_flag=True, help="Fail (exit 1) on any unreadable file or missing pair instead of "
              "reporting it and scoring the rest.")
@click.option("--no-figures", is_flag=True, help="Skip the matplotlib figures.")
@click.option("--fgd", "fgd_model", type=click.Path(path_type=pathlib.Path), default=None, metavar="MODEL",
              help="Also compute FGD with this trained feature extractor (needs the learned extra).")
@click.option("--fgd-raw", is_flag=True, help="With --fgd, also the raw-space FD of whole windows (slow: one "
              "eigendecomposition of window x pose dimensions per condition).")
@click.option("--fgd-n", "fgd_n", type=click.IntRange(min=2), default=None, metavar="N",
              help="With --fgd, also FGD on N windows per side (row fgd[n=N]): 200 draws without replacement, their "
              "mean and 2.5-97.5 percentiles, so FGDs from different numbers of windows compare.")
@click.option("--fgd-inf", is_flag=True, help="With --fgd, also FGD extrapolated to infinitely many windows (row "
              "fgd_inf; Chong & Forsyth): FGD at 10 sizes from N/5 to N fitted against 1/N, with figure fgd_inf.")
@click.option("--gac", "gac_spec", default=None, metavar="CONVENTION[:KEY=VALUE,...]",
              help="Also compute Gesture Area Coverage (gac_dice, gac_fp, gac_fn) under this convention: tonoli2024 "
              "(the authors' code: every bone from the third joint, frontal plane, 200 x 200 units in 0.5-unit "
              "pixels, root-locked) or wrists (the wrists' paths), with overrides such as tonoli2024:step=0.005,"
              "range=2 for motion in metres (docs/metrics.md). -m gac alone uses tonoli2024.")
@click.option("--samples", type=click.Choice(["first", "each"]), default="first", show_default=True,
              help="Conditions with several samples per sequence (<name>_<k> files, k a number, first = lowest k): "
              "score the first sample, or each sample index and report the mean over them (summary.csv column "
              "samples; metrics that take every sample at once say all).")
@click.option("--quiet", is_flag=True, help="No progress bar and no table on the terminal.")
@click.option("--preset", type=click.Choice(["genea-leaderboard"]), default=None,
              help="Score exactly as a benchmark does instead: genea-leaderboard = the GENEA Leaderboard's objective "
              "metrics on SMPL-X .npz (fgd, fid_g, fid_k, var_k, sample_div, bc_a2m, bc_m2a, div, srgr) with its "
              "naming, sampling and pairing rules (-r: the ground truth folder or BEAT2 language folder; "
              "docs/leaderboard.md). It uses -m, --audio, --fgd, --bootstrap, --seed, --quiet and the options below.")
@click.option("--sem", "sem_dir", type=click.Path(file_okay=False, path_type=pathlib.Path), default=None,
              metavar="DIR", help="With --preset genea-leaderboard: BEAT2 sem/ folder of <video_id>.txt for srgr "
              "[default: sem/ of a BEAT2 folder given as -r].")
@click.option("--bc-mean-vel", "bc_mean_vel", type=click.Path(dir_okay=False, path_type=pathlib.Path), default=None,
              metavar="FILE", help="With --preset genea-leaderboard: per-joint mean speed .npy (55,) that beat "
              "alignment divides by (EMAGE's mean_vel_smplxflame_30.npy, or evalsuite.leaderboard.beats."
              "mean_velocity of a training split).")
@click.option("--sampling", type=click.Choice(["fixed", "all"]), default="fixed", show_default=True,
              help="With --preset genea-leaderboard: the samples each metric uses: fixed = the first file of a "
              "recording in text order (_10 before _2), all = every sample.")
@click.option("--fgd-pairing", "fgd_pairing", type=click.Choice(["published", "corrected"]), default="published",
              show_default=True, help="With --preset genea-leaderboard and --sampling all: published = samples 2..k "
              "join the ground truth's side of FGD (as the organisers' script does); corrected = ground truth against "
              "every sample.")
@on_mismatch_option
@smplx_model_option
def score(reference, conditions, out_dir, joints, metrics, convention, audio_dir, corpus_dir, sigma, fps, resample, speed_bins,
          acceleration_bins, groups, bootstrap, seed, jobs, dask_address, strict, no_figures, fgd_model, fgd_raw, fgd_n,
          fgd_inf, gac_spec, samples, quiet, preset, sem_dir, bc_mean_vel, sampling, fgd_pairing):
    """Score generated motion (CONDITIONS) against natural motion (--reference).

    Every folder holds one file per sequence, or several samples <name>_<k>; files are paired with
    the natural ones by name (stem). Condition names are the folder names, or give NAME=FOLDER. Writes summary.csv
    (long form: condition, metric, value, unit, ci_low, ci_high, ...), per_sequence.csv,
    per_joint.csv, histograms.csv, results.json (with provenance and file hashes),
    summary.md, summary.tex and figures/ (PNG and SVG).

    Example: evalsuite score -r natural=data/NA data/SysA data/SysB --joints genea2020_upper -o scores

    Leaderboard: evalsuite score --preset genea-leaderboard -r BEAT2/beat_english_v2.0.0 mysystem/ -o lb
    --smplx-model SMPLX_NEUTRAL_2020.npz --bc-mean-vel mean_vel_smplxflame_30.npy --fgd aeskconv.pt
    """
    if preset is not None:
        from evalsuite.leaderboard.preset import run_preset

        run_preset(preset, reference, conditions, out_dir, metrics=metrics, audio_dir=audio_dir, sem_dir=sem_dir,
                   mean_vel=bc_mean_vel, sampling=sampling, fgd_pairing=fgd_pairing, fgd_model=fgd_model,
                   bootstrap=bootstrap, seed=seed, quiet=quiet)
        return
    from evalsuite.metrics.engine import ScoreOptions, score_folders
    from evalsuite.metrics.figures import write_figures
    from evalsuite.metrics.report import format_table, grouped_issues, summary_frame, write_outputs

    group_list = [g.replace(";", ",") for g in groups.split(",") if g.strip()] if groups else []
    if fgd_model is None and (fgd_n is not None or fgd_inf):
        raise InputError("--fgd-n and --fgd-inf need a model: pass --fgd MODEL", field="fgd-n")
    extra = [_fgd_family(fgd_model, fgd_raw, fgd_n, fgd_inf)] if fgd_model is not None else []
    if gac_spec is not None:
        from evalsuite.metrics.families.gac import GacFamily

        extra.append(GacFamily(gac_spec, default=True))
    options = ScoreOptions(joints=joints, metrics=list(metrics) or None, convention=convention, audio_dir=audio_dir,
                           corpus=corpus_dir, fps=fps, resample=resample, speed_bins=speed_bins,
                           acceleration_bins=acceleration_bins, groups=group_list, sigma=sigma, bootstrap=bootstrap,
                           seed=seed, jobs=jobs, dask_address=dask_address, strict=strict, progress=not quiet,
                           figures=not no_figures, extra_families=extra, samples=samples)
    result = score_folders(reference, conditions, options)
    paths = write_outputs(result, out_dir)
    figures = [] if no_figures else write_figures(result, out_dir / "figures")
    for issue in grouped_issues(result.issues, result.plan.conditions):
        click.secho(f"warning: {issue}", fg="yellow", err=True)
    for line in _resampling_lines(result.resampled):
        click.secho(f"warning: {line}", fg="yellow", err=True)
    if not quiet:
        click.echo(format_table(summary_frame(result.summary)))
        click.echo(f"\nWrote {paths['summary_csv']} (and per_sequence.csv, per_joint.csv, histograms.csv, "
                   f"results.json, summary.md, summary.tex){'' if no_figures else f', {len(figures)} figure files'}"
                   f" to {out_dir}")
    # The other conditions' results are written above; a condition with nothing scored is still a
    # failure the caller (often a script) must notice.
    # (the natural condition has no summary row of its own with FGD alone: count files scored, not rows)
    unscored = [c for c in result.plan.conditions if not result.files.get(c)]
    if unscored:
        raise click.ClickException(f"nothing could be scored for condition(s) {', '.join(unscored)} (see the "
                                   f"warnings above); the other results are in {out_dir}")


def _resampling_lines(resampled: list[str]) -> list[str]:
    """``path (a -> b fps, why)`` entries as one line per (a, b, why) with a count and an example."""
    import re

    groups: dict[str, list[str]] = {}
    for entry in resampled:
        m = re.match(r"(.*) \((.*)\)$", entry)
        path, what = (m.group(1), m.group(2)) if m else (entry, "")
        groups.setdefault(what, []).append(path)
    return [f"{len(paths)} file(s) resampled by interpolation ({what}), e.g. {paths[0]}; all listed in "
            "results.json (resampled_files)" for what, paths in sorted(groups.items())]
