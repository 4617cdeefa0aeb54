"""Load + forward kinematics: evalsuite vs pymotion on generated 60-joint, 60 fps BVH files.

    pip install upc-pymotion      # the peer, only for this benchmark
    python benchmarks/bench_motion.py [--repeats 5] [--workdir DIR]

Generates a 1-minute and a 10-minute file (60 joints, ZXY channels, 6 channels on the root,
60 fps) once, then measures, in this process and after a warm-up of both libraries, the
wall time of "read the file and compute world positions of every joint for every frame":

* evalsuite: ``load_motion(path).positions()``
* pymotion:  ``BVH().load(path)`` + ``get_data()`` + ``ops.skeleton_np.fk(...)``

It prints the median and best of ``--repeats`` runs, the ratio, and the largest difference
between the two libraries' positions (they must agree). It also times one cold run of
evalsuite in a fresh Python process (imports included), which is what a CLI user sees.
"""
from __future__ import annotations

import argparse
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import evalsuite
from evalsuite.motion.io import save_motion
from evalsuite.motion.synthetic import synthetic_motion


def ensure_files(workdir: pathlib.Path) -> dict[str, pathlib.Path]:
    workdir.mkdir(parents=True, exist_ok=True)
    files = {}
    for label, seconds in (("1 min", 60), ("10 min", 600)):
        path = workdir / f"bench_60j_60fps_{seconds}s.bvh"
        if not path.exists():
            print(f"generating {path} ...", flush=True)
            save_motion(synthetic_motion(n_joints=60, fps=60, seconds=seconds, seed=7), path)
        files[label] = path
    return files


def evalsuite_positions(path):
    return evalsuite.load_motion(path).positions()


def pymotion_positions(path):
    from pymotion.io.bvh import BVH
    from pymotion.ops.skeleton_np import fk

    bvh = BVH()
    bvh.load(str(path))
    rots, pos, parents, offsets, _, _ = bvh.get_data()
    positions, _ = fk(rots, pos[:, 0, :], offsets, parents)
    return positions


def timed(func, path, repeats):
    times = []
    result = None
    for _ in range(repeats):
        start = time.perf_counter()
        result = func(path)
        times.append(time.perf_counter() - start)
        del result  # free the motion before the next run
    return times


def cold_run(path) -> float:
    code = ("import time; t=time.perf_counter(); import evalsuite; "
            f"evalsuite.load_motion({str(path)!r}).positions(); print(time.perf_counter()-t)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return float(out.stdout.strip())


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--workdir", type=pathlib.Path,
                        default=pathlib.Path(tempfile.gettempdir()) / "evalsuite-bench-motion")
    args = parser.parse_args(argv)
    try:
        import pymotion  # noqa: F401
    except ImportError:
        sys.exit("the peer is missing: pip install upc-pymotion")

    files = ensure_files(args.workdir)
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} (1 min)")
    # Warm-up: imports, first-touch allocations, page cache.
    evalsuite_positions(files["1 min"])
    pymotion_positions(files["1 min"])

    print(f"\n{'file':<8} {'size':>8} {'evalsuite median (best)':>26} {'pymotion median (best)':>26} "
          f"{'speed-up':>9} {'max |diff|':>11}")
    rows = []
    for label, path in files.items():
        ours = timed(evalsuite_positions, path, args.repeats)
        peer = timed(pymotion_positions, path, max(1, args.repeats // 2 + 1))
        diff = float(np.abs(evalsuite_positions(path) - pymotion_positions(path)).max())
        ratio = statistics.median(peer) / statistics.median(ours)
        rows.append((label, ours, peer, ratio, diff))
        size = path.stat().st_size / 1e6
        print(f"{label:<8} {size:>6.1f}MB {statistics.median(ours):>15.3f} s ({min(ours):.3f})"
              f" {statistics.median(peer):>15.3f} s ({min(peer):.3f}) {ratio:>8.1f}x {diff:>11.2e}", flush=True)
    cold = cold_run(files["10 min"])
    print(f"\nevalsuite, 10 min file, cold process (imports included): {cold:.3f} s")
    return rows


if __name__ == "__main__":
    main()
