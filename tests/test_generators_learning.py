"""The re-implementations learn from a synthetic speaker (a CI-sized corpus and budget: 4 minutes of speech,
20-40 seconds of training each). The full criteria of issue 14 are measured on 30 minutes of corpus by
benchmarks/bench_generators.py; these tests check that training uses the speech and text at all and is
reproducible."""
from __future__ import annotations

import json

import numpy as np
import pytest

from evalsuite.corpus import load_corpus
from evalsuite.errors import InputError
from evalsuite.generators import find_generator
from evalsuite.generators.evaluation import (
    causal_mean_through_rate,
    conditional_mean_through_rate,
    evaluate_condition,
    natural_through_rate,
    swapped_audio,
)
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.generators.training import train
from evalsuite.synth.corpus import synthesize_corpus

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    root = tmp_path_factory.mktemp("speaker")
    synthesize_corpus(root, 4.0, seed=5, progress=False)
    return load_corpus(root)


@pytest.fixture(scope="module")
def test_requests(corpus):
    return requests_from_corpus(corpus, "test", 30.0)


def _trained(name, corpus, tmp_path_factory, minutes, **config):
    model = tmp_path_factory.mktemp(name)
    train(find_generator(name), corpus, model, seed=0, budget_minutes=minutes, config=config, progress=False)
    return model


@pytest.mark.parametrize("name", ["aud2repr2pose", "aud2motion", "aud2pose"])
def test_aud2_systems_follow_the_speech(corpus, test_requests, tmp_path_factory, name):
    model = _trained(name, corpus, tmp_path_factory, 0.4)
    out = tmp_path_factory.mktemp(f"{name}_out")
    entry = find_generator(name)
    generate(entry, test_requests, out / "own", model_dir=model, progress=False)
    generate(entry, swapped_audio(test_requests), out / "swapped", model_dir=model, progress=False)
    own, swapped = evaluate_condition(out / "own", corpus), evaluate_condition(out / "swapped", corpus)
    # wrist speed follows this segment's speech energy, and not when the model hears another segment's speech
    assert own["energy_speed_r"] > 0.3
    assert own["energy_speed_r"] > swapped["energy_speed_r"] + 0.15
    record = json.loads((model / "model.json").read_text())
    assert any(r.get("best") for r in record["history"])            # early stopping chose an epoch
    assert record["corpus"]["splits"]["train"] == len(corpus.split("train"))


def test_gesticulator_trains_and_generates_from_audio_and_text(corpus, test_requests, tmp_path_factory):
    model = _trained("gesticulator", corpus, tmp_path_factory, 0.3, words="hash", epochs=6)
    out = tmp_path_factory.mktemp("gest_out")
    entry = find_generator("gesticulator")
    both = generate(entry, test_requests, out / "both", model_dir=model, progress=False)
    text_only = generate(entry, test_requests, out / "text_only", model_dir=model, config={"zero_audio": True},
                         progress=False)
    for row, req in zip(both.files, test_requests):
        assert row["frames"] == req.n_frames
        assert row["file"].endswith(".bvh")
        assert [n["rule"] for n in row["notes"]][0] == "fps"         # generated at 20 fps, resampled to 30
    # both input streams reach the network: silencing the audio features changes the motion
    assert [r["sha256"] for r in both.files] != [r["sha256"] for r in text_only.files]
    history = json.loads((model / "model.json").read_text())["history"]
    assert history[0]["stage"] == "pretrain"
    assert all("val_loss" in r for r in history)


@pytest.mark.parametrize("name, options", [("aud2repr2pose", {"epochs": 3, "dae_epochs": 2}),
                                           ("aud2motion", {"epochs": 3}),
                                           ("gesticulator", {"epochs": 5, "words": "hash"})])
def test_training_twice_with_one_seed_gives_the_same_weights(corpus, tmp_path_factory, name, options):
    hashes = []
    for _ in range(2):
        model = _trained(name, corpus, tmp_path_factory, None, **options)
        hashes.append(json.loads((model / "model.json").read_text())["weights_sha256"])
    assert hashes[0] == hashes[1]


def test_aud2repr2pose_model_folders_of_either_autoencoder_load(corpus, test_requests, tmp_path_factory):
    """The autoencoder of poses and velocities (the default) and of poses alone (``dae_inputs=poses``, and every
    model folder saved before the option existed, whose settings.json does not name it) both load and generate;
    so does a speech network with the velocity target (``velocity_target=true``; off by default, as the paper)."""
    entry = find_generator("aud2repr2pose")
    for inputs, velocity in (("poses+velocities", False), ("poses", True)):
        model = _trained("aud2repr2pose", corpus, tmp_path_factory, None, epochs=2, dae_epochs=1,
                         dae_inputs=inputs, velocity_target=velocity)
        settings = json.loads((model / "settings.json").read_text())
        assert settings["dae_inputs"] == inputs and settings["net"]["velocity_target"] is velocity
        out = tmp_path_factory.mktemp("a2r_dae")
        generate(entry, test_requests[:1], out / "a", model_dir=model, progress=False)
        first = sorted((out / "a").glob("*.bvh"))
        assert len(first) == 1
        if inputs == "poses":   # a folder from before: no dae_inputs in its settings
            del settings["dae_inputs"]
            (model / "settings.json").write_text(json.dumps(settings))
            generate(entry, test_requests[:1], out / "b", model_dir=model, progress=False)
            assert (out / "b" / first[0].name).read_bytes() == first[0].read_bytes()


def test_aud2motion_folders_from_before_past_frames_load_with_one_frame_per_step(corpus, test_requests,
                                                                               tmp_path_factory):
    """A model folder saved before the option existed (its settings name no ``past_frames``) was trained on one
    frame per step; it loads as such, not with today's default of 5, and generates the same motion."""
    entry = find_generator("aud2motion")
    model = _trained("aud2motion", corpus, tmp_path_factory, None, epochs=2, past_frames=1)
    out = tmp_path_factory.mktemp("a2m_old")
    generate(entry, test_requests[:1], out / "a", model_dir=model, progress=False)
    settings = json.loads((model / "settings.json").read_text())
    assert settings["past_frames"] == 1 and settings["net"]["past_frames"] == 1
    del settings["past_frames"], settings["net"]["past_frames"]
    (model / "settings.json").write_text(json.dumps(settings))
    generate(entry, test_requests[:1], out / "b", model_dir=model, progress=False)
    first = sorted((out / "a").glob("*.bvh"))
    assert len(first) == 1 and (out / "b" / first[0].name).read_bytes() == first[0].read_bytes()


def test_natural_motion_through_20_fps_keeps_its_poses_but_loses_energy_coupling(corpus, tmp_path):
    """The benchmark's first reference row: a 20-fps copy of the speaker's performance. Its poses and keyword
    gestures are the natural ones, but the syllable-long wrist flicks are smoothed, so the energy / wrist-speed r
    drops (0.60 -> 0.50 on the benchmark's corpus)."""
    own_fps = corpus.split("test")[0].load_motion().fps
    native = evaluate_condition(natural_through_rate(corpus, tmp_path / "native", own_fps), corpus)
    via20 = evaluate_condition(natural_through_rate(corpus, tmp_path / "via20", 20.0), corpus)
    assert native["pose_mse"] == 0.0
    assert via20["pose_mse"] < 0.1    # cm²; the mean pose's is about 36
    assert via20["lexical_mean"] == pytest.approx(native["lexical_mean"], rel=0.02)
    assert via20["energy_speed_r"] < native["energy_speed_r"] - 0.05


def test_conditional_mean_of_performances_beats_one_performance_and_keeps_the_coupling(corpus, tmp_path):
    """The benchmark's second reference row: the mean of 16 performances of the test speech estimates the
    conditional mean, the best a deterministic model of the pose error can do. It is closer to the speaker's
    motion than another single performance, its wrists follow the loudness as the speaker's do (on this corpus
    r 0.81 against 0.75; the benchmark's 0.66 against 0.60), and 20 fps smooths that (0.69; benchmark 0.54)."""
    own_fps = corpus.split("test")[0].load_motion().fps
    natural = evaluate_condition(natural_through_rate(corpus, tmp_path / "natural", own_fps), corpus)
    one = evaluate_condition(conditional_mean_through_rate(corpus, tmp_path / "one", 1), corpus)
    mean = evaluate_condition(conditional_mean_through_rate(corpus, tmp_path / "mean", 16), corpus)
    via20 = evaluate_condition(conditional_mean_through_rate(corpus, tmp_path / "via20", 16, 20.0), corpus)
    assert len(list((tmp_path / "mean").glob("*.npz"))) == len(corpus.split("test"))
    assert mean["pose_mse"] < 0.8 * one["pose_mse"]
    assert mean["energy_speed_r"] > natural["energy_speed_r"] - 0.05
    assert via20["energy_speed_r"] < mean["energy_speed_r"] - 0.05
    assert via20["pose_mse"] == pytest.approx(mean["pose_mse"], rel=0.05)


def test_causal_mean_knows_less_than_the_conditional_mean_and_more_than_nothing(corpus, tmp_path):
    """The causal reference rows: per frame, the mean of performances whose words not yet begun are drawn at
    random. The less of the speech is known, the larger the pose error: every word known (the conditional mean
    given the whole speech) < words known from their start (a causal listener) < from 0.3 s into them < none known
    (the mean over random speech with these timings). A seed gives the same files."""
    def error(heard_after, name, seed=0):
        folder = causal_mean_through_rate(corpus, tmp_path / name, 16, heard_after=heard_after, seed=seed)
        return evaluate_condition(folder, corpus)["pose_mse"]

    every, causal, late, none = (error(h, n) for h, n in ((-1e3, "every"), (0.0, "causal"), (0.3, "late"),
                                                            (1e3, "none")))
    assert every < 0.8 * causal and causal < late < none
    assert len(list((tmp_path / "causal").glob("*.npz"))) == len(corpus.split("test"))
    again = causal_mean_through_rate(corpus, tmp_path / "again", 16, seed=0)
    for f in (tmp_path / "causal").glob("*.npz"):
        np.testing.assert_array_equal(np.load(f)["positions"], np.load(again / f.name)["positions"])
    with pytest.raises(InputError, match="k must be at least 1"):
        causal_mean_through_rate(corpus, tmp_path / "none", 0)


def test_conditional_mean_needs_a_synthetic_corpus_and_one_performance(corpus, tmp_path):
    import dataclasses

    with pytest.raises(InputError, match="k must be at least 1"):
        conditional_mean_through_rate(corpus, tmp_path / "none", 0)
    elsewhere = dataclasses.replace(corpus, root=tmp_path, meta={})   # a corpus without the speaker's corpus.json
    with pytest.raises(InputError, match="not a synthetic-speaker corpus"):
        conditional_mean_through_rate(elsewhere, tmp_path / "none")
    (tmp_path / "corpus.json").write_text('{"format": "genea"}', encoding="utf-8")
    with pytest.raises(InputError, match="expected format"):
        conditional_mean_through_rate(elsewhere, tmp_path / "none")
