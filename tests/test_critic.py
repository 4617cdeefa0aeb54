"""evalsuite.critic: a Bradley-Terry head on a frozen encoder, learned from simulated votes of known quality."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.critic.core import agreement, fit_head, rater_ci

SYSTEMS = ["S0", "S1", "S2", "S3", "S4"]
JITTER = {"NA": 0.0, "S0": 0.002, "S1": 0.006, "S2": 0.012, "S3": 0.02, "S4": 0.03}   # latent quality: less is better


def _motions(root, n_segments=6, frames=120, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(frames) / 30.0
    for s in range(n_segments):
        phase = rng.uniform(0, 6, size=(4, 3))
        base = 0.2 * np.sin(2 * np.pi * 0.7 * t[:, None, None] + phase)
        for c, amp in JITTER.items():
            (root / c).mkdir(parents=True, exist_ok=True)
            np.save(root / c / f"seg{s}.npy", base + amp * rng.standard_normal(base.shape))


def _votes(path, n_raters=24, n_segments=6, seed=1):
    """Each rater judges every pair on one segment; P(a wins) = sigmoid(2 (q_a - q_b)), q = -rank of jitter."""
    rng = np.random.default_rng(seed)
    q = {c: -i for i, c in enumerate(SYSTEMS)}
    rows = []
    for r in range(n_raters):
        seg = f"seg{r % n_segments}"
        for i, a in enumerate(SYSTEMS):
            for b in SYSTEMS[i + 1:]:
                a_, b_ = (a, b) if rng.random() < 0.5 else (b, a)
                win = rng.random() < 1 / (1 + np.exp(-2 * (q[a_] - q[b_])))
                rows.append(dict(participant=f"r{r}", item=seg, condition_a=a_, condition_b=b_,
                                 winner="a" if win else "b"))
    pd.DataFrame(rows).to_csv(path, index=False)


def test_fit_head_recovers_a_known_direction():
    rng = np.random.default_rng(0)
    w_true = np.array([2.0, -1.0, 0.0])
    d = rng.standard_normal((2000, 3))
    y = (rng.random(2000) < 1 / (1 + np.exp(-d @ w_true))).astype(float)
    w = fit_head(d, y, l2=0.1)
    assert np.corrcoef(w, w_true)[0, 1] > 0.99 and w[0] == pytest.approx(2.0, rel=0.15)
    assert list(agreement(np.array([1.0, 0, 2]), np.array([0.0, 1, 2]), np.array([1.0, 1, 0]))) == [1.0, 0.0, 0.5]
    mean, lo, hi = rater_ci(np.array([1.0, 1, 0, 1]), np.array(["a", "a", "b", "b"]), 200, 0)
    assert mean == 0.75 and lo <= mean <= hi


def test_critic_train_and_score_on_simulated_votes(tmp_path):
    _motions(tmp_path / "motion")
    _votes(tmp_path / "battles.csv")
    r = CliRunner().invoke(main, ["critic", "train", str(tmp_path / "battles.csv"), "--motion", str(tmp_path / "motion"),
                                  "--natural", "NA", "--bootstrap", "300", "-o", str(tmp_path / "c")])
    assert r.exit_code == 0, r.output
    t = pd.read_csv(tmp_path / "c" / "agreement.csv").set_index(["split", "scorer"])
    for split in ("rater", "system"):
        assert t.loc[(split, "critic"), "ci_low"] > 0.5          # better than chance, with a CI
    assert t.loc[("rater", "critic"), "n_votes"] == 24 * 10
    assert ("rater", "fd_natural") in t.index
    r = CliRunner().invoke(main, ["critic", "score", str(tmp_path / "c" / "critic.npz"), "--motion",
                                  str(tmp_path / "motion"), "-o", str(tmp_path / "scores.csv")])
    assert r.exit_code == 0, r.output
    s = pd.read_csv(tmp_path / "scores.csv").set_index("condition")["value"]
    assert list(s[SYSTEMS].rank(ascending=False).astype(int)) == [1, 2, 3, 4, 5]   # the known order
    assert (tmp_path / "scores_per_segment.csv").is_file()


def test_critic_names_a_missing_motion(tmp_path):
    (tmp_path / "motion").mkdir()
    _votes(tmp_path / "battles.csv")
    r = CliRunner().invoke(main, ["critic", "train", str(tmp_path / "battles.csv"), "--motion", str(tmp_path / "motion")])
    assert r.exit_code != 0 and "no motion for condition 'S0'" in r.output


def test_critic_trains_on_an_evalsuite_results_export(tmp_path):
    _motions(tmp_path / "motion", n_segments=3)
    _votes(tmp_path / "battles.csv", n_raters=9, n_segments=3)
    r = CliRunner().invoke(main, ["import-judgements", "battles", str(tmp_path / "battles.csv"), "--study", "demo",
                                  "-o", str(tmp_path / "results.csv")])
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["critic", "train", str(tmp_path / "results.csv"), "--motion", str(tmp_path / "motion"),
                                  "--folds", "3", "--bootstrap", "100", "-o", str(tmp_path / "c")])
    assert r.exit_code == 0, r.output
    assert "90 decided votes" in r.output and "held out by rater  critic" in r.output
    assert "fd_natural" not in r.output          # no --natural: no baseline rows


def test_critic_with_the_fgd_encoder(tmp_path):
    """The FGD encoder as the frozen encoder: the baseline is then FGD itself, on the same held-out votes."""
    from learned_helpers import natural, trained

    from evalsuite.motion.io import save_motion

    model = trained()
    model.save(tmp_path / "fgd.pt")
    rng = np.random.default_rng(0)
    pieces = list(natural().values())[:4]
    for s, m in enumerate(pieces):
        for c, amp in JITTER.items():
            (tmp_path / "motion" / c).mkdir(parents=True, exist_ok=True)
            noisy = m.with_values(m.values + 200 * amp * rng.standard_normal(m.values.shape))
            save_motion(noisy, tmp_path / "motion" / c / f"seg{s}.bvh")
    _votes(tmp_path / "battles.csv", n_raters=12, n_segments=4)
    r = CliRunner().invoke(main, ["critic", "train", str(tmp_path / "battles.csv"), "--motion", str(tmp_path / "motion"),
                                  "--encoder", "fgd", "--fgd-model", str(tmp_path / "fgd.pt"), "--natural", "NA",
                                  "--folds", "3", "--bootstrap", "200", "-o", str(tmp_path / "c")])
    assert r.exit_code == 0, r.output
    t = pd.read_csv(tmp_path / "c" / "agreement.csv").set_index(["split", "scorer"])
    assert set(t.index) == {(s, k) for s in ("rater", "system") for k in ("critic", "fd_natural")}
    assert t.loc[("rater", "critic"), "ci_low"] > 0.5


def test_critic_runs_on_a_simulated_study_export(tmp_path):
    """End to end on an evalsuite study export (the analysis simulate module's results.csv)."""
    from evalsuite.analysis.simulate import simulate_results

    simulate_results().to_csv(tmp_path / "results.csv", index=False)
    rng = np.random.default_rng(0)
    t = np.arange(600) / 30.0
    amp = {"NA": 0.0, "SysA": 0.005, "SysB": 0.01, "BL": 0.03}
    for seg in ("seg00", "seg01", "seg02", "seg_check"):
        base = 0.2 * np.sin(2 * np.pi * 0.7 * t[:, None, None] + rng.uniform(0, 6, size=(4, 3)))
        for c, a in amp.items():
            (tmp_path / "motion" / c).mkdir(parents=True, exist_ok=True)
            np.save(tmp_path / "motion" / c / f"{seg}.npy", base + a * rng.standard_normal(base.shape))
    args = ["critic", "train", str(tmp_path / "results.csv"), "--motion", str(tmp_path / "motion"), "--natural", "NA",
            "--folds", "3", "--bootstrap", "100", "-o", str(tmp_path / "c")]
    r = CliRunner().invoke(main, [*args, "--question", "human_likeness"])
    assert r.exit_code == 0, r.output
    assert "from 12 raters on 4 conditions" in r.output     # mismatch pages, training and checks left out
    table = pd.read_csv(tmp_path / "c" / "agreement.csv")
    assert set(table["split"]) == {"rater", "system"} and set(table["scorer"]) == {"critic", "fd_natural"}
    assert ((table["ci_low"] <= table["agreement"]) & (table["agreement"] <= table["ci_high"])).all()


def test_load_votes_needs_one_question(tmp_path):
    from evalsuite.critic.core import load_votes
    from evalsuite.errors import InputError

    (tmp_path / "b.csv").write_text("participant,item,condition_a,condition_b,winner,question\n"
                                    "p1,s1,A,B,a,hl\np1,s1,A,B,b,app\np2,s1,A,A:mismatched,a,app\n")
    with pytest.raises(InputError, match="votes on several questions \\(app, hl\\): pick one with --question"):
        load_votes(tmp_path / "b.csv")
    v = load_votes(tmp_path / "b.csv", question="app")
    assert list(v["answer"]) == ["b"]                  # the matched-vs-mismatched vote left out


def test_critic_without_torch(tmp_path):
    """The kinematic critic needs numpy only; the fgd encoder without torch names the extra, no traceback."""
    from test_learned_optional import HINT, _run

    _motions(tmp_path / "motion", n_segments=2)
    _votes(tmp_path / "battles.csv", n_raters=6, n_segments=2)
    cli = "from evalsuite.cli import main; main()"
    r = _run(tmp_path, cli, "critic", "train", "battles.csv", "--motion", "motion", "--folds", "3", "--bootstrap", "50")
    assert r.returncode == 0, r.stderr
    assert "held out by rater" in r.stdout
    r = _run(tmp_path, cli, "critic", "train", "battles.csv", "--motion", "motion", "--encoder", "fgd",
             "--fgd-model", "x.pt")
    assert r.returncode == 1 and HINT in r.stderr and "Traceback" not in r.stderr
