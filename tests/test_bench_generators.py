"""benchmarks/bench_generators.py's bookkeeping over several training seeds (the trainings themselves are the
benchmark's; tests/test_generators_learning.py and tests/test_gesticulator_criteria.py train in CI)."""
from __future__ import annotations

import importlib.util
import pathlib

import pytest

_PATH = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "bench_generators.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_generators", _PATH)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _row(name, seed, pose, r, swap=2.5, **extra):
    return {"generator": name, "train_seed": seed, "pose_err_vs_mean_pose": pose, "energy_speed_r": r,
            "swapped_audio_err_ratio": swap, "lexical_vs_natural": 0.7, **extra}


def test_issue14_criteria_of_one_training(bench):
    assert bench.issue14_holds(_row("aud2motion", 0, 0.59, 0.52))
    assert not bench.issue14_holds(_row("aud2motion", 0, 0.623, 0.52))      # pose error bound 0.6
    assert not bench.issue14_holds(_row("aud2motion", 0, 0.59, 0.487))      # r bound 0.5
    assert not bench.issue14_holds(_row("aud2motion", 0, 0.59, 0.52, swap=1.1))   # uses the speech: +20 %
    assert bench.issue14_holds(_row("gesticulator", 0, 0.58, 0.53, lexical_text_only_vs_natural=0.48))
    assert not bench.issue14_holds(_row("gesticulator", 0, 0.58, 0.53, lexical_text_only_vs_natural=0.0))


def test_summary_over_seeds_counts_the_trainings_that_hold(bench):
    rows = [{"generator": "natural via 20 fps", "pose_err_vs_mean_pose": 0.0, "energy_speed_r": 0.5},
            _row("aud2repr2pose", 0, 0.577, 0.596), _row("aud2repr2pose", 1, 0.631, 0.588),
            _row("aud2repr2pose", 2, 0.579, 0.582), _row("gesticulator-audio", 0, 0.89, 0.72),
            _row("gesticulator-audio", 1, 0.9, 0.7)]
    table = bench.seeds_summary(rows).set_index("generator")
    assert list(table.index) == ["aud2repr2pose", "gesticulator-audio"]   # reference rows are not trainings
    a2r = table.loc["aud2repr2pose"]
    assert a2r["trainings"] == 3 and a2r["criteria held"] == "2 of 3"
    assert a2r["pose_err mean"] == pytest.approx((0.577 + 0.631 + 0.579) / 3)
    assert a2r["r range"] == "0.582-0.596"
    assert table.loc["gesticulator-audio", "criteria held"] == ""          # an ablation: not judged


@pytest.mark.parametrize(("argv", "message"), [
    (["--train-seeds", "0,x"], "--train-seeds: expected comma-separated integers"),
    (["--train-seeds", "0,1", "--train-seed", "3"], "exclude each other"),
    (["--set", "dae_inputs"], "--set: expected KEY=VALUE"),
])
def test_bad_arguments_are_named(bench, argv, message, capsys):
    with pytest.raises(SystemExit):
        bench.main(argv)
    assert message in capsys.readouterr().err
