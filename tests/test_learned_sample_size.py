"""FGD and its sample size: the small-N bias on Gaussians with a known Fréchet distance, FGD at a fixed N,
FGD∞ (Chong & Forsyth), and the rows and figure they give in ``evalsuite score``."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner
from learned_helpers import natural, trained

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.learned.sample_size import fgd_at_n, fgd_infinity, n_grid
from evalsuite.metrics.frechet import frechet_distance_samples
from evalsuite.motion.io import save_motion

D = 8
SHIFT = np.full(D, 0.3)
SCALE = np.linspace(0.6, 1.4, D)
# FD between N(0, I) and N(SHIFT, diag(SCALE^2)): ||mu||^2 + sum(1 + s^2 - 2 s)
TRUTH = float(SHIFT @ SHIFT + np.sum(1 + SCALE**2 - 2 * SCALE))


def _pools(seed: int, n: int = 600) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.normal(size=(n, D)), SHIFT + SCALE * rng.normal(size=(n, D))


def test_small_samples_are_biased_up_and_fgd_infinity_removes_most_of_it():
    a, b = _pools(0, 4000)
    biases = [fgd_at_n(a, b, n, draws=100, seed=1)["value"] - TRUTH for n in (25, 50, 100, 400)]
    # the bias is about c / N: large at 25 windows, shrinking with N, still positive at 400
    assert biases[0] > 1.0 and all(x > y for x, y in zip(biases, biases[1:])) and biases[-1] > 0
    assert biases[0] * 25 == pytest.approx(biases[2] * 100, rel=0.3)
    full, inf = [], []
    for seed in range(100):
        x, y = _pools(100 + seed, 150)
        full.append(frechet_distance_samples(x, y) - TRUTH)
        inf.append(fgd_infinity(x, y, seed=seed)["value"] - TRUTH)
    # 150 windows a side: the plain FGD is biased up by ~0.35 (a quarter of the distance; standard error of
    # the mean over 100 pools ~0.03); FGD∞ from the same pools removes most of it
    assert np.mean(full) > 0.25
    assert abs(np.mean(inf)) < 0.3 * np.mean(full)


def test_fgd_at_n_draws_without_replacement_and_is_seeded():
    a, b = _pools(3, 300)
    whole = fgd_at_n(a, b, 300, draws=5)
    assert whole["value"] == pytest.approx(frechet_distance_samples(a, b)) and whole["std"] < 1e-9
    assert whole["with_replacement"] == 0.0
    r1, r2 = fgd_at_n(a, b, 60, draws=50, seed=4), fgd_at_n(a, b, 60, draws=50, seed=4)
    assert r1 == r2 and r1["ci_low"] < r1["value"] < r1["ci_high"]
    assert fgd_at_n(a, b[:40], 60, draws=10)["with_replacement"] == 1.0
    with pytest.raises(InputError):
        fgd_at_n(a, b, 1)


def test_fgd_infinity_fit_and_too_few_windows():
    grid = n_grid(600, D)
    assert grid[0] == 120 and grid[-1] == 600 and len(grid) == 10
    a, b = _pools(5)
    fit = fgd_infinity(a, b, seed=2)
    means, ns = fit["fgd_n"], fit["ns"]
    assert fit["draws"].shape == (10, 20)
    # the line goes through the means: its value at the largest N is near the mean there
    assert fit["value"] + fit["slope"] / ns[-1] == pytest.approx(means[-1], abs=0.05)
    assert fit["slope"] > 0 and fit["ci_low"] < fit["value"] < fit["ci_high"]
    with pytest.raises(InputError, match="more windows"):
        n_grid(20, D)


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("fgd_n")
    model_path = tmp / "model.pt"
    trained().save(model_path)
    nat = natural()
    names = sorted(nat)
    for folder, pick in (("natural", names[0::2]), ("sys", names[1::2])):
        (tmp / folder).mkdir()
        for i, n in enumerate(pick):
            save_motion(nat[n], tmp / folder / f"seq{i}.npz")
    return tmp, model_path


def test_score_reports_fgd_n_fgd_at_n_and_fgd_infinity(folders):
    tmp, model = folders
    out = tmp / "out"
    res = CliRunner().invoke(main, ["score", "-r", str(tmp / "natural"), str(tmp / "sys"), "-m", "kinematics",
                                    "--fgd", str(model), "--fgd-n", "40", "--fgd-inf", "-o", str(out), "--quiet"])
    assert res.exit_code == 0, res.output
    summary = pd.read_csv(out / "summary.csv")
    rows = summary[summary.condition == "sys"].set_index("metric")
    assert rows.loc["fgd_n", "value"] == rows.loc["fgd", "n_windows_condition"] > 40
    assert rows.loc["fgd[n=40]", "ci_low"] <= rows.loc["fgd[n=40]", "value"] <= rows.loc["fgd[n=40]", "ci_high"]
    # fewer windows, more bias: FGD on 40 windows a side exceeds FGD on all of them, FGD∞ lies below
    assert rows.loc["fgd[n=40]", "value"] > rows.loc["fgd", "value"] > rows.loc["fgd_inf", "value"] - 1e-9
    assert (out / "figures" / "fgd_inf.png").exists()
    plain = CliRunner().invoke(main, ["score", "-r", str(tmp / "natural"), str(tmp / "sys"), "-m", "kinematics",
                                      "--fgd-n", "40", "-o", str(tmp / "o2"), "--quiet"])
    assert plain.exit_code != 0 and "--fgd MODEL" in plain.output
