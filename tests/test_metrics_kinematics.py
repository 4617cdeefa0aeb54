"""Kinematic metrics: analytic oracles and the reference scripts' formulas (written here independently)."""
import numpy as np
import pytest

from evalsuite.errors import InputError
from evalsuite.metrics import (
    CONVENTIONS,
    across_sequences,
    average_acceleration,
    average_jerk,
    average_speed,
    derivative_norms,
    sequence_means,
)


def _times(fps, seconds=2.0):
    return np.arange(int(seconds * fps)) / fps


@pytest.mark.parametrize("fps", [20.0, 30.0, 59.94, 120.0])
def test_constant_velocity_gives_speed_norm_and_zero_acceleration_and_jerk(fps):
    v = np.array([[3.0, -4.0, 12.0], [0.5, 0.0, 0.0]])  # two joints, |v| = 13 and 0.5
    t = _times(fps)
    pos = t[:, None, None] * v[None] + np.array([1.0, 2.0, 3.0])
    np.testing.assert_allclose(average_speed(pos, fps), [13.0, 0.5], rtol=1e-9)
    np.testing.assert_allclose(average_acceleration(pos, fps), 0.0, atol=1e-6)
    np.testing.assert_allclose(average_jerk(pos, fps), 0.0, atol=1e-3)


def test_constant_acceleration_and_cubic_jerk_are_exact():
    fps = 25.0
    t = _times(fps, 3.0)
    a = np.array([0.0, -9.81, 2.0])
    pos_a = (0.5 * t[:, None] ** 2 * a)[:, None, :]
    np.testing.assert_allclose(average_acceleration(pos_a, fps), [np.linalg.norm(a)], rtol=1e-7)
    c = np.array([1.5, -2.0, 0.0])
    pos_c = (t[:, None] ** 3 * c)[:, None, :]
    np.testing.assert_allclose(average_jerk(pos_c, fps), [6 * np.linalg.norm(c)], rtol=1e-6)


def test_no_fps_gives_units_per_frame():
    pos = np.arange(10.0)[:, None, None] * np.array([0.0, 2.0, 0.0])
    np.testing.assert_allclose(average_speed(pos, None), [2.0])
    assert derivative_norms(pos, 1).shape == (9, 1)


# --- the reference scripts, re-written here from their published formulas -------------------
def _reference_average(data_tj3, n, rate):
    """calk_jerk_or_acceleration.py / calc_jerk.py: flatten, np.diff n, per-joint norm loop, mean, x rate^n."""
    flat = data_tj3.reshape(data_tj3.shape[0], -1)
    d = np.diff(flat, n=n, axis=0)
    norms = np.zeros((d.shape[0], d.shape[1] // 3))
    for i in range(d.shape[0]):
        for j in range(d.shape[1] // 3):
            norms[i, j] = np.linalg.norm(d[i, 3 * j:3 * j + 3])
    average = np.mean(norms, axis=0)
    return average if rate is None else average * rate ** n


@pytest.mark.parametrize("convention,rate", [("genea2020", 20), ("genea2022", 30), ("aud2repr2pose", None)])
def test_reference_conventions_reproduce_the_scripts(convention, rate):
    rng = np.random.default_rng(1)
    data = np.cumsum(rng.normal(size=(120, 7, 3)), axis=0) * 2.0
    conv = CONVENTIONS[convention]
    for n in (1, 2, 3):
        ours = derivative_norms(data, n).mean(axis=0) * conv.scale(fps=55.0, order=n)  # data fps is ignored
        np.testing.assert_allclose(ours, _reference_average(data, n, rate), rtol=1e-9, atol=1e-9)


def test_default_convention_scales_by_the_data_fps():
    conv = CONVENTIONS["default"]
    assert conv.scale(24.0, 3) == 24.0 ** 3
    assert conv.unit(2) == "units/s^2"
    assert CONVENTIONS["aud2repr2pose"].unit(1) == "units/frame"


def test_summaries_follow_genea_mean_and_std_across_sequences():
    table = np.array([[1.0, 3.0], [2.0, 6.0], [0.0, 0.0]])   # 3 sequences x 2 joints
    per_seq = sequence_means(table)
    np.testing.assert_allclose(per_seq, [2.0, 4.0, 0.0])
    mean, std = across_sequences(per_seq, ddof=0)
    assert mean == pytest.approx(np.mean(table.mean(axis=1)))
    assert std == pytest.approx(np.std(table.mean(axis=1)))   # GENEA: np.std, across sequences
    assert across_sequences(per_seq, ddof=1)[1] == pytest.approx(np.std(per_seq, ddof=1))


@pytest.mark.parametrize("bad", [np.zeros((10, 3)), np.zeros((3, 2, 3)), np.full((10, 2, 3), np.nan), "abc"])
def test_bad_positions_raise_input_error(bad):
    with pytest.raises(InputError):
        average_jerk(bad, 30.0)


def test_bad_fps_raises_input_error():
    with pytest.raises(InputError):
        average_speed(np.zeros((5, 1, 3)), -1)
