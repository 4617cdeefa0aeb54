"""Benchmark: `evalsuite score --bootstrap 1000` on the full skeleton, against the same run without bootstrap.

GENEA 2023-like data: 83 joints (249 pose dimensions for FD_g/FD_k), 30 fps, takes cut into 10 s
segments. Generates once, into a cache folder (``--cache``, default ``$TMPDIR/evalsuite-bench-bootstrap``),
a natural folder and 9 condition folders (10 conditions, as in a GENEA-sized study) of 40 synthetic
10-second BVH segments each (``evalsuite.motion.synthetic``; conditions are other takes, noisy and
smoothed versions of the natural ones). Then runs the real command line twice, with every default metric
family (kinematics, histograms, errors, distribution with FD_g/FD_k, CCA), ``--jobs 2``:

    evalsuite score -r natural=... cond00 ... cond08 --jobs 2 -o OUT            (no bootstrap)
    evalsuite score -r natural=... cond00 ... cond08 --jobs 2 --bootstrap 1000 -o OUT

and prints both wall times side by side with their ratio (target: the bootstrap run under 2 minutes on
2 cores), the load average before and after, and, as a peer, the former resample-by-resample FD
computation timed on a few resamples and extrapolated to the run's 18,000 resampled distances.

Run: python benchmarks/bench_score_bootstrap.py [--cache DIR] [--jobs 2] [--bootstrap 1000]
"""
from __future__ import annotations

import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import time
import warnings

N_CONDITIONS = 9        # plus the natural reference: 10 conditions
N_SEQUENCES = 40
SECONDS = 10.0
N_JOINTS = 83
FPS = 30.0


def generate(cache: pathlib.Path) -> pathlib.Path:
    """The natural folder and 9 condition folders (``bench_score.generate`` with GENEA 2023-like sizes)."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from bench_score import generate as generate_folders

    return generate_folders(cache, n_conditions=N_CONDITIONS, n_sequences=N_SEQUENCES, seconds=SECONDS,
                            n_joints=N_JOINTS, fps=FPS)


def load() -> str:
    return ", ".join(f"{x:.2f}" for x in os.getloadavg())


def score(cache: pathlib.Path, out: pathlib.Path, jobs: int, bootstrap: int) -> float:
    conds = [str(cache / f"cond{c:02d}") for c in range(N_CONDITIONS)]
    cmd = [sys.executable, "-m", "evalsuite", "score", "-r", f"natural={cache / 'natural'}", *conds,
           "--jobs", str(jobs), "--bootstrap", str(bootstrap), "-o", str(out)]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)   # the progress bars stay on stderr
    return time.perf_counter() - t0


def former_per_resample(cache: pathlib.Path, n: int = 8) -> float:
    """Seconds per resampled FD with the former code (moments combined, then the FD, per resample)."""
    from evalsuite.metrics.distribution import combine_moments, frechet_from_moments, moments
    from evalsuite.metrics.families import bootstrap_weights
    from evalsuite.motion.io import load_motion

    def parts(folder: str) -> list:
        pos = [load_motion(p).positions() for p in sorted((cache / folder).glob("*.bvh"))]
        return [moments(x.reshape(len(x), -1)) for x in pos]

    ref, cond = parts("natural"), parts("cond03")
    weights = bootstrap_weights(len(ref), n, 0, 1)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for w in weights:
            frechet_from_moments(combine_moments(ref, w), combine_moments(cond, w))
    return (time.perf_counter() - t0) / n


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cache", type=pathlib.Path,
                        default=pathlib.Path(tempfile.gettempdir()) / "evalsuite-bench-bootstrap")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--bootstrap", type=int, default=1000)
    args = parser.parse_args()

    cache = generate(args.cache)
    print(f"data: natural + {N_CONDITIONS} conditions x {N_SEQUENCES} segments x {SECONDS:g} s, {N_JOINTS} joints "
          f"({3 * N_JOINTS} pose dimensions), {FPS:g} fps BVH; all default metric families, --jobs {args.jobs}")
    print(f"machine: {os.cpu_count()} CPUs; load average before: {load()}")
    with tempfile.TemporaryDirectory() as tmp:
        plain = score(cache, pathlib.Path(tmp) / "plain", args.jobs, 0)
        print(f"  without bootstrap: {plain:.1f} s (load average now {load()})")
        boot = score(cache, pathlib.Path(tmp) / "boot", args.jobs, args.bootstrap)
        print(f"  --bootstrap {args.bootstrap}: {boot:.1f} s (load average now {load()})")
    n_fd = 2 * N_CONDITIONS * args.bootstrap
    print(f"\n| run | wall time |\n|---|---|\n| without bootstrap | {plain:.1f} s |\n"
          f"| --bootstrap {args.bootstrap} | {boot:.1f} s |\n| ratio | {boot / plain:.2f} x |")
    print(f"bootstrap {'meets' if boot < 120 else 'MISSES'} the target of 120 s on 2 cores; "
          f"its share: {boot - plain:.1f} s for {n_fd} resampled Fréchet distances (FD_g, FD_k) "
          f"= {1000 * (boot - plain) / n_fd:.2f} ms each, with every other metric's bootstrap")
    per = former_per_resample(cache)
    print(f"peer: the former resample-by-resample FD takes {1000 * per:.1f} ms per resample here (as it ran: "
          f"NumPy's default BLAS threads), "
          f"~{per * n_fd / 60:.1f} min for the run's {n_fd} (load average {load()})")


if __name__ == "__main__":
    main()
