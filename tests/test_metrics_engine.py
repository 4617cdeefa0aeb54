"""The scoring engine's interface (:mod:`evalsuite.metrics.engine`): ``score_folders`` takes one ScoreOptions
or keyword overrides of it, and ``score_plan`` is the one plan -> tasks -> run -> reduce sequence that
``evalsuite score`` and the validity benchmark share."""
from __future__ import annotations

import numpy as np
import pytest

from evalsuite.metrics.engine import (
    ScoreOptions,
    ScoreTask,
    plan_for,
    reduce_results,
    score_folders,
    score_plan,
    score_sequence,
    setup_for,
    tasks_for,
)


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    from evalsuite.metrics.demo import build_conditions

    return build_conditions(tmp_path_factory.mktemp("engine"), seed=2)


def _args(folders):
    return f"natural={folders['natural']}", [f"{c}={folders[c]}" for c in ("jitter", "static")]


def _values(result):
    return {(r["condition"], r["metric"]): (r["value"], r.get("ci_low"), r.get("ci_high")) for r in result.summary}


def _same(a, b):
    """The same summary rows, NaN equal to NaN."""
    va, vb = _values(a), _values(b)
    keys = sorted(va)
    return keys == sorted(vb) and np.array_equal(np.array([va[k] for k in keys], dtype=float),
                                                 np.array([vb[k] for k in keys], dtype=float), equal_nan=True)


def test_keywords_build_the_options_and_override_given_ones(folders):
    ref, conds = _args(folders)
    opts = ScoreOptions(metrics=("kinematics", "distribution"), bootstrap=20, seed=4, progress=False, figures=False)
    by_options = score_folders(ref, conds, opts)
    by_keywords = score_folders(ref, conds, metrics=["kinematics", "distribution"], bootstrap=20, seed=4,
                                progress=False, figures=False)
    assert _same(by_options, by_keywords)
    assert {m for _, m in _values(by_options)} >= {"speed", "jerk", "fd_g"}
    assert np.isfinite(by_options.summary[0]["ci_low"])
    other_seed = score_folders(ref, conds, opts, seed=5)            # an override of one option
    assert (other_seed.seed, other_seed.bootstrap) == (5, 20)
    assert not _same(other_seed, by_options)


def test_an_unknown_keyword_names_the_closest_option(folders):
    ref, conds = _args(folders)
    with pytest.raises(TypeError, match=r"unknown scoring option 'bootstraps'.*Did you mean 'bootstrap'\?"):
        score_folders(ref, conds, bootstraps=100)


def test_score_plan_keeps_the_task_results_unfolded_and_reducing_them_again_gives_the_same_rows(folders):
    ref, conds = _args(folders)
    opts = ScoreOptions(metrics="kinematics,distribution", progress=False, figures=False)
    plan = plan_for(ref, conds, opts)
    result = score_plan(plan, opts, keep_task_results=True)
    kept = result.task_results
    assert [r["name"] for r in kept] == plan.names
    # the folded-and-dropped summaries are still in the kept records (the reduce worked on copies)
    assert all("pose_moments" in rec for r in kept for rec in r["records"].values())
    again = reduce_results(plan, result.setup, kept)
    assert _same(again, result)
    assert score_plan(plan, opts).task_results == []


def test_tasks_are_typed_one_per_sequence_with_the_natural_file_first(folders):
    ref, conds = _args(folders)
    opts = ScoreOptions(metrics="kinematics", progress=False)
    plan = plan_for(ref, conds, opts)
    tasks = tasks_for(plan, setup_for(plan, opts))
    assert [t.name for t in tasks] == plan.names and all(isinstance(t, ScoreTask) for t in tasks)
    assert [c for c, _ in tasks[0].entries] == ["natural", "jitter", "static"]
    out = score_sequence(tasks[0])
    assert out["name"] == plan.names[0] and set(out["records"]) == {"natural", "jitter", "static"}


def test_the_validity_benchmark_scores_through_the_same_seam_as_score(tmp_path):
    from evalsuite.corpus import load_corpus
    from evalsuite.generators import find_generator
    from evalsuite.generators.requests import requests_from_corpus
    from evalsuite.generators.runner import generate
    from evalsuite.synth import Layout, synthesize_corpus
    from evalsuite.validity.scoring import score_conditions

    synthesize_corpus(tmp_path / "corpus", 0.5, 11, layout=Layout(segment_s=10.0), progress=False)
    requests = requests_from_corpus(load_corpus(tmp_path / "corpus"), "all", 30.0)
    folders = {}
    for name in ("natural", "mean_pose", "mismatched"):
        folders[name] = tmp_path / name
        generate(find_generator(name), requests, folders[name], seed=7, progress=False)
    scored = score_conditions(folders, tmp_path / "corpus", progress=False)
    direct = score_folders(f"natural={folders['natural']}", [f"{n}={folders[n]}" for n in ("mean_pose", "mismatched")],
                           corpus=tmp_path / "corpus", figures=False, progress=False)
    assert _same(scored.result, direct)
    assert {"energy_speed_r", "beat_a2m", "speed"} <= {m for _, m in _values(direct)}
    assert [r["name"] for r in scored.results] == direct.plan.names and len(direct.plan.names) == 4
