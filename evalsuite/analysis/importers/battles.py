"""The GENEA Leaderboard's pairwise votes (battles CSV) as results.csv rows (``docs/human-data.md``).

The reading and checks are :func:`evalsuite.analysis.io.read_battles`' (``user, input_code, model_a, model_b,
winner, is_strong`` or evalsuite's own ``participant, item, condition_a, condition_b, winner, strength``)."""
from __future__ import annotations

import pandas as pd

from evalsuite.analysis.importers import Importer
from evalsuite.analysis.io import read_battles
from evalsuite.contracts.results import COLUMNS


def read(path, *, study: str | None = None, question: str | None = None) -> pd.DataFrame:
    df = read_battles(path)
    out = df.copy()
    for col in COLUMNS:
        if col not in out.columns:
            out[col] = ""
    out["study"] = study or "battles"
    if question:
        out["question"] = question
    out["is_training"] = "0"
    out["is_attention_check"] = "0"
    return out[list(COLUMNS)].astype(str)


BATTLES = Importer("battles", "GENEA Leaderboard battles CSV (pairwise votes)", read)
