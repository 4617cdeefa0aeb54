"""Adaptive pair selection for pairwise blocks (``adaptive: true``, ``exploration: 0.2``).

A block's plans are built as usual (balanced pairs, segments, sides). When a participant first opens one
of its trial pages, the server replaces the planned pair by the pair that is most informative under the
current Bradley-Terry estimate of the block (fitted from every stored answer of the block), or, with
probability ``exploration``, by a pair drawn uniformly from the block's ``pairs``. The page keeps its
planned segment; the side of A is a coin flip seeded per session and page. The choice is written into
the session's plan (``chosen``: ``informative`` or ``explore``; ``planned``: the files planned before), so
media, answers and the export use it; a page answered without being opened keeps its planned pair.

Model (natural-log strengths ``t``, mean 0): ``P(i preferred to j) = sigma(t_i - t_j)``. Each answer of the
block's first question adds 1 to ``W[winner, loser]`` (a tie 1/2 each way); every pair gets ``PRIOR / 2``
virtual ties each way, which keeps the fit finite before any answer. ``t`` maximises
``sum_ij W_ij log sigma(t_i - t_j)`` (:func:`evalsuite.analysis.ranking.bradley_terry`). The Laplace
approximation gives its covariance: ``cov = pinv(F)`` with the Fisher information ``F`` the Laplacian of
``w_ij = N_ij p_ij (1 - p_ij)`` (``N = W + W^T``, ``p_ij = sigma(t_i - t_j)``).

Informativeness of a pair: the expected gain in information about ``t`` from one more judgement of it,
``gain_ij = 1/2 log(1 + p_ij (1 - p_ij) Var(t_i - t_j))`` (the Gaussian posterior's log-determinant
change): large for close strengths (``p`` near 1/2) that are still uncertain.

Stopping: the ranking has separated when, for every two neighbours in the estimated order, the 95 %
interval of their difference ``t_(k) - t_(k+1) +- 1.96 sd`` excludes 0 (:func:`separation`). The admin page
and ``evalsuite study status`` say so; the researcher decides to stop.

Thread and process safety: there is no state in memory. The estimate is read from the stored answers,
and the choice is written in one transaction that locks the session (``BEGIN IMMEDIATE`` on SQLite,
``SELECT ... FOR UPDATE`` on PostgreSQL) and keeps a choice another request made first.
"""
from __future__ import annotations

import random
from dataclasses import dataclass
from statistics import NormalDist
from typing import Any

import numpy as np
from sqlalchemy import func, select

__all__ = ["DEFAULT_EXPLORATION", "PRIOR", "Estimate", "Separation", "fit", "pair_gains", "choose_pair",
           "separation", "adaptive_options", "adaptive_record", "block_estimate", "assign_pair", "adaptive_status"]

DEFAULT_EXPLORATION = 0.2
PRIOR = 0.5              # virtual ties per pair (total weight), half each way
LEVEL = 0.95             # of the intervals that decide whether the ranking has separated


@dataclass(frozen=True)
class Estimate:
    conditions: tuple[str, ...]
    theta: np.ndarray          # (C,) natural-log strengths, mean 0
    cov: np.ndarray            # (C, C) Laplace covariance of theta
    votes: float               # judgements behind it (a tie counts 1)


@dataclass(frozen=True)
class Separation:
    order: tuple[str, ...]     # strongest first
    separated: int             # neighbouring pairs whose difference's interval excludes 0
    pairs: int                 # neighbouring pairs (C - 1)

    @property
    def done(self) -> bool:
        return self.pairs > 0 and self.separated == self.pairs


def fit(conditions, outcomes, prior: float = PRIOR) -> Estimate:
    """Bradley-Terry fit of ``outcomes`` = ``[(a, b, s), ...]`` (``s``: 1 a preferred, 0 b, 0.5 a tie; an optional
    4th item counts the judgements alike) over ``conditions`` (``C`` names): strengths ``(C,)`` and their
    covariance ``(C, C)`` (module docstring)."""
    conditions = tuple(conditions)
    idx = {c: i for i, c in enumerate(conditions)}
    C = len(conditions)
    W = np.full((C, C), prior / 2)
    np.fill_diagonal(W, 0.0)
    votes = 0.0
    for a, b, s, *count in outcomes:
        n = count[0] if count else 1
        if a in idx and b in idx and a != b:
            W[idx[a], idx[b]] += n * s
            W[idx[b], idx[a]] += n * (1 - s)
            votes += n
    # imported here, not at the top: evalsuite.analysis pulls in pandas and the report's plotting, seconds of
    # every gunicorn worker's start (and of its restart after a crash) that a study without adaptive pages never uses
    from evalsuite.analysis.ranking import bradley_terry

    theta = np.asarray(bradley_terry(W, prior=0.0)) * np.log(10)
    p = 1 / (1 + np.exp(-(theta[:, None] - theta[None, :])))
    w = (W + W.T) * p * (1 - p)
    F = np.diag(w.sum(axis=1)) - w
    return Estimate(conditions, theta, np.linalg.pinv(F), votes)


def pair_gains(est: Estimate, pairs) -> np.ndarray:
    """``gain_ij = 1/2 log(1 + p_ij (1 - p_ij) Var(t_i - t_j))`` for each ``[i, j]`` of ``pairs``, shape ``(P,)``."""
    idx = {c: k for k, c in enumerate(est.conditions)}
    out = np.empty(len(pairs))
    for n, (x, y) in enumerate(pairs):
        i, j = idx[x], idx[y]
        p = 1 / (1 + np.exp(-(est.theta[i] - est.theta[j])))
        var = est.cov[i, i] + est.cov[j, j] - 2 * est.cov[i, j]
        out[n] = 0.5 * np.log1p(p * (1 - p) * max(var, 0.0))
    return out


def choose_pair(est: Estimate, pairs, exploration: float, rng: random.Random) -> tuple[int, str]:
    """Index into ``pairs`` of the next pair and why: ``explore`` (uniform, probability ``exploration``) or
    ``informative`` (largest :func:`pair_gains`, ties broken at random)."""
    if rng.random() < exploration:
        return rng.randrange(len(pairs)), "explore"
    gains = pair_gains(est, pairs)
    best = [k for k, g in enumerate(gains) if g >= gains.max() - 1e-12]
    return rng.choice(best), "informative"


def separation(est: Estimate, level: float = LEVEL) -> Separation:
    """Whether neighbours in the estimated order differ: ``|t_(k) - t_(k+1)| > z sd`` with ``z`` the
    ``(1 + level) / 2`` normal quantile and ``sd`` from the covariance of the difference."""
    order = np.argsort(-est.theta, kind="stable")
    z = NormalDist().inv_cdf((1 + level) / 2)
    sep = 0
    for i, j in zip(order[:-1], order[1:]):
        var = est.cov[i, i] + est.cov[j, j] - 2 * est.cov[i, j]
        sep += bool(est.theta[i] - est.theta[j] > z * np.sqrt(max(var, 0.0)))
    return Separation(tuple(est.conditions[k] for k in order), sep, max(len(order) - 1, 0))


# --- the study app ----------------------------------------------------------------------------------

def adaptive_options(chk: Any, page: dict, where: str, cfg: dict) -> None:
    """``adaptive`` (bool, default false) and ``exploration`` (0..1, default 0.2) of a pairwise block."""
    cfg["adaptive"] = chk.get(page, "adaptive", where, bool, default=False)
    value = chk.get(page, "exploration", where, (int, float), default=DEFAULT_EXPLORATION,
                    expected="a number from 0 to 1")
    if isinstance(value, bool) or not 0 <= value <= 1:
        chk.fail(f"{where}.exploration", f"expected a number from 0 to 1, got {value!r}")
    cfg["exploration"] = float(value)
    if "exploration" in page and not cfg["adaptive"]:
        chk.fail(f"{where}.exploration", "only used with adaptive: true")
    if cfg["adaptive"] and (cfg.get("mismatched") or cfg.get("audio_mismatch")):
        chk.fail(f"{where}.adaptive", "not with mismatched or audio_mismatch (their pages show one condition); "
                 "expected a block of pairs")


def adaptive_record(spec: dict, by_file: dict, side: str) -> dict:
    """What an answer to an adaptive page stores for the estimate: the conditions shown as A and B, and
    ``s`` = 1 (A preferred), 0 (B) or 0.5 (equal), from the first question's screen side."""
    a_side = spec["position_a"]
    s = 0.5 if side == "equal" else 1.0 if side == a_side else 0.0
    return {"a": by_file[spec["a"]].condition, "b": by_file[spec["b"]].condition, "s": s,
            "chosen": spec.get("chosen", "planned")}


def block_estimate(db, study, block_id: str) -> Estimate:
    """The estimate of one adaptive block from its stored answers (sessions that failed left out), counted
    in SQL: one row per (A, B, outcome) from the answers' ``adaptive`` record."""
    from study_app.storage.tables import Answer, ParticipantSession  # (the storage package imports the pages)
    rec = Answer.data["adaptive"]
    a, b, s = rec["a"].as_string(), rec["b"].as_string(), rec["s"].as_float()
    rows = db.execute(select(a, b, s, func.count()).join(ParticipantSession, Answer.session_id == ParticipantSession.id)
                      .where(ParticipantSession.study == study.id, ParticipantSession.status != "failed",
                             Answer.page_id.like(f"{block_id}-%"), a.is_not(None))
                      .group_by(a, b, s))
    outcomes = [(x, y, float(v), int(n)) for x, y, v, n in rows if x and y and v is not None]
    return fit(study.page(block_id).cfg["conditions"], outcomes)


def _file(study, condition: str, segment: str) -> str:
    for s in study.manifest.stimuli:
        if s.kind == "stimulus" and not s.mismatched and s.condition == condition and s.segment == segment:
            return s.file
    raise LookupError(f"no stimulus for {condition!r} on segment {segment!r}")


def assign_pair(store, study, sid: str, index: int, spec: dict) -> dict:
    """The page hook: the pair of adaptive page ``index`` of session ``sid``, chosen at its first view and
    stored in the plan (module docstring); returns the page's spec (unchanged when already chosen)."""
    if spec.get("type") != "pairwise" or "chosen" in spec or spec.get("check") or spec.get("training"):
        return spec
    cfg = study.page(spec["block"]).cfg
    if not cfg.get("adaptive"):
        return spec
    from study_app.storage.tables import ParticipantSession, Plan
    with store.ReadSession() as db:
        est = block_estimate(db, study, spec["block"])
    rng = random.Random(f"{study.seed}|adaptive|{sid}|{index}")
    k, how = choose_pair(est, cfg["pairs"], cfg["exploration"], rng)
    x, y = cfg["pairs"][k]
    with store.Session.begin() as db:
        sess = db.scalars(store._locked(select(ParticipantSession).where(ParticipantSession.id == sid))).first()
        plan = db.get(Plan, sess.plan_id) if sess is not None and sess.plan_id is not None else None
        if plan is None:
            return spec
        current = plan.pages[index]
        if "chosen" in current:             # another request of this session chose first
            return current
        new = {**current, "a": _file(study, x, current["segment"]), "b": _file(study, y, current["segment"]),
               "position_a": rng.choice(("left", "right")), "chosen": how,
               "planned": [current["a"], current["b"]]}
        pages = list(plan.pages)
        pages[index] = new
        plan.pages = pages
    return new


def adaptive_status(store, study) -> list[dict]:
    """One row per adaptive block: votes, the estimated order with Elo-scale strengths, and whether the
    ranking has separated (the study may stop)."""
    out = []
    with store.ReadSession() as db:
        for bid, block in study.blocks.items():
            if not block.cfg.get("adaptive"):
                continue
            est = block_estimate(db, study, bid)
            sep = separation(est)
            elo = {c: round(float(1000 + 400 * t / np.log(10))) for c, t in zip(est.conditions, est.theta)}
            out.append({"block": bid, "votes": int(est.votes), "order": list(sep.order),
                        "elo": [elo[c] for c in sep.order], "separated": sep.separated, "neighbours": sep.pairs,
                        "done": sep.done})
    return out
