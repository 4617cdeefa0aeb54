"""SIMULATED participants for any set of conditions (the demo's study; never a human result).

Each simulated participant rates every condition on one MUSHRA page per segment (0-100; ``natural`` is the
hidden reference) and answers pairwise human-likeness pages for every pair of conditions on one segment.
Answers follow a stated latent quality per condition:

* MUSHRA: ``50 + 20 q + b_p + e``, clipped to 0..100, with a participant bias ``b_p ~ N(0, 4^2)`` and noise
  ``e ~ N(0, 9^2)``; the hidden reference ``97 + N(0, 2.5^2)``;
* pairwise: ``P(tie) = 0.22 exp(-|d|)``, ``P(A) = (1 - P(tie)) / (1 + exp(-1.6 d))`` with ``d = q_A - q_B``.

Every row carries ``data_note`` saying it is simulated.
"""
from __future__ import annotations

import itertools
from collections.abc import Mapping, Sequence
from datetime import datetime, timedelta, timezone

import numpy as np
import pandas as pd

from evalsuite.analysis.simulate import _pairwise_answer, results_frame

__all__ = ["simulate_study"]


def _row(rng: np.random.Generator, t0: datetime, p: int, trial: int, page: str, ptype: str,
         fields: dict[str, str]) -> dict[str, str]:
    shown = t0 + timedelta(minutes=23 * p, seconds=45 * trial)
    return {"study": "simulated_demo", "participant": f"SIM{p + 1:02d}", "platform": "prolific",
            "session": f"S{p + 1:02d}", "session_status": "finished", "page": page, "page_type": ptype,
            "trial": str(trial), "is_training": "0", "is_attention_check": "0", "attention_expected": "",
            "attention_passed": "", "rt_ms": str(int(6000 + rng.integers(0, 20000))),
            "shown_at": shown.isoformat().replace("+00:00", "Z"),
            "answered_at": (shown + timedelta(seconds=30)).isoformat().replace("+00:00", "Z"), **fields}


def simulate_study(quality: Mapping[str, float], segments: Sequence[str], *, participants: int = 16,
                   seed: int = 0, reference: str = "natural") -> pd.DataFrame:
    """A results table (``results.csv`` columns) of simulated participants (module docstring)."""
    if len(quality) < 2 or not segments:
        raise ValueError("simulate_study needs at least two conditions and one segment")
    rng = np.random.default_rng(seed)
    names = list(quality)
    t0 = datetime(2026, 11, 2, 9, 0, tzinfo=timezone.utc)
    rows = []
    for p in range(participants):
        bias = rng.normal(0, 4)
        trial = 0


        for seg in segments:
            order = list(rng.permutation(names))
            for slot, c in enumerate(order):
                q = float(quality[c])
                v = 97 + rng.normal(0, 2.5) if c == reference else 50 + 20 * q + bias + rng.normal(0, 9)
                fields = {"question": "human_likeness_rating", "condition": c, "segment": seg,
                          "position_a": str(slot), "answer": str(int(np.clip(round(v), 0, 100))),
                          "role": "reference" if c == reference else ""}
                rows.append(_row(rng, t0, p, trial, f"mushra_{seg}", "mushra", fields))
            trial += 1
        seg = segments[p % len(segments)]
        for k, (a, b) in enumerate(itertools.combinations(names, 2)):
            if rng.random() < 0.5:
                a, b = b, a
            ans, strength = _pairwise_answer(rng, float(quality[a]), float(quality[b]), False)
            rows.append(_row(rng, t0, p, trial, f"pair_{k}", "pairwise", {"question": "human_likeness", "condition_a": a, "condition_b": b,
                                         "segment": seg, "answer": ans, "strength": strength,
                                         "position_a": "left" if rng.random() < 0.5 else "right"}))
            trial += 1
    return results_frame(rows)
