"""Sample-size planning (evalsuite.analysis.power, `evalsuite study power`): the exact binomial power agrees
with one computed independently here from scipy.stats.binom term by term; simulations are seeded and sane."""
from __future__ import annotations

import math

import pytest
from click.testing import CliRunner
from scipy.stats import binom, binomtest

from evalsuite.analysis.power import binomial_power, likert_power, mushra_power, pairwise_judgements, smallest_n
from evalsuite.cli import main


def exact_power(n: int, p: float, level: float) -> float:
    """Independent: sum of Binomial(n, p) probabilities of every k whose exact two-sided test rejects."""
    total = 0.0
    for k in range(n + 1):
        if binomtest(k, n, 0.5).pvalue <= level:
            total += binom.pmf(k, n, p)
    return total


def exact_n(p: float, alpha: float, power: float, comparisons: int) -> int:
    n = 1
    while exact_power(n, p, alpha / comparisons) < power:
        n += 1
    return n


@pytest.mark.parametrize("n, p, level", [(20, 0.7, 0.05), (57, 0.6, 0.005), (100, 0.35, 0.01), (1, 0.9, 0.05)])
def test_binomial_power_matches_a_term_by_term_sum(n, p, level):
    assert binomial_power(n, p, level) == pytest.approx(exact_power(n, p, level), abs=1e-12)


@pytest.mark.parametrize("p, alpha, power, k", [(0.65, 0.05, 0.8, 10), (0.7, 0.05, 0.9, 1), (0.3, 0.01, 0.8, 3)])
def test_judgements_are_the_smallest_n_reaching_the_power(p, alpha, power, k):
    n, achieved = pairwise_judgements(p, alpha=alpha, power=power, comparisons=k)
    assert n == exact_n(p, alpha, power, k)
    assert achieved >= power > exact_power(n - 1, p, alpha / k)


def test_cli_without_a_definition_prints_the_judgements_last():
    r = CliRunner().invoke(main, ["study", "power", "--design", "pairwise", "--preference", "0.65", "--comparisons",
                                  "10", "--alpha", "0.05", "--power", "0.8"])
    assert r.exit_code == 0, r.output
    assert int(r.output.strip().splitlines()[-1]) == exact_n(0.65, 0.05, 0.8, 10) == 147
    assert "alpha/K = 0.005" in r.output
    ties = CliRunner().invoke(main, ["study", "power", "--design", "pairwise", "--comparisons", "10", "--ties", "0.2"])
    assert int(ties.output.strip().splitlines()[-1]) == math.ceil(147 / 0.8)
    bad = CliRunner().invoke(main, ["study", "power", "--design", "pairwise", "--preference", "0.5"])
    assert bad.exit_code == 1 and "no effect" in bad.output and "Traceback" not in bad.output
    assert CliRunner().invoke(main, ["study", "power"]).exit_code == 2


def test_simulated_power_is_seeded_and_grows_with_n():
    assert mushra_power(40, 10, 20, 0.05, sims=300, seed=1) == mushra_power(40, 10, 20, 0.05, sims=300, seed=1)
    curve = [mushra_power(n, 10, 20, 0.05, sims=300) for n in (10, 40, 160)]
    assert curve == sorted(curve) and curve[0] < 0.4 < curve[-1]
    assert mushra_power(60, 0.0, 20, 0.05, sims=1000) < 0.09                 # no effect: about alpha
    # Likert: a paired design needs fewer participants than one group per condition
    paired = smallest_n(lambda n: likert_power(n, 0.5, 1.0, 0.05, statements=2, sims=300), 0.8)[0]
    groups = smallest_n(lambda n: likert_power(n, 0.5, 1.0, 0.05, statements=2, paired=False, sims=300), 0.8)[0]
    assert paired < groups


def test_simulated_mushra_sample_size_is_near_the_paired_normal_approximation():
    # Paired differences have SD 20 * sqrt(2); a t-test would need about ((z_.9917 + z_.8) / d)^2 pairs.
    from scipy.stats import norm

    d = 10 / (20 * math.sqrt(2))
    approx = ((norm.ppf(1 - 0.05 / 3 / 2) + norm.ppf(0.8)) / d) ** 2
    r = CliRunner().invoke(main, ["study", "power", "--design", "mushra", "--comparisons", "3", "--sims", "500"])
    assert r.exit_code == 0, r.output
    n = int(r.output.strip().splitlines()[-1])
    assert approx < n < 1.25 * approx                                   # Wilcoxon: a little above the t-test


def test_power_of_a_study_definition(tmp_path):
    import study_helpers as h

    from study_app.definition import load_study
    from study_app.design import build_plans
    from study_app.planning import Effects, study_power

    path = h.make_study(tmp_path, sessions=12)
    study = load_study(path)
    rows = {r["block"]: r for r in study_power(study, build_plans(study), Effects(sims=300, exclusion_rate=0.2))}
    hl, app, ratings, stmts = rows["hl"], rows["app"], rows["ratings"], rows["stmts"]
    assert hl["family"] == app["family"] == 5                          # 3 + 2 pairwise comparisons, one question
    assert hl["needed"] == exact_n(0.65, 0.05, 0.8, 5)
    # 12 sessions x 3 trial pages over 3 comparisons: 1 judgement per session and comparison
    assert hl["per_session"] == 1.0
    assert hl["participants"] == math.ceil(hl["needed"] / 0.8)
    assert ratings["family"] == 3 and ratings["per_session"] == 2.0    # 2 pages, each rating all three
    assert not stmts["paired"]                                          # one Likert page: Welch t per condition
    r = CliRunner().invoke(main, ["study", "power", str(path), "--sims", "300", "--exclusion-rate", "0.2"])
    assert r.exit_code == 0, r.output
    assert int(r.output.strip().splitlines()[-1]) == max(x["participants"] for x in rows.values())
    assert "family of 5, level 0.01" in r.output
