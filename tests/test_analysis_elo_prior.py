"""`--elo-prior` and `--preset leaderboard`: the unpenalised estimate equals an independent maximum
likelihood fit, and the preset reproduces the Leaderboard's bootstrap draw for draw."""
import math

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm
from click.testing import CliRunner
from scipy import optimize

from evalsuite.analysis import report
from evalsuite.analysis.ranking import bradley_terry, elo_table
from evalsuite.cli import main

CONDS = ["A", "B", "C", "D", "E"]
QUALITY = {"A": 1.0, "B": 0.6, "C": 0.1, "D": -0.3, "E": -0.9}


def make_battles(seed=3, users=14, per_user=30):
    """Leaderboard-style votes: weak/strong wins and ties; every set of systems wins and loses."""
    rng = np.random.default_rng(seed)
    rows = []
    for u in range(users):
        for k in range(per_user):
            a, b = rng.choice(CONDS, 2, replace=False)
            d = QUALITY[a] - QUALITY[b]
            u_ = rng.random()
            p_tie = 0.2
            p_a = (1 - p_tie) / (1 + math.exp(-1.5 * d))
            winner = "a" if u_ < p_a else "tie" if u_ < p_a + p_tie else "b"
            strength = "" if winner == "tie" else ("strong" if rng.random() < 0.4 else "weak")
            rows.append({"participant": f"{u:024x}", "item": f"seg{k}", "condition_a": a, "condition_b": b,
                         "winner": winner, "strength": strength})
    return pd.DataFrame(rows)


def weights(df, conds):
    """The Leaderboard's win table: strong 4, weak 2, tie 1 each way; W[i, j] = i beats j."""
    idx = {c: i for i, c in enumerate(conds)}
    W = np.zeros((len(conds), len(conds)))
    for r in df.itertuples(index=False):
        a, b = idx[r.condition_a], idx[r.condition_b]
        w = 4.0 if r.strength == "strong" else 2.0
        if r.winner == "a":
            W[a, b] += w
        elif r.winner == "b":
            W[b, a] += w
        else:
            W[a, b] += 1
            W[b, a] += 1
    return W


def mle_scipy(W):
    """Elo by direct maximisation of the Bradley-Terry log-likelihood (analytic gradient)."""
    C = W.shape[0]
    N = W + W.T

    def f(th):
        d = th[:, None] - th[None, :]
        return (W * np.logaddexp(0, -d)).sum()

    def grad(th):
        d = th[:, None] - th[None, :]
        s = 1 / (1 + np.exp(-d))
        return -(W.sum(axis=1) - (N * s).sum(axis=1))
    th = optimize.minimize(f, np.zeros(C), jac=grad, method="BFGS", options={"gtol": 1e-12, "maxiter": 10_000}).x
    return 400 * (th - th.mean()) / math.log(10) + 1000


def mle_logit(W):
    """Elo as the Leaderboard computes it: weighted logistic regression on +-log(10) design rows,
    no intercept, no penalty (statsmodels GLM; the last system's coefficient fixed at 0, then the
    mean set to 1000)."""
    C = W.shape[0]
    X, y, w = [], [], []
    for i in range(C):
        for j in range(C):
            if i == j:
                continue
            row = np.zeros(C)
            row[i], row[j] = math.log(10), -math.log(10)
            X += [row, row]
            y += [1.0, 0.0]
            w += [W[i, j], W[j, i]]
    X = np.array(X)[:, :-1]
    fit = sm.GLM(np.array(y), X, family=sm.families.Binomial(), freq_weights=np.array(w)).fit(tol=1e-14)
    coef = np.r_[fit.params, 0.0]
    return 400 * (coef - coef.mean()) + 1000


def write(df, path):
    df.to_csv(path, index=False)
    return path


def invoke(*args):
    return CliRunner().invoke(main, ["analyze", *map(str, args)], catch_exceptions=False)


def test_independent_references_agree():
    W = weights(make_battles(), CONDS)
    assert mle_scipy(W) == pytest.approx(mle_logit(W), abs=1e-6)


def test_cli_prior_zero_is_the_maximum_likelihood_estimate(tmp_path):
    df = make_battles()
    r = invoke(write(df, tmp_path / "b.csv"), "-o", tmp_path / "o", "--elo-prior", "0", "--bootstrap", "0",
               "--no-figures")
    assert r.exit_code == 0, r.output
    elo = pd.read_csv(tmp_path / "o" / "elo.csv").set_index("condition")["elo"]
    ref = mle_logit(weights(df, CONDS))
    assert elo[CONDS].to_numpy() == pytest.approx(ref, abs=1e-6)
    assert elo[CONDS].to_numpy() == pytest.approx(mle_scipy(weights(df, CONDS)), abs=1e-6)


def test_default_prior_is_documented_penalty_and_moves_the_estimate(tmp_path):
    df = make_battles()
    W = weights(df, CONDS)
    default = elo_table(df.rename(columns={"winner": "answer"}).assign(question="q"), n_boot=0)
    e = default.set_index("condition")["elo"][CONDS].to_numpy()
    # The default (0.1 virtual ties per pair) is the MLE of the table with those ties added ...
    pairs = ((W + W.T) > 0) & ~np.eye(len(CONDS), dtype=bool)
    assert e == pytest.approx(mle_scipy(W + 0.05 * pairs), abs=1e-6)
    # ... which is not the plain MLE: the report must not call it that.
    assert np.abs(e - mle_scipy(W)).max() > 1e-3
    assert report.elo_method(0.1) != report.elo_method(0) == "Bradley-Terry MLE"
    assert "penalised" in report.elo_method(0.1)


def leaderboard_bootstrap(df, rounds, seed=42):
    """The Leaderboard's bootstrap, re-implemented independently: np.random.seed, np.random.choice
    over the sorted user ids, refit each resample."""
    np.random.seed(seed)
    users = sorted(df["participant"].unique())
    groups = {u: g for u, g in df.groupby("participant")}
    out = []
    for _ in range(rounds):
        sample = pd.concat([groups[u] for u in np.random.choice(users, size=len(users), replace=True)])
        out.append(mle_logit(weights(sample, CONDS)))
    return np.array(out)


def test_preset_leaderboard_reproduces_their_procedure(tmp_path):
    df = make_battles()
    r = invoke(write(df, tmp_path / "b.csv"), "-o", tmp_path / "o", "--preset", "leaderboard",
               "--bootstrap", "60", "--no-figures")
    assert r.exit_code == 0, r.output
    elo = pd.read_csv(tmp_path / "o" / "elo.csv").set_index("condition").loc[CONDS]
    assert elo["elo"].to_numpy() == pytest.approx(mle_logit(weights(df, CONDS)), abs=1e-6)
    boot = leaderboard_bootstrap(df, 60)
    lo, med, hi = np.percentile(boot, [2.5, 50, 97.5], axis=0)
    assert elo["ci_low"].to_numpy() == pytest.approx(lo, abs=1e-5)
    assert elo["ci_high"].to_numpy() == pytest.approx(hi, abs=1e-5)
    assert elo["boot_median"].to_numpy() == pytest.approx(med, abs=1e-5)
    import json
    opts = json.loads((tmp_path / "o" / "summary.json").read_text())["options"]
    assert opts["preset"] == "leaderboard"
    assert opts["n_boot"] == 60                 # given explicitly: overrides the preset's 10000
    assert opts["elo_prior"] == 0 and opts["attention_fails"] == 1 and opts["tie_policy"] == "half"


def test_prior_zero_without_finite_mle_says_so():
    # C never wins anything: the MLE runs away; with the default prior it is finite.
    df = pd.DataFrame([{"question": "q", "participant": f"p{i}", "condition_a": a, "condition_b": b,
                        "answer": "a", "strength": ""}
                       for i in range(3) for a, b in (("A", "B"), ("B", "A"), ("A", "C"), ("B", "C"))])
    t0 = elo_table(df, n_boot=0, prior=0)
    assert t0["elo"].isna().all()
    assert t0["note"].str.contains("no finite maximum-likelihood estimate").all()
    t1 = elo_table(df, n_boot=50, prior=0.1)
    assert np.isfinite(t1[["elo", "ci_low", "ci_high"]].to_numpy(float)).all()


def test_bradley_terry_rejects_a_negative_prior():
    with pytest.raises(ValueError):
        bradley_terry(np.ones((2, 2)), prior=-1)
