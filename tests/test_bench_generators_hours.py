"""benchmarks/bench_generators_hours.py: the corpus of N copies of a train split that the benchmark trains on (the
trainings themselves are the benchmark's)."""
from __future__ import annotations

import importlib.util
import json
import pathlib

import pytest
from synth_helpers import build_corpus

from evalsuite.corpus import load_corpus

_PATH = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "bench_generators_hours.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_generators_hours", _PATH)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_replicate_repeats_the_train_split_only(bench, tmp_path):
    base = build_corpus(tmp_path / "base", minutes=0.5, seed=1)
    out = bench.replicate(base, tmp_path / "x3", 3)
    one, three = load_corpus(base), load_corpus(out)
    assert len(three.split("train")) == 3 * len(one.split("train"))
    assert {s.id for s in three.split("val")} == {s.id for s in one.split("val")}
    seg = next(s for s in three.split("train") if s.id.endswith("_r2"))
    orig = next(s for s in one.split("train") if s.id == seg.id[:-3])
    assert seg.duration == orig.duration
    assert (seg.load_motion().values == orig.load_motion().values).all()
    assert json.loads((out / "corpus.json").read_text())["splits"]["train"][-1].endswith("_r2")


def test_throughput_counts_every_pass(bench):
    row = {"system": "gesticulator", "frames": 1000, "train_s": 10.0}
    assert bench.throughput(row) == 500.0
