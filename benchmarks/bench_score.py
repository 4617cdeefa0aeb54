"""Benchmark: `evalsuite score` on 10 conditions x 40 sequences x 60 s (56 joints, 30 fps, BVH).

Generates the BVH files once into a cache folder (``--cache``, default
``$TMPDIR/evalsuite-bench-score``): a natural folder and 10 condition folders of 40
synthetic 60-second takes each (``evalsuite.motion.synthetic``; conditions are other seeds,
noisy and smoothed versions). Then times the scorer on the kinematic and histogram metrics
(the target: under 60 s on a 2-core machine), with 1 and with 2 local processes, and, as a
peer measured in the same run, the reference scripts' per-frame/per-joint Python loops on a
few of the same files (the approach evalsuite replaces), reported as a ratio.

Run: python benchmarks/bench_score.py [--cache DIR] [--jobs 2] [--all-metrics]
"""
from __future__ import annotations

import argparse
import os
import pathlib
import tempfile
import time

import numpy as np

N_CONDITIONS = 10
N_SEQUENCES = 40
SECONDS = 60.0
N_JOINTS = 56
FPS = 30.0


def generate(cache: pathlib.Path, *, n_conditions: int = N_CONDITIONS, n_sequences: int = N_SEQUENCES,
             seconds: float = SECONDS, n_joints: int = N_JOINTS, fps: float = FPS) -> pathlib.Path:
    """``cache/natural`` and ``cache/cond00 ...`` of ``n_sequences`` synthetic takes each (made once): every third
    condition other takes, then natural plus noise, then over-smoothed natural. Also used by
    bench_score_bootstrap.py with other sizes."""
    from evalsuite.motion.filters import smooth
    from evalsuite.motion.io import save_motion
    from evalsuite.motion.synthetic import synthetic_motion

    done = cache / ".complete"
    if done.exists():
        return cache
    t0 = time.perf_counter()
    rng = np.random.default_rng(0)
    for s in range(n_sequences):
        natural = synthetic_motion(n_joints, fps, seconds, seed=s)
        takes = {"natural": natural}
        for c in range(n_conditions):
            kind = c % 3
            if kind == 0:      # another take: right style, wrong moment
                takes[f"cond{c:02d}"] = synthetic_motion(n_joints, fps, seconds, seed=1000 * (c + 1) + s)
            elif kind == 1:    # natural plus noise
                noisy = natural.values + rng.normal(0, 1.0 + c / 5, natural.values.shape)
                takes[f"cond{c:02d}"] = natural.with_values(noisy)
            else:              # over-smoothed
                takes[f"cond{c:02d}"] = smooth(natural, "moving_average", window=5 + 2 * c)
        for name, motion in takes.items():
            folder = cache / name
            folder.mkdir(parents=True, exist_ok=True)
            save_motion(motion, folder / f"take{s:03d}.bvh", precision=4)
    done.write_text("ok\n")
    print(f"generated {(n_conditions + 1) * n_sequences} BVH files in {time.perf_counter() - t0:.1f} s -> {cache}")
    return cache


def reference_loops(positions: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """The reference scripts' way: per-frame, per-joint np.linalg.norm loops (AJ and the speed histogram)."""
    flat = positions.reshape(len(positions), -1)
    jerks = np.diff(flat, n=3, axis=0)
    norms = np.zeros((jerks.shape[0], jerks.shape[1] // 3))
    for i in range(jerks.shape[0]):
        for j in range(jerks.shape[1] // 3):
            norms[i, j] = np.linalg.norm(jerks[i, 3 * j:3 * j + 3])
    vels = np.diff(flat, n=1, axis=0)
    vnorms = np.zeros((vels.shape[0], vels.shape[1] // 3))
    for i in range(vels.shape[0]):
        for j in range(vels.shape[1] // 3):
            vnorms[i, j] = np.linalg.norm(vels[i, 3 * j:3 * j + 3])
    bins = np.arange(0, 49 + 0.05, 0.05)
    hists = [np.histogram(vnorms[:, j] * fps, bins=bins)[0] for j in range(vnorms.shape[1])]
    return norms.mean(axis=0) * fps ** 3, np.sum(hists, axis=0)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", type=pathlib.Path,
                        default=pathlib.Path(tempfile.gettempdir()) / "evalsuite-bench-score")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--all-metrics", action="store_true", help="also time every default metric family")
    args = parser.parse_args()

    import evalsuite
    from evalsuite.metrics.engine import score_folders
    from evalsuite.metrics.histograms import joint_histograms
    from evalsuite.metrics.kinematics import derivative_norms

    cache = generate(args.cache)
    conds = [str(cache / f"cond{c:02d}") for c in range(N_CONDITIONS)]
    ref = str(cache / "natural")
    print(f"machine: {os.cpu_count()} CPUs, load average before timing: "
          + ", ".join(f"{x:.2f}" for x in os.getloadavg()))
    n_files = (N_CONDITIONS + 1) * N_SEQUENCES
    runs = [("kinematics+histograms", "kinematics,histograms", 1),
            ("kinematics+histograms", "kinematics,histograms", args.jobs)]
    if args.all_metrics:
        runs.append(("all default metrics", None, args.jobs))
    for label, metrics, jobs in runs:
        t0 = time.perf_counter()
        result = score_folders(ref, conds, metrics=metrics, jobs=jobs, progress=False, figures=False)
        wall = time.perf_counter() - t0
        print(f"score {label}, jobs={jobs}: {wall:.1f} s wall for {n_files} files "
              f"({N_CONDITIONS} conditions + natural x {N_SEQUENCES} x {SECONDS:g} s, {N_JOINTS} joints, "
              f"{FPS:g} fps); {len(result.summary)} summary rows; load average now "
              + ", ".join(f"{x:.2f}" for x in os.getloadavg()))

    # Peer in the same run: metric computation only, on the same positions, vectorised vs reference loops.
    files = sorted((cache / "natural").glob("*.bvh"))[:3]
    positions = [evalsuite.load_motion(f).positions() for f in files]
    t0 = time.perf_counter()
    for p in positions:
        derivative_norms(p, 3, FPS).mean(axis=0)
        joint_histograms(derivative_norms(p, 1, FPS), np.arange(0, 49 + 0.05, 0.05))
    ours = (time.perf_counter() - t0) / len(positions)
    t0 = time.perf_counter()
    for p in positions:
        reference_loops(p, FPS)
    loops = (time.perf_counter() - t0) / len(positions)
    print(f"per file, jerk + speed histogram only: evalsuite {1000 * ours:.1f} ms, reference-style loops "
          f"{1000 * loops:.0f} ms (x{loops / ours:.0f}); reference loops for all {n_files} files would take "
          f"~{loops * n_files:.0f} s of computation alone")


if __name__ == "__main__":
    main()
