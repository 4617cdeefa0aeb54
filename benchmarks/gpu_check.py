"""Does each re-implementation train and generate on CUDA, and does its output agree with the CPU's?

Writes a small synthetic corpus, then for each system trains one short run (one epoch of each stage, or the few
steps below) with ``--device cpu`` and, when torch sees a CUDA GPU, with ``--device cuda`` from the same seed,
generates the test split with each model on its device, and prints per system: training and generation seconds
on each device, their ratio (CPU / CUDA), and how far the CUDA output is from the CPU output (max |difference|
of the joint positions, divided by the CPU output's range). GPU kernels are not bitwise deterministic and the
initial weights are drawn on each device, so the two are not expected to be equal; the figure shows the size of
the difference. Without a GPU the CPU part runs and the script says "no GPU: CUDA part not run".

    python benchmarks/gpu_check.py [--minutes 1] [--only aud2pose,gesture2vec] [--amp]
"""
from __future__ import annotations

import argparse
import pathlib
import tempfile
import time

import numpy as np

from evalsuite.corpus import load_corpus
from evalsuite.generators import find_generator
from evalsuite.generators.device import resolve_device, use_device
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.generators.training import train
from evalsuite.motion.io import load_motion
from evalsuite.synth.corpus import synthesize_corpus

ONE_EPOCH = {
    "gesticulator": {"epochs": 5, "words": "hash"},      # its schedule needs 5 (pretraining, 3 stages, free)
    "aud2pose": {"epochs": 1},
    "aud2motion": {"epochs": 1},
    "aud2repr2pose": {"epochs": 1, "dae_epochs": 1},
    "gesture2vec": {"words": "hash", "codebook": 8, "dae_epochs": 1, "vq_epochs": 1, "vq_decoder_epochs": 1,
                    "translation_epochs": 1},
    "ferstl-mogan": {"classifier_epochs": 1, "pretrain_epochs": 1, "adversarial_steps": 4, "batch_size": 4,
                     "realism_pretrain_steps": 2, "phase_pretrain_tries": 2},
}


def _run(name: str, corpus, root: pathlib.Path, device: str, amp: bool) -> tuple[float, float, list[np.ndarray]]:
    entry = find_generator(name)
    with use_device(device, amp and device == "cuda"):
        t0 = time.perf_counter()
        train(entry, corpus, root / f"{name}-{device}", seed=0, config=ONE_EPOCH[name], progress=False)
        t1 = time.perf_counter()
        run = generate(entry, requests_from_corpus(corpus, ["test"], 20.0), root / f"{name}-{device}-out",
                       model_dir=root / f"{name}-{device}", seed=0, progress=False)
        t2 = time.perf_counter()
    out = [load_motion(run.out_dir / r["file"]).positions() for r in run.files]
    return t1 - t0, t2 - t1, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--minutes", type=float, default=1.0, help="Size of the synthetic corpus (minutes).")
    ap.add_argument("--only", default="", help="Comma-separated systems (default: all six).")
    ap.add_argument("--amp", action="store_true", help="Mixed precision on CUDA.")
    args = ap.parse_args()
    names = [n for n in args.only.split(",") if n] or list(ONE_EPOCH)
    cuda = resolve_device("auto") == "cuda"
    with tempfile.TemporaryDirectory() as tmp:
        root = pathlib.Path(tmp)
        synthesize_corpus(root / "corpus", args.minutes, 0, progress=False)
        corpus = load_corpus(root / "corpus")
        for name in names:
            cpu_train, cpu_gen, cpu_out = _run(name, corpus, root, "cpu", False)
            line = f"{name:14s} cpu: train {cpu_train:7.2f} s, generate {cpu_gen:6.2f} s"
            if cuda:
                gpu_train, gpu_gen, gpu_out = _run(name, corpus, root, "cuda", args.amp)
                diff = max(float(np.max(np.abs(a - b)) / max(np.ptp(a), 1e-12)) for a, b in zip(cpu_out, gpu_out))
                line += (f" | cuda{' amp' if args.amp else ''}: train {gpu_train:7.2f} s, generate {gpu_gen:6.2f} s"
                         f" | cpu/cuda train {cpu_train / gpu_train:5.2f}x | output max|cpu-cuda|/range {diff:.3g}")
            print(line, flush=True)
    if not cuda:
        print("no GPU: CUDA part not run (torch.cuda.is_available() is False)")


if __name__ == "__main__":
    main()
