"""Outputs of ``evalsuite correlate``: ``correlations.csv`` / ``.md`` / ``.tex``, one scatter plot per
metric, and the "Metrics vs humans" section of the ``evalsuite analyze`` report (``--scores``)."""
from __future__ import annotations

import html
import math
import pathlib

import numpy as np
import pandas as pd

from evalsuite.analysis import report
from evalsuite.analysis.correlate.bootstrap import ParticipantResampler
from evalsuite.analysis.correlate.io import read_human, read_scores
from evalsuite.analysis.correlate.statistics import EXACT_MAX_N
from evalsuite.analysis.correlate.table import COLUMNS, correlate
from evalsuite.errors import InputError

__all__ = ["write_outputs", "display_table", "fig_scatter", "report_section", "group_notes", "write_notes"]

_ARROW = {"lower": "↓", "higher": "↑", "closer to natural": "≈nat"}
_TEX_WORD = {"lower": "(lower better)", "higher": "(higher better)", "closer to natural": "(closer to natural)"}


def _num(v, fmt: str = ".3f") -> str:
    return report.DASH if v is None or not math.isfinite(float(v)) else format(float(v), fmt)


def _p(v) -> str:
    if v is None or not math.isfinite(float(v)):
        return report.DASH
    return "<0.0001" if v < 1e-4 else f"{v:.4f}"


def _p_from(rho_method, tau_method) -> str:
    """How the p-values were computed: one word when both agree, else each named."""
    rho_method, tau_method = (m if isinstance(m, str) else "" for m in (rho_method, tau_method))
    if not rho_method and not tau_method:
        return report.DASH
    return rho_method if rho_method == tau_method else f"rho {rho_method or report.DASH}; tau_b {tau_method or report.DASH}"


def group_notes(row_notes, examples: int = 3) -> list[str]:
    """One line per kind of note (``row_notes``: ``(kind, metric, human_measure, text)`` as collected by
    :func:`~evalsuite.analysis.correlate.table.correlate`): how many rows have it and the first ``examples``."""
    groups: dict[str, list[tuple[str, str, str]]] = {}
    for kind, metric, measure, text in row_notes:
        groups.setdefault(kind, []).append((metric, measure, text))
    lines = []
    for kind, items in groups.items():
        shown = "; ".join(f"{m} / {h}: {t}" for m, h, t in items[:examples])
        more = f"; and {len(items) - examples} more" if len(items) > examples else ""
        lines.append(f"{kind} ({len(items)} row{'s' if len(items) != 1 else ''}): {shown}{more}")
    return lines


def write_notes(row_notes, path) -> pathlib.Path | None:
    """Every row's notes as ``notes.csv`` (``kind, metric, human_measure, note``); no file (and an older one
    removed) when there are none."""
    path = pathlib.Path(path)
    if not row_notes:
        path.unlink(missing_ok=True)
        return None
    pd.DataFrame(list(row_notes), columns=["kind", "metric", "human_measure", "note"]).to_csv(path, index=False)
    return path


def _ci(lo, hi) -> str:
    return report.DASH if not math.isfinite(float(lo)) else f"[{_num(lo, '.2f')}, {_num(hi, '.2f')}]"


def display_table(table: pd.DataFrame, alpha: float = 0.05, arrows: dict | None = None) -> pd.DataFrame:
    """The compact table of the Markdown, LaTeX and HTML outputs (rounded; CSV keeps everything).
    ``arrows``: how the metric's direction is shown after its name (default ↓, ↑, ≈nat)."""
    arrows = _ARROW if arrows is None else arrows
    level = f"{100 * (1 - alpha):g}%"
    part = bool(np.isfinite(table["spearman_ci_low_participants"].astype(float)).any()) if len(table) else False
    rows = []
    for r in table.to_dict("records"):
        d = {"metric": f"{r['metric']} {arrows.get(r['better'], '')}".strip(), "human measure": r["human_measure"],
             "n": str(r["n"]), "rho": _num(r["spearman_rho"]), "p (rho)": _p(r["spearman_p"]),
             f"rho {level} CI": _ci(r["spearman_ci_low"], r["spearman_ci_high"])}
        if part:
            d["rho CI (participants)"] = _ci(r["spearman_ci_low_participants"], r["spearman_ci_high_participants"])
            d["rho CI (systems+raters)"] = _ci(r["spearman_ci_low_both"], r["spearman_ci_high_both"])
        d.update({"tau_b": _num(r["kendall_tau_b"]), "p (tau_b)": _p(r["kendall_p"]),
                  f"tau_b {level} CI": _ci(r["kendall_ci_low"], r["kendall_ci_high"])})
        if part:
            d["tau_b CI (participants)"] = _ci(r["kendall_ci_low_participants"], r["kendall_ci_high_participants"])
            d["tau_b CI (systems+raters)"] = _ci(r["kendall_ci_low_both"], r["kendall_ci_high_both"])
        d["agrees"] = {True: "yes", False: "no"}.get(r["agrees"], report.DASH)
        d["p from"] = _p_from(r["spearman_p_method"], r["kendall_p_method"])
        d["note"] = r["note"]
        rows.append(d)
    return pd.DataFrame(rows)


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in str(name))


def fig_scatter(metric: str, rows: pd.DataFrame, scores: pd.DataFrame, human: pd.DataFrame):
    """One panel per human measure: the metric (x) against the measure (y), conditions labelled,
    rho and tau_b in the panel title."""
    import matplotlib.pyplot as plt

    k = len(rows)
    ncol = min(k, 3)
    nrow = -(-k // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 3.6 * nrow), squeeze=False)
    svals = scores[scores["metric"] == metric].set_index("condition")["value"]
    better = rows["better"].iloc[0]
    for ax, r in zip(axes.ravel(), rows.to_dict("records")):
        h = human[(human["question"] == r["question"]) & (human["measure"] == r["measure"])]
        hvals = h.set_index("condition")["value"]
        conds = [c for c in str(r["conditions"]).split(";") if c]
        x = np.array([svals[c] for c in conds], dtype=float)
        y = np.array([hvals[c] for c in conds], dtype=float)
        ax.scatter(x, y, color="#4c72b0", zorder=3)
        for c, xi, yi in zip(conds, x, y):
            ax.annotate(c, (xi, yi), textcoords="offset points", xytext=(4, 4), fontsize=8)
        ax.set_xlabel(f"{metric} {_ARROW.get(better, '')}".strip())
        ax.set_ylabel(r["human_measure"])
        ax.set_title(f"rho = {_num(r['spearman_rho'], '.2f')}, tau_b = {_num(r['kendall_tau_b'], '.2f')} "
                     f"(n = {r['n']})", fontsize=9)
        ax.grid(alpha=0.3)
        ax.margins(0.15)
    for ax in axes.ravel()[k:]:
        ax.set_visible(False)
    fig.suptitle(f"{metric} vs human judgements", fontsize=11)
    fig.tight_layout()
    return fig


def write_outputs(table: pd.DataFrame, scores: pd.DataFrame, human: pd.DataFrame, out_dir, *,
                  alpha: float = 0.05, figures: bool = True) -> list[tuple[pathlib.Path, str]]:
    """Write ``correlations.csv`` (full precision, empty cells for no value), ``correlations.md``,
    ``correlations.tex`` and ``figures/scatter_<metric>.png``; returns the figures with captions."""
    out_dir = pathlib.Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    table[COLUMNS].to_csv(out_dir / "correlations.csv", index=False, na_rep="")
    shown = display_table(table, alpha)
    (out_dir / "correlations.md").write_text(report.to_markdown(shown), encoding="utf-8")
    # pdfLaTeX has no arrows in text mode, and to_latex escapes math: the direction in words
    (out_dir / "correlations.tex").write_text(report.to_latex(display_table(table, alpha, _TEX_WORD)),
                                              encoding="utf-8")
    figs = []
    if figures and len(table):
        fig_dir = out_dir / "figures"
        fig_dir.mkdir(exist_ok=True)
        for metric, rows in table.groupby("metric", sort=False):
            rows = rows[rows["n"] > 0]
            if rows.empty:
                continue
            path = report.save_figure(fig_scatter(str(metric), rows, scores, human),
                                      fig_dir / f"scatter_{_safe(metric)}.png")
            figs.append((path, f"{metric} vs human judgements"))
    return figs


# --- the analysis report ------------------------------------------------------------------------

_REPORT_SOURCES = ("ratings", "likert_means", "elo")  # pairwise win rates = elo.csv's win_rate


def report_section(scores_path, out_dir, data: pd.DataFrame, *, n_boot: int = 1000, seed: int = 42,
                   alpha: float = 0.05, figures: bool = True, mismatch_suffix: str = ":mismatched",
                   elo_prior: float = 0.1, codes: dict | None = None, echo=print) -> tuple[str, list[str]]:
    """``("Metrics vs humans", [html])`` for ``evalsuite analyze --scores``: every metric of
    ``scores_path`` against every human measure of the tables already written to ``out_dir``, on the
    conditions both share, with condition and participant bootstrap CIs (``data``: the judgements
    after exclusions; ``elo_prior``: the analysis's, for the Elo of the participant resamples). ``codes``: a blind
    analysis's name -> code map (score conditions outside the study are then left out without being named)."""
    out_dir = pathlib.Path(out_dir)
    scores = read_scores(scores_path)
    parts, notes = [], []
    if codes is not None:
        known = scores["condition"].isin(list(codes))
        if (~known).any():
            notes.append(f"{int((~known).sum())} score row(s) of conditions outside the study left out "
                         "(names hidden: blind analysis)")
        scores = scores[known].assign(condition=scores.loc[known, "condition"].map(codes))
    resampler = ParticipantResampler(data, mismatch_suffix, elo_prior)
    tables, humans = [], []
    for source in _REPORT_SOURCES:
        path = out_dir / f"{source}.csv"
        if not path.is_file():
            continue
        human = read_human(path, mismatch_suffix=mismatch_suffix)
        found: list[str] = []
        try:
            t = correlate(scores, human, n_boot=n_boot, seed=seed, alpha=alpha, participants=resampler,
                          shared_only=True, notes=found)
        except InputError as exc:
            found.append(exc.reason)
            t = None
        notes += [f"{source}.csv: {n}" for n in found]
        if t is None:
            continue
        tables.append(t)
        humans.append(human)
    intro = (f"<p>Each metric of <code>{html.escape(pathlib.Path(scores_path).name)}</code> against each human "
             "measure across the conditions both have: Spearman's rho and Kendall's tau-b (scipy; p-values "
             f"exact, over every ordering of the conditions, up to n = {EXACT_MAX_N}; <em>p from</em> says which), "
             f"{100 * (1 - alpha):g}% percentile bootstrap CIs over conditions and over participants "
             f"({n_boot} resamples, seed {seed}). <em>agrees</em>: the sign a valid metric gives "
             "(lower-is-better metrics should correlate negatively with ratings).</p>")
    parts.append(intro)
    if not tables:
        notes.append("no correlation computed")
    if notes:
        for n in notes:
            echo(f"note: metrics vs humans: {n}")
        parts.append('<div class="note"><ul>' + "".join(f"<li>{html.escape(n)}</li>" for n in notes)
                     + "</ul></div>")
    if tables:
        table = pd.concat(tables, ignore_index=True)
        human = pd.concat(humans, ignore_index=True)
        figs = write_outputs(table, scores, human, out_dir, alpha=alpha, figures=figures)
        parts.append(report.html_table(display_table(table, alpha)))
        parts.extend(report.html_figure(p, c) for p, c in figs)
    return "Metrics vs humans", parts

