"""Several samples per sequence (evalsuite.metrics.samples): <name>_<k> files are paired with the natural <name>,
each metric says in summary.csv whether it used the first sample, each (mean over samples) or all of them."""
from __future__ import annotations

import pathlib
import shutil
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from evalsuite.metrics.engine import score_folders
from evalsuite.metrics.families.base import MetricInfo
from evalsuite.metrics.report import write_outputs
from evalsuite.metrics.samples import label_samples, split_samples

OPTS = {"metrics": ("kinematics", "distribution"), "progress": False, "figures": False}


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    from evalsuite.metrics.demo import build_conditions

    root = tmp_path_factory.mktemp("samples")
    folders = build_conditions(root, seed=3)
    sampled = root / "sampled"
    sampled.mkdir()
    for path in sorted(folders["jitter"].glob("*.bvh")):  # sample 1: jitter, sample 2: static
        shutil.copy(path, sampled / f"{path.stem}_1.bvh")
        shutil.copy(folders["static"] / path.name, sampled / f"{path.stem}_2.bvh")
    folders["sampled"] = sampled
    return folders


def _values(result, cond):
    return {r["metric"]: r["value"] for r in result.summary if r["condition"] == cond}


def test_sample_files_are_recognised_in_number_order_against_the_natural_names():
    p = pathlib.Path
    files = {s: p(f"{s}.npz") for s in ("2_scott_0_1_1_10", "2_scott_0_1_1_2", "2_scott_0_1_1_1", "seg_sample_3",
                                        "seg_sample_1", "a_7", "a", "stray_1", "notes")}
    first, samples, other = split_samples(files, ["2_scott_0_1_1", "seg", "a", "a_7"])
    assert first == {"2_scott_0_1_1": p("2_scott_0_1_1_1.npz"), "seg": p("seg_sample_1.npz"), "a": p("a.npz"),
                     "a_7": p("a_7.npz")}
    assert samples == {"2_scott_0_1_1": [p("2_scott_0_1_1_1.npz"), p("2_scott_0_1_1_2.npz"), p("2_scott_0_1_1_10.npz")],
                       "seg": [p("seg_sample_1.npz"), p("seg_sample_3.npz")]}
    assert other == {"stray_1": p("stray_1.npz"), "notes": p("notes.npz")}


def test_first_scores_the_first_sample_and_says_so(folders, tmp_path):
    result = score_folders(f"natural={folders['natural']}", [f"jitter={folders['jitter']}",
                                                             f"sampled={folders['sampled']}"], **OPTS)
    assert not [i for i in result.issues if "no natural counterpart" in i]
    assert result.plan.samples["sampled"]["seg00"] == [folders["sampled"] / "seg00_1.bvh",
                                                       folders["sampled"] / "seg00_2.bvh"]
    assert _values(result, "sampled") == _values(result, "jitter")
    rows = [r for r in result.summary if r["condition"] == "sampled"]
    assert {r["samples"] for r in rows} == {"first"} and {r["n_samples"] for r in rows} == {2}
    assert {r["n_samples"] for r in result.summary if r["condition"] == "jitter"} == {1}
    write_outputs(result, tmp_path)
    frame = pd.read_csv(tmp_path / "summary.csv")
    assert "samples" in frame.columns and set(frame["samples"]) == {"first"}


def test_each_is_the_mean_over_sample_indices(folders):
    conds = [f"jitter={folders['jitter']}", f"static={folders['static']}", f"sampled={folders['sampled']}"]
    result = score_folders(f"natural={folders['natural']}", conds, samples="each", **OPTS)
    jitter, static, sampled = (_values(result, c) for c in ("jitter", "static", "sampled"))
    assert sampled and set(sampled) == set(jitter)
    for metric, value in sampled.items():
        np.testing.assert_allclose(value, (jitter[metric] + static[metric]) / 2, rtol=1e-12, err_msg=metric)
    rows = [r for r in result.summary if r["condition"] == "sampled"]
    assert {r["samples"] for r in rows} == {"each"} and all(r["ci_low"] is None for r in rows)
    assert result.plan.conditions == ["natural", "jitter", "static", "sampled"]
    assert set(result.files) == {"natural", "jitter", "static", "sampled"}
    seq = [r for r in result.per_sequence if r["condition"] == "sampled"]
    assert {r["sample"] for r in seq} == {1, 2}
    assert not any("#sample" in str(r["condition"]) for r in result.summary + result.per_sequence)


def test_a_metric_that_takes_all_samples_is_labelled_all():
    family = SimpleNamespace(metrics=(MetricInfo("sample_div", samples="all"), MetricInfo("fd_g")))
    plan = SimpleNamespace(conditions=["natural", "sys"], samples={"sys": {"a": [1, 2, 3]}})
    result = SimpleNamespace(plan=plan, summary=[{"condition": "sys", "metric": "sample_div", "value": 1.0},
                                                 {"condition": "sys", "metric": "fd_g", "value": 2.0},
                                                 {"condition": "sys", "metric": "fgd", "value": 3.0, "samples": "all"}])
    label_samples(result, plan, "first", [family])
    assert [(r["metric"], r["samples"], r["n_samples"]) for r in result.summary] == [
        ("sample_div", "all", 3), ("fd_g", "first", 3), ("fgd", "all", 3)]  # a family's own value is kept


def test_score_samples_option_writes_the_column(folders, tmp_path):
    from click.testing import CliRunner

    from evalsuite.cli import main

    out = tmp_path / "scores"
    r = CliRunner().invoke(main, ["score", "-r", f"natural={folders['natural']}", f"jitter={folders['jitter']}",
                                  f"static={folders['static']}", f"sampled={folders['sampled']}", "-m", "kinematics",
                                  "--samples", "each", "--no-figures", "--quiet", "-o", str(out)])
    assert r.exit_code == 0, r.output
    frame = pd.read_csv(out / "summary.csv").set_index(["condition", "metric"])
    assert set(frame.loc["sampled", "samples"]) == {"each"} and set(frame.loc["sampled", "n_samples"]) == {2}
    np.testing.assert_allclose(frame.loc["sampled", "value"],
                               (frame.loc["jitter", "value"] + frame.loc["static", "value"]) / 2, rtol=1e-9)
