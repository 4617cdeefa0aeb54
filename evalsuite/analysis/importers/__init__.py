"""Human judgements from other tools as evalsuite's ``results.csv``: ``evalsuite import-judgements``.

Every source is an :class:`Importer` in the :data:`IMPORTERS` registry (entry-point group
``evalsuite.judgement_formats``, so a plug-in can add its own); each turns one file into a DataFrame with the
``results.csv`` columns (:data:`evalsuite.contracts.results.COLUMNS`) that ``evalsuite analyze`` and
``evalsuite correlate --results`` read. The built-in sources (formats: ``docs/human-data.md``):

===================  =========================================================================================
``battles``          the GENEA Leaderboard's pairwise votes (battles CSV) -> pairwise rows
``genea-ratings``    GENEA 2022/2023 released 0-100 ratings (one rating per rater, system, segment) -> mushra rows
``genea-pairwise``   GENEA 2023-style 5-option pairwise preferences (-2..2 for the first stimulus) -> pairwise rows
``hemvip``           HEMVIP (webMUSHRA) session JSON exports: rating pages and pairwise pages
``evalsuite``        evalsuite's own ``results.csv`` export (validated; one study picked with ``study=``)
===================  =========================================================================================
"""
from __future__ import annotations

import pathlib
from collections.abc import Callable
from dataclasses import dataclass

import pandas as pd

from evalsuite.contracts.results import COLUMNS
from evalsuite.registry import Registry

__all__ = ["IMPORTERS", "Importer", "import_judgements", "write_results"]


@dataclass(frozen=True)
class Importer:
    """One source of judgements: ``read(path, study=..., question=...)`` gives results.csv rows."""

    name: str
    summary: str
    read: Callable[..., pd.DataFrame]


IMPORTERS: Registry[Importer] = Registry("judgement format", "evalsuite.judgement_formats", base=Importer,
                                         name_of=lambda imp: imp.name, field="format")
for _name, _target in (("battles", "evalsuite.analysis.importers.battles:BATTLES"),
                       ("genea-ratings", "evalsuite.analysis.importers.genea:RATINGS"),
                       ("genea-pairwise", "evalsuite.analysis.importers.genea:PAIRWISE"),
                       ("hemvip", "evalsuite.analysis.importers.hemvip:HEMVIP"),
                       ("evalsuite", "evalsuite.analysis.importers.own:EVALSUITE")):
    IMPORTERS.register_lazy(_name, _target)


def import_judgements(fmt: str, path, *, study: str | None = None, question: str | None = None) -> pd.DataFrame:
    """The judgements in ``path`` (a file in format ``fmt``) as a results.csv table (columns ``COLUMNS``)."""
    imp = IMPORTERS.get(fmt)
    out = imp.read(pathlib.Path(path), study=study, question=question)
    return out[list(COLUMNS)]


def write_results(df: pd.DataFrame, out) -> pathlib.Path:
    """Write the table as ``results.csv`` (columns in the contract's order)."""
    out = pathlib.Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    df[list(COLUMNS)].to_csv(out, index=False)
    return out
