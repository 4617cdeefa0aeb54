"""``analyze``: read, exclude, test, and write every table, figure and the HTML report."""
from __future__ import annotations

import hashlib
import html
import json
import pathlib
from dataclasses import asdict, dataclass, field

import numpy as np
import pandas as pd

from evalsuite.analysis import blind as blinding
from evalsuite.analysis import report
from evalsuite.analysis.audio_mismatch import audio_mismatch_tables
from evalsuite.analysis.exclusions import apply_exclusions
from evalsuite.analysis.io import read_any
from evalsuite.analysis.likert import likert_tables
from evalsuite.analysis.pairwise import is_mismatch, mismatch_tables, orient, pairwise_table
from evalsuite.analysis.ranking import elo_table
from evalsuite.analysis.ratings import rating_summary, significance_matrix, wilcoxon_pairs
from evalsuite.analysis.sections import collapse_notes, display_order, settings_rows


@dataclass
class AnalysisOptions:
    """Every choice that changes a number in the outputs (all shown in the report)."""

    tie_policy: str = "exclude"
    ci_method: str = "clopper-pearson"
    holm_scope: str = "study"
    alpha: float = 0.05
    attention_fails: int = 2
    keep_incomplete: bool = False
    duplicates: str = "keep-first"
    mushra_screening: bool = False    # BS.1534-3 post-screening: the ``mushra-itu`` preset
    implausible_playback: int = 1
    zero_method: str = "wilcox"
    n_boot: int = 1000
    seed: int = 42
    elo_prior: float = 0.1
    bootstrap_sampler: str = "multinomial"
    preset: str | None = None
    mismatch_suffix: str = ":mismatched"
    mismatch_tie_policy: str = "split"
    study: str | None = None
    figures: bool = True
    scores: str | None = None  # summary.csv of `evalsuite score`: adds "Metrics vs humans" (correlate)


@dataclass
class AnalysisResult:
    out_dir: pathlib.Path
    tables: dict = field(default_factory=dict)
    figures: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    note_details: list = field(default_factory=list)
    exclusions: object = None
    blinded: bool = False
    key_path: pathlib.Path | None = None
    report_path: pathlib.Path | None = None


def _notes(table: pd.DataFrame, what: str, keys, name: str) -> list[tuple[str, str, str, str]]:
    """(what, subject, note, table name) for every row of ``table`` with a note."""
    if table is None or table.empty or "note" not in table.columns:
        return []
    sub = table[table["note"].astype(str) != ""]
    subjects = sub[list(keys)].astype(str).agg(" / ".join, axis=1) if len(sub) else []
    return [(what, s, str(n), name) for s, n in zip(subjects, sub["note"])]


def analyze(path, out_dir, options: AnalysisOptions | None = None, *, blind: bool = False,
            reveal: bool = False, echo=print) -> AnalysisResult:
    """Analyse a results.csv or battles CSV into ``out_dir`` (see docs/analysis.md)."""
    opt = options or AnalysisOptions()
    out_dir = pathlib.Path(out_dir)
    raw = read_any(path, study=opt.study)
    rows_excluded = pd.DataFrame(list(raw.attrs.get("rows_excluded", ())), columns=["line", "reason", "detail"])
    out_dir.mkdir(parents=True, exist_ok=True)
    salt, reveal_salt = blinding.resolve(out_dir, blind, reveal)
    names = blinding.all_conditions(raw)
    res = AnalysisResult(out_dir=out_dir, blinded=salt is not None)
    if salt is not None:
        raw = blinding.apply_codes(raw, blinding.blind_codes(names, salt, opt.mismatch_suffix))
        echo("Blind analysis: condition names are replaced by codes (B01, ...); run with --reveal to unblind.")

    excl = apply_exclusions(raw, attention_fails=opt.attention_fails, keep_incomplete=opt.keep_incomplete,
                            duplicates=opt.duplicates, mushra_screening=opt.mushra_screening,
                            implausible_playback=opt.implausible_playback)
    res.exclusions = excl
    data = excl.data
    s = excl.summary
    echo(f"Participants: {s['participants_total']} ({s['sessions_total']} sessions); "
         f"excluded sessions: {s['sessions_excluded']}; analysed: {s['sessions_included']} sessions, "
         f"{s['rows_analysed']} judgements")
    if s["mushra_screening_would_exclude"] and not opt.mushra_screening:
        echo(f"BS.1534-3 post-screening (--preset mushra-itu) is off; it would exclude "
             f"{s['mushra_screening_would_exclude']} session(s) (hidden reference < 90 on > 15% of items)")
    T = res.tables
    T["exclusions"] = excl.table
    T["rows_excluded"] = rows_excluded
    row_counts = rows_excluded["reason"].value_counts().to_dict()
    if row_counts:
        echo("Rows excluded before the analysis: " + ", ".join(f"{n} {r}" for r, n in sorted(row_counts.items()))
             + " (rows_excluded.csv)")
    items: list[tuple[str, str, str, str]] = []

    # The design = every judgement row of the file (any session), so a comparison emptied
    # by the exclusions is still listed, with a note instead of a p-value.
    design = raw[(raw["is_training"] == 0) & (raw["is_attention_check"] == 0)]
    pw_design = design[design["page_type"] == "pairwise"]
    pw = data[data["page_type"] == "pairwise"]
    if not pw_design.empty:
        comps = orient(pw_design)[["question", "condition_a", "condition_b"]].drop_duplicates()
        T["pairwise"] = pairwise_table(pw, tie_policy=opt.tie_policy, ci_method=opt.ci_method,
                                       holm_scope=opt.holm_scope, alpha=opt.alpha,
                                       comparisons=comps.itertuples(index=False, name=None))
        items += _notes(T["pairwise"], "pairwise", ["question", "condition_a", "condition_b"], "pairwise")
        per, between = mismatch_tables(T["pairwise"], suffix=opt.mismatch_suffix,
                                       tie_policy=opt.mismatch_tie_policy, alpha=opt.alpha)
        if not per.empty:
            T["mismatch"] = per
            items += _notes(per, "matched/mismatched", ["question", "condition"], "mismatch")
        if not between.empty:
            T["mismatch_barnard"] = between
            items += _notes(between, "Barnard", ["question", "condition_1", "condition_2"], "mismatch_barnard")
        audio, audio_between = audio_mismatch_tables(T["pairwise"], tie_policy=opt.mismatch_tie_policy,
                                                     alpha=opt.alpha)
        if not audio.empty:   # the Leaderboard's audio mismatching: per system vs 50 %, ranked
            T["audio_mismatch"] = audio
            items += _notes(audio, "audio mismatch", ["question", "condition"], "audio_mismatch")
        if not audio_between.empty:
            T["audio_mismatch_barnard"] = audio_between
        # A ranking needs comparisons between systems; matched-vs-mismatched pairs (motion or audio) are not.
        ranked = pw[~is_mismatch(pw["condition_a"], pw["condition_b"], opt.mismatch_suffix)]
        if not ranked.empty:
            T["elo"] = elo_table(ranked, n_boot=opt.n_boot, seed=opt.seed, alpha=opt.alpha,
                                 prior=opt.elo_prior, sampler=opt.bootstrap_sampler)
            items += _notes(T["elo"].drop_duplicates(["question", "note"]), "ranking", ["question"], "elo")
    mu_design = design[design["page_type"] == "mushra"]
    mu = data[data["page_type"] == "mushra"]
    if not mu_design.empty:
        T["ratings"] = rating_summary(mu, opt.alpha,
                                      expected=set(zip(mu_design["question"], mu_design["condition"])))
        items += _notes(T["ratings"], "ratings", ["question", "condition"], "ratings")
        T["ratings_pairwise"] = wilcoxon_pairs(mu, zero_method=opt.zero_method, holm_scope=opt.holm_scope,
                                               alpha=opt.alpha)
        items += _notes(T["ratings_pairwise"], "Wilcoxon", ["question", "condition_1", "condition_2"],
                            "ratings_pairwise")
    lk = data[data["page_type"] == "likert"]
    if not design[design["page_type"] == "likert"].empty:
        if lk.empty:
            items.append(("likert", "", "no responses left after exclusions", ""))
        else:
            for name, t in likert_tables(lk, opt.alpha).items():
                T[f"likert_{name}"] = t
            items += _notes(T["likert_reliability"], "Cronbach's alpha", ["scale"], "likert_reliability")
            items += _notes(T["likert_anova"], "ANOVA", ["scale", "test"], "likert_anova")
    if data.empty:
        items.append(("data", "", "no judgements left after exclusions: nothing to test", ""))

    res.note_details = [f"{w} {sub}: {n}" if sub else f"{w}: {n}" for w, sub, n, _ in items]
    res.notes = collapse_notes(items)
    for note in res.notes:
        echo(f"note: {note}")
    for name, table in T.items():
        report.write_table(table, out_dir, name)

    sections = _figures_and_sections(res, opt, data, out_dir, raw, path)
    if opt.scores:
        from evalsuite.analysis.correlate.output import report_section
        codes = blinding.blind_codes(names, salt, opt.mismatch_suffix) if salt is not None else None
        sections.append(report_section(opt.scores, out_dir, data, n_boot=opt.n_boot, seed=opt.seed, alpha=opt.alpha,
                                       figures=opt.figures, mismatch_suffix=opt.mismatch_suffix,
                                       elo_prior=opt.elo_prior, codes=codes, echo=echo))
    title = f"evalsuite analysis: {raw.attrs.get('study', '')}"
    res.report_path = out_dir / "report.html"
    res.report_path.write_text(report.html_report(title, sections), encoding="utf-8")
    summary = {"input": str(path), "study": raw.attrs.get("study"), "format": raw.attrs.get("format"),
               "blinded": res.blinded, "options": asdict(opt),
               "exclusions": {k: v for k, v in excl.summary.items()}, "rows_excluded": row_counts,
               "notes": res.notes,
               "note_details": res.note_details}
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2, default=str), encoding="utf-8")
    if reveal_salt is not None:
        res.key_path = blinding.finish_reveal(out_dir, reveal_salt, names, opt.mismatch_suffix)
        echo(f"Revealed: code -> condition key in {res.key_path}")
    elif reveal:
        echo("--reveal: this folder was not blinded; outputs use the real condition names.")
    echo(f"Report: {res.report_path}")
    return res


def _figures_and_sections(res, opt, data, out_dir, raw, path):
    T = res.tables
    fig_dir = out_dir / "figures"
    fig_dir.mkdir(exist_ok=True)
    figs = res.figures

    def add(fig, name, caption):
        p = report.save_figure(fig, fig_dir / f"{name}.png")
        figs.append((p, caption))
        return report.html_figure(p, caption)

    names = {id(t): n for n, t in T.items()}

    def tbl(df):
        return report.html_table(display_order(df), names.get(id(df)))

    s = res.exclusions.summary
    settings = settings_rows(opt, raw, T, f"{pathlib.Path(path).name} ({raw.attrs.get('format')})")
    head = []
    if res.blinded:
        head.append('<p class="blind">BLIND ANALYSIS: condition names are replaced by codes. '
                    "Run <code>evalsuite analyze ... --reveal</code> to unblind.</p>")
    head.append(report.html_table(settings))
    sections = [("Settings", head)]

    ex = [f"<p>{s['participants_total']} participants in {s['sessions_total']} sessions; "
          f"{s['sessions_excluded']} sessions excluded, {s['sessions_included']} analysed "
          f"({s['participants_included']} participants, {s['rows_analysed']} judgements). "
          f"Removed rows: {s['training_rows_removed']} training, "
          f"{s['attention_check_rows_removed']} attention-check trials.</p>"]
    if s["sessions_with_implausible_playback"]:
        ex.append(f"<p>{s['sessions_with_implausible_playback']} sessions have pages with implausible playback "
                  "(media never fetched, or answered faster than the clips last); "
                  + ("they are excluded (implausible_playback)." if opt.implausible_playback else
                     "the rule is off (--implausible-playback), so they are analysed.") + "</p>")
    dropped = T["rows_excluded"]
    if not dropped.empty:
        ex.append("<p>Rows excluded by the reader before any statistic (each listed in rows_excluded.csv):</p>")
        ex.append(report.html_table(dropped["reason"].value_counts().rename_axis("reason").reset_index(name="rows")))
    if s["reasons"]:
        ex.append(report.html_table(pd.DataFrame(sorted(s["reasons"].items()), columns=["reason", "sessions"])))
    ex.append(tbl(T["exclusions"]) if not T["exclusions"].empty else "<p>Nobody was excluded.</p>")
    sections.append(("Exclusions", ex))
    if res.notes:
        sections.append(("Notes", ['<div class="note"><ul>' + "".join(
            f"<li>{html.escape(n)}</li>" for n in res.notes) + "</ul></div>"]))

    if "pairwise" in T:
        parts = [tbl(T["pairwise"])]
        if opt.figures:
            for q in sorted(T["pairwise"]["question"].unique()):
                parts.append(add(report.fig_preferences(T["pairwise"], q, opt.tie_policy),
                                 f"preference_{_safe(q)}", f"Pairwise preference with 95% CIs: {q}"))
        sections.append(("Pairwise preferences", parts))
    if "mismatch" in T:
        parts = [tbl(T["mismatch"])]
        if "mismatch_barnard" in T:
            parts.append("<p>Barnard's exact test between conditions (Holm-corrected):</p>")
            parts.append(tbl(T["mismatch_barnard"]))
        if opt.figures:
            for q, sub in T["mismatch"].groupby("question"):
                parts.append(add(report.fig_bars_ci(sub, "condition", "pref_matched",
                                                    f"Matched preferred: {q}", "share preferring matched "
                                                    f"(ties {opt.mismatch_tie_policy}, Clopper-Pearson 95% CI)",
                                                    ref=0.5, xlim=(0, 1)),
                                 f"mismatch_{_safe(q)}", f"Matched vs mismatched: {q}"))
        sections.append(("Matched vs mismatched", parts))
    if "audio_mismatch" in T:
        parts = [tbl(T["audio_mismatch"])]
        if "audio_mismatch_barnard" in T:
            parts += ["<p>Barnard's exact test between systems (Holm-corrected):</p>", tbl(T["audio_mismatch_barnard"])]
        if opt.figures:
            for q, sub in T["audio_mismatch"].groupby("question"):
                parts.append(add(report.fig_bars_ci(sub, "condition", "pref_matched", f"Own speech preferred: {q}",
                                                    f"share preferring the video with its own speech (ties "
                                                    f"{opt.mismatch_tie_policy}, Clopper-Pearson 95% CI)",
                                                    ref=0.5, xlim=(0, 1)),
                                 f"audio_mismatch_{_safe(q)}", f"Audio mismatch: {q}"))
        sections.append(("Audio mismatch (speech-gesture alignment)", parts))
    if "elo" in T:
        parts = [tbl(T["elo"])]
        if opt.figures:
            for q in sorted(T["elo"]["question"].unique()):
                if np.isfinite(T["elo"].loc[T["elo"]["question"] == q, "elo"].astype(float)).any():
                    parts.append(add(report.fig_elo(T["elo"], q, opt.elo_prior, 100 * (1 - opt.alpha)),
                                     f"elo_{_safe(q)}", f"Elo ({report.elo_method(opt.elo_prior)}) with "
                                     f"{100 * (1 - opt.alpha):g}% CIs: {q}"))
        sections.append(("Ranking (Bradley-Terry / Elo)", parts))
    if "ratings" in T:
        parts = [tbl(T["ratings"]), "<p>Pairwise Wilcoxon signed-rank tests:</p>",
                 tbl(T["ratings_pairwise"])]
        mu = data[data["page_type"] == "mushra"]
        for q in sorted(mu["question"].unique()):
            conds = T["ratings"].loc[T["ratings"]["question"] == q].sort_values(
                "median", ascending=False)["condition"].tolist()
            # the matrix is a table (docs/analysis.md): written with or without figures
            m = significance_matrix(T["ratings_pairwise"], q, conds)
            m.to_csv(out_dir / f"significance_{_safe(q)}.csv")
            if opt.figures:
                parts.append(add(report.fig_ratings(mu, q), f"ratings_{_safe(q)}", f"Ratings: {q}"))
                parts.append(add(report.fig_significance(m, q), f"significance_{_safe(q)}",
                                 f"Significance matrix: {q}"))
        sections.append(("Ratings (0-100)", parts))
    if "likert_means" in T:
        parts = ["<p>Reliability:</p>", tbl(T["likert_reliability"]),
                 "<p>Means:</p>", tbl(T["likert_means"]),
                 "<p>ANOVA:</p>", tbl(T["likert_anova"]),
                 "<p>Post-hoc tests (Bonferroni):</p>", tbl(T["likert_posthoc"])]
        if opt.figures:
            for sc, sub in T["likert_means"].groupby("scale"):
                parts.append(add(report.fig_bars_ci(sub, "condition", "mean", f"Likert: {sc}",
                                                    "mean scale score (95% CI)"),
                                 f"likert_{_safe(sc)}", f"Likert means: {sc}"))
        sections.append(("Likert scales", parts))
    return sections


def _safe(name: str, limit: int = 120) -> str:
    """A file-name part for ``name``: letters, digits, '-' and '_'; one of more than ``limit`` bytes in UTF-8
    (file names end at 255 bytes) is cut to 24 characters and 8 hex digits of its hash (names stay distinct)."""
    safe = "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in str(name))
    if len(safe.encode()) <= limit:
        return safe
    return f"{safe[:24]}_{hashlib.sha256(str(name).encode()).hexdigest()[:8]}"
