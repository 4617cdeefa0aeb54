"""Writing the validity table: ``validity.csv``, ``validity.md``, ``validity.tex`` and the heat map of tau."""
from __future__ import annotations

import csv
import math
import pathlib
from collections.abc import Sequence

from evalsuite.validity.analysis import FamilyResult

__all__ = ["COLUMNS", "SYMBOLS", "write_csv", "markdown", "latex", "write_heatmap", "speech_blind", "text_table"]

COLUMNS = ("metric", "family", "tau", "ci_low", "ci_high", "n_levels", "verdict", "better", "worsening",
           "worsening_ci_low", "worsening_ci_high")
SYMBOLS = {"correct": "✓", "partial": "~", "blind": "○", "inverted": "✗", "n/a": "·"}
LEGEND = ("τ: Kendall τ-b between the true order (oracle best, then increasing degradation) and the metric "
          "(its own direction); ✓ correct (τ = 1, interval above 0), ~ partial (sees the strongest level, not "
          "every step), ○ blind (strongest level within bootstrap noise of the oracle), ✗ inverted; "
          "95 % intervals in validity.csv.")


def _grid(results: Sequence[FamilyResult]) -> tuple[list[str], list[str], dict[tuple[str, str], FamilyResult]]:
    metrics = list(dict.fromkeys(r.metric for r in results))
    families = list(dict.fromkeys(r.family for r in results))
    return metrics, families, {(r.metric, r.family): r for r in results}


def _num(x: float) -> str:
    return "" if x is None or not math.isfinite(x) else f"{x:.6g}"


def write_csv(results: Sequence[FamilyResult], path: pathlib.Path) -> None:
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(COLUMNS)
        for r in results:
            row = r.row()
            w.writerow([_num(v) if isinstance(v, float) else v for v in (row[c] for c in COLUMNS)])


def _cell(r: FamilyResult | None) -> str:
    if r is None:
        return ""
    tau = "–" if not math.isfinite(r.tau) else f"{r.tau:+.2f}"
    return f"{tau} {SYMBOLS[r.verdict]}"


def speech_blind(results: Sequence[FamilyResult]) -> list[str]:
    """Metrics that cannot tell a 1.2 s speech-gesture offset from the oracle (blind in the offset family)."""
    return [r.metric for r in results if r.family == "offset" and r.verdict == "blind"]


def markdown(results: Sequence[FamilyResult], levels: dict[str, list[str]] | None = None) -> str:
    metrics, families, cell = _grid(results)
    lines = ["| metric | " + " | ".join(families) + " |", "|---|" + "---|" * len(families)]
    for m in metrics:
        lines.append(f"| {m} | " + " | ".join(_cell(cell.get((m, f))) for f in families) + " |")
    lines += ["", LEGEND]
    if levels:
        lines += ["", "Families (best to worst): " + "; ".join(f"{f}: {' > '.join(v)}" for f, v in levels.items()
                                                              if f in families) + "."]
    blind = speech_blind(results)
    lines += ["", "Blind to speech (a 1.2 s speech-gesture offset within bootstrap noise of the oracle): "
              + (", ".join(blind) if blind else "none") + "."]
    return "\n".join(lines) + "\n"


def _tex(text: str) -> str:
    for a, b in (("\\", r"\textbackslash{}"), ("_", r"\_"), ("%", r"\%"), ("&", r"\&"), ("#", r"\#")):
        text = text.replace(a, b)
    return text


def latex(results: Sequence[FamilyResult]) -> str:
    """A booktabs table of tau with verdict marks (metrics as rows, families as columns)."""
    metrics, families, cell = _grid(results)
    marks = {"correct": r"$\checkmark$", "partial": r"$\sim$", "blind": r"$\circ$", "inverted": r"$\times$",
             "n/a": ""}
    out = [r"\begin{tabular}{l" + "r" * len(families) + "}", r"\toprule",
           "metric & " + " & ".join(_tex(f) for f in families) + r" \\", r"\midrule"]
    for m in metrics:
        cells = []
        for f in families:
            r = cell.get((m, f))
            cells.append("" if r is None or not math.isfinite(r.tau) else f"${r.tau:+.2f}$ {marks[r.verdict]}")
        out.append(_tex(m) + " & " + " & ".join(cells) + r" \\")
    out += [r"\bottomrule", r"\end{tabular}"]
    return "\n".join(out) + "\n"


def text_table(results: Sequence[FamilyResult]) -> str:
    """The table for a terminal (fixed-width columns)."""
    metrics, families, cell = _grid(results)
    width = max(len(m) for m in metrics) if metrics else 6
    cols = [max(len(f), 7) for f in families]
    head = "metric".ljust(width) + "  " + "  ".join(f.rjust(c) for f, c in zip(families, cols))
    rows = [head, "-" * len(head)]
    for m in metrics:
        rows.append(m.ljust(width) + "  " + "  ".join(_cell(cell.get((m, f))).rjust(c) for f, c in zip(families, cols)))
    return "\n".join(rows) + "\n" + LEGEND + "\n"


def write_heatmap(results: Sequence[FamilyResult], path: pathlib.Path) -> list[pathlib.Path]:
    """Heat map of tau by metric x family (PNG and SVG), verdict marks in the cells."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    import numpy as np

    metrics, families, cell = _grid(results)
    grid = np.array([[cell[(m, f)].tau if (m, f) in cell else np.nan for f in families] for m in metrics])
    # a blind cell's tau orders differences within the bootstrap noise: grey, not coloured
    blind = np.array([[(m, f) in cell and cell[(m, f)].verdict in ("blind", "n/a") for f in families]
                      for m in metrics])
    fig, ax = plt.subplots(figsize=(1.0 + 0.75 * len(families), 1.2 + 0.28 * len(metrics)))
    ax.imshow(np.where(blind, 1.0, np.nan), cmap="Greys", vmin=0, vmax=5, aspect="auto")
    im = ax.imshow(np.ma.masked_where(blind | ~np.isfinite(grid), grid), cmap="RdBu", vmin=-1, vmax=1, aspect="auto")
    ax.set_xticks(range(len(families)), families, rotation=45, ha="right")
    ax.set_yticks(range(len(metrics)), metrics, fontsize=8)
    marks = {"correct": "✓", "partial": "~", "blind": "o", "inverted": "x", "n/a": ""}
    for i, m in enumerate(metrics):
        for j, f in enumerate(families):
            r = cell.get((m, f))
            if r is not None:
                dark = not blind[i, j] and math.isfinite(r.tau) and abs(r.tau) > 0.6
                ax.text(j, i, marks[r.verdict], ha="center", va="center", fontsize=8, color="white" if dark else "black")
    fig.colorbar(im, ax=ax, label="Kendall τ with the true order", shrink=0.6)
    ax.set_title("Which metric orders which degradation correctly\n(✓ correct, ~ partial, x inverted; grey o: blind, "
                 "within bootstrap noise)", fontsize=9)
    fig.tight_layout()
    out = []
    for ext in ("png", "svg"):
        p = path.with_suffix(f".{ext}")
        fig.savefig(p, dpi=130)
        out.append(p)
    plt.close(fig)
    return out
