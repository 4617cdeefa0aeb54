"""`evalsuite demo` end to end at a tiny scale: speech to statistics, every step, nothing skipped."""
from __future__ import annotations

import pandas as pd
import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.pipeline.steps import BUILTINS, STEPS


@pytest.mark.slow
def test_demo_runs_every_step_from_speech_to_statistics(tmp_path):
    out = tmp_path / "demo"
    res = CliRunner().invoke(main, ["demo", "-o", str(out), "--minutes", "3", "--budget-minutes", "0.05"],
                             catch_exceptions=False)
    assert res.exit_code == 0, res.output
    for i, (title, _) in enumerate(STEPS, 1):
        assert f"[{i}/{len(STEPS)}] {title}" in res.output
    assert "skipped" not in res.output
    conditions = {p.name for p in (out / "conditions").iterdir()}
    assert set(BUILTINS) | {"gesticulator", "aud2repr2pose"} <= conditions
    for name in ("gesticulator", "aud2repr2pose"):
        assert (out / "models" / name / "model.json").is_file()
    summary = pd.read_csv(out / "score" / "summary.csv")
    assert {"fgd", "energy_speed_r", "beat_a2m", "hellinger_speed"} <= set(summary.metric)
    assert conditions - {"natural"} <= set(summary.condition)
    assert (out / "render" / "compare.mp4").stat().st_size > 10_000
    assert (out / "study" / "study.yaml").is_file()
    results = pd.read_csv(out / "results.csv", keep_default_na=False)
    assert results["data_note"].str.contains("SIMULATED").all()
    assert (out / "analysis" / "report.html").is_file()
    corr = pd.read_csv(out / "correlate" / "correlations.csv")
    assert {"spearman_rho", "kendall_tau_b", "spearman_p"} <= set(corr.columns)
    assert "total" in (out / "summary.txt").read_text()
