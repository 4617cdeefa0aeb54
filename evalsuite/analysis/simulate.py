"""Simulated study responses for the demo and the docs (NOT real participants).

``python -m evalsuite.analysis.simulate [OUT.csv]`` regenerates the bundled
``evalsuite/data/sample_results.csv`` (deterministic: fixed seed). Every row carries
``data_note = "SIMULATED responses (evalsuite demo), not real participants"``.

The design covers every page type the analysis handles:

- ``human_likeness``: 3-level pairwise (A / B / tie), every pair of NA, SysA, SysB, BL;
- ``appropriateness``: 5-level pairwise matched vs mismatched (``X`` vs ``X:mismatched``);
- ``hl_rating``: MUSHRA page with the hidden reference (NA, role ``reference``) and an
  anchor (``Jitter``, role ``anchor``);
- Likert statements on two scales (``naturalness``, ``engagement``);
- one training page and two attention checks per session.

Participants behave according to latent quality ``NA > SysA > SysB > BL``. Planted
cases for the exclusion rules: ``P09`` rates the hidden reference low (BS.1534-3
post-screening), ``P10`` fails two attention checks, ``P11``'s session failed early,
``P03`` took the study twice (duplicate id).
"""
from __future__ import annotations

import itertools
import pathlib
import sys
from datetime import datetime, timedelta, timezone

import numpy as np
import pandas as pd

from evalsuite.analysis.io import RESULTS_COLUMNS

NOTE = "SIMULATED responses (evalsuite demo), not real participants"
QUALITY = {"NA": 1.4, "SysA": 0.7, "SysB": 0.4, "BL": -0.5}
SEGMENTS = ["seg01", "seg02", "seg03", "seg04"]


def _pairwise_answer(rng, qa, qb, five_level):
    d = qa - qb
    p_tie = 0.22 * np.exp(-abs(d))
    p_a = (1 - p_tie) / (1 + np.exp(-1.6 * d))
    u = rng.random()
    if u < p_a:
        ans = "a"
    elif u < p_a + p_tie:
        ans = "tie"
    else:
        ans = "b"
    strength = ""
    if five_level and ans != "tie":
        strength = "strong" if rng.random() < min(0.85, 0.25 + 0.3 * abs(d)) else "weak"
    return ans, strength


def simulate_results(seed: int = 2024) -> pd.DataFrame:
    """Deterministic simulated results table (module docstring)."""
    rng = np.random.default_rng(seed)
    t0 = datetime(2026, 3, 2, 9, 0, tzinfo=timezone.utc)
    rows = []
    sessions = [(f"P{i:02d}", f"S{i:02d}") for i in range(1, 13)] + [("P03", "S13")]
    for s_idx, (part, sess) in enumerate(sessions):
        status = "failed" if part == "P11" else "finished"
        start = t0 + timedelta(minutes=37 * s_idx)
        pages = []  # (page dict, list of row dicts)
        # Training page (excluded from analysis).
        pages.append(("train", "pairwise", [dict(question="human_likeness", condition_a="SysA",
                                                  condition_b="BL", segment="seg00", is_training="1")]))
        hl_pairs = list(itertools.combinations(["NA", "SysA", "SysB", "BL"], 2))
        for k, (c1, c2) in enumerate(hl_pairs):
            for seg in SEGMENTS[:2]:
                a, b = (c1, c2) if rng.random() < 0.5 else (c2, c1)
                pages.append((f"hl_{k}_{seg}", "pairwise",
                              [dict(question="human_likeness", condition_a=a, condition_b=b, segment=seg)]))
        for c in ["NA", "SysA", "SysB"]:
            for seg in SEGMENTS[:2]:
                m = c + ":mismatched"
                a, b = (c, m) if rng.random() < 0.5 else (m, c)
                pages.append((f"app_{c}_{seg}", "pairwise",
                              [dict(question="appropriateness", condition_a=a, condition_b=b, segment=seg)]))
        for seg in SEGMENTS:
            slots = ["NA", "SysA", "SysB", "BL", "Jitter"]
            rng.shuffle(slots)
            pages.append((f"mu_{seg}", "mushra",
                          [dict(question="hl_rating", condition=c, segment=seg, position_a=str(i),
                                role="reference" if c == "NA" else "anchor" if c == "Jitter" else "")
                           for i, c in enumerate(slots)]))
        for c in ["NA", "SysA", "SysB"]:
            stmts = [("nat1", "naturalness"), ("nat2", "naturalness"), ("nat3", "naturalness"),
                     ("eng1", "engagement"), ("eng2", "engagement"), ("eng3", "engagement")]
            pages.append((f"lk_{c}", "likert", [dict(question=q, scale=sc, condition=c, segment="seg03")
                                                  for q, sc in stmts]))
        order = [pages[0]] + [pages[i] for i in 1 + rng.permutation(len(pages) - 1)]
        # Two attention checks, at fixed positions.
        fail_checks = {"P10": 2, "P11": 2, "P05": 1}.get(part, 0)
        check_rows = [(5, "pairwise", "a"), (15, "mushra", "35")]
        if part == "P11":
            order = order[:14]  # ended early after the second failed check
            check_rows = [(3, "pairwise", "a"), (9, "mushra", "35")]
        checks_done = 0
        trial = 0
        now = start
        person_bias = rng.normal(0, 4)
        for page_id, ptype, items in order:
            for pos, ctype, expected in check_rows:
                if trial == pos:
                    failed = checks_done < fail_checks
                    checks_done += 1
                    answer = expected if not failed else ("b" if ctype == "pairwise" else "70")
                    base = dict(question="human_likeness" if ctype == "pairwise" else "hl_rating",
                                segment="seg_check", is_attention_check="1", attention_expected=expected,
                                attention_passed="0" if failed else "1", answer=answer)
                    if ctype == "pairwise":
                        base.update(condition_a="SysA", condition_b="SysB")
                    else:
                        base.update(condition="SysA")
                    rows.append(_row(part, sess, status, f"check_{pos}", ctype, trial, now, base, rng))
                    trial += 1
                    now += timedelta(seconds=25)
            for it in items:
                it = dict(it)
                if ptype == "pairwise":
                    qa, qb = (QUALITY[c.replace(":mismatched", "")] - (1.2 if c.endswith(":mismatched") else 0)
                              if it["question"] == "appropriateness" else QUALITY[c]
                              for c in (it["condition_a"], it["condition_b"]))
                    it["answer"], it["strength"] = _pairwise_answer(
                        rng, qa, qb, five_level=it["question"] == "appropriateness")
                    it["position_a"] = "left" if rng.random() < 0.5 else "right"
                elif ptype == "mushra":
                    c = it["condition"]
                    if c == "NA":
                        v = 60 + rng.normal(0, 8) if part == "P09" else 97 + rng.normal(0, 2.5)
                    elif c == "Jitter":
                        v = 12 + rng.normal(0, 6)
                    else:
                        v = 55 + 18 * QUALITY[c] + person_bias + rng.normal(0, 9)
                    it["answer"] = f"{int(np.clip(round(v), 0, 100))}"
                else:
                    c = it["condition"]
                    v = 4 + 1.3 * QUALITY[c] + person_bias / 6 + rng.normal(0, 0.8)
                    it["answer"] = f"{int(np.clip(round(v), 1, 7))}"
                rows.append(_row(part, sess, status, page_id, ptype, trial, now, it, rng))
            trial += 1
            now += timedelta(seconds=40)
    return results_frame(rows)


def results_frame(rows: list[dict]) -> pd.DataFrame:
    """Simulated rows as a results table: every results.csv column in order, and the simulation note."""
    df = pd.DataFrame(rows)
    for col in RESULTS_COLUMNS:
        if col not in df.columns:
            df[col] = ""
    df = df[list(RESULTS_COLUMNS)].fillna("")
    df["data_note"] = NOTE
    return df


def _row(part, sess, status, page, ptype, trial, now, fields, rng):
    row = {"study": "simulated_demo", "participant": part, "platform": "anonymous", "session": sess,
           "session_status": status, "page": page, "page_type": ptype, "trial": str(trial),
           "is_training": "0", "is_attention_check": "0", "attention_expected": "", "attention_passed": "",
           "rt_ms": str(int(4000 + rng.integers(0, 20000))),
           "shown_at": now.isoformat().replace("+00:00", "Z"),
           "answered_at": (now + timedelta(seconds=20)).isoformat().replace("+00:00", "Z")}
    row.update(fields)
    return row


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    out = pathlib.Path(argv[0]) if argv else pathlib.Path(__file__).resolve().parents[1] / "data" / "sample_results.csv"
    simulate_results().to_csv(out, index=False)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
