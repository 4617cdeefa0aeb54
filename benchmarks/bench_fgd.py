"""Benchmark of the learned metrics (needs the learned extra).

1. Training: 30 minutes of 30 fps, 56-joint motion (synthetic BVH-like motion, 30 one-minute
   takes), window 30 / stride 15, GENEA recipe (batch 64, Adam 5e-4), deterministic single-thread
   training. Target: < 10 minutes. Peer in the same run: one epoch with torch's default thread
   count (the non-reproducible setting) for the per-epoch cost of determinism.
2. FGD: 10 conditions x 40 one-minute sequences against 40 natural one-minute sequences
   (56 joints, 30 fps, BVH-like motion so forward kinematics is included), feature-space FGD
   with a 1000-resample sequence bootstrap. Target: < 60 s. Peer: the reference scripts' FD
   (``scipy.linalg.sqrtm`` of the covariance product) on the same features.
3. Raw-space FGD cost per condition (4760 windows x 5040 dims), measured on 2 conditions.

Usage: python benchmarks/bench_fgd.py [--epochs 50] [--quick]
Other processes on the machine slow every figure down; the script prints the load average.
"""
from __future__ import annotations

import argparse
import os
import time
import warnings

import numpy as np


def _takes(n: int, seconds: float, seed0: int):
    from evalsuite.motion.synthetic import synthetic_motion

    return {f"take{i:03d}": synthetic_motion(n_joints=56, fps=30.0, seconds=seconds, seed=seed0 + i)
            for i in range(n)}


def _reference_fd(x, y):
    from scipy import linalg

    m1, m2 = x.mean(0), y.mean(0)
    s1, s2 = np.cov(x, rowvar=False), np.cov(y, rowvar=False)
    with warnings.catch_warnings():  # sqrtm's complex round-off warnings, as the references ignore them
        warnings.simplefilter("ignore")
        covmean = linalg.sqrtm(s1 @ s2)
    return float((m1 - m2) @ (m1 - m2) + np.trace(s1) + np.trace(s2) - 2 * np.trace(covmean.real))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--epochs", type=int, default=50)
    ap.add_argument("--quick", action="store_true", help="Small sizes, to check the script runs.")
    ap.add_argument("--part", choices=["all", "fgd", "raw"], default="all",
                    help="fgd/raw: skip the training figures (a 1-epoch model is used for scoring).")
    args = ap.parse_args()
    import torch

    from evalsuite.learned.training import train_model

    minutes = 2 if args.quick else 30
    n_seq = 4 if args.quick else 40
    n_cond = 2 if args.quick else 10
    print(f"torch {torch.__version__}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} "
          "(other processes share the CPU; figures are wall-clock)")

    # --- 1. training -----------------------------------------------------------------------
    train_data = _takes(minutes, 60.0, 1000)
    if args.part != "all":
        args.epochs = 1
    t0 = time.perf_counter()
    model = train_model(train_data, joints="all", window=30, stride=15, fps=30.0, epochs=args.epochs, seed=0,
                        progress=False)
    t_train = time.perf_counter() - t0
    prov = model.meta["training"]
    print(f"\n[train] {minutes} min of 30 fps 56-joint motion: {prov['train_windows']} training + "
          f"{prov['val_windows']} validation windows, {args.epochs} epochs: {t_train:.1f} s "
          f"({t_train / args.epochs:.2f} s/epoch incl. data preparation), target < 600 s -> "
          f"{'PASS' if t_train < 600 else 'FAIL'}")
    print(f"[train] final losses: train {prov['history'][-1]['train_loss']:.4f}, "
          f"validation {prov['history'][-1]['val_loss']:.4f}")
    if args.part == "all":
        _train_peer(train_data, torch)
    del train_data
    reference = _takes(n_seq, 60.0, 0)
    conditions = {f"SYS{c:02d}": _takes(n_seq, 60.0, 10_000 * (c + 1)) for c in range(n_cond)}
    if args.part in ("all", "fgd"):
        _fgd(model, reference, conditions, n_seq, n_cond)
    if args.part in ("all", "raw"):
        _raw(model, reference, conditions)


def _train_peer(train_data, torch):
    from evalsuite.learned.training import train_model

    t0 = time.perf_counter()
    train_model(train_data, joints="all", window=30, stride=15, fps=30.0, epochs=1, seed=0, progress=False,
                threads=None)
    t_peer = time.perf_counter() - t0
    t0 = time.perf_counter()
    train_model(train_data, joints="all", window=30, stride=15, fps=30.0, epochs=1, seed=0, progress=False)
    t_one = time.perf_counter() - t0
    print(f"[train] peer: 1 epoch with torch's default {torch.get_num_threads()} threads {t_peer:.2f} s vs "
          f"deterministic 1 thread {t_one:.2f} s (ratio {t_one / t_peer:.2f})")


def _fgd(model, reference, conditions, n_seq, n_cond):
    from evalsuite.learned.fgd import WindowSet, score_fgd

    t0 = time.perf_counter()
    rows = score_fgd(model, reference, conditions, raw=False, n_bootstrap=1000)
    t_fgd = time.perf_counter() - t0
    print(f"\n[fgd] {n_cond} conditions x {n_seq} one-minute sequences (+{n_seq} reference), "
          f"{rows[0]['n_windows_reference']} windows per set, bootstrap 1000 x sequence: {t_fgd:.1f} s "
          f"(FK + windows + encoding + FD + CI), target < 60 s -> {'PASS' if t_fgd < 60 else 'FAIL'}")
    print("[fgd] values: " + ", ".join(f"{r['condition']} {r['value']:.3f} [{r['ci_low']:.3f}, {r['ci_high']:.3f}]"
                                     for r in rows[:3]) + " ...")
    # Peer: the reference FD formula on the same features.
    ref_feat = WindowSet(model, reference, raw=False, label="reference").all_features
    cond_feat = WindowSet(model, conditions["SYS00"], raw=False, label="SYS00").all_features
    from evalsuite.metrics.frechet import frechet_distance_samples

    t0 = time.perf_counter()
    ours = [frechet_distance_samples(ref_feat, cond_feat) for _ in range(20)][0]
    t_ours = (time.perf_counter() - t0) / 20
    t0 = time.perf_counter()
    theirs = [_reference_fd(ref_feat, cond_feat) for _ in range(20)][0]
    t_theirs = (time.perf_counter() - t0) / 20
    print(f"[fgd] peer (reference sqrtm FD) on the same features: {theirs:.6f} vs ours {ours:.6f} "
          f"(|diff| {abs(theirs - ours):.2e}); time per FD {t_theirs * 1e3:.2f} ms vs ours {t_ours * 1e3:.2f} ms "
          f"(ratio {t_ours / t_theirs:.2f})")



def _raw(model, reference, conditions):
    from evalsuite.learned.fgd import score_fgd

    two = dict(list(conditions.items())[:2])
    t0 = time.perf_counter()
    raw_rows = score_fgd(model, reference, two, raw=True, n_bootstrap=0)
    t_raw = time.perf_counter() - t0
    t0 = time.perf_counter()
    score_fgd(model, reference, two, raw=False, n_bootstrap=0)
    t_feat = time.perf_counter() - t0
    per_cond = (t_raw - t_feat) / len(two)
    dims = model.window * model.arch.pose_dim
    print(f"\n[raw] raw-space FGD ({raw_rows[0]['n_windows_reference']} windows x {dims} dims): "
          f"{per_cond:.1f} s per condition on top of the feature FGD (mean of {len(two)} conditions): "
          + ", ".join(f"{r['condition']} {r['value']:.1f}" for r in raw_rows if r["metric"] == "fgd_raw"))


if __name__ == "__main__":
    main()
