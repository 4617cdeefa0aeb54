"""`evalsuite demo` end to end: every step runs and leaves what the next one reads."""
from __future__ import annotations

import importlib.util

import pandas as pd
import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.demo import STEPS


@pytest.mark.slow
def test_demo_runs_every_step_and_writes_its_outputs(tmp_path):
    out = tmp_path / "demo"
    res = CliRunner().invoke(main, ["demo", "-o", str(out)], catch_exceptions=False)
    assert res.exit_code == 0, res.output
    for i, (title, _) in enumerate(STEPS, 1):
        assert f"[{i}/{len(STEPS)}] {title}" in res.output
    assert (out / "positions" / "walk01.npz").is_file()
    summary = pd.read_csv(out / "score" / "summary.csv", keep_default_na=False)
    assert {"natural", "mismatched", "static", "jitter", "smoothed"} <= set(summary.condition)
    assert {"condition", "metric", "value", "unit", "ci_low", "ci_high"} <= set(summary.columns)
    assert (out / "render" / "compare.mp4").stat().st_size > 10_000
    manifest = pd.read_csv(out / "render" / "stimuli" / "manifest.csv", keep_default_na=False)
    assert len(manifest) == 13
    assert all((out / "render" / "stimuli" / f).is_file() for f in manifest.file)
    if importlib.util.find_spec("torch") is not None:  # the learned extra (installed by .ci/run)
        fgd = pd.read_csv(out / "fgd" / "fgd.csv", keep_default_na=False)
        rows = dict(zip(fgd.condition, fgd.value))
        assert rows["natural"] < 1e-6
        assert rows["static"] > rows["natural"]
        assert rows["jitter"] > rows["natural"]
    assert (out / "study" / "study.yaml").is_file()
    html = (out / "analysis" / "report.html").read_text()
    assert html.count("data:image/png;base64,") >= 5

