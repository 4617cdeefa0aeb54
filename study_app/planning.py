"""Sample size for a study definition (``evalsuite study power study.yaml``): per block, how many judgements a
comparison needs (:mod:`evalsuite.analysis.power`), how many a session gives (counted in the study's own plans)
and so how many participants the study needs, with the power its planned ``sessions`` give.

Families follow ``evalsuite analyze`` (Holm over the whole study): every pairwise comparison of every question
of every pairwise block is one family (matched vs mismatched included); every pair of conditions rated together
(hidden reference and anchor included) of every MUSHRA question another; a Likert scale's post-hoc tests are
Bonferroni over its condition pairs (paired t-tests when participants rate both conditions, else Welch's
t-test on one group per condition). Each comparison is planned at ``alpha / K``.

A session gives a comparison what its plan shows of it (trial pages; practice and attention checks do not
count): the scarcest comparison of a block decides. Participants = ``ceil(units / (units per session x
(1 - exclusion rate)))``; pairwise judgements are divided by ``1 - ties`` first (ties are left out of the
test).
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass

from evalsuite.analysis.power import binomial_power, likert_power, mushra_power, pairwise_judgements, smallest_n
from study_app.model import Study
from study_app.pages.base import export_condition

__all__ = ["Effects", "block_plans", "study_power"]


@dataclass(frozen=True)
class Effects:
    """What the researcher expects, and the test settings (``evalsuite study power``'s options)."""

    preference: float = 0.65        # pairwise: A's share of the judgements without ties
    ties: float = 0.0               # pairwise: share of tie answers expected
    difference: float = 10.0        # MUSHRA: difference of two conditions in rating points (0-100)
    sd: float = 20.0                # MUSHRA: SD of one rating
    likert_difference: float = 0.5  # Likert: difference of two conditions in scale points
    likert_sd: float = 1.0          # Likert: SD of one answer (and of a participant's offset)
    alpha: float = 0.05
    power: float = 0.8
    exclusion_rate: float = 0.0     # share of sessions expected to be excluded
    sims: int = 1000
    seed: int = 0


def _units(study: Study, plans: dict) -> dict[str, dict]:
    """Per block: ``{"units": Counter(comparison -> units over all plans), "single": Counter(condition ->
    sessions rating it)}``. A unit is a judgement (pairwise), a page rating both conditions (MUSHRA), a
    participant rating both conditions (Likert; ``single`` counts participants rating one)."""
    by_file = study.manifest.by_file()
    out: dict[str, dict] = {bid: {"units": Counter(), "single": Counter()} for bid in study.blocks}
    for plan in plans["plans"]:
        seen: dict[str, set] = {}
        for p in plan["pages"]:
            if "block" not in p or p["training"] or p["check"]:
                continue
            units = out[p["block"]]["units"]
            if p["type"] == "pairwise":
                units[tuple(sorted((export_condition(by_file[p["a"]]), export_condition(by_file[p["b"]]))))] += 1
            elif p["type"] == "mushra":
                conds = sorted({by_file[f].condition for f in p["slots"]})
                for i, c1 in enumerate(conds):
                    for c2 in conds[i + 1:]:
                        units[(c1, c2)] += 1
            else:
                seen.setdefault(str(p["block"]), set()).add(by_file[p["stimulus"]].condition)
        for bid, shown in seen.items():
            out[bid]["single"].update(shown)
            ordered = sorted(shown)
            for i, c1 in enumerate(ordered):
                for c2 in ordered[i + 1:]:
                    out[bid]["units"][(c1, c2)] += 1
    return out


def block_plans(study: Study, plans: dict) -> list[dict]:
    """One entry per rating block: its design, comparisons, family size and units per session."""
    units = _units(study, plans)
    sessions = len(plans["plans"])
    rows = []
    for bid, page in study.blocks.items():
        kind = page.type
        cfg = page.cfg
        if kind == "pairwise":
            shown = list(cfg["conditions"])
            pairs = ([(c, c + ":mismatched") for c in shown] if cfg["mismatched"]
                     else [(c, c + ":audio_mismatched") for c in shown] if cfg["audio_mismatch"]
                     else [tuple(sorted(p)) for p in cfg["pairs"]])
            questions = [q["id"] for q in cfg["questions"]]
        elif kind == "mushra":
            shown = list(cfg["conditions"]) + [c for c in (cfg.get("reference"), cfg.get("anchor")) if c]
            ordered = sorted(shown)
            pairs = [(a, b) for i, a in enumerate(ordered) for b in ordered[i + 1:]]
            questions = [cfg["question"]["id"]]
        elif kind == "likert":
            ordered = sorted(cfg["conditions"])
            pairs = [(a, b) for i, a in enumerate(ordered) for b in ordered[i + 1:]]
            questions = sorted({s["scale"] for s in cfg["statements"]})
        else:
            continue
        counts = units[bid]["units"]
        scarcest = min((counts.get(tuple(sorted(p)), 0) for p in pairs), default=0)
        paired = kind != "likert" or scarcest > 0
        if not paired:      # Likert without participants rating both: one group per condition (Welch)
            scarcest = min((units[bid]["single"].get(c, 0) for c in cfg["conditions"]), default=0)
        rows.append({"block": bid, "design": kind, "questions": questions, "pairs": pairs,
                     "statements": len(cfg.get("statements", [])) // max(1, len(questions)),
                     "points": cfg.get("points", 7), "paired": paired,
                     "per_session": scarcest / sessions if sessions else 0.0,
                     "sessions": sessions})
    return rows


def study_power(study: Study, plans: dict, effects: Effects) -> list[dict]:
    """Per block: family size ``K``, level ``alpha / K``, units needed per comparison, units per session,
    participants needed and the power the planned sessions give (module docstring)."""
    rows = block_plans(study, plans)
    family: Counter = Counter()
    for r in rows:
        if r["design"] == "likert":
            r["family"] = len(r["pairs"])                       # Bonferroni within each scale
        else:
            family[r["design"]] += len(r["pairs"]) * len(r["questions"])
    e = effects
    keep = 1 - e.exclusion_rate
    for r in rows:
        k = r.get("family") or family[r["design"]]
        level = e.alpha / k
        planned = r["per_session"] * r["sessions"] * keep
        if r["design"] == "pairwise":
            n, _ = pairwise_judgements(e.preference, alpha=e.alpha, power=e.power, comparisons=k)
            needed = math.ceil(n / (1 - e.ties))
            achieved = binomial_power(int(planned * (1 - e.ties)), e.preference, level)
            unit, effect = "judgements", f"preference {e.preference:g}, ties {e.ties:g}"
        elif r["design"] == "mushra":
            def mushra_at(m: int, level: float = level) -> float:
                return mushra_power(m, e.difference, e.sd, level, sims=e.sims, seed=e.seed)

            needed, _ = smallest_n(mushra_at, e.power)
            achieved = mushra_at(int(planned))
            unit, effect = "pages", f"difference {e.difference:g} points, SD {e.sd:g}"
        else:
            def likert_at(m: int, r: dict = r, level: float = level) -> float:
                return likert_power(m, e.likert_difference, e.likert_sd, level, points=r["points"],
                                    statements=max(1, r["statements"]), paired=r["paired"], sims=e.sims,
                                    seed=e.seed)

            needed, _ = smallest_n(likert_at, e.power)
            achieved = likert_at(int(planned))
            unit = "participants rating both" if r["paired"] else "participants per condition (Welch t)"
            effect = f"difference {e.likert_difference:g} points, SD {e.likert_sd:g}"
        per = r["per_session"] * keep
        r.update(family=k, level=level, unit=unit, effect=effect, needed=needed, planned=planned,
                 achieved=achieved, participants=math.ceil(needed / per) if per > 0 else None)
    return rows
