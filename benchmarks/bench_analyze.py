"""Benchmark: `evalsuite analyze` with the CLI defaults on 100,000- and 1,000,000-row results.csv files.

Generates the files once into a cache folder (``--cache``, default ``$TMPDIR/evalsuite-bench-analyze``):
the simulated study of ``evalsuite.analysis.simulate`` (3- and 5-level pairwise with matched/mismatched
pairs, MUSHRA with hidden reference and anchor, Likert, attention checks and the planted exclusion
cases), drawn with 40 seeds and repeated with renamed participants and sessions until the row count
is reached. Then runs ``python -m evalsuite analyze FILE -o OUT`` (defaults: 1000 bootstrap rounds,
figures, report) in a fresh process per file and prints the wall-clock and CPU time (user + system;
on a shared machine the CPU time is the steadier figure, the 1-minute load average is printed with it),
imports included, and which test each matched/mismatched comparison used (Barnard's exact test or its
large-n path).

Run: python benchmarks/bench_analyze.py [--cache DIR] [--rows 100000 1000000]
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np
import pandas as pd


def generate(path: pathlib.Path, rows: int, seeds: int = 40) -> pathlib.Path:
    from evalsuite.analysis.simulate import simulate_results

    if path.is_file():
        return path
    blocks = [simulate_results(seed=s) for s in range(seeds)]
    per_copy = sum(len(b) for b in blocks)
    copies = -(-rows // per_copy)
    parts = []
    for k in range(copies):
        for s, b in enumerate(blocks):
            tag = f"_{k}_{s}"
            parts.append(b.assign(participant=b["participant"] + tag, session=b["session"] + tag))
    df = pd.concat(parts, ignore_index=True).iloc[:rows]
    # A cut in the middle of a session would leave a partial session: cut at a session boundary.
    last = df["session"].iloc[-1]
    df = df[df["session"] != last] if len(df) == rows else df
    path.parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(path, index=False)
    return path


def run(path: pathlib.Path, out: pathlib.Path) -> tuple[float, float]:
    """Wall-clock and CPU seconds (user + system) of one `evalsuite analyze` process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "evalsuite", "analyze", str(path), "-o", str(out)],
                       capture_output=True, text=True, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    dt = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode != 0:
        raise SystemExit(f"analyze failed on {path}:\n{r.stdout}\n{r.stderr}")
    return dt, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", type=pathlib.Path,
                    default=pathlib.Path(tempfile.gettempdir()) / "evalsuite-bench-analyze")
    ap.add_argument("--rows", type=int, nargs="+", default=[100_000, 1_000_000])
    args = ap.parse_args(argv)
    print(f"{'rows':>10} {'sessions':>9} {'file MB':>8} {'wall s':>7} {'CPU s':>7} {'load':>5}  "
          "matched/mismatched tests")
    for n in args.rows:
        t0 = time.perf_counter()
        path = generate(args.cache / f"results_{n}.csv", n)
        gen = time.perf_counter() - t0
        out = args.cache / f"out_{n}"
        dt, cpu = run(path, out)
        load = os.getloadavg()[0]
        summary = json.loads((out / "summary.json").read_text())
        tests = pd.read_csv(out / "mismatch_barnard.csv")["test"].value_counts().to_dict() \
            if (out / "mismatch_barnard.csv").is_file() else {}
        with open(path, encoding="utf-8") as fh:
            rows = sum(1 for _ in fh) - 1
        print(f"{rows:>10,} {summary['exclusions']['sessions_total']:>9,} {path.stat().st_size / 1e6:>8.1f} "
              f"{dt:>7.1f} {cpu:>7.1f} {load:>5.1f}  {tests}  (generation {gen:.1f} s)", flush=True)
    print(f"python {sys.version.split()[0]}, numpy {np.__version__}, pandas {pd.__version__}, "
          f"{os.cpu_count()} CPUs")


if __name__ == "__main__":
    main()
