"""Typed option accessors of the plug-in contract (a bad --set value is a GeneratorError naming the field), and
evalsuite.generators.options: each re-implementation's options declared once."""
from __future__ import annotations

import re

import pytest

from evalsuite.generators import GeneratorError, find_generator
from evalsuite.generators.options import Option, Options
from evalsuite.generators.presets import SYSTEM_OPTIONS, apply_preset, markdown_table, system_options
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


# -- each system's options declared once (evalsuite.generators.options) ------------------------------------------
# _settings() with no option and with the paper preset, as the plug-ins returned them before the declarations
# were gathered (hard-coded from that code): the same values, of the same types
_AUD2 = {"batch_size": 16, "code_dim": 40, "dae_epochs": 20, "dae_inputs": "poses+velocities", "ema": 0.99,
         "epochs": 300, "features": "mfcc", "form": "sequence", "learning_rate": 0.001, "lr_schedule": "constant",
         "past_frames": 1, "patience": 50, "representation": "expmap", "scale_floor": 0.1, "threads": 1,
         "validate_on": "poses", "velocity_target": False, "width": 64}
_AUD2_PAPER = {"batch_size": 2056, "ema": 0.0, "epochs": 120, "form": "windowed", "patience": 120,
               "representation": "positions", "scale_floor": 0.0, "width": 256}
SETTINGS_BEFORE = {
    "gesticulator": (
        {"autoregressive": True, "batch_size": 64, "dropout": 0.1, "ema": 0.0, "epochs": 90, "film": True,
         "film_identity": False, "frame_layers": 1, "future": 20, "inputs": "audio+text", "learning_rate": 0.001,
         "lr_schedule": "cosine", "past": 10, "patience": None, "prev_pose_dropout": 0.8, "scale_floor": 0.0,
         "size": "cpu", "text_dropout": 0.8, "threads": 1, "velocity_weight": 7.0, "weight_decay": 0.001,
         "words": "minilm-static"},
        {"dropout": 0.2, "epochs": 95, "learning_rate": 0.0001, "lr_schedule": "constant", "size": "paper",
         "text_dropout": 0.0, "velocity_weight": 0.6, "weight_decay": 0.0, "words": "minilm"}),
    "aud2pose": ({**_AUD2, "velocity_target": True}, _AUD2_PAPER),
    "aud2repr2pose": (_AUD2, _AUD2_PAPER),
    "aud2motion": ({**_AUD2, "past_frames": 5},
                   {"ema": 0.0, "epochs": 500, "past_frames": 1, "patience": 500, "representation": "positions",
                    "scale_floor": 0.0, "width": 256}),
    "gesture2vec": (
        {"aligned": True, "batch_size": 128, "chunk": 30, "codebook": 300, "dae_epochs": 10, "decoding": "generative",
         "learning_rate": 0.001, "reset_dead_codes": True, "scale_floor": 0.1, "size": "cpu", "stride": 10,
         "temperature": 0.0, "threads": 1, "translation_epochs": 60, "vq_decoder_epochs": 10, "vq_epochs": 15,
         "weakened_decoder": False, "words": "minilm-static", "conditioned_decoder": False},
        {"aligned": False, "dae_epochs": 20, "reset_dead_codes": False, "scale_floor": 0.0, "size": "paper",
         "translation_epochs": 250, "vq_decoder_epochs": 20, "vq_epochs": 20, "weakened_decoder": True,
         "conditioned_decoder": True}),
    "ferstl-mogan": (
        {"ablation": "none", "adversarial_learning_rate": 0.0005, "adversarial_steps": 400, "batch_size": 16,
         "classifier_epochs": 30, "discriminator_learning_rate": 0.0001, "discriminator_width": 64,
         "learning_rate": 0.001, "noise_dim": 8, "phase_labels": "corpus", "phase_pretrain_tries": 40,
         "pretrain_epochs": 30, "realism_pretrain_steps": 100, "scale_floor": 0.1, "threads": 1, "width": 128},
        {"noise_dim": 0, "scale_floor": 0.0, "width": 256}),
}


def _same(got, expected):
    assert got == expected
    assert {k: type(v) for k, v in got.items()} == {k: type(v) for k, v in expected.items()}


@pytest.mark.parametrize("name", list(SETTINGS_BEFORE))
def test_settings_are_those_of_the_code_before_the_options_were_declared_once(name):
    default, paper = SETTINGS_BEFORE[name]
    _same(_configured(name)._settings(), default)
    _same(_configured(name, **apply_preset(name, "paper", {}))._settings(), {**default, **paper})


@pytest.mark.parametrize("name", list(SETTINGS_BEFORE))
def test_spec_config_and_preset_rows_derive_from_the_declarations(name):
    options = system_options(name)
    cls = generator_class(find_generator(name).target)
    assert cls.spec.config == options.config_help()
    assert SYSTEM_OPTIONS[name] == options.preset_rows()
    g = _configured(name)
    settings = g._settings()
    assert set(settings) == {o.name for o in options if o.settings}
    for option in options:      # every row's cpu-small value is the plug-in's default
        if option.settings:
            assert settings[option.name] == option.default, option.name
    assert [line.split(" | ")[0] for line in markdown_table(name).splitlines()[2:]] == \
        [f"| `{row.name}`" for row in SYSTEM_OPTIONS[name]]


def test_the_three_aud2_systems_share_one_help_and_differ_where_declared():
    configs = [generator_class(find_generator(n).target).spec.config for n in ("aud2pose", "aud2motion", "aud2repr2pose")]
    assert configs[0] == configs[1] == configs[2]
    assert [o.name for o in SYSTEM_OPTIONS["aud2motion"]] == ["width", "past_frames", "epochs", "patience", "ema",
                                                              "scale_floor", "representation"]
    assert _configured("aud2pose", form="windowed")._settings()["batch_size"] == 2056  # the windowed form's batch
    assert _configured("aud2pose", form="windowed", batch_size=8)._settings()["batch_size"] == 8


@pytest.mark.parametrize(("option", "value", "expected"), [
    ("decoding", "beam", "decoding must be generative or retrieval, got 'beam'"),
    ("codebook", "0", "codebook must be a positive integer, got 0"),
    ("threads", 0, "threads must be a positive integer, got 0"),
    ("temperature", "-1", "temperature must be >= 0, got -1.0"),
])
def test_gesture2vec_ranges_are_checked_with_the_same_messages(option, value, expected):
    with pytest.raises(GeneratorError, match=re.escape(expected)) as err:
        _configured("gesture2vec", **{option: value})._settings()
    assert err.value.field == option


def test_an_option_parses_by_its_kind():
    g = _configured("gesticulator", frame_layers="2", patience="7", zero_audio="yes")
    opts = system_options("gesticulator")
    assert opts["frame_layers"].parse(g) == 2 and opts["patience"].parse(g) == 7
    assert opts.value(g, "zero_audio") is True and "zero_audio" not in g._settings()  # read at generation only
    assert opts["patience"].parse(_configured("gesticulator")) is None
    with pytest.raises(GeneratorError, match="frame_layers must be one of 1, 2, got '3'"):
        opts["frame_layers"].parse(_configured("gesticulator", frame_layers=3))
    assert opts["velocity_weight"].paper_value == 0.6 and opts["inputs"].paper_value == "audio+text"


def test_declarations_refuse_mistakes():
    with pytest.raises(ValueError, match="kind must be one of"):
        Option("x", "integer", 1, "help")
    with pytest.raises(ValueError, match="needs its choices"):
        Option("x", "choice", "a", "help")
    with pytest.raises(ValueError, match="declared twice"):
        Options("s", (Option("x", "int", 1, "help"), Option("x", "int", 2, "help")))
    with pytest.raises(ValueError, match="no option"):
        system_options("gesticulator").revised("other", {"nonexistent": {"default": 1}})
    revised = Options("s", (Option("x", "int", 1, "h", source="paper"), Option("y", "int", 2, "h"))).revised(
        "t", {"y": {"default": 3}}, drop=("x",))
    assert revised.defaults() == {"y": 3} and revised.preset_rows() == ()


def _stated_defaults(text):
    """The values a help text gives as the default: "(default 90)", "(default: 0.1", "cpu (default)"."""
    return (re.findall(r"\(default[:;]? ?'?([^\s;,):']+)", text)
            + re.findall(r"'?([\w+.-]+)'? \(default", text))


def _states(token, value):
    if isinstance(value, bool) or value is None:
        return token.lower() == str(value).lower()
    if isinstance(value, (int, float)):
        try:
            return float(token) == float(value)
        except ValueError:
            return False
    return token == value


# the aud2 systems share these two help texts, which give each system's default in prose ("5 for aud2motion")
PER_SYSTEM_PROSE = {"past_frames", "velocity_target"}


@pytest.mark.parametrize("name", list(SETTINGS_BEFORE))
def test_the_help_states_the_declared_default(name):
    """A help text that names a default names the declared one (a changed default cannot leave stale help)."""
    for option in system_options(name):
        if "default" in option.help and option.name not in PER_SYSTEM_PROSE:
            stated = _stated_defaults(option.help)
            assert any(_states(t, option.default) for t in stated), (option.name, option.default, stated)


def test_gesture2vec_is_stochastic_only_with_retrieval_or_a_temperature():
    assert [_configured("gesture2vec", **c).stochastic for c in ({}, {"decoding": "retrieval"},
                                                                 {"temperature": "0.5"})] == [False, True, True]


def test_the_stage_settings_take_their_defaults_from_the_declared_options():
    from evalsuite.generators.ferstl_mogan import options as mogan_options
    from evalsuite.generators.ferstl_mogan.training import MoganStages
    from evalsuite.generators.gesticulator.options import OPTIONS as GESTICULATOR
    from evalsuite.generators.gesticulator.training import PREDICTED_FRAMES, TrainSchedule, budgeted_schedule
    from evalsuite.generators.gesture2vec.options import OPTIONS as G2V
    from evalsuite.generators.gesture2vec.training import G2VStages

    d = GESTICULATOR.defaults()
    assert TrainSchedule() == budgeted_schedule(d["epochs"])
    assert (TrainSchedule().epochs, TrainSchedule().batch_size, TrainSchedule().learning_rate,
            TrainSchedule().lr_schedule) == (d["epochs"], d["batch_size"], d["learning_rate"], d["lr_schedule"])
    assert TrainSchedule().sequence == d["past"] + PREDICTED_FRAMES + d["future"]
    g2v, stages = G2V.defaults(), G2VStages()
    for name in ("dae_epochs", "vq_epochs", "vq_decoder_epochs", "translation_epochs", "learning_rate",
                 "batch_size", "reset_dead_codes", "scale_floor", "weakened_decoder"):
        assert getattr(stages, name) == g2v[name], name
    mogan, ms = mogan_options.OPTIONS.defaults(), MoganStages()
    for name in ("classifier_epochs", "pretrain_epochs", "realism_pretrain_steps", "phase_pretrain_tries",
                 "adversarial_steps", "batch_size", "learning_rate", "adversarial_learning_rate",
                 "discriminator_learning_rate", "scale_floor"):
        assert getattr(ms, name) == mogan[name], name
    assert ms.discriminators == mogan_options.ABLATIONS[mogan["ablation"]]
