"""benchmarks/bench_presets.py's set-up and bookkeeping (its trainings are the benchmark's; the systems' own tests
train in CI)."""
from __future__ import annotations

import importlib.util
import pathlib

import pytest

from evalsuite.generators import find_generator
from evalsuite.generators.presets import SYSTEM_OPTIONS, apply_preset
from evalsuite.generators.registry import generator_class

_PATH = pathlib.Path(__file__).resolve().parents[1] / "benchmarks" / "bench_presets.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_presets", _PATH)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_system_with_a_paper_preset_has_a_budget(bench):
    assert set(bench.BUDGETS) == set(SYSTEM_OPTIONS)


@pytest.mark.parametrize("preset", ["cpu-small", "paper"])
def test_each_budget_is_accepted_by_its_system_under_both_presets(bench, preset):
    for name, (budget, _) in bench.BUDGETS.items():
        gen = generator_class(find_generator(name).target)()
        gen.configure(apply_preset(name, preset, budget))      # an option the system does not have raises
        for key, value in budget.items():
            assert gen.config[key] == value, (name, key)


def test_train_command_names_the_preset_and_the_same_budget_for_both(bench, tmp_path):
    small = bench.train_command("aud2pose", "cpu-small", tmp_path / "c", tmp_path / "m", 3)
    paper = bench.train_command("aud2pose", "paper", tmp_path / "c", tmp_path / "m", 3)
    assert small[small.index("--preset") + 1] == "cpu-small" and paper[paper.index("--preset") + 1] == "paper"
    sets = [a for i, a in enumerate(paper) if i and paper[i - 1] == "--set"]
    assert sets == [a for i, a in enumerate(small) if i and small[i - 1] == "--set"] == ["epochs=1", "patience=1"]
    assert paper[paper.index("--seed") + 1] == "3" and "--budget-minutes" not in paper


def test_parameters_are_counted_over_every_saved_network(bench, tmp_path):
    import torch

    torch.save(torch.nn.Linear(3, 4).state_dict(), tmp_path / "a.pt")                  # 12 + 4
    torch.save({"net": torch.nn.GRU(2, 5).state_dict(), "step": 7}, tmp_path / "b.pt")  # 3*5*(2+5) + 2*15
    assert bench.count_parameters(tmp_path) == 16 + 105 + 30


def test_markdown_leaves_missing_and_nan_cells_empty(bench):
    table = bench.markdown([{"system": "x", "preset": "paper", "parameters": 12345, "r": float("nan"),
                             "pose_err": 0.61234}])
    header, rule, row = table.splitlines()
    assert header.startswith("| system | preset | parameters |") and rule.count("---") == len(bench.COLUMNS)
    assert row == "| x | paper | 12,345 |  |  | 0.612 |  |  |  |  |  |  |"


def test_bad_arguments_are_named(bench, capsys):
    with pytest.raises(SystemExit):
        bench.main(["--only", "nosuch"])
    assert "unknown ['nosuch']" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        bench.main(["--presets", "huge"])
    assert "--presets" in capsys.readouterr().err


def test_reuse_models_only_takes_a_model_of_the_same_preset_and_budget(bench, tmp_path):
    import json

    assert not bench.reusable(tmp_path / "none", "aud2pose", "paper")
    (tmp_path / "model.json").write_text(json.dumps({"preset": "paper", "config": {"epochs": 1, "patience": 1}}))
    assert bench.reusable(tmp_path, "aud2pose", "paper")
    with pytest.raises(SystemExit, match="another preset or budget"):
        bench.reusable(tmp_path, "aud2pose", "cpu-small")
    (tmp_path / "model.json").write_text(json.dumps({"preset": "paper", "config": {"epochs": 120}}))
    with pytest.raises(SystemExit, match="another preset or budget"):
        bench.reusable(tmp_path, "aud2pose", "paper")
