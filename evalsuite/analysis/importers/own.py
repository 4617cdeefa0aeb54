"""evalsuite's own ``results.csv`` export (``docs/results_format.md``), validated by ``evalsuite analyze``'s
reader and written back with one study (``study=``) and, when given, every question renamed (``question=``)."""
from __future__ import annotations

import pandas as pd

from evalsuite.analysis.importers import Importer
from evalsuite.analysis.io import read_results
from evalsuite.contracts.results import COLUMNS


def read(path, *, study: str | None = None, question: str | None = None) -> pd.DataFrame:
    df = read_results(path, study=study)
    out = df[list(COLUMNS)].copy()
    if question:
        out["question"] = question
    return out.astype(str)


EVALSUITE = Importer("evalsuite", "evalsuite's own results.csv export", read)
