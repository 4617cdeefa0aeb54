"""The known-truth validity benchmark (``evalsuite validate-metrics``): on a small synthetic corpus, the
metrics that must see a time offset see it, the histogram metrics do not, FGD grows with jitter, and the
command writes its table, figure and scores. Plus the pure parts (tau-b, verdicts, the plan) on their own."""
from __future__ import annotations

import csv
import os
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import stats

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.validity.analysis import analyse, badness, kendall_tau_b
from evalsuite.validity.plan import build_plan

OFFSETS = ("oracle", "offset_0.3", "offset_0.6", "offset_1.2")
HISTOGRAM_BOUND = 0.02      # H: the largest change of a pooled histogram metric from the oracle to offset 1.2 s


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """One run of the command on a 1.5-minute corpus of 10 s segments (9 segments, all scored)."""
    from evalsuite.synth import Layout, synthesize_corpus

    root = tmp_path_factory.mktemp("validity")
    synthesize_corpus(root / "corpus", 1.5, 11, layout=Layout(segment_s=10.0), progress=False)
    out = root / "out"
    # as a user runs it, in its own process; one BLAS thread, as on any shared machine (docs/validity.md)
    env = {**os.environ, **{k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}}
    result = subprocess.run([sys.executable, "-m", "evalsuite", "validate-metrics", "--corpus", str(root / "corpus"),
                             "-o", str(out), "--split", "all", "--bootstrap", "30", "--fgd-epochs", "3", "--quiet"],
                            env=env, capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stderr[-3000:]
    with open(out / "scores" / "summary.csv", newline="") as fh:
        values = {(r["condition"], r["metric"]): float(r["value"] or "nan") for r in csv.DictReader(fh)}
    with open(out / "validity.csv", newline="") as fh:
        table = {(r["metric"], r["family"]): r for r in csv.DictReader(fh)}
    return out, values, table


@pytest.mark.slow
def test_time_offsets_lower_energy_speed_correlation_and_beat_alignment_monotonically(run):
    _, values, _ = run
    for metric in ("energy_speed_r", "beat_a2m"):
        series = [values[(c, metric)] for c in OFFSETS]
        assert all(a > b for a, b in zip(series, series[1:])), (metric, series)
    # the strongest offset takes most of the coupling away
    assert values[("offset_1.2", "energy_speed_r")] < 0.5 * values[("oracle", "energy_speed_r")]


@pytest.mark.slow
def test_histogram_metrics_are_blind_to_time_offsets(run):
    _, values, table = run
    for metric in ("hellinger_speed", "hellinger_acceleration", "hellinger_speed_seq", "hellinger_acceleration_seq"):
        change = abs(values[("offset_1.2", metric)] - values[("oracle", metric)])
        seen = values[("jitter_0.005", metric)] - values[("oracle", metric)]
        assert change < HISTOGRAM_BOUND, (metric, change)
        assert seen > 10 * HISTOGRAM_BOUND, (metric, seen)        # while the slightest jitter is plain to them
        # the verdict may be "partial" on 7.5 s segments: an offset pushes the last gestures past the end
        assert table[(metric, "offset")]["verdict"] != "correct", table[(metric, "offset")]


@pytest.mark.slow
def test_fgd_grows_with_jitter(run):
    _, values, table = run
    series = [values[(c, "fgd")] for c in ("oracle", "jitter_0.005", "jitter_0.01", "jitter_0.02")]
    assert all(a < b for a, b in zip(series, series[1:])), series
    row = table[("fgd", "jitter")]
    assert float(row["tau"]) == 1.0 and row["verdict"] == "correct"


@pytest.mark.slow
def test_the_command_writes_the_table_figure_and_scores(run):
    out, values, table = run
    for name in ("validity.csv", "validity.md", "validity.tex", "validity.json", "validity_tau.png",
                 "validity_tau.svg", "scores/summary.csv", "scores/per_sequence.csv", "fgd_model.pt"):
        assert (out / name).is_file(), name
    with open(out / "validity.csv", newline="") as fh:
        header = next(csv.reader(fh))
    assert header[:7] == ["metric", "family", "tau", "ci_low", "ci_high", "n_levels", "verdict"]
    families = {f for _, f in table}
    assert {"offset", "semantic", "beats", "amplitude", "jitter", "smoothing", "mismatched", "random_segments",
            "mean_pose"} <= families
    assert table[("speed", "offset")]["n_levels"] == "5" and table[("speed", "amplitude")]["n_levels"] == "4"
    for row in table.values():
        if row["tau"]:
            assert -1.0 <= float(row["tau"]) <= 1.0
            assert float(row["ci_low"]) <= float(row["ci_high"])
    md = (out / "validity.md").read_text()
    assert "| metric | offset |" in md and "Blind to speech" in md
    assert r"\toprule" in (out / "validity.tex").read_text()
    # APE against the time-aligned natural motion sees every offset
    assert table[("ape", "offset")]["verdict"] == "correct"


@pytest.mark.slow
def test_the_command_reports_the_mismatch_test(run):
    out, _, _ = run
    with open(out / "mismatch.csv", newline="") as fh:
        rows = {(r["metric"], r["condition"]): r for r in csv.DictReader(fh)}
    oracle, offset = rows[("energy_speed_r", "oracle")], rows[("energy_speed_r", "offset_1.2")]
    assert oracle["verdict"] == "sees speech" and float(oracle["effect"]) > float(offset["effect"])
    assert "## Mismatch test" in (out / "validity.md").read_text()


@pytest.mark.slow
def test_gesture_area_coverage_sees_attenuation_but_not_offsets(run):
    _, _, table = run
    assert table[("gac_dice", "amplitude")]["verdict"] == "correct"
    assert table[("gac_dice", "offset")]["verdict"] == "blind"


def test_tau_b_matches_scipy_including_ties():
    rng = np.random.default_rng(0)
    rows = np.vstack([rng.normal(size=(20, 5)), rng.integers(0, 3, size=(20, 5)).astype(float)])
    ours = kendall_tau_b(rows)
    for row, tau in zip(rows, ours):
        expected = stats.kendalltau(np.arange(5), row).statistic
        assert (np.isnan(tau) and np.isnan(expected)) or tau == pytest.approx(expected, abs=1e-12)
    assert np.isnan(kendall_tau_b(np.array([1.0, np.nan, 2.0])))
    assert np.isnan(kendall_tau_b(np.array([2.0, 2.0, 2.0])))


def test_directions_and_verdicts():
    assert badness(np.array([3.0]), np.array([1.0]), "higher")[0] == -3.0
    assert badness(np.array([0.5, 1.5]), np.array([1.0]), "closer to natural").tolist() == [0.5, 0.5]
    families = {"f": ["oracle", "a", "b"]}
    conds = ["natural", "oracle", "a", "b"]
    rng = np.random.default_rng(1)
    noise = rng.normal(scale=0.01, size=(41, 4, 1))
    grow = np.array([0.0, 1.0, 2.0, 3.0])[None, :, None] + noise           # lower is better: degrades in order
    flat = np.full((41, 4, 1), 1.0) + noise                               # cannot tell anything apart
    shrink = -grow                                                        # says the degradations are better
    for table, verdict, tau in ((grow, "correct", 1.0), (flat, "blind", None), (shrink, "inverted", -1.0)):
        (res,) = analyse(table, conds, ["m"], {"m": "lower"}, families)
        assert res.verdict == verdict and res.n_levels == 3
        if tau is not None:
            assert res.tau == tau and res.worsening == pytest.approx(tau * 2.0, abs=0.1)


def test_the_plan_has_the_graded_families_in_order():
    plan = build_plan()
    assert plan.families["offset"] == ["oracle", "offset_0.1", "offset_0.3", "offset_0.6", "offset_1.2"]
    assert plan.families["amplitude"] == ["oracle", "amplitude_0.75", "amplitude_0.5", "amplitude_0.25"]
    assert len(plan.families["jitter"]) == 4 and len(plan.families["smoothing"]) == 4
    by_name = {c.name: c for c in plan.conditions}
    assert by_name["jitter_0.02"].generator == "gaussian_noise" and by_name["jitter_0.02"].of == "oracle"
    assert by_name["no_semantic"].config == {"semantic": False}
    with pytest.raises(InputError, match="used twice"):
        build_plan([("oracle", None, "natural")])  # type: ignore[list-item]


def test_a_corpus_that_is_not_synthetic_is_refused_with_the_way_out(tmp_path):
    from evalsuite.generators.checking import tiny_corpus

    tiny_corpus(tmp_path / "tiny")
    result = CliRunner().invoke(main, ["validate-metrics", "--corpus", str(tmp_path / "tiny"), "-o",
                                       str(tmp_path / "out"), "--quiet"])
    assert result.exit_code == 1
    assert "evalsuite corpus synth" in result.output and "not a synthetic-speaker corpus" in result.output
    assert "Traceback" not in result.output


def test_help_has_an_example():
    result = CliRunner().invoke(main, ["validate-metrics", "--help"])
    assert result.exit_code == 0 and "evalsuite validate-metrics --corpus" in result.output
