"""The oracle condition: the synthetic speaker's model run on each segment's speech."""
from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.corpus import load_corpus
from evalsuite.generators import GeneratorError, find_generator
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.motion.io import load_motion
from evalsuite.synth.corpus import synthesize_corpus


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    root = tmp_path_factory.mktemp("synth")
    synthesize_corpus(root, 1.0, seed=3, progress=False)
    return load_corpus(root)


def test_same_seed_reproduces_the_corpus_motion_and_other_seeds_differ(corpus, tmp_path):
    run = CliRunner().invoke(main, ["generate", "-g", "oracle", "--corpus", str(corpus.root), "--split", "all",
                                    "--set", "same_seed=true", "-o", str(tmp_path / "same")])
    assert run.exit_code == 0, run.output
    for seg in corpus.segments:
        ours, theirs = load_motion(tmp_path / "same" / f"{seg.id}.bvh"), seg.load_motion()
        np.testing.assert_allclose(ours.values, theirs.values, atol=1e-5)
    reqs = requests_from_corpus(corpus, "all", 30.0)
    other = generate(find_generator("oracle"), reqs, tmp_path / "other", config={"corpus": str(corpus.root)},
                     samples=2, seed=1, progress=False)
    hashes = {r["segment"]: set() for r in other.files}
    for r in other.files:
        hashes[r["segment"]].add(r["sha256"])
    assert all(len(h) == 2 for h in hashes.values())


def test_switches_change_the_motion_as_stated(corpus, tmp_path):
    reqs = requests_from_corpus(corpus, "all", 30.0)[:1]
    base = {"corpus": str(corpus.root), "same_seed": True}
    calm = generate(find_generator("oracle"), reqs, tmp_path / "calm", progress=False,
                    config={**base, "amplitude": 0.25})
    plain = load_motion(corpus.segments[0].motion)
    small = load_motion(tmp_path / "calm" / calm.files[0]["file"])
    speed = lambda m: np.abs(np.diff(m.positions(), axis=0)).mean()  # noqa: E731
    assert speed(small) < 0.6 * speed(plain)
    assert calm.files[0]["meta"]["switches"]["amplitude"] == 0.25


def test_the_oracle_needs_a_synthetic_corpus(tmp_path):
    from evalsuite.generators.checking import tiny_corpus

    c = tiny_corpus(tmp_path / "tiny")
    (tmp_path / "tiny" / "splits.csv").write_text("segment,split\n" + "".join(f"{s.id},test\n" for s in c))
    with pytest.raises(GeneratorError, match="oracle needs the synthetic corpus"):
        generate(find_generator("oracle"), requests_from_corpus(c, "test", 30.0), tmp_path / "o", progress=False)
