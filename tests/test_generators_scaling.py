"""The re-implementations' pose scaling with a relative floor (evalsuite.generators.scaling)."""
from __future__ import annotations

import numpy as np
import pytest

from evalsuite.generators.scaling import DEFAULT_FLOOR, floored_spread


def test_dimensions_that_hardly_move_keep_their_small_size():
    spread = np.array([1.6, 0.8, 0.2, 0.014, 0.0])
    out = floored_spread(spread, 0.1)
    # limbs keep their own scale; sway and a still channel are divided by 0.16, not stretched to +-1
    np.testing.assert_allclose(out, [1.6, 0.8, 0.2, 0.16, 0.16])
    # floor 0 is the papers' per-dimension scaling (with the old 1e-6 guard for a still channel)
    np.testing.assert_allclose(floored_spread(spread, 0.0), [1.6, 0.8, 0.2, 0.014, 1e-6])
    assert 0 < DEFAULT_FLOOR < 1


def test_a_floor_outside_zero_to_one_is_refused():
    with pytest.raises(ValueError, match=r"scale_floor must be in \[0, 1\)"):
        floored_spread(np.ones(3), 1.0)
    with pytest.raises(ValueError, match="scale_floor"):
        floored_spread(np.ones(3), -0.1)


def test_the_aud2_scaler_and_the_gesticulator_normaliser_use_it():
    # torch is required by the test suite (.ci/run installs it), not skipped
    from evalsuite.generators.aud2repr2pose.training import MaxAbsScaler
    from evalsuite.generators.gesticulator.training import Normaliser

    rng = np.random.default_rng(0)
    x = np.stack([rng.uniform(-1, 1, 500), 0.01 * rng.uniform(-1, 1, 500)], axis=1)
    scaled = MaxAbsScaler.fit([x], 0.1)(x)
    assert np.abs(scaled[:, 0]).max() == pytest.approx(1.0, abs=1e-6)
    assert np.abs(scaled[:, 1]).max() < 0.11          # the swaying channel stays small
    assert np.abs(MaxAbsScaler.fit([x], 0.0)(x)[:, 1]).max() == pytest.approx(1.0, abs=1e-6)
    norm = Normaliser.fit([x], 0.1)
    assert norm.std[1] == pytest.approx(0.1 * norm.std[0])


def test_learning_rate_schedules():
    from evalsuite.generators.schedules import learning_rate_at

    assert learning_rate_at("constant", 1e-3, 7, 60) == 1e-3
    assert learning_rate_at("cosine", 1e-3, 0, 60) == pytest.approx(1e-3)
    assert learning_rate_at("cosine", 1e-3, 59, 60) == pytest.approx(1e-5)
    # halfway the cosine is at its midpoint between the rate and its floor
    assert learning_rate_at("cosine", 1.0, 50, 101) == pytest.approx(0.01 + 0.99 * 0.5)
    with pytest.raises(ValueError, match="lr_schedule must be"):
        learning_rate_at("step", 1e-3, 0, 10)


def test_aud2_plugins_name_a_bad_schedule():
    from evalsuite.generators import GeneratorError
    from evalsuite.generators.aud2repr2pose.plugin import Aud2Pose

    g = Aud2Pose()
    g.configure({"lr_schedule": "step"})
    with pytest.raises(GeneratorError, match="lr_schedule must be one of constant, cosine"):
        g._settings()
    g.configure({})
    assert g._settings()["lr_schedule"] == "constant" and g._settings()["scale_floor"] == DEFAULT_FLOOR


@pytest.mark.parametrize("name", ["aud2pose", "aud2motion", "aud2repr2pose", "gesticulator", "gesture2vec",
                                  "ferstl-mogan"])
@pytest.mark.parametrize("value, message", [(1.5, r"scale_floor must be in \[0, 1\), got 1.5"),
                                            ("wide", "scale_floor must be a number")])
def test_every_reimplementation_names_a_bad_scale_floor(name, value, message):
    from evalsuite.generators import GeneratorError, find_generator
    from evalsuite.generators.registry import generator_class

    g = generator_class(find_generator(name).target)()
    g.configure({"scale_floor": value})
    with pytest.raises(GeneratorError, match=message) as err:
        g._settings()
    assert err.value.field == "scale_floor"
