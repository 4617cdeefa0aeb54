"""Adaptive pair selection (study_app.adaptive): the Bradley-Terry estimate and its covariance, the most
informative pair, exploration, separation of the ranking, and an adaptive block in the study app (the pair
chosen at the first view and stored, answers feeding the estimate, concurrent views, status and admin)."""
from __future__ import annotations

import csv
import io
import random
import re
import threading
from collections import Counter

import numpy as np
import pytest
import study_helpers as h
from click.testing import CliRunner

from evalsuite.cli import main
from study_app import create_app
from study_app.adaptive import (
    Estimate,
    adaptive_status,
    assign_pair,
    block_estimate,
    choose_pair,
    fit,
    pair_gains,
    separation,
)
from study_app.context import store_of, study_of
from study_app.definition import load_study
from study_app.errors import StudyDefinitionError

CONDS = ("A", "B", "C", "D")


def _votes(truth, pairs, n, rng):
    """``n`` simulated judgements per pair under Bradley-Terry strengths ``truth`` (natural log)."""
    out = []
    for x, y in pairs:
        p = 1 / (1 + np.exp(-(truth[x] - truth[y])))
        out += [(x, y, float(rng.random() < p)) for _ in range(n)]
    return out


def test_fit_recovers_known_strengths_and_its_covariance_matches_the_spread():
    truth = {"A": 1.0, "B": 0.3, "C": -0.2, "D": -1.1}
    pairs = [(x, y) for i, x in enumerate(CONDS) for y in CONDS[i + 1:]]
    rng = np.random.default_rng(0)
    fits = [fit(CONDS, _votes(truth, pairs, 100, rng)) for _ in range(60)]
    est = np.array([f.theta for f in fits])
    np.testing.assert_allclose(est.mean(axis=0), [truth[c] for c in CONDS], atol=0.06)
    assert all(abs(f.theta.sum()) < 1e-9 for f in fits)
    assert fits[0].votes == 600
    # the Laplace standard deviation of a difference is the spread over repetitions (within 25 %)
    sd_laplace = np.sqrt(fits[0].cov[0, 0] + fits[0].cov[1, 1] - 2 * fits[0].cov[0, 1])
    assert np.std(est[:, 0] - est[:, 1]) == pytest.approx(sd_laplace, rel=0.25)


def test_no_answers_gives_equal_strengths_and_finite_uncertainty():
    est = fit(CONDS, [])
    np.testing.assert_allclose(est.theta, 0, atol=1e-12)
    assert np.isfinite(est.cov).all() and est.votes == 0
    gains = pair_gains(est, [("A", "B"), ("C", "D")])
    assert gains[0] == pytest.approx(gains[1]) and gains[0] > 0


def _estimate(theta, var):
    """An estimate with given strengths and independent variances (for the choice rules)."""
    return Estimate(CONDS, np.array(theta, float), np.diag(np.array(var, float)), 0)


def test_the_informative_pair_is_close_and_uncertain():
    pairs = [("A", "B"), ("A", "C"), ("B", "C"), ("C", "D")]
    # A-B close but well known; C-D close and uncertain; A-C far apart
    est = _estimate([2.0, 1.9, 0.0, -0.1], [0.01, 0.01, 1.0, 1.0])
    gains = pair_gains(est, pairs)
    p = 1 / (1 + np.exp(-0.1))
    assert gains[3] == pytest.approx(0.5 * np.log1p(p * (1 - p) * 2.0))
    assert int(np.argmax(gains)) == 3
    assert choose_pair(est, pairs, 0.0, random.Random(1)) == (3, "informative")


def test_exploration_draws_uniform_pairs_at_its_rate():
    pairs = [("A", "B"), ("A", "C"), ("B", "C"), ("C", "D")]
    est = _estimate([2.0, 1.9, 0.0, -0.1], [0.01, 0.01, 1.0, 1.0])
    rng = random.Random(7)
    picks = [choose_pair(est, pairs, 0.2, rng) for _ in range(4000)]
    explored = [k for k, how in picks if how == "explore"]
    assert len(explored) / len(picks) == pytest.approx(0.2, abs=0.03)
    counts = Counter(explored)
    assert set(counts) == {0, 1, 2, 3} and min(counts.values()) > 0.7 * len(explored) / 4
    assert all(k == 3 for k, how in picks if how == "informative")
    assert all(how == "explore" for _, how in (choose_pair(est, pairs, 1.0, rng) for _ in range(50)))


def test_the_ranking_separates_with_enough_votes_only():
    truth = {"A": 1.5, "B": 0.5, "C": -0.5, "D": -1.5}
    pairs = [(x, y) for i, x in enumerate(CONDS) for y in CONDS[i + 1:]]
    few = separation(fit(CONDS, _votes(truth, pairs, 2, np.random.default_rng(1))))
    many = separation(fit(CONDS, _votes(truth, pairs, 400, np.random.default_rng(1))))
    assert few.pairs == many.pairs == 3
    assert not few.done and few.separated < 3
    assert many.done and many.order == CONDS


# ------------------------------------------------------------------------------------------ the app

ADAPTIVE_YAML = h.STUDY_YAML.split("  - type: questionnaire")[0].replace(
    "min_width: 800", "min_width: 800\nnew_sessions_per_address: 0") + """\
  - type: pairwise
    id: hl
    conditions: [SYSALPHA, SYSBETA, NATURALGT]
    questions:
      - {{id: human_likeness, text: "Which one moves more like a real person?"}}
    pages: 3
    adaptive: true
    exploration: {exploration}
  - type: finish
    id: finish
    text: Thank you.
"""
TRUTH = {"NATURALGT": 2.0, "SYSALPHA": 0.0, "SYSBETA": -2.0}


def _app(tmp_path, exploration=0.2, sessions=12, url=None):
    path = h.make_study(tmp_path, yaml_text=ADAPTIVE_YAML.format(sessions=sessions, exploration=exploration))
    return create_app({"STUDY": str(path), "DATABASE_URL": url or f"sqlite:///{tmp_path / 'a.db'}", "SECRET_KEY": h.SECRET,
                       "ADMIN_TOKEN": h.ADMIN, "SESSION_COOKIE_SECURE": False, "INSTANCE_PATH": str(tmp_path / "i")})


def _rater(app, pid, rng):
    """A participant preferring the video of the stronger condition (Bradley-Terry with TRUTH); returns the
    participant and the plan pages it was shown (as stored after each view)."""
    study = study_of(app)
    by_file = study.manifest.by_file()
    p = h.Participant(app.test_client(), h.valid_pid(pid))
    assert p.enter().status_code == 302
    shown = []
    while True:
        _, data, csrf = p.page()
        if data is None:
            return p, shown
        spec = h.plan_pages(app, p.sid)[data["index"]]
        if spec["type"] == "pairwise":
            shown.append(spec)
            a, b = by_file[spec["a"]].condition, by_file[spec["b"]].condition
            a_wins = rng.random() < 1 / (1 + np.exp(-(TRUTH[a] - TRUTH[b])))
            left = a_wins == (spec["position_a"] == "left")
            answer = {"choices": {"human_likeness": "left" if left else "right"}, "reasons": []}
        else:
            answer = h.make_answer(study, spec, rng)
        assert p.submit(data, csrf, answer).status_code == 200


def test_definition_options_are_checked(tmp_path):
    h.make_study(tmp_path)
    for bad, fragment in (("adaptive: true\n    exploration: 1.5", "expected a number from 0 to 1"),
                          ("exploration: 0.3", "only used with adaptive: true"),
                          ("adaptive: yes please", "adaptive")):
        text = ADAPTIVE_YAML.format(sessions=2, exploration=0.2).replace(
            "adaptive: true\n    exploration: 0.2", bad)
        (tmp_path / "bad.yaml").write_text(text)
        with pytest.raises(StudyDefinitionError, match=fragment):
            load_study(tmp_path / "bad.yaml")
    text = h.STUDY_YAML.format(sessions=2).replace("    mismatched: true\n", "    mismatched: true\n    adaptive: true\n")
    (tmp_path / "mm.yaml").write_text(text)
    with pytest.raises(StudyDefinitionError, match="not with mismatched"):
        load_study(tmp_path / "mm.yaml")


def test_an_adaptive_block_chooses_each_pair_at_the_first_view_and_learns_the_ranking(tmp_path, db_url):
    """On SQLite and PostgreSQL (the estimate reads the answers' JSON in SQL)."""
    app = _app(tmp_path, exploration=0.2, sessions=12, url=db_url)
    study, store = study_of(app), store_of(app)
    rng = np.random.default_rng(11)
    chosen = Counter()
    for k in range(12):
        p, shown = _rater(app, f"adapt{k:03d}", rng)
        assert len(shown) == 3
        for spec in shown:
            assert spec["chosen"] in ("informative", "explore") and len(spec["planned"]) == 2
            chosen[spec["chosen"]] += 1
    assert chosen["explore"] > 0 and chosen["informative"] > chosen["explore"]
    # the stored answers carry what the estimate learns, and the export shows the chosen pair
    auth = {"Authorization": f"Bearer {h.ADMIN}"}
    rows = list(csv.DictReader(io.StringIO(app.test_client().get("/admin/export/results.csv", headers=auth)
                                           .get_data(as_text=True))))
    assert len(rows) == 36
    with store.ReadSession() as db:
        est = block_estimate(db, study, "hl")
    assert est.votes == 36
    assert [c for c in separation(est).order] == ["NATURALGT", "SYSALPHA", "SYSBETA"]
    status = adaptive_status(store, study)
    assert status[0]["block"] == "hl" and status[0]["votes"] == 36
    assert status[0]["order"] == ["NATURALGT", "SYSALPHA", "SYSBETA"] and status[0]["neighbours"] == 2
    # the admin page and status.json report it
    client = app.test_client()
    js = client.get("/admin/status.json", headers=auth).get_json()
    assert js["adaptive"] == status
    html = client.get("/admin/", headers=auth).get_data(as_text=True)
    assert "Adaptive pair selection" in html and "NATURALGT" in html


def test_without_exploration_the_most_informative_pair_is_shown_and_kept(tmp_path):
    app = _app(tmp_path, exploration=0, sessions=4)
    study, store = study_of(app), store_of(app)
    rng = np.random.default_rng(3)
    _rater(app, "first0001", rng)
    p = h.Participant(app.test_client(), h.valid_pid("second001"))
    assert p.enter().status_code == 302
    _, data, csrf = p.page()
    assert p.submit(data, csrf, {"agree": True, "website": ""}).status_code == 200
    with store.ReadSession() as db:
        est = block_estimate(db, study, "hl")
    pairs = study.page("hl").cfg["pairs"]
    gains = pair_gains(est, pairs)
    _, data, _ = p.page()
    spec = h.plan_pages(app, p.sid)[data["index"]]
    by_file = study.manifest.by_file()
    assert spec["chosen"] == "informative"
    shown = sorted([by_file[spec["a"]].condition, by_file[spec["b"]].condition])
    assert gains[[sorted(q) for q in pairs].index(shown)] == pytest.approx(gains.max())
    assert by_file[spec["a"]].segment == by_file[spec["b"]].segment == spec["segment"]
    # a second view (a reload) keeps the stored choice
    p.page()
    assert h.plan_pages(app, p.sid)[data["index"]] == spec


def test_concurrent_views_of_one_page_store_one_choice(tmp_path, db_url):
    app = _app(tmp_path, exploration=1.0, sessions=2, url=db_url)
    study, store = study_of(app), store_of(app)
    p = h.Participant(app.test_client(), h.valid_pid("racer0001"))
    assert p.enter().status_code == 302
    _, data, csrf = p.page()
    assert p.submit(data, csrf, {"agree": True, "website": ""}).status_code == 200
    index = 1
    spec = h.plan_pages(app, p.sid)[index]
    assert spec["type"] == "pairwise" and "chosen" not in spec
    results, barrier = [], threading.Barrier(6)

    def view(k):
        barrier.wait()
        # each thread its own seed stream would choose differently; the stored first choice must win
        results.append(assign_pair(store, study, p.sid, index, spec))

    threads = [threading.Thread(target=view, args=(k,)) for k in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    stored = h.plan_pages(app, p.sid)[index]
    assert len(results) == 6 and all(r == stored for r in results)
    assert stored["planned"] == [spec["a"], spec["b"]]      # chosen once: no thread re-chose over another


def test_study_status_command_says_whether_the_ranking_separated(tmp_path):
    app = _app(tmp_path, exploration=0.2, sessions=6)
    rng = np.random.default_rng(5)
    for k in range(6):
        _rater(app, f"status{k:03d}", rng)
    res = CliRunner().invoke(main, ["study", "status", str(tmp_path / "study.yaml"), "--db",
                                    f"sqlite:///{tmp_path / 'a.db'}"])
    assert res.exit_code == 0, res.output
    assert "hl: 18 votes" in res.output
    assert re.search(r"NATURALGT \(\d+\) > SYSALPHA \(\d+\) > SYSBETA \(\d+\)", res.output)
    assert re.search(r"ranking separated: the study may stop|[01] of 2 neighbouring pairs separated: not separated",
                     res.output)
    assert "sessions: 6 started, 0 active, 6 finished, 0 failed, 0 expired; 24 answers" in res.output


def test_the_preregistration_draft_states_the_adaptive_stopping_rule(tmp_path):
    from study_app.design import build_plans
    from study_app.prereg import prereg_markdown
    path = h.make_study(tmp_path, yaml_text=ADAPTIVE_YAML.format(sessions=4, exploration=0.3))
    study = load_study(path)
    text = prereg_markdown(study, build_plans(study))
    rule = text.split("Stopping rule", 1)[1].split("\n#", 1)[0]
    assert "Adaptive pairwise blocks `hl` (exploration 0.3)" in rule and "No interim analysis" not in rule
    assert "**TO COMPLETE**: state whether data collection stops there" in rule
    plain = load_study(h.make_study(tmp_path / "plain"))
    assert "No interim analysis." in prereg_markdown(plain, build_plans(plain))


def test_a_pair_chosen_in_one_server_process_is_seen_by_another(tmp_path):
    # plan pages change here (the chosen pair), so no process may keep them (Store.fixed_pages is off)
    app, other = _app(tmp_path, exploration=1.0, sessions=2), _app(tmp_path, exploration=1.0, sessions=2)
    assert not store_of(other).fixed_pages
    p = h.Participant(app.test_client(), h.valid_pid("worker001"))
    assert p.enter().status_code == 302
    _, data, csrf = p.page()
    assert p.submit(data, csrf, {"agree": True, "website": ""}).status_code == 200
    assert "chosen" not in h.plan_pages(other, p.sid)[1]        # read by the other process first
    _, data, _ = p.page()                                        # this process chooses the pair
    assert data["index"] == 1
    assert "chosen" in h.plan_pages(other, p.sid)[1]
    assert h.plan_pages(other, p.sid)[1] == h.plan_pages(app, p.sid)[1]
