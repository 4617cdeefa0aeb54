"""APE / MAE against time-aligned ground truth."""
import warnings

import numpy as np
import pytest

from evalsuite.errors import InputError
from evalsuite.metrics import LengthMismatchWarning, align_lengths, average_position_error, mean_absolute_error


def test_constant_offset_oracle():
    nat = np.random.default_rng(0).normal(size=(50, 3, 3))
    gen = nat + np.array([3.0, 4.0, 0.0])
    np.testing.assert_allclose(average_position_error(gen, nat), [5.0] * 3)
    np.testing.assert_allclose(mean_absolute_error(gen, nat), [7.0 / 3] * 3)


def test_mae_matches_reference_formula():
    rng = np.random.default_rng(1)
    nat, gen = rng.normal(size=(2, 40, 5, 3))
    # calc_errors.py: mean_absolute_error(multioutput="raw_values") per coordinate, then mean of each joint's 3
    per_coord = np.abs(nat.reshape(40, -1) - gen.reshape(40, -1)).mean(axis=0)
    np.testing.assert_allclose(mean_absolute_error(gen, nat), per_coord.reshape(5, 3).mean(axis=1), rtol=1e-12)
    ape_loop = np.mean([[np.linalg.norm(nat[t, j] - gen[t, j]) for j in range(5)] for t in range(40)], axis=0)
    np.testing.assert_allclose(average_position_error(gen, nat), ape_loop, rtol=1e-12)


def test_align_lengths_truncates_and_warns_beyond_one_second():
    a, b = np.zeros((100, 2, 3)), np.ones((80, 2, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        x, y, d = align_lengths(a, b, fps=30)   # 20 frames = 0.67 s: no warning
    assert len(x) == len(y) == 80
    assert d == pytest.approx(20 / 30)
    with pytest.warns(LengthMismatchWarning, match="truncated to 80"):
        align_lengths(a, b, fps=10)             # 2 s apart


def test_shape_mismatch_is_an_input_error():
    with pytest.raises(InputError):
        average_position_error(np.zeros((5, 2, 3)), np.zeros((6, 2, 3)))
    with pytest.raises(InputError):
        align_lengths(np.zeros((5, 2, 3)), np.zeros((5, 3, 3)), fps=30)
