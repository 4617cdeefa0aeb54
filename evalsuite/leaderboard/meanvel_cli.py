"""``evalsuite corpus mean-velocity BEAT2_DIR -o FILE``: the per-joint mean speed file that
``evalsuite score --preset genea-leaderboard --bc-mean-vel FILE`` divides joint speeds by
(:func:`evalsuite.leaderboard.meanvel.mean_velocity_of_split`)."""
from __future__ import annotations

import pathlib

import click
import numpy as np

from evalsuite.errors import InputError
from evalsuite.leaderboard.meanvel import mean_velocity_of_split
from evalsuite.motion.smplx_option import smplx_model_option

__all__ = ["mean_velocity_command"]


@click.command("mean-velocity")
@click.argument("beat2_dir", type=click.Path(exists=True, file_okay=False, path_type=pathlib.Path))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False, path_type=pathlib.Path),
              help="The .npy file to write: 55 float32 speeds in m/s, one per SMPL-X joint.")
@click.option("--split", default="train", show_default=True,
              help="Recordings of this split of train_test_split.csv, or 'all' for every file of smplxflame_30/ "
                   "(as EMAGE made mean_vel_smplxflame_30.npy).")
@smplx_model_option
@click.option("--quiet", is_flag=True, help="No progress bar.")
def mean_velocity_command(beat2_dir: pathlib.Path, output: pathlib.Path, split: str, quiet: bool) -> None:
    """Per-joint mean speed of a BEAT2 language folder's recordings (full SMPL-X positions with each file's betas,
    speed by central differences at 30 fps, the mean over every frame of every file), for --bc-mean-vel.

    \b
    Example:
      evalsuite corpus mean-velocity BEAT2/beat_english_v2.0.0 --smplx-model SMPLX_NEUTRAL_2020.npz \\
          -o mean_vel_train.npy
    """
    try:
        speeds = mean_velocity_of_split(beat2_dir, None, None if split == "all" else split, progress=not quiet)
    except InputError as exc:
        raise click.ClickException(str(exc)) from None
    output.parent.mkdir(parents=True, exist_ok=True)
    np.save(output, speeds.astype(np.float32))
    source = "every recording" if split == "all" else f"the {split!r} split"
    click.echo(f"Wrote {output}: 55 joint speeds in m/s (mean {float(speeds.mean()):.3f}) from {source} of "
               f"{beat2_dir}")
