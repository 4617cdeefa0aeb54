"""The divergence guard (evalsuite.generators.divergence): a training whose loss or output scale is off by
orders of magnitude stops with an error and leaves no model folder."""
from __future__ import annotations

import math
import pathlib

import numpy as np
import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.generators.checking import tiny_corpus
from evalsuite.generators.divergence import DivergenceError, loss_divergence, scale_ratio
from evalsuite.generators.registry import find_generator
from evalsuite.generators.training import train
from evalsuite.motion import Motion
from tests.synth_helpers import build_corpus

SCALED = '''
import numpy as np
from evalsuite.generators import Generator, GeneratorSpec, GenerationResult, TrainingResult
from evalsuite.motion import Motion

class Scaled(Generator):
    """A falling loss; output = the first training segment's joint positions spread ``factor`` times."""
    spec = GeneratorSpec(name="scaled", version="0.1", summary="a test plug-in", audio="required",
                         output="positions", native_fps=None, units="cm", trainable=True,
                         config={"factor": "scale of the positions around their mean"})

    def load(self, config, model_dir=None):
        super().load(config, model_dir)
        data = np.load(model_dir / "positions.npz")
        self.pos, self.names, self.fps = data["pos"], [str(n) for n in data["names"]], float(data["fps"])

    def generate(self, request):
        p = self.pos.mean(axis=0) + float(self.option("factor", 1.0)) * (self.pos - self.pos.mean(axis=0))
        n = int(round(request.duration * self.fps))
        return GenerationResult(Motion.from_positions(np.resize(p, (n,) + p.shape[1:]), self.names, self.fps))

    def fit(self, corpus, out_dir, *, seed, budget_minutes=None, progress=None):
        m = corpus.split("train")[0].load_motion()
        np.savez(out_dir / "positions.npz", pos=m.positions(), names=np.array(m.joint_names), fps=m.fps)
        return TrainingResult(out_dir, [{"epoch": 1, "train_loss": 1.0}, {"epoch": 2, "train_loss": 0.9}])
'''


@pytest.fixture(scope="module")
def corpus_dir(tmp_path_factory) -> pathlib.Path:
    return build_corpus(tmp_path_factory.mktemp("div") / "corpus", minutes=0.6, segment_s=8.0)


def test_loss_divergence_nan_growth_and_stages():
    assert loss_divergence([{"train_loss": 1.0}, {"train_loss": 0.5}, {"train_loss": 0.4}]) is None
    assert "is nan" in loss_divergence([{"train_loss": 1.0}, {"train_loss": float("nan")}])
    assert "is inf" in loss_divergence([{"val_loss": 1.0}, {"val_loss": float("inf")}])
    grown = loss_divergence([{"stage": "a", "train_loss": 0.2}, {"stage": "a", "train_loss": 25.0}])
    assert "train_loss reached 25" in grown and "stage a" in grown and "100 x" in grown
    # a new stage with another loss (cross-entropy after a reconstruction) is compared with its own start
    assert loss_divergence([{"stage": "ae", "train_loss": 0.01}, {"stage": "translation", "train_loss": 2.0},
                            {"stage": "translation", "train_loss": 1.9}]) is None
    assert loss_divergence([{"epoch": 1, "seconds": float("nan")}]) is None    # only columns named *loss


def test_scale_ratio_of_scaled_motion():
    rng = np.random.default_rng(0)
    pos = rng.normal(size=(50, 4, 3))
    nat = Motion.from_positions(pos, ["Hips", "Head", "RightHand", "LeftHand"], 20.0)
    big = Motion.from_positions(pos * 1000.0, ["Hips", "Head", "RightHand", "LeftHand"], 20.0)
    assert scale_ratio(nat, nat) == pytest.approx(1.0)
    assert scale_ratio(big, nat) == pytest.approx(1000.0)
    other = Motion.from_positions(pos, ["a", "b", "c", "d"], 20.0)
    assert math.isnan(scale_ratio(other, nat))


def test_huge_learning_rate_stops_training_and_writes_no_model(corpus_dir, tmp_path):
    out = tmp_path / "model"
    result = CliRunner().invoke(main, ["train", "-g", "aud2pose", "--corpus", str(corpus_dir), "--set", "epochs=3",
                                       "--set", "learning_rate=1e8", "-o", str(out)])
    assert result.exit_code != 0
    assert "the training diverged" in result.output and "no model was written" in result.output
    assert not out.exists()


def test_output_scale_off_by_orders_of_magnitude_is_divergence(tmp_path):
    plugin = tmp_path / "scaled.py"
    plugin.write_text(SCALED)
    corpus = tiny_corpus(tmp_path / "corpus")
    entry = find_generator(f"{plugin}:Scaled")
    train(entry, corpus, tmp_path / "ok", config={"factor": 1.0}, progress=False)
    assert (tmp_path / "ok" / "model.json").is_file()
    for factor, word in ((1e4, "spreads"), (0.0, "spreads")):
        with pytest.raises(DivergenceError, match=word):
            train(entry, corpus, tmp_path / f"bad{factor:g}", config={"factor": factor}, progress=False)
        assert not (tmp_path / f"bad{factor:g}").exists()
    # retraining into an existing model folder that diverges leaves no model.json behind
    with pytest.raises(DivergenceError):
        train(entry, corpus, tmp_path / "ok", config={"factor": 1e4}, progress=False)
    assert not (tmp_path / "ok" / "model.json").exists()
