"""How much of the synthetic speaker's pose is left to chance: the floor of a learned model's pose error.

For each handedness setting, on the test split of a synthetic corpus (default: 30 minutes, seed 0, as
``bench_generators.py``), the "natural" motion is the speaker model with the corpus's own random draws and
that setting; against it, relative to the error of the mean pose (world positions of the GENEA 2020 upper-body
joints, the pose error of ``evalsuite.generators.evaluation``):

* ``another``: another performance of the same speech (another seed);
* ``mean_of_k``: the mean of k performances -- about the best a deterministic model can do (the conditional
  mean of the pose given the speech, estimated from k samples).

A learned model's pose error below ``mean_of_k`` would be luck; the issue's criterion (0.6 x mean pose) must
lie well above it for the criterion to judge the model rather than the data.

Usage: python benchmarks/bench_speaker_chance.py [--corpus DIR | --minutes 30 --seed 0] [--k 16]
"""
from __future__ import annotations

import argparse
import pathlib
import sys
import tempfile

import numpy as np

from evalsuite.corpus import load_corpus
from evalsuite.motion import Motion
from evalsuite.motion.presets import GENEA2020_UPPER
from evalsuite.synth.corpus import synthesize_corpus
from evalsuite.synth.oracle import segment_oracle
from evalsuite.synth.params import MotionParams

SETTINGS = ((0.8, 0.1, 0.1), (0.9, 0.05, 0.05), (0.9, 0.02, 0.08))


def _positions(m: Motion) -> np.ndarray:
    return m.positions()[:, [m.joint_index(n) for n in GENEA2020_UPPER if n in m.joint_names]]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--corpus", type=pathlib.Path, default=None)
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--k", type=int, default=16)
    args = ap.parse_args(argv)
    root = args.corpus
    if root is None:
        root = pathlib.Path(tempfile.mkdtemp(prefix="bench-chance-")) / "corpus"
        synthesize_corpus(root, args.minutes, seed=args.seed, progress=False)
    corpus = load_corpus(root)
    meta = corpus.meta.get("corpus_json") or corpus.meta
    base = MotionParams.from_dict(meta["model"]["params"])
    segments = list(corpus.split("test"))
    print(f"{len(segments)} test segments of {root}; k = {args.k}")
    print("| handedness R/L/both | another | mean_of_k |\n|---|---|---|")
    for hands in SETTINGS:
        params = base.replace(hands_p=hands)
        natural = [_positions(segment_oracle(corpus, s.id, params=params)[0]) for s in segments]
        mean_pose = np.concatenate(natural).mean(axis=0)
        other, mean_k, still = [], [], []
        for seg, nat in zip(segments, natural):
            runs = np.stack([_positions(segment_oracle(corpus, seg.id, seed=10_000 + j, params=params)[0])[:len(nat)]
                             for j in range(args.k)])
            other.append(((runs[0] - nat) ** 2).sum(-1).mean())
            mean_k.append(((runs.mean(0) - nat) ** 2).sum(-1).mean())
            still.append(((mean_pose - nat) ** 2).sum(-1).mean())
        print(f"| {'/'.join(f'{round(100 * h)}' for h in hands)} | {np.mean(other) / np.mean(still):.3f} | "
              f"{np.mean(mean_k) / np.mean(still):.3f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
