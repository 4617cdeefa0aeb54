"""The objective mismatch test (evalsuite.validity.mismatch) on the synthetic speaker at CI scale: motion in
time with its speech (natural, oracle) loses more from deranged speech than motion shifted 1.2 s against it."""
from __future__ import annotations

import numpy as np
import pytest
from synth_helpers import build_conditions, build_corpus

from evalsuite.errors import InputError
from evalsuite.metrics.engine import ScoreOptions, plan_for, score_plan
from evalsuite.validity.mismatch import derangement, mismatch_test, separation
from evalsuite.validity.scoring import Scored


def test_derangement_keeps_no_segment_and_stays_within_speakers():
    ids = [f"s{i}" for i in range(9)]
    speakers = {s: ("a" if i < 5 else "b") for i, s in enumerate(ids)}
    speakers["s8"] = "c"                                  # alone: cannot be deranged
    pi = derangement(ids, speakers, seed=3)
    assert sorted(pi) == ids[:8] and sorted(pi.values()) == ids[:8]
    assert all(pi[s] != s and speakers[pi[s]] == speakers[s] for s in pi)
    assert pi == derangement(ids, speakers, seed=3) and pi != derangement(ids, speakers, seed=4)


@pytest.fixture(scope="module")
def scored(tmp_path_factory):
    root = tmp_path_factory.mktemp("mismatch")
    corpus = build_corpus(root / "corpus", minutes=1.5, seed=5, segment_s=10.0)
    folders = build_conditions(corpus, root / "conds", offsets=(1.2,))
    options = ScoreOptions(corpus=corpus, metrics="beats,coupling", figures=False, progress=False)
    plan = plan_for(f"natural={folders['natural']}", [f"{n}={p}" for n, p in folders.items() if n != "natural"],
                    options)
    result = score_plan(plan, options, keep_task_results=True)
    return Scored(result, result.task_results)


def test_oracle_loses_more_from_deranged_speech_than_the_offset(scored):
    results = mismatch_test(scored, n_bootstrap=300, seed=0)
    by = {(r.metric, r.condition): r for r in results}
    r = by[("energy_speed_r", "oracle")]
    assert r.n >= 8 and r.effect > 0.1 and r.ci_low > 0 and r.verdict == "sees speech"
    assert by[("energy_speed_r", "natural")].verdict == "sees speech"
    assert r.own > r.deranged
    off = by[("energy_speed_r", "offset_1.2")]
    assert off.effect < 0.5 * r.effect
    sep = separation(results)
    diff, lo, hi = sep["energy_speed_r"]
    assert diff == pytest.approx(r.effect - off.effect) and lo > 0
    # phase statistics come from label files, not the speech; a mean pose has no beats to align
    assert by[("phase_rest_fraction", "oracle")].verdict == "unchanged"
    assert by[("beat_a2m", "mean_pose")].verdict == "unchanged"
    assert {"beat_a2m", "beat_m2a"} <= {m for m, _ in by}
    # seeded: the same run gives the same table
    again = mismatch_test(scored, n_bootstrap=300, seed=0)
    assert [repr(x.row()) for x in again] == [repr(x.row()) for x in results]
    assert np.isfinite([x.effect for x in results]).all()
    # a metric measured on a single segment gets no verdict
    assert all(x.verdict == "n/a" for x in results if x.n < 2)


def test_csv_and_markdown(scored, tmp_path):
    from evalsuite.validity.mismatch import COLUMNS, markdown, write_csv

    results = mismatch_test(scored, ["oracle", "offset_1.2"], n_bootstrap=50, seed=1)
    write_csv(results, tmp_path / "m.csv")
    lines = (tmp_path / "m.csv").read_text().splitlines()
    assert lines[0] == ",".join(COLUMNS) and len(lines) == 1 + len(results)
    text = markdown(results)
    assert "| energy_speed_r |" in text and "oracle − strongest offset" in text and "sees speech" in text


def test_a_run_without_speech_is_a_clear_error(tmp_path):
    from evalsuite.metrics.engine import score_folders

    folder = tmp_path / "m"
    folder.mkdir()
    from evalsuite.motion.io import save_motion
    from evalsuite.motion.synthetic import synthetic_motion

    save_motion(synthetic_motion(n_joints=20, fps=30.0, seconds=2.0, seed=0), folder / "a.npz")
    result = score_folders(folder, [f"copy={folder}"], ScoreOptions(metrics="kinematics", progress=False,
                                                                    figures=False))
    with pytest.raises(InputError, match="reads the speech"):
        mismatch_test(Scored(result, []))
