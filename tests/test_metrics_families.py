"""The metric-family registry: a family defined here is scored end to end, and the engine's numbers are
the public metric functions' numbers."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

import evalsuite
from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.metrics import average_jerk, average_position_error, average_speed, div_k, l1div
from evalsuite.metrics.engine import score_folders
from evalsuite.metrics.families import (
    MetricFamily,
    MetricInfo,
    ReduceContext,
    SequenceContext,
    register_family,
    registered_families,
    unregister_family,
)


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    from evalsuite.metrics.demo import build_conditions

    return build_conditions(tmp_path_factory.mktemp("families"), seed=5)


class WristHeightFamily(MetricFamily):
    """A toy family: mean height (y) of the wrists, per sequence and per condition."""

    name = "toy_wrist_height"
    metrics = (MetricInfo("toy_wrist_height", "units", "closer to natural", description="mean wrist height"),)

    def measure(self, ctx: SequenceContext) -> None:
        wrists = [i for i, j in enumerate(ctx.setup.joints) if j in ctx.setup.groups.get("wrists", [])]
        ctx.record["toy_wrist_height"] = float(ctx.pos[:, wrists, 1].mean())

    def reduce(self, ctx: ReduceContext) -> None:
        ctx.mean_metric("toy_wrist_height", [ctx.recs[s]["toy_wrist_height"] for s in ctx.names])


@pytest.fixture
def toy_family():
    family = register_family(WristHeightFamily())
    yield family
    unregister_family(family.name)


def test_a_family_defined_in_a_test_is_scored_end_to_end_by_the_command(folders, toy_family, tmp_path):
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["score", "-r", str(folders["natural"]), str(folders["jitter"]),
                                    str(folders["static"]), "-m", "kinematics,toy_wrist_height", "--no-figures",
                                    "--quiet", "-o", str(out)])
    assert res.exit_code == 0, res.output
    summary = pd.read_csv(out / "summary.csv")
    rows = summary[summary.metric == "toy_wrist_height"].set_index("condition")
    assert sorted(rows.index) == ["jitter", "natural", "static"]
    assert (rows.unit == "units").all()
    assert (rows.better == "closer to natural").all()
    # the value is the mean over sequences of the mean wrist height, computed here independently
    heights = []
    for path in sorted(folders["static"].glob("*.bvh")):
        m = evalsuite.load_motion(path)
        idx = [m.joint_names.index(j) for j in m.joint_names if j.lower().endswith(("wrist", "hand"))]
        heights.append(m.positions()[:, idx, 1].mean())
    assert rows.loc["static", "value"] == pytest.approx(np.mean(heights), rel=1e-12)
    per_seq = pd.read_csv(out / "per_sequence.csv")
    assert (per_seq.metric == "toy_wrist_height").sum() == 3 * len(heights)


def test_registered_families_and_unknown_names(toy_family):
    assert list(registered_families())[:6] == ["kinematics", "histograms", "errors", "distribution", "cca", "beats"]
    assert "toy_wrist_height" in registered_families()
    with pytest.raises(ValueError, match="registered already"):
        register_family(WristHeightFamily())


def test_unknown_metric_names_the_registered_families(folders):
    with pytest.raises(InputError, match=r"expected a family \(kinematics, histograms"):
        score_folders(folders["natural"], [folders["jitter"]], metrics=["nonsense"], progress=False)


def test_the_engine_reports_what_the_public_functions_compute(folders):
    result = score_folders(f"natural={folders['natural']}", [f"jitter={folders['jitter']}"], progress=False,
                           figures=False)
    per_seq = pd.DataFrame(result.per_sequence)
    summary = pd.DataFrame(result.summary).set_index(["condition", "metric"])
    natural = {p.stem: evalsuite.load_motion(p).positions() for p in sorted(folders["natural"].glob("*.bvh"))}
    jitter = {p.stem: evalsuite.load_motion(p).positions() for p in sorted(folders["jitter"].glob("*.bvh"))}
    fps = 30.0
    for name, pos in jitter.items():
        def value(metric, name=name):
            row = per_seq[(per_seq.condition == "jitter") & (per_seq.sequence == name) & (per_seq.metric == metric)]
            return float(row.value.iloc[0])

        assert value("speed") == pytest.approx(average_speed(pos, fps).mean(), rel=1e-12)
        assert value("jerk") == pytest.approx(average_jerk(pos, fps).mean(), rel=1e-12)
        assert value("ape") == pytest.approx(average_position_error(pos, natural[name]).mean(), rel=1e-12)
        assert value("div_k") == pytest.approx(div_k([pos]), rel=1e-12)
    assert summary.loc[("jitter", "l1div"), "value"] == pytest.approx(l1div(list(jitter.values())), rel=1e-12)


def test_centred_interval_contains_the_estimate_when_every_resample_lies_above_it():
    from evalsuite.metrics.families.base import bootstrap_bias, centred_ci, percentile_ci

    samples = 5.0 + np.random.default_rng(0).exponential(3.0, size=1000)  # a Fréchet distance's biased resamples
    low, high = percentile_ci(samples)
    assert low > 1.0  # the percentile interval excludes the estimate 1.0
    q_low, q_mid, q_high = np.percentile(samples, [2.5, 50, 97.5])
    assert centred_ci(1.0, samples) == pytest.approx((0.0, 1.0 + q_high - q_mid))   # clipped at 0
    assert centred_ci(1.0, samples, floor=None) == pytest.approx((1.0 - (q_mid - q_low), 1.0 + q_high - q_mid))
    assert centred_ci(10.0, samples)[0] <= 10.0 <= centred_ci(10.0, samples)[1]
    assert bootstrap_bias(1.0, samples) == pytest.approx(samples.mean() - 1.0)
    assert np.isnan(centred_ci(1.0, [np.nan])[0])
