"""Shared data for the gesture2vec / ferstl-mogan tests: one small synthetic-speaker corpus per test session.

The corpus is small (about 6 minutes: ~14 training, 2 validation, 2 test segments) so that CI can train on it;
the learning criteria are measured on its test split with budgets and epochs far below the benchmark's
(benchmarks/bench_generators.py trains on 30 minutes with the defaults).
"""
from __future__ import annotations

import functools
import pathlib
import tempfile

MINUTES = 6.0
SEED = 3


@functools.cache
def synth_corpus_dir() -> pathlib.Path:
    """Built once per test session (EVALSUITE_TEST_SYNTH_CORPUS names an existing one, for local iterations)."""
    import os

    from evalsuite.synth.corpus import synthesize_corpus

    if os.environ.get("EVALSUITE_TEST_SYNTH_CORPUS"):
        return pathlib.Path(os.environ["EVALSUITE_TEST_SYNTH_CORPUS"])
    root = pathlib.Path(tempfile.mkdtemp(prefix="evalsuite-g2v-mogan-")) / "corpus"
    synthesize_corpus(root, MINUTES, SEED, jobs=2, progress=False)
    return root


@functools.cache
def synth_corpus():
    from evalsuite.corpus import load_corpus

    return load_corpus(synth_corpus_dir())


def natural_scores(corpus, split: str = "test") -> dict[str, float]:
    """The oracle: the criteria of :mod:`evalsuite.generators.evaluation` on the corpus's own motion."""
    import numpy as np

    from evalsuite.generators.evaluation import POSITION_CLASSES, segment_scores

    rows = [segment_scores(s.load_motion(), s) for s in corpus.split(split)]
    keys = sorted({k for r in rows for k in r})
    out = {k: float(np.nanmean([r.get(k, np.nan) for r in rows])) for k in keys}
    out["lexical_mean"] = float(np.nanmean([out.get(f"lexical_{c}", np.nan) for c in POSITION_CLASSES]))
    return out
