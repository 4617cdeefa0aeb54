"""Outputs of ``evalsuite analyze``: tables (CSV, Markdown, LaTeX), figures, HTML report.

CSV files keep full precision and leave cells without a value empty (never ``nan``), so
other tools can read them; Markdown, LaTeX and HTML show rounded numbers and a dash for
"no value", with the reason in the ``note`` column.
"""
from __future__ import annotations

import base64
import html
import math
import pathlib
from typing import Any

import matplotlib

matplotlib.use("Agg")  # files only, never a window
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

DASH = "–"
_P_COLUMNS = {"p_value", "p_holm", "p_bonferroni"}
_INT_LIKE = {"n", "k", "n_a", "n_b", "n_tie", "n_a_strong", "n_b_strong", "n_participants", "levels",
             "n_pages", "n_zero", "n_items", "n_units", "n_judgements", "n_matched", "n_mismatched",
             "df_num", "df_den", "sessions", "rows", "line"}


def _fmt(col: str, v, dash: str = DASH) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return dash
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "no"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        if col in _INT_LIKE and float(v).is_integer():
            return str(int(v))
        if col in _P_COLUMNS:
            return "<0.0001" if v < 1e-4 else f"{v:.4f}"
        return f"{v:.3f}"
    s = str(v)
    return s if s else (dash if col != "note" else "")


def display_frame(df: pd.DataFrame, dash: str = DASH) -> pd.DataFrame:
    """All cells as display strings (rounded numbers, dashes for missing values)."""
    return pd.DataFrame({c: [_fmt(c, v, dash) for v in df[c]] for c in df.columns}, index=df.index)


def to_markdown(df: pd.DataFrame) -> str:
    """A GitHub-flavoured Markdown table."""
    d = display_frame(df)
    esc = lambda s: str(s).replace("|", "\\|")  # noqa: E731
    lines = ["| " + " | ".join(esc(c) for c in d.columns) + " |",
             "|" + "|".join("---" for _ in d.columns) + "|"]
    lines += ["| " + " | ".join(esc(v) for v in row) + " |" for row in d.itertuples(index=False)]
    return "\n".join(lines) + "\n"


_TEX = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_",
        "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}", "<": r"\textless{}",
        ">": r"\textgreater{}", DASH: "--"}


def _tex(s: str) -> str:
    return "".join(_TEX.get(ch, ch) for ch in str(s))


def to_latex(df: pd.DataFrame) -> str:
    """A ``tabular`` (booktabs rules) with LaTeX special characters escaped."""
    d = display_frame(df)
    align = "".join("r" if pd.api.types.is_numeric_dtype(df[c]) and df[c].dtype != bool else "l"
                    for c in df.columns)
    out = [f"\\begin{{tabular}}{{{align}}}", r"\toprule",
           " & ".join(_tex(c) for c in d.columns) + r" \\", r"\midrule"]
    out += [" & ".join(_tex(v) for v in row) + r" \\" for row in d.itertuples(index=False)]
    out += [r"\bottomrule", r"\end{tabular}"]
    return "\n".join(out) + "\n"


def write_table(df: pd.DataFrame, out_dir: pathlib.Path, name: str) -> list[pathlib.Path]:
    """Write ``name.csv``, ``name.md`` and ``name.tex``; returns the paths."""
    out_dir = pathlib.Path(out_dir)
    paths = [out_dir / f"{name}.csv", out_dir / f"{name}.md", out_dir / f"{name}.tex"]
    df.to_csv(paths[0], index=False, na_rep="")
    paths[1].write_text(to_markdown(df), encoding="utf-8")
    paths[2].write_text(to_latex(df), encoding="utf-8")
    return paths


# --- figures -----------------------------------------------------------------------------

def _finite(v) -> bool:
    return v is not None and isinstance(v, (int, float, np.number)) and math.isfinite(v)


def fig_preferences(table: pd.DataFrame, question: str, tie_policy: str):
    """Stacked A / tie / B shares per comparison, with the tested preference for A and its
    95 % CI (like Gesticulator's Figures 6-7). Comparisons without data say so."""
    sub = table[table["question"] == question].reset_index(drop=True)
    fig, ax = plt.subplots(figsize=(8, 0.55 * len(sub) + 1.6))
    y = np.arange(len(sub))[::-1]
    for yi, r in zip(y, sub.itertuples(index=False)):
        tot = r.n_a + r.n_b + r.n_tie
        if tot == 0:
            ax.text(0.5, yi, "no data", ha="center", va="center", color="0.3", style="italic")
            continue
        fa, ft = r.n_a / tot, r.n_tie / tot
        ax.barh(yi, fa, color="#4c72b0", height=0.6)
        ax.barh(yi, ft, left=fa, color="#cccccc", height=0.6)
        ax.barh(yi, 1 - fa - ft, left=fa + ft, color="#dd8452", height=0.6)
        if _finite(r.pref_a):
            err = [[r.pref_a - r.ci_low], [r.ci_high - r.pref_a]]
            ax.errorbar(r.pref_a, yi, xerr=err, fmt="o", color="black", capsize=4, ms=4)
            if r.significant:
                ax.text(1.01, yi, "*", va="center", fontsize=14)
        else:
            ax.text(1.01, yi, "n/a", va="center", fontsize=8, color="0.3")
    ax.axvline(0.5, color="black", lw=0.8, ls="--")
    ax.set_yticks(y, [f"{r.condition_a} vs {r.condition_b}" for r in sub.itertuples(index=False)])
    ax.set_xlim(0, 1)
    ax.set_ylim(-0.8, len(sub) - 0.2)
    ax.set_xlabel(f"judgements: A (blue), tie (grey), B (orange)\n"
                  f"dot: preference for A (ties {tie_policy}) with 95% CI")
    ax.set_title(f"Pairwise preference: {question}  (* = significant after Holm)")
    fig.tight_layout()
    return fig


VIOLIN_MAX = 20_000
HTML_MAX_ROWS = 500


def fig_ratings(mu: pd.DataFrame, question: str):
    """Violin + box plot of 0-100 ratings per condition, sorted by median; mean as a dot. Box, median
    and mean use every rating; the violin's density estimate uses at most :data:`VIOLIN_MAX` of them
    per condition (a seeded random subsample: its outline does not change visibly, its cost does)."""
    sub = mu[mu["question"] == question]
    order = sub.groupby("condition")["value"].median().sort_values(ascending=False).index.tolist()
    data = [sub.loc[sub["condition"] == c, "value"].to_numpy(float) for c in order]
    fig, ax = plt.subplots(figsize=(max(5, 0.9 * len(order) + 2), 4.5))
    pos = np.arange(1, len(order) + 1)
    rng = np.random.default_rng(0)   # the density outline of a large study from a seeded subsample
    vio = [d if d.size > 1 else np.r_[d, d + 1e-9] for d in data]
    vio = [rng.choice(d, VIOLIN_MAX, replace=False) if d.size > VIOLIN_MAX else d for d in vio]
    parts = ax.violinplot(vio, positions=pos, showextrema=False, widths=0.85)
    bodies: Any = parts["bodies"]
    for b in bodies:
        b.set_facecolor("#9ecae1")
        b.set_alpha(0.6)
    ax.boxplot(data, positions=pos, widths=0.25, showfliers=True, medianprops={"color": "black"})
    ax.plot(pos, [d.mean() for d in data], "o", color="#d62728", ms=4, label="mean")
    ax.set_xticks(pos, order, rotation=30, ha="right")
    ax.set_ylim(-2, 102)
    ax.set_ylabel("rating (0-100)")
    ax.set_title(f"Ratings: {question}")
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    return fig


SIGNIFICANCE_LEGEND = (("#4dac26", "row rated significantly higher than column"),
                       ("#d6604d", "row rated significantly lower than column"),
                       ("#bbbbbb", "not significant"),
                       ("white", "no test (same condition, or never on the same page)"))


def fig_significance(matrix: pd.DataFrame, question: str):
    """Significance matrix: green = row rated significantly higher than column, red = lower,
    grey = not significant, white = no test; all four in the legend."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    m = matrix.to_numpy(float)
    n = len(matrix)
    fig, ax = plt.subplots(figsize=(max(5.5, 0.55 * n + 2.5), max(4.5, 0.55 * n + 2.8)))
    cmap = ListedColormap(["#d6604d", "#bbbbbb", "#4dac26"]).with_extremes(bad="white")
    ax.imshow(np.ma.masked_invalid(m), cmap=cmap, vmin=-1, vmax=1)
    ax.set_xticks(range(n), matrix.columns, rotation=45, ha="right")
    ax.set_yticks(range(n), matrix.index)
    ax.set_xticks(np.arange(-0.5, n, 1), minor=True)
    ax.set_yticks(np.arange(-0.5, n, 1), minor=True)
    ax.grid(which="minor", color="0.6", lw=0.5)
    ax.tick_params(which="minor", length=0)
    ax.set_title(f"Wilcoxon signed-rank + Holm: {question}", fontsize=10)
    ax.legend(handles=[Patch(facecolor=c, edgecolor="0.4", label=lab) for c, lab in SIGNIFICANCE_LEGEND],
              loc="upper center", bbox_to_anchor=(0.5, -0.22), fontsize=8, frameon=False, ncol=1)
    fig.tight_layout()
    return fig


def elo_method(prior: float) -> str:
    """What the Elo column is, in words, for figure labels and the report."""
    if prior == 0:
        return "Bradley-Terry MLE"
    return f"Bradley-Terry, penalised by {prior:g} virtual ties per pair"


def fig_elo(elo: pd.DataFrame, question: str, prior: float = 0.1, level: float = 95):
    """Elo (Bradley-Terry) per condition with bootstrap CIs; the label says which fit."""
    sub = elo[(elo["question"] == question) & np.isfinite(elo["elo"].astype(float))]
    sub = sub.sort_values("elo")
    fig, ax = plt.subplots(figsize=(7, 0.45 * len(sub) + 1.5))
    y = np.arange(len(sub))
    have_ci = np.isfinite(sub["ci_low"].astype(float)).to_numpy()
    # A bootstrap percentile interval need not contain the estimate (few participants): drawn as a line
    # from its low to its high end, not as error bars around the estimate.
    ax.hlines(y[have_ci], sub["ci_low"][have_ci], sub["ci_high"][have_ci], color="#4c72b0")
    ax.plot(sub["elo"], y, "o", color="#4c72b0")
    ax.set_yticks(y, sub["condition"])
    ax.axvline(1000, color="0.5", lw=0.8, ls="--")
    ax.set_xlabel(f"Elo ({elo_method(prior)}; {level:g}% participant-bootstrap CI)")
    ax.set_title(f"Ranking: {question}")
    fig.tight_layout()
    return fig


def fig_bars_ci(df: pd.DataFrame, label_col: str, value_col: str, title: str, xlabel: str,
                ref: float | None = None, xlim=None):
    """Horizontal point + CI plot (matched preference, Likert means)."""
    fig, ax = plt.subplots(figsize=(7, 0.45 * len(df) + 1.5))
    y = np.arange(len(df))[::-1]
    v = df[value_col].astype(float).to_numpy()
    lo = df["ci_low"].astype(float).to_numpy()
    hi = df["ci_high"].astype(float).to_numpy()
    ok = np.isfinite(lo) & np.isfinite(v)
    ax.barh(y, np.nan_to_num(v), color="#9ecae1", height=0.6)
    ax.errorbar(v[ok], y[ok], xerr=[v[ok] - lo[ok], hi[ok] - v[ok]], fmt="none", ecolor="black", capsize=4)
    for yi in y[~np.isfinite(v)]:
        ax.text(0.02, yi, "no data", transform=ax.get_yaxis_transform(), va="center", style="italic", color="0.3")
    if ref is not None:
        ax.axvline(ref, color="black", lw=0.8, ls="--")
    if xlim:
        ax.set_xlim(*xlim)
    ax.set_yticks(y, df[label_col])
    ax.set_xlabel(xlabel)
    ax.set_title(title)
    fig.tight_layout()
    return fig


def save_figure(fig, path: pathlib.Path) -> pathlib.Path:
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


# --- HTML --------------------------------------------------------------------------------

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2em auto;max-width:1100px;
color:#222;padding:0 1em}
h1{border-bottom:2px solid #444}h2{border-bottom:1px solid #bbb;margin-top:2em}
table{border-collapse:collapse;font-size:13px;margin:0.6em 0}
th,td{border:1px solid #ccc;padding:3px 7px;text-align:right;white-space:nowrap}th{background:#f0f0f0}
td:first-child,th:first-child{text-align:left}
.note{background:#fff6d5;border-left:4px solid #e0b000;padding:0.5em 1em}
.blind{background:#e8f0ff;border-left:4px solid #3366cc;padding:0.5em 1em}
figure{margin:1em 0}img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:13px;color:#555}.scroll{overflow-x:auto}
"""


def html_table(df: pd.DataFrame, name: str | None = None) -> str:
    """A report table; more than :data:`HTML_MAX_ROWS` rows are cut there, with a line saying how
    many more are in the CSV file (``name``)."""
    if df is None or df.empty:
        return "<p><em>(no rows)</em></p>"
    more = ""
    if len(df) > HTML_MAX_ROWS:
        where = f" (all in {name}.csv)" if name else ""
        more = f"<p><em>... and {len(df) - HTML_MAX_ROWS} more rows{where}</em></p>"
        df = df.head(HTML_MAX_ROWS)
    return ('<div class="scroll">' + display_frame(df).to_html(index=False, escape=True, border=0)
            + "</div>" + more)


def html_figure(path: pathlib.Path, caption: str) -> str:
    data = base64.b64encode(pathlib.Path(path).read_bytes()).decode("ascii")
    return (f'<figure><img alt="{html.escape(caption)}" src="data:image/png;base64,{data}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def html_report(title: str, sections: list[tuple[str, list[str]]]) -> str:
    """A self-contained HTML page: ``sections`` = [(heading, [html fragments])]."""
    body = [f"<h1>{html.escape(title)}</h1>"]
    for heading, parts in sections:
        body.append(f"<h2>{html.escape(heading)}</h2>")
        body.extend(parts)
    return ("<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{html.escape(title)}</title><style>{_CSS}</style></head><body>"
            + "\n".join(body) + "</body></html>\n")
