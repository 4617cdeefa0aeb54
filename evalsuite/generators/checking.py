"""``evalsuite generators check``: the contract's rules on a tiny corpus, for plug-in authors.

:func:`tiny_corpus` makes a few seconds of (noise-burst "speech" with word timings, BVH motion on the
synthetic humanoid) per segment, in memory plus files in a folder, with nothing to install or download.
:func:`check_generator` trains a trainable generator on it for a few seconds when no model is given, then
generates every segment with the runner (which enforces length, fps, finite values, joint names and
determinism), twice with samples where the generator is stochastic, and reports each rule.
"""
from __future__ import annotations

import pathlib
import tempfile
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np

from evalsuite.audio import write_wav
from evalsuite.corpus.types import Corpus, Segment, Stream, Transcript, Word
from evalsuite.generators.contract import GeneratorError
from evalsuite.generators.registry import GeneratorEntry
from evalsuite.motion.bvh_writer import write_bvh
from evalsuite.motion.synthetic import synthetic_motion

__all__ = ["tiny_corpus", "check_generator"]

_WORDS = ("so", "the", "idea", "is", "up", "here", "and", "you", "see", "it", "all", "now")


def tiny_corpus(folder: str | pathlib.Path, *, n_segments: int = 6, seconds: float = 4.0, fps: float = 30.0,
                rate: int = 16000, seed: int = 0, n_joints: int = 24) -> Corpus:
    """``n_segments`` segments (first two thirds train, then val, then test) of ``seconds`` each."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    segments = []
    n_train = max(1, (2 * n_segments) // 3)
    for i in range(n_segments):
        sid = f"seg{i:02d}"
        t, words, audio = 0.2, [], np.zeros(int(seconds * rate))
        while t < seconds - 0.6:
            length = float(rng.uniform(0.15, 0.45))
            a, b = int(t * rate), int((t + length) * rate)
            audio[a:b] = 0.3 * rng.standard_normal(b - a) * np.hanning(b - a)
            words.append(Word(str(rng.choice(_WORDS)), round(t, 4), round(t + length, 4)))
            t += length + float(rng.uniform(0.05, 0.3))
        write_wav(folder / f"{sid}.wav", audio[:, None], rate)
        motion = synthetic_motion(n_joints=n_joints, fps=fps, seconds=seconds, seed=seed * 100 + i)
        write_bvh(folder / f"{sid}.bvh", motion.skeleton, motion.values, 1.0 / fps)
        split = "train" if i < n_train else ("val" if i < n_train + max(1, (n_segments - n_train) // 2) else "test")
        segments.append(Segment(id=sid, main=Stream(folder / f"{sid}.wav", Transcript(tuple(words)),
                                                    folder / f"{sid}.bvh"),
                                duration=seconds, speaker="tiny", split=split))
    return Corpus(folder, "tiny", tuple(segments))


def check_generator(entry: GeneratorEntry, config: Mapping[str, Any],
                    model_dir: pathlib.Path | None) -> Iterator[str]:
    """Yield one line per rule checked; raise :class:`GeneratorError` at the first broken one."""
    from evalsuite.generators.requests import requests_from_corpus
    from evalsuite.generators.runner import generate
    from evalsuite.generators.training import train

    assert entry.spec is not None
    spec = entry.spec
    with tempfile.TemporaryDirectory(prefix="evalsuite-check-") as tmp:
        root = pathlib.Path(tmp)
        corpus = tiny_corpus(root / "corpus")
        yield f"tiny corpus: {len(corpus)} segments of 4 s (noise-burst speech, 24-joint BVH at 30 fps)"
        if spec.trainable and model_dir is None:
            result = train(entry, corpus, root / "model", seed=0, budget_minutes=0.1, config=config, progress=False)
            model_dir = result.model_dir
            yield f"fit: {len(result.history)} epochs in the 6-second budget, model folder written"
        elif spec.needs_model and model_dir is None:
            raise GeneratorError(f"{spec.name} needs --model to be checked")
        requests = requests_from_corpus(corpus, "all", 30.0)
        samples = 2 if spec.stochastic else 1
        run = generate(entry, requests, root / "out", config=config, model_dir=model_dir, seed=1, samples=samples,
                       progress=False)
        yield (f"generate: {len(run.files)} files; length, fps, finite values, joint names: ok; "
               "same seed twice: identical")
        fixes = [n for row in run.files for n in row["notes"]]
        if fixes:
            yield f"  the rules adjusted {len(fixes)} outputs (e.g. {fixes[0]['rule']}: {fixes[0]['action']})"
        if samples > 1:
            by_seg: dict[str, set[str]] = {}
            for row in run.files:
                by_seg.setdefault(row["segment"], set()).add(row["sha256"])
            same = [s for s, hashes in by_seg.items() if len(hashes) < samples]
            if same:
                raise GeneratorError(f"{spec.name} is declared stochastic but its {samples} samples of segment "
                                     f"{same[0]!r} are identical")
            yield "samples: differ between samples of a segment"
        yield f"{spec.name}: all checks passed"
