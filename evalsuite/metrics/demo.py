"""Demo step: build sample conditions from the bundled motion and score them.

The bundled ``mocapbank.bvh`` (30 fps, 15 s) is cut into four 3.5 s segments, the "sequences".
Conditions, each a folder ``out_dir/conditions/<name>/seg0N.bvh`` with the same file names
(later demo steps render and study these folders):

* ``natural``: the segments themselves (the reference);
* ``mismatched``: natural motion of the *next* segment (right motion, wrong moment);
* ``static``: one pose held still (the frame closest to the segment's mean pose);
* ``jitter``: natural plus seeded Gaussian noise of 2 degrees on every rotation channel;
* ``smoothed``: natural smoothed with a 15-frame moving average (over-smoothed).
"""
from __future__ import annotations

import pathlib
from collections.abc import Callable

import numpy as np

from evalsuite.motion.filters import smooth
from evalsuite.motion.io import load_motion, save_motion
from evalsuite.motion.motion import Motion
from evalsuite.motion.ops import cut
from evalsuite.motion.samples import sample_path

SEGMENT_S = 3.5
N_SEGMENTS = 4


def build_conditions(out_dir: pathlib.Path, seed: int = 0) -> dict[str, pathlib.Path]:
    """Write the sample condition folders; returns ``{condition: folder}``."""
    source = load_motion(sample_path("mocapbank"))
    segments = [cut(source, k * SEGMENT_S, (k + 1) * SEGMENT_S) for k in range(N_SEGMENTS)]
    rng = np.random.default_rng(seed)
    rot_cols = [i for i, c in enumerate(source.skeleton.channel_names()) if c.endswith("rotation")]
    folders = {}

    def write(cond: str, k: int, motion: Motion) -> None:
        folder = out_dir / "conditions" / cond
        folder.mkdir(parents=True, exist_ok=True)
        save_motion(motion, folder / f"seg{k:02d}.bvh")
        folders[cond] = folder

    for k, seg in enumerate(segments):
        write("natural", k, seg)
        write("mismatched", k, segments[(k + 1) % N_SEGMENTS])
        pos = seg.positions()
        closest = int(np.argmin(((pos - pos.mean(axis=0)) ** 2).sum(axis=(1, 2))))
        write("static", k, seg.with_values(np.repeat(seg.values[closest:closest + 1], seg.n_frames, axis=0)))
        noisy = seg.values.copy()
        noisy[:, rot_cols] += rng.normal(0.0, 2.0, size=(seg.n_frames, len(rot_cols)))
        write("jitter", k, seg.with_values(noisy))
        write("smoothed", k, smooth(seg, "moving_average", window=15))
    return folders


def run(out_dir: pathlib.Path, echo: Callable[[str], None]) -> None:
    from evalsuite.metrics.engine import score_folders
    from evalsuite.metrics.figures import write_figures
    from evalsuite.metrics.report import format_table, summary_frame, write_outputs

    folders = build_conditions(out_dir)
    echo(f"  conditions written to {out_dir / 'conditions'}: {', '.join(folders)} "
         f"({N_SEGMENTS} sequences of {SEGMENT_S:g} s each)")
    result = score_folders(f"natural={folders['natural']}",
                           [f"{c}={p}" for c, p in folders.items() if c != "natural"],
                           progress=False, bootstrap=200, seed=0)
    score_dir = out_dir / "score"
    write_outputs(result, score_dir)
    write_figures(result, score_dir / "figures")
    for issue in result.issues:
        echo(f"  note: {issue}")
    echo(format_table(summary_frame(result.summary)))
    echo(f"  tables, JSON and figures written to {score_dir}")
