"""Writing a scoring run: CSV (long form), JSON with provenance, Markdown, LaTeX, terminal table.

``summary.csv`` has the stable columns ``condition, metric, value, unit, ci_low, ci_high``
followed by ``std, n, better, convention, samples, n_samples`` (other tools read it; new columns go at the end).
"""
from __future__ import annotations

import json
import math
import pathlib
import platform
from collections.abc import Iterable
from typing import Any

import numpy as np
import pandas as pd

from evalsuite.contracts import summary as summary_contract
from evalsuite.metrics.engine import ScoreResult

__all__ = ["SUMMARY_COLUMNS", "summary_frame", "format_table", "markdown_table", "latex_table", "write_outputs",
           "grouped_issues"]

SUMMARY_COLUMNS = list(summary_contract.COLUMNS)
_ARROW = {"lower": "lower is better", "higher": "higher is better", "closer to natural": "closer to natural"}
_SYMBOL = {"lower": "↓", "higher": "↑", "closer to natural": "≈nat"}
_TEX_SYMBOL = {"lower": r"$\downarrow$", "higher": r"$\uparrow$", "closer to natural": r"$\approx$nat"}


def grouped_issues(issues: Iterable[str], conditions: Iterable[str]) -> list[str]:
    """The run's issues for the terminal, one line per distinct message: ``"<condition>: <message>"`` lines that
    differ only in their condition become ``"<message> (conditions a, b, c)"`` (``results.json`` keeps every one)."""
    names = sorted(conditions, key=len, reverse=True)       # the longest name first: "a_b" before "a"
    groups: dict[str, list[str]] = {}
    for issue in issues:
        cond = next((c for c in names if issue.startswith(f"{c}: ")), None)
        key = issue[len(cond) + 2:] if cond is not None else issue
        groups.setdefault(key, [])
        if cond is not None:
            groups[key].append(cond)
    out = []
    for message, conds in groups.items():
        if len(conds) == 1:
            out.append(f"{conds[0]}: {message}")
        elif conds:
            out.append(f"{message} (conditions {', '.join(conds)})")
        else:
            out.append(message)
    return out


def summary_frame(rows: Iterable[dict[str, Any]]) -> pd.DataFrame:
    frame = pd.DataFrame(list(rows))
    for c in SUMMARY_COLUMNS:
        if c not in frame.columns:
            frame[c] = np.nan
    extra = [c for c in frame.columns if c not in SUMMARY_COLUMNS]
    return frame[SUMMARY_COLUMNS + extra]


def _fmt(x: float | None, digits: int = 4) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "n/a"
    ax = abs(x)
    if ax != 0 and (ax >= 1e5 or ax < 1e-3):
        return f"{x:.{digits - 1}e}"
    return f"{x:.{digits}g}" if ax >= 1 else f"{x:.{digits}f}".rstrip("0").rstrip(".") or "0"


def _cell(row: dict[str, Any]) -> str:
    text = _fmt(row["value"])
    if isinstance(row.get("std"), float) and math.isfinite(row["std"]):
        text += f" ± {_fmt(row['std'], 3)}"
    if isinstance(row.get("ci_low"), float) and math.isfinite(row["ci_low"]):
        text += f" [{_fmt(row['ci_low'], 3)}, {_fmt(row['ci_high'], 3)}]"
    return text


def _pivot(frame: pd.DataFrame) -> tuple[list[str], list[str], dict[tuple[str, str], str], dict[str, tuple[str, str]]]:
    conditions = list(dict.fromkeys(frame["condition"]))
    metrics = list(dict.fromkeys(frame["metric"]))
    cells = {(r["condition"], r["metric"]): _cell(r) for r in frame.to_dict("records")}
    meta = {r["metric"]: (r["unit"], r["better"]) for r in frame.to_dict("records")}
    return conditions, metrics, cells, meta


def format_table(frame: pd.DataFrame) -> str:
    """Plain-text table: one row per metric (with unit and better direction), one column per condition."""
    conditions, metrics, cells, meta = _pivot(frame)
    header = ["metric", "unit", "better"] + conditions
    rows = [[m, str(meta[m][0]), _SYMBOL.get(meta[m][1], str(meta[m][1]))] +
            [cells.get((c, m), "") for c in conditions] for m in metrics]
    widths = [max(len(str(x)) for x in col) for col in zip(header, *rows)]
    def line(r: list[str]) -> str:
        return "  ".join(str(x).ljust(w) for x, w in zip(r, widths)).rstrip()

    out = [line(header), line(["-" * w for w in widths])] + [line(r) for r in rows]
    has_ci = bool(np.isfinite(pd.to_numeric(frame["ci_low"], errors="coerce")).any())
    legend = ("value ± std across sequences" + (" [bootstrap 95% CI]" if has_ci else "")
              + "; ↓ lower is better, ↑ higher is better, ≈nat closer to natural is better")
    return "\n".join(out + ["", legend])


def markdown_table(frame: pd.DataFrame) -> str:
    """Markdown table: conditions as rows, metrics as columns (header: metric, unit, direction)."""
    conditions, metrics, cells, meta = _pivot(frame)
    head = ["condition"] + [f"{m} ({meta[m][0]}) {_SYMBOL.get(meta[m][1], '')}" for m in metrics]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for c in conditions:
        lines.append("| " + " | ".join([c] + [cells.get((c, m), "") for m in metrics]) + " |")
    lines += ["", "Values: mean ± std across sequences [bootstrap 95% CI where computed]. "
              "↓ lower is better, ↑ higher is better, ≈nat closer to natural is better."]
    return "\n".join(lines) + "\n"


def _tex_escape(text: str) -> str:
    for a, b in (("\\", r"\textbackslash "), ("_", r"\_"), ("%", r"\%"), ("&", r"\&"), ("#", r"\#"),
                 ("^", r"\^{}"), ("±", r"$\pm$")):
        text = text.replace(a, b)
    return text


def latex_table(frame: pd.DataFrame) -> str:
    """A booktabs LaTeX table (conditions as rows, metrics as columns)."""
    conditions, metrics, cells, meta = _pivot(frame)
    cols = "l" + "r" * len(metrics)
    head = " & ".join(["Condition"] + [f"{_tex_escape(m)} {_TEX_SYMBOL.get(meta[m][1], '')}" for m in metrics])
    units = " & ".join([""] + [_tex_escape(f"[{meta[m][0]}]") for m in metrics])
    body = [" & ".join([_tex_escape(c)] + [_tex_escape(cells.get((c, m), "")) for m in metrics]) + r" \\"
            for c in conditions]
    return "\n".join([r"\begin{tabular}{" + cols + "}", r"\toprule", head + r" \\", units + r" \\", r"\midrule",
                      *body, r"\bottomrule", r"\end{tabular}"]) + "\n"


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(float(x)) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, pathlib.Path):
        return str(x)
    return x


def provenance(result: ScoreResult) -> dict[str, Any]:
    """What a run depended on: versions, convention, joints, fps, bins, every input file's SHA-256."""
    import scipy

    from evalsuite._version import __version__

    plan, setup, conv = result.plan, result.setup, result.convention
    return {
        "evalsuite_version": __version__,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "convention": {"name": conv.name, "description": conv.description, "time_scale": conv.time_scale,
                       "overflow_bin": conv.overflow, "std_ddof": conv.std_ddof,
                       "cca": "in-sample" if conv.cca_in_sample else "cross-fitted (two folds over sequences)"},
        "reference": plan.reference,
        "conditions": plan.conditions,
        "folders": {k: str(v) for k, v in plan.folders.items()},
        "joints": setup.joints,
        "joint_groups": setup.groups,
        "fps": result.fps,
        "resampled_to": setup.resample,
        "resampled_files": result.resampled,
        "metrics": setup.metrics,
        "histogram_edges": {q: e for q, e in setup.edges.items()},
        "beat_sigma_s": setup.sigma,
        "bootstrap": {"resamples": result.bootstrap, "seed": result.seed, "unit": "sequences (paired)",
                      "interval": "percentile 2.5-97.5; Fréchet distances (fd_g, fd_k, fgd): moved to have the "
                                  "resamples' median on the estimate, bias in bootstrap_bias"},
        "files": result.files,
    }


def write_outputs(result: ScoreResult, out_dir: str | pathlib.Path) -> dict[str, pathlib.Path]:
    """Write every table and the JSON under ``out_dir``; returns ``{kind: path}``."""
    out = pathlib.Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    frame = summary_frame(result.summary)
    paths = {"summary_csv": out / "summary.csv", "per_sequence_csv": out / "per_sequence.csv",
             "per_joint_csv": out / "per_joint.csv", "histograms_csv": out / "histograms.csv",
             "json": out / "results.json", "markdown": out / "summary.md", "latex": out / "summary.tex"}
    frame.to_csv(paths["summary_csv"], index=False)
    pd.DataFrame(result.per_sequence, columns=["condition", "sequence", "metric", "value", "unit"]).to_csv(
        paths["per_sequence_csv"], index=False)
    pd.DataFrame(result.per_joint, columns=["condition", "joint", "metric", "value", "unit"]).to_csv(
        paths["per_joint_csv"], index=False)
    hist_rows = []
    edges = result.setup.edges
    for h in result.histograms:
        e = edges[h["quantity"]]
        lows = list(e[:-1]) + [e[-1]]
        highs = list(e[1:]) + [float("inf")]
        for lo, hi, c in zip(lows, highs, h["counts"]):
            hist_rows.append({"condition": h["condition"], "quantity": h["quantity"], "group": h["group"],
                              "bin_low": lo, "bin_high": hi, "count": int(c)})
    pd.DataFrame(hist_rows, columns=["condition", "quantity", "group", "bin_low", "bin_high", "count"]).to_csv(
        paths["histograms_csv"], index=False)
    payload = {"provenance": provenance(result), "summary": frame.to_dict("records"),
               "issues": result.issues}
    paths["json"].write_text(json.dumps(_jsonable(payload), indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    paths["markdown"].write_text(markdown_table(frame), encoding="utf-8")
    paths["latex"].write_text(latex_table(frame), encoding="utf-8")
    return paths
