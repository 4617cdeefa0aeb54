"""evalsuite.generators.presets: the ``paper`` and ``cpu-small`` presets of each re-implementation."""
from __future__ import annotations

import json

import pytest
import torch
from click.testing import CliRunner
from synth_helpers import build_corpus

from evalsuite.corpus import load_corpus
from evalsuite.errors import InputError
from evalsuite.generators import find_generator
from evalsuite.generators.presets import SYSTEM_OPTIONS, apply_preset, markdown_table, preset_values
from evalsuite.generators.registry import generator_class
from evalsuite.generators.training import train

SYSTEMS = ["gesticulator", "aud2pose", "aud2repr2pose", "aud2motion", "gesture2vec", "ferstl-mogan"]
# a couple of steps of each stage, on top of the paper preset (the preset's own values otherwise)
SHORT = {
    "gesticulator": {"words": "hash", "epochs": 5},
    "aud2pose": {"epochs": 1},
    "aud2repr2pose": {"epochs": 1, "dae_epochs": 1},
    "aud2motion": {"epochs": 1},
    "gesture2vec": {"words": "hash", "dae_epochs": 1, "vq_epochs": 1, "vq_decoder_epochs": 1,
                    "translation_epochs": 1},
    "ferstl-mogan": {"classifier_epochs": 1, "pretrain_epochs": 1, "adversarial_steps": 2, "batch_size": 4,
                     "realism_pretrain_steps": 1, "phase_pretrain_tries": 1},
}


def _settings(name, config):
    gen = generator_class(find_generator(name).target)()
    gen.configure(config)
    return gen._settings()


@pytest.fixture(scope="module")
def corpus_dir(tmp_path_factory):
    return build_corpus(tmp_path_factory.mktemp("speaker") / "c", minutes=1.0, seed=2)


@pytest.mark.parametrize("name", SYSTEMS)
def test_cpu_small_is_the_plugin_default_and_paper_differs_where_the_table_says(name):
    default = _settings(name, {})
    paper = _settings(name, apply_preset(name, "paper", {}))
    for option in SYSTEM_OPTIONS[name]:
        assert default[option.name] == option.cpu_small, option.name
        assert paper[option.name] == option.paper, option.name
    differing = [o.name for o in SYSTEM_OPTIONS[name] if o.cpu_small != o.paper]
    assert differing and all(default[k] != paper[k] for k in differing)
    assert preset_values(name, "cpu-small") == {}
    assert f"`{differing[0]}`" in markdown_table(name)


def test_the_users_options_win_over_the_preset_and_unknown_presets_are_refused():
    assert apply_preset("gesticulator", "paper", {"velocity_weight": 2})["velocity_weight"] == 2
    assert apply_preset("gesticulator", "paper", {})["velocity_weight"] == 0.6
    with pytest.raises(InputError, match="unknown preset"):
        preset_values("gesticulator", "huge")
    with pytest.raises(InputError, match="no 'paper' preset"):
        preset_values("mean_pose", "paper")


@pytest.mark.parametrize("name", SYSTEMS)
def test_each_paper_preset_trains_a_few_steps(name, corpus_dir, tmp_path):
    corpus = load_corpus(corpus_dir)
    out = tmp_path / "model"
    result = train(find_generator(name), corpus, out, seed=0, config=SHORT[name], preset="paper", progress=False)
    assert result.history
    record = json.loads((out / "model.json").read_text())
    assert record["preset"] == "paper"
    for option in SYSTEM_OPTIONS[name]:
        if option.name not in SHORT[name]:
            assert record["config"][option.name] == option.paper


def test_train_and_generate_name_the_preset(corpus_dir, tmp_path):
    from evalsuite.cli import main

    model, out = tmp_path / "model", tmp_path / "out"
    runner = CliRunner()
    res = runner.invoke(main, ["train", "-g", "aud2pose", "--corpus", str(corpus_dir), "--preset", "paper",
                               "--set", "epochs=1", "--set", "representation=expmap", "-o", str(model)])
    assert res.exit_code == 0, res.output
    assert json.loads((model / "model.json").read_text())["preset"] == "paper"
    res = runner.invoke(main, ["generate", "-g", "aud2pose", "--model", str(model), "--corpus", str(corpus_dir),
                               "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert json.loads((out / "generation.json").read_text())["preset"] == "paper"
    res = runner.invoke(main, ["train", "-g", "aud2pose", "--corpus", str(corpus_dir), "--preset", "huge",
                               "-o", str(tmp_path / "x")])
    assert res.exit_code != 0 and "huge" in res.output


def test_the_weakened_decoder_is_frozen_in_the_first_vq_stage(monkeypatch):
    import numpy as np

    from evalsuite.generators.gesture2vec import training as g2v
    from evalsuite.generators.gesture2vec.net import G2VConfig

    made = []

    class Recorded(g2v.VQDVAE):
        def __init__(self, config):
            super().__init__(config)
            made.append((self, {k: v.clone() for k, v in self.state_dict().items()}))

    monkeypatch.setattr(g2v, "VQDVAE", Recorded)
    rng = np.random.default_rng(0)
    poses = [rng.normal(size=(200, 12)).astype(np.float32) for _ in range(2)]
    words = [[(rng.normal(size=8).astype(np.float32), 0.5 * k) for k in range(20)] for _ in range(2)]
    config = G2VConfig(pose_dim=12, text_dim=8, codebook=8, latent_dim=6, vq_hidden=8, vq_layers=1, text_hidden=8)

    def decoder_moved(weakened):
        made.clear()
        stages = g2v.G2VStages(dae_epochs=1, vq_epochs=2, vq_decoder_epochs=0, translation_epochs=1,
                               weakened_decoder=weakened)
        g2v.train_gesture2vec(poses, words, config, 20.0, stages, seed=0)
        vq, start = made[0]
        now = vq.state_dict()
        moved = {k: not torch.equal(now[k], start[k]) for k in now}
        return moved

    weak, full = decoder_moved(True), decoder_moved(False)
    decoder_keys = [k for k in weak if k.startswith(("decoder.", "out."))]
    assert decoder_keys and not any(weak[k] for k in decoder_keys)
    assert any(weak[k] for k in weak if k.startswith("encoder."))
    assert all(full[k] for k in decoder_keys)
