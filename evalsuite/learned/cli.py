"""``evalsuite fgd``: train, import, check and use learned-feature motion encoders."""
from __future__ import annotations

import json
import math
import pathlib

import click

from evalsuite.errors import InputError

_DATA_FPS = click.option("--data-fps", type=float, default=None,
                         help="Frame rate of positions files that store none (GENEA .npy files).")


def _rows_markdown(rows: list[dict], columns: list[str]) -> str:
    def fmt(v):
        if v is None:
            return ""
        if isinstance(v, float):
            return "" if math.isnan(v) else f"{v:.4f}"
        return str(v)

    lines = ["| " + " | ".join(columns) + " |", "|" + "|".join("---" for _ in columns) + "|"]
    lines += ["| " + " | ".join(fmt(r.get(c, "")) for c in columns) + " |" for r in rows]
    return "\n".join(lines)


def _write_rows(rows: list[dict], fmt: str, out) -> str:
    import pandas as pd

    frame = pd.DataFrame(rows)
    if fmt == "csv":
        text = frame.to_csv(index=False)
    elif fmt == "json":
        text = json.dumps(rows, indent=2, default=float)
    else:
        cols = [c for c in ("condition", "metric", "value", "ci_low", "ci_high", "unit", "n_windows_reference",
                            "n_windows_condition", "n_windows") if c in frame.columns]
        text = _rows_markdown(rows, cols) + "\n"
    if out:
        pathlib.Path(out).write_text(text)
    return text


def _warn_small(rows: list[dict], reference: dict, conditions: dict) -> None:
    """Warn (stderr) where the FGD's samples are too small (the rule of `evalsuite score`)."""
    from evalsuite.learned.network import LATENT_DIM
    from evalsuite.metrics.frechet import sample_size_warnings
    from evalsuite.metrics.report import grouped_issues

    issues = [f"{r['condition']}: fgd: {line}" for r in rows if r["metric"] == "fgd"
              for line in sample_size_warnings((r["n_windows_reference"], r["n_windows_condition"]), LATENT_DIM,
                                               (len(reference), len(conditions[r["condition"]])), "windows")]
    for line in grouped_issues(issues, conditions):
        click.secho(f"warning: {line}", fg="yellow", err=True)


def _warn_resampled(model_fps: float, label_sets: dict, why: str = "to the model's frame rate") -> list[dict]:
    """Warn (stderr) about every file the model will resample; returns the records for provenance."""
    from evalsuite.learned.representation import describe_resampling, resampled_files

    records = []
    for label, motions in label_sets.items():
        records += resampled_files(motions, model_fps, label)
    for line in describe_resampling(records, why):
        click.secho(f"warning: {line}", fg="yellow", err=True)
    return records


@click.group()
def fgd():
    """Learned-feature metrics: FGD, raw-space FGD, NSD, codebook diversity.

    Needs the optional extra: pip install "evalsuite[learned]" (PyTorch, CPU).
    Typical use: `evalsuite fgd train NATURAL_DIR -o model.pt`, `evalsuite fgd check model.pt
    NATURAL_DIR`, then `evalsuite fgd score model.pt NATURAL_DIR SYSTEM_A_DIR SYSTEM_B_DIR`.
    """


@fgd.command()
@click.argument("natural_dir", type=click.Path(exists=True, path_type=pathlib.Path))
@click.option("-o", "--out", type=click.Path(dir_okay=False, path_type=pathlib.Path), required=True,
              help="Model file to write.")
@click.option("--joints", default="genea2023", show_default=True,
              help="Joint preset (genea2023 also selects the PyMO convention), 'all', or A,B,C.")
@click.option("--window", type=int, default=30, show_default=True, help="Window length in frames.")
@click.option("--stride", type=int, default=None, help="Window step in frames [default: window // 2].")
@click.option("--fps", type=float, default=30.0, show_default=True, help="Frame rate the model works at.")
@click.option("--epochs", type=int, default=50, show_default=True)
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--batch-size", type=int, default=64, show_default=True)
@click.option("--lr", "learning_rate", type=float, default=5e-4, show_default=True, help="Adam learning rate.")
@click.option("--val-fraction", type=float, default=0.1, show_default=True,
              help="Share of each sequence (at its end) held out for the validation loss.")
@click.option("--architecture", type=click.Choice(["genea2023", "genea2022", "genea2020", "yoon2020"]),
              default="genea2023", show_default=True, help="Layer widths of the reference network.")
@click.option("--representation", type=click.Choice(["positions", "bone_directions"]), default="positions",
              show_default=True)
@click.option("--convention", type=click.Choice(["default", "pymo", "pymotion", "bvhtoolbox"]), default=None,
              help="BVH translation convention [default: the joint preset's, else as loaded].")
@click.option("--threads", type=int, default=1, show_default=True,
              help="CPU threads while training (results are reproducible for a fixed value).")
@_DATA_FPS
@click.option("--quiet", is_flag=True, help="No progress bar or epoch lines.")
def train(natural_dir, out, joints, window, stride, fps, epochs, seed, batch_size, learning_rate, val_fraction,
          architecture, representation, convention, threads, data_fps, quiet):
    """Train a motion encoder on natural motion (a folder of BVH/.npz/.npy/.csv files)."""
    from evalsuite.learned.data import load_folder
    from evalsuite.learned.presets import resolve_joint_spec
    from evalsuite.learned.training import train_model

    names, preset_conv = resolve_joint_spec(joints, []) if joints != "all" else (None, None)
    motions = load_folder(natural_dir, convention=convention or preset_conv, fps=data_fps, joint_names=names)
    _warn_resampled(fps, {"": motions}, f"for training at {fps:g} fps (each sequence's source_fps is in the "
                    "model's provenance)")
    model = train_model(motions, joints=joints, window=window, stride=stride, fps=fps, epochs=epochs, seed=seed,
                        batch_size=batch_size, learning_rate=learning_rate, val_fraction=val_fraction,
                        representation=representation, convention=convention, architecture=architecture,
                        threads=threads, progress=not quiet, log=None if quiet else click.echo)
    digest = model.save(out)
    hist = model.meta["training"]["history"][-1]
    click.echo(f"wrote {out}: {len(motions)} sequences, {model.meta['training']['train_windows']} training / "
               f"{model.meta['training']['val_windows']} validation windows, final validation loss "
               f"{hist['val_loss']:.4f}")
    click.echo(f"content hash {digest}")


@fgd.command("import-genea")
@click.argument("checkpoint", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
@click.option("--stats", "stats", default=None, metavar="PRESET|FILE",
              help="Normalisation vectors (mean/std of the extractor's input); needed for GENEA checkpoints. A "
                   "preset shipped with evalsuite (genea2020, genea2022_fullbody, genea2022_upperbody, genea2023: "
                   "the official numbers) or a file: .npz with mean/std, .npy of shape (2, D), or MEAN.npy,STD.npy. "
                   "Without it the import stops with an error, except for Yoon et al. checkpoints read with "
                   "--unsafe-pickle (their args.mean_dir_vec, std 1).")
@click.option("--joints", required=True,
              help="Joints in the checkpoint's input order: a preset (genea2023) or A,B,C.")
@click.option("-o", "--out", type=click.Path(dir_okay=False, path_type=pathlib.Path), required=True,
              help="Model file to write.")
@click.option("--fps", type=float, default=30.0, show_default=True, help="Frame rate the extractor was trained at.")
@click.option("--stride", type=int, default=None, help="Window step [default: window // 2].")
@click.option("--window-rule", type=click.Choice(["genea", "complete"]), default="genea", show_default=True,
              help="genea: the reference scripts' windows (last complete window unused); complete: all.")
@click.option("--convention", type=click.Choice(["default", "pymo", "pymotion", "bvhtoolbox"]), default=None,
              help="BVH translation convention [default: the joint preset's].")
@click.option("--representation", type=click.Choice(["positions", "bone_directions"]), default="positions",
              show_default=True, help="bone_directions for Yoon et al. 2020 checkpoints.")
@click.option("--bones", default=None, help="For bone_directions: PARENT-CHILD,... [default: Yoon et al.'s 9].")
@click.option("--unsafe-pickle", is_flag=True,
              help="Allow pickled objects in the checkpoint (Yoon et al.'s 'args'). Only for trusted files.")
def import_genea(checkpoint, stats, joints, out, fps, stride, window_rule, convention, representation, bones,
                 unsafe_pickle):
    """Convert a GENEA (2020/2022/2023) or Yoon et al. FGD checkpoint into an evalsuite model file.

    Example: evalsuite fgd import-genea model_checkpoint_30.bin --stats genea2023 --joints genea2023 -o genea30.pt
    """
    from evalsuite.learned.genea import import_checkpoint

    bone_list = None
    if bones:
        bone_list = []
        for pair in bones.split(","):
            if "-" not in pair:
                raise InputError(f"bones must be PARENT-CHILD pairs, got {pair!r}")
            bone_list.append([s.strip() for s in pair.split("-", 1)])
    model = import_checkpoint(checkpoint, joints=joints, stats=stats, fps=fps, stride=stride, convention=convention,
                              representation=representation, bones=bone_list, window_rule=window_rule,
                              allow_pickle=unsafe_pickle)
    digest = model.save(out)
    click.echo(model.describe())
    click.echo(f"wrote {out}; content hash {digest}")


@fgd.command("import-emage")
@click.argument("checkpoint", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
@click.option("-o", "--out", type=click.Path(dir_okay=False, path_type=pathlib.Path), required=True,
              help="Model file to write (state dict, provenance and input convention).")
@click.option("--unsafe-pickle", is_flag=True,
              help="Allow pickled objects besides tensors in the checkpoint (if the plain read fails). Only for "
                   "trusted files.")
def import_emage(checkpoint, out, unsafe_pickle):
    """Convert EMAGE's AESKConv_240_100.bin (the GENEA Leaderboard's FGD encoder) into an evalsuite model file.

    Example: evalsuite fgd import-emage AESKConv_240_100.bin -o aeskconv.pt
    """
    from evalsuite.learned.emage_aeskconv import import_emage as run_import

    run_import(checkpoint, out, allow_pickle=unsafe_pickle)
    click.echo(f"wrote {out}")


@fgd.command()
@click.argument("model_path", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
@click.option("--json", "as_json", is_flag=True, help="Print the full metadata as JSON.")
def info(model_path, as_json):
    """Describe a model file: architecture, joints, window, provenance, content hash."""
    from evalsuite.learned.modelfile import load_model

    model = load_model(model_path)
    if as_json:
        click.echo(json.dumps(model.meta, indent=2, default=str))
        return
    click.echo(model.describe())
    prov = model.meta.get("training") or {}
    if prov.get("kind") == "trained":
        last = prov["history"][-1]
        click.echo(f"  trained on {len(prov['data'])} sequences ({prov['train_windows']} windows), "
                   f"{prov['epochs']} epochs, seed {prov['seed']}, final losses train {last['train_loss']:.4f} "
                   f"/ validation {last['val_loss']:.4f}")
    elif prov.get("kind") == "imported":
        click.echo(f"  imported from {prov['checkpoint_file']} (sha256 {prov['checkpoint_sha256']}), "
                   f"{prov['source_format']}")


def _load_sets(model, natural_dir, condition_dirs, data_fps):
    from evalsuite.learned.data import load_folder

    conv = model.representation.get("convention")
    reference = load_folder(natural_dir, convention=conv, fps=data_fps, joint_names=model.joints)
    conditions = {}
    for d in condition_dirs:
        name = pathlib.Path(d).name
        if name in conditions:
            raise InputError(f"two condition folders are named {name!r}", path=d)
        conditions[name] = load_folder(d, convention=conv, fps=data_fps, joint_names=model.joints)
    return reference, conditions


@fgd.command()
@click.argument("model_path", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
@click.argument("natural_dir", type=click.Path(exists=True, path_type=pathlib.Path))
@click.argument("condition_dirs", nargs=-1, required=True, type=click.Path(exists=True, path_type=pathlib.Path))
@click.option("--raw/--no-raw", default=True, show_default=True,
              help="Also the raw-space FGD (one large eigen-decomposition per condition).")
@click.option("--latent/--no-latent", default=True, show_default=True,
              help="Also NSD (k=1,2) and codebook Hellinger/perplexity.")
@click.option("--bootstrap", "n_bootstrap", type=int, default=1000, show_default=True,
              help="Bootstrap resamples for the FGD CI (0: none).")
@click.option("--unit", "bootstrap_unit", type=click.Choice(["sequence", "window"]), default="sequence",
              show_default=True, help="What the bootstrap resamples.")
@click.option("--codes", "n_codes", type=int, default=64, show_default=True, help="Codebook size (k-means).")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--format", "fmt", type=click.Choice(["markdown", "csv", "json"]), default="markdown",
              show_default=True)
@click.option("-o", "--out", type=click.Path(dir_okay=False), default=None, help="Also write the table here.")
@_DATA_FPS
def score(model_path, natural_dir, condition_dirs, raw, latent, n_bootstrap, bootstrap_unit, n_codes, seed, fmt,
          out, data_fps):
    """FGD of each CONDITION_DIR (generated motion) against NATURAL_DIR, with the model's hash."""
    from evalsuite.learned.fgd import score_fgd
    from evalsuite.learned.latent import score_latent
    from evalsuite.learned.modelfile import load_model

    model = load_model(model_path)
    reference, conditions = _load_sets(model, natural_dir, condition_dirs, data_fps)
    _warn_resampled(model.fps, {"reference": reference, **conditions},
                    f"for the model ({model.fps:g} fps; listed in the output's resampled field)")
    rows = score_fgd(model, reference, conditions, raw=raw, n_bootstrap=n_bootstrap, bootstrap_unit=bootstrap_unit,
                     seed=seed, progress=True)
    _warn_small(rows, reference, conditions)
    if latent:
        for r in score_latent(model, reference, conditions, n_codes=n_codes, seed=seed):
            rows.append({"condition": r["condition"], "metric": r["metric"], "value": r["value"], "unit": r["unit"],
                         "ci_low": math.nan, "ci_high": math.nan, "model_hash": r["model_hash"],
                         "window": r["window"], "n_windows_reference": None, "n_windows_condition": r["n_windows"],
                         "resampled": r["resampled"]})
    if fmt == "markdown":
        click.echo(f"{model.describe()}\n")
        click.echo(f"reference: {natural_dir} ({len(reference)} sequences); bootstrap {n_bootstrap} x "
                   f"{bootstrap_unit}, 95% percentile CI moved to have its median on the value, seed {seed} (the "
                   "FD's small-sample bias is in the bootstrap_bias column of --format csv/json; see docs/learned.md)\n")
    text = _write_rows(rows, fmt, out)
    click.echo(text, nl=False)


@fgd.command()
@click.argument("model_path", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
@click.argument("natural_dir", type=click.Path(exists=True, path_type=pathlib.Path))
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@_DATA_FPS
def check(model_path, natural_dir, seed, as_json, data_fps):
    """Sanity suite: natural halves near 0; FGD grows with noise, jitter and a static pose.

    Exits with status 1 when a check fails.
    """
    from evalsuite.learned.data import load_folder
    from evalsuite.learned.modelfile import load_model
    from evalsuite.learned.sanity import check_model, format_table

    model = load_model(model_path)
    natural = load_folder(natural_dir, convention=model.representation.get("convention"), fps=data_fps,
                          joint_names=model.joints)
    resampled = _warn_resampled(model.fps, {"natural": natural}, f"for the model ({model.fps:g} fps)")
    result = check_model(model, natural, seed=seed)
    result["resampled"] = resampled
    for line in result["warnings"]:
        click.secho(f"warning: {line}", fg="yellow", err=True)
    if as_json:
        click.echo(json.dumps(result, indent=2, default=float))
    else:
        click.echo(f"model {model.short_hash} on {natural_dir}: {result['n_sequences'][0]} + "
                   f"{result['n_sequences'][1]} sequences, motion scale {result['motion_scale']:.4g}\n")
        click.echo(format_table(result))
    if not result["passed"]:
        raise click.ClickException("some sanity checks failed (see the table)" + (
            "; the natural halves are too small for FGD (see the warnings)" if result["warnings"] else ""))


@fgd.command()
@click.argument("model_path", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
@click.argument("motion_file", type=click.Path(exists=True, dir_okay=False, path_type=pathlib.Path))
@click.option("-o", "--out", type=click.Path(dir_okay=False), required=True, help=".npy file for the features.")
@click.option("--stride", type=int, default=None, help="Window step [default: the model's].")
@_DATA_FPS
def features(model_path, motion_file, out, stride, data_fps):
    """Write the encoder features (N, 32) of every window of one motion file."""
    import numpy as np

    from evalsuite.learned.data import load_folder
    from evalsuite.learned.modelfile import load_model

    model = load_model(model_path)
    loaded = load_folder(motion_file, convention=model.representation.get("convention"), fps=data_fps,
                         joint_names=model.joints)
    _warn_resampled(model.fps, {"": loaded}, f"for the model ({model.fps:g} fps)")
    (motion,) = loaded.values()
    feats = model.features(motion, stride)
    np.save(out, feats)
    click.echo(f"wrote {out}: {feats.shape[0]} windows x {feats.shape[1]} features (model {model.short_hash})")
