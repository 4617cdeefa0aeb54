"""Typed option accessors of the plug-in contract: a bad --set value is a GeneratorError naming the field."""
from __future__ import annotations

import pytest

from evalsuite.generators import GeneratorError, find_generator
from evalsuite.generators.registry import generator_class


def _configured(name: str, **config):
    g = generator_class(find_generator(name).target)()
    g.configure(config)
    return g


def test_numbers_and_flags_are_parsed_as_the_cli_gives_them():
    g = _configured("ferstl-mogan", adversarial_steps="40", discriminator_learning_rate="2e-4", width=64)
    assert g.int_option("adversarial_steps") == 40 and g.int_option("width") == 64
    assert g.float_option("discriminator_learning_rate") == pytest.approx(2e-4)
    assert g.int_option("noise_dim", 8) == 8           # the default when not set
    g = _configured("gesticulator", film="false", autoregressive=True)
    assert g.bool_option("film", True) is False and g.bool_option("autoregressive", False) is True


@pytest.mark.parametrize(("name", "option", "value", "expected"), [
    ("ferstl-mogan", "discriminator_learning_rate", "abc", "must be a finite number, got 'abc'"),
    ("ferstl-mogan", "adversarial_steps", "2.5", "must be an integer"),
    ("gesture2vec", "codebook", True, "must be an integer"),
    ("aud2pose", "learning_rate", "nan", "finite number"),
    ("gesticulator", "film", "maybe", "must be true or false, got 'maybe'"),
    ("aud2repr2pose", "ema", "1", r"ema must be in \[0, 1\)"),
    ("gesticulator", "ema", "abc", "ema must be a number"),
    ("ferstl-mogan", "scale_floor", "1.5", r"scale_floor must be in \[0, 1\)"),
    ("gesticulator", "velocity_weight", "x", "must be a finite number"),
    ("aud2motion", "past_frames", "0", "past_frames must be at least 1"),
    ("aud2pose", "past_frames", "2.5", "must be an integer"),
])
def test_a_bad_value_names_the_option(name, option, value, expected):
    g = _configured(name, **{option: value})
    with pytest.raises(GeneratorError, match=expected) as err:
        g._settings()
    assert err.value.field == option


def test_past_frames_are_refused_for_the_windowed_form():
    g = _configured("aud2pose", form="windowed", past_frames=5)
    with pytest.raises(GeneratorError, match="applies to the sequence form") as err:
        g._settings()
    assert err.value.field == "past_frames"


@pytest.mark.parametrize(("name", "past_frames"), [("aud2pose", 1), ("aud2motion", 5), ("aud2repr2pose", 1)])
def test_only_aud2motion_reads_the_speech_before_each_frame_by_default(name, past_frames):
    """The causal aud2motion reads each frame with the 4 before it (0.25 s, a documented deviation); the
    bidirectional systems keep the paper's one frame per step, as does an explicit ``past_frames=1``."""
    assert _configured(name)._settings()["past_frames"] == past_frames
    assert _configured(name, past_frames="1")._settings()["past_frames"] == 1


@pytest.mark.parametrize(("name", "velocity", "dae_inputs"), [("aud2pose", True, "poses+velocities"),
                                                              ("aud2motion", False, "poses+velocities"),
                                                              ("aud2repr2pose", False, "poses+velocities")])
def test_aud2_defaults_are_the_papers_velocity_target_and_the_japanese_autoencoder(name, velocity, dae_inputs):
    settings = _configured(name)._settings()
    assert settings["velocity_target"] is velocity and settings["dae_inputs"] == dae_inputs
    assert _configured(name, velocity_target="true", dae_inputs="poses")._settings()["velocity_target"] is True
    with pytest.raises(GeneratorError, match="dae_inputs") as err:
        _configured(name, dae_inputs="velocities")._settings()
    assert err.value.field == "dae_inputs"
