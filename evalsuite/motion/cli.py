"""``evalsuite info`` and ``evalsuite convert``."""
from __future__ import annotations

import json
import pathlib
from typing import TYPE_CHECKING

import click

from evalsuite.motion.fk import CONVENTIONS
from evalsuite.motion.smplx_option import positions_mode_option, smplx_model_option

_CONVENTION = click.option(
    "--convention", type=click.Choice(sorted(CONVENTIONS)), default="default", show_default=True,
    help="How BVH position channels combine with OFFSETs: default (root channels absolute, joint "
         "channels replace the OFFSET), pymo (joint channels added to the OFFSET, as GENEA 2023 FGD), "
         "pymotion/bvhtoolbox (joint channels ignored).")

if TYPE_CHECKING:
    from evalsuite.motion.motion import Motion


def _load(path: str, fps: float | None, joints_file: str | None, convention: str | None,
          positions: str = "full") -> Motion:
    from evalsuite.motion.io import load_motion

    names = None
    if joints_file:
        names = [line.strip() for line in pathlib.Path(joints_file).read_text().splitlines() if line.strip()]
    return load_motion(path, fps=fps, joint_names=names, convention=convention, positions=positions)


@click.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(exists=True, dir_okay=False))
@click.option("--fps", type=float, help="Frame rate of positions files that do not store one (.npy).")
@click.option("--joint-names", "joints_file", type=click.Path(exists=True, dir_okay=False),
              help="Text file with one joint name per line, for positions files without names.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
@click.option("--joints/--no-joints", "list_joints", default=False, help="Also list every joint and its channels.")
@_CONVENTION
@smplx_model_option
def info(files: tuple[str, ...], fps: float | None, joints_file: str | None, as_json: bool, list_joints: bool,
         convention: str | None) -> None:
    """Summarise motion files: joints, channels, fps, frames, duration, a guess of the units.

    For SMPL-X files also the pose width, betas, expressions, gender, model and whether joint positions are
    available (they need --smplx-model)."""
    out = []
    for path in files:
        motion = _load(path, fps, joints_file, convention)
        summary = motion.summary()
        if list_joints:
            summary["joint_list"] = [
                {"name": n, "parent": motion.joint_names[p] if p >= 0 else None, "channels": list(c)}
                for n, p, c in zip(motion.joint_names, motion.parents, motion.skeleton.channels)]
        out.append(summary)
        if not as_json:
            click.secho(path, bold=True)
            labels = {"kind": "kind", "format": "format", "joints": "joints", "end_sites": "end sites",
                      "channels": "channels", "frames": "frames", "fps": "fps", "duration_s": "duration",
                      "roots": "roots", "units_guess": "units", "units": "units", "pose_width": "pose width",
                      "betas": "betas", "expressions": "expression", "gender": "gender", "model": "model",
                      "positions": "positions"}
            for key, label in labels.items():
                value = summary.get(key)
                if key == "duration_s":
                    value = f"{value:.3f} s"
                elif key == "roots" and value:
                    value = ", ".join(value)
                if value is not None:
                    click.echo(f"  {label:<10} {value}")
            if list_joints:
                for item in summary["joint_list"]:
                    click.echo(f"    {item['name']:<28} parent={item['parent'] or '-':<24} {' '.join(item['channels'])}")
    if as_json:
        click.echo(json.dumps(out if len(out) > 1 else out[0], indent=2))


@click.command()
@click.argument("src", type=click.Path(exists=True, dir_okay=False))
@click.argument("dst", type=click.Path(dir_okay=False, writable=True))
@click.option("--joints", help="Keep only these joints: a preset (genea2020_upper, genea2023, ...) or "
                               "comma-separated names.")
@click.option("--start", type=float, default=None, metavar="SECONDS",
              help="Keep the motion from this time on (seconds of the input, from its own frame rate; "
                   "the frame nearest to it is the first kept) [default: 0].")
@click.option("--end", type=float, default=None, metavar="SECONDS",
              help="Keep the motion up to this time (seconds of the input; the frame nearest to it is the "
                   "first dropped). Must be after --start and within the file [default: the end].")
@click.option("--fps", type=float, help="Resample to this frame rate (slerp for rotations). For .npy input "
                                        "without a stored rate, use --input-fps.")
@click.option("--input-fps", type=float, help="Frame rate of a positions input that does not store one.")
@click.option("--joint-names", "joints_file", type=click.Path(exists=True, dir_okay=False),
              help="Text file with one joint name per line, for positions inputs without names.")
@click.option("--center", "center_axes", default=None, metavar="AXES",
              help="Subtract the root trajectory on these axes, e.g. 'xz' (hip-centering) or 'xyz'.")
@click.option("--smooth", type=click.Choice(["moving_average", "savgol", "one_euro"]),
              help="Smoothing filter: moving average (5 frames), Savitzky-Golay (9, 3) or One-Euro.")
@click.option("--end-sites", is_flag=True, help="Include End Sites in positions outputs (as <parent>_End).")
@_CONVENTION
@smplx_model_option
@positions_mode_option
def convert(src: str, dst: str, joints: str | None, start: float | None, end: float | None, fps: float | None,
            input_fps: float | None, joints_file: str | None, center_axes: str | None, smooth: str | None,
            end_sites: bool, convention: str | None, positions: str) -> None:
    """Convert motion between BVH, SMPL-X and positions (.npz, .npy, .csv), optionally cut in time.

    Operations run in this order: cut (--start/--end), select joints, resample, center, smooth.
    A .npz output holds positions (T, J, 3), joint_names, fps and parents; from an SMPL-X input it is an
    SMPL-X .npz again. SMPL-X to .bvh (J(beta) OFFSETs, metres) or to positions (T, 55, 3 in metres, in the
    --positions mode) needs --smplx-model.
    """
    from evalsuite.motion import filters, ops
    from evalsuite.motion.io import save_motion

    motion = _load(src, input_fps, joints_file, convention, positions)
    if start is not None or end is not None:
        motion = ops.cut(motion, 0.0 if start is None else start, end, past_end=False)
    if joints:
        motion = ops.select_joints(motion, joints)
    if fps:
        motion = ops.resample(motion, fps)
    if center_axes:
        motion = ops.center(motion, axes=center_axes)
    if smooth:
        motion = filters.smooth(motion, smooth)
    save_motion(motion, dst, end_sites=end_sites)
    click.echo(f"wrote {dst}: {motion.n_joints} joints, {motion.n_frames} frames @ {motion.fps:g} fps")
