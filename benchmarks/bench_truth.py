"""Known-truth validity benchmark of the objective metrics (``evalsuite validate-metrics``).

1. Synthesises a speaker corpus with a fixed seed (12 minutes of speech, segments of about 12.5 s: about 58
   segments; the val and test splits, about 12 segments, are scored; the train split trains the FGD encoder,
   20 epochs).
2. Runs the validation: the oracle and its graded degradations (time offsets 0.1/0.3/0.6/1.2 s, semantic
   gestures removed, beats removed, amplitude x0.75/0.5/0.25, jitter 0.005/0.01/0.02 rad, moving averages of
   5/9/15 frames), mismatched, random segments and mean pose, all generated through the plug-ins; every metric
   of ``evalsuite score`` (FGD included); Kendall's tau with the true order and a 200-resample paired bootstrap
   over segments.
3. Prints the table (tau and verdict per metric and family), the speech-blind metrics and the time of each step.

Usage: python benchmarks/bench_truth.py [--out DIR] [--minutes 12] [--jobs 2] [--bootstrap 200] [--fgd-epochs 20]
One BLAS thread per process (set below, before numpy loads): on a shared 2-core machine multi-threaded BLAS
makes the small eigendecompositions of the bootstrap many times slower. The load average is printed; other
processes slow every figure down.
"""
from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import pathlib  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=pathlib.Path, default=None, help="Output folder (default: a temporary one).")
    ap.add_argument("--minutes", type=float, default=12.0)
    ap.add_argument("--segment-seconds", type=float, default=15.0)
    ap.add_argument("--fgd-epochs", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--bootstrap", type=int, default=200)
    args = ap.parse_args()

    from evalsuite.synth import Layout, synthesize_corpus
    from evalsuite.validity.cli import run_validation
    from evalsuite.validity.report import markdown, speech_blind

    out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="bench_truth_"))
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at the start (other processes share "
          f"the CPU; times are wall-clock); output in {out}")
    t_all = time.perf_counter()
    corpus = out / "corpus"
    t0 = time.perf_counter()
    if not (corpus / "corpus.json").is_file():
        meta = synthesize_corpus(corpus, args.minutes, args.seed, layout=Layout(segment_s=args.segment_seconds),
                                 jobs=args.jobs, progress=False)
        n_seg = len(meta["segments"])
    else:
        from evalsuite.corpus import load_corpus

        n_seg = len(load_corpus(corpus).segments)
    t_corpus = time.perf_counter() - t0
    print(f"[corpus] {args.minutes:g} min, {n_seg} segments (--segment-seconds {args.segment_seconds:g}), seed {args.seed}: "
          f"{t_corpus:.1f} s")
    run = run_validation(corpus, out / "validity", split="val,test", n_bootstrap=args.bootstrap, seed=args.seed,
                         jobs=args.jobs, fgd_epochs=args.fgd_epochs, progress=False, echo=lambda s: None)
    total = time.perf_counter() - t_all
    t = run.timings
    print(f"[validate] {len(run.conditions)} conditions, {len(run.metrics)} metrics, {len(run.families)} families: "
          f"generation {t['generate_s']:.1f} s, FGD encoder {t.get('fgd_train_s', 0.0):.1f} s, scoring "
          f"{t['score_s']:.1f} s, bootstrap ({args.bootstrap} resamples) {t['bootstrap_s']:.1f} s; "
          f"validation {t['total_s']:.1f} s")
    print(f"[total] {total:.1f} s with the corpus (load average now {os.getloadavg()[0]:.2f})\n")
    print(markdown(run.results, None))
    blind = speech_blind(run.results)
    print(f"{len(blind)} of {len(run.metrics)} metrics are blind to speech.")


if __name__ == "__main__":
    main()
