"""Statistics of perceptual studies: ``evalsuite analyze`` (see docs/analysis.md).

Modules: :mod:`~evalsuite.analysis.io` (read/validate results.csv and battles CSV),
:mod:`~evalsuite.analysis.exclusions`, :mod:`~evalsuite.analysis.pairwise`,
:mod:`~evalsuite.analysis.ratings`, :mod:`~evalsuite.analysis.likert`,
:mod:`~evalsuite.analysis.ranking`, :mod:`~evalsuite.analysis.blind`,
:mod:`~evalsuite.analysis.report`, :mod:`~evalsuite.analysis.pipeline`.
"""
from evalsuite.analysis.exclusions import apply_exclusions, mushra_post_screening
from evalsuite.analysis.io import read_any, read_battles, read_results
from evalsuite.analysis.pipeline import AnalysisOptions, analyze

__all__ = ["AnalysisOptions", "analyze", "apply_exclusions", "mushra_post_screening", "read_any",
           "read_battles", "read_results"]
