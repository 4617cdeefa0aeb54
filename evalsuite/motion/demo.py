"""Demo step: load the bundled BVH samples, print their summaries, write their positions."""
from __future__ import annotations

import pathlib
from collections.abc import Callable

from evalsuite.motion.io import load_motion, save_motion
from evalsuite.motion.samples import sample_paths


def run(out_dir: pathlib.Path, echo: Callable[[str], None]) -> None:
    target = out_dir / "positions"
    target.mkdir(parents=True, exist_ok=True)
    for path in sample_paths():
        motion = load_motion(path)
        s = motion.summary()
        echo(f"  {path.name}: {s['joints']} joints, {s['frames']} frames @ {s['fps']:g} fps "
             f"({s['duration_s']:.2f} s), units: {s['units_guess']}")
        save_motion(motion, target / f"{path.stem}.npz", end_sites=True)
    echo(f"  world positions written to {target}/*.npz (positions (T, J, 3), joint_names, fps)")
