"""Demo step: analyse the bundled, simulated ``sample_results.csv``."""
from __future__ import annotations

import pathlib
from importlib import resources

from evalsuite.analysis.pipeline import AnalysisOptions, analyze


def sample_results_path() -> pathlib.Path:
    """The bundled sample results (SIMULATED responses, see evalsuite.analysis.simulate)."""
    return pathlib.Path(str(resources.files("evalsuite") / "data" / "sample_results.csv"))


def run(out_dir: pathlib.Path, echo) -> None:
    src = sample_results_path()
    echo(f"Analysing {src.name} (simulated responses, not real participants)")
    res = analyze(src, pathlib.Path(out_dir) / "analysis", AnalysisOptions(), echo=echo)
    echo(f"{len(res.tables)} tables and {len(res.figures)} figures; open {res.report_path}")
