"""``evalsuite correlate``: objective metrics against human judgements across conditions."""
from __future__ import annotations

import json
import math
import pathlib

import click

from evalsuite.errors import InputError


def _names(values) -> list[str]:
    return [v.strip() for item in values for v in str(item).split(",") if v.strip()]


def _renames(values) -> dict[str, str]:
    out = {}
    for item in values:
        old, sep, new = item.partition("=")
        if not sep or not old.strip() or not new.strip():
            raise click.BadParameter(f"{item!r}: expected SCORE_NAME=HUMAN_NAME", param_hint="--rename")
        out[old.strip()] = new.strip()
    return out


def _analysis_options(human: pathlib.Path) -> dict:
    """The options of the ``evalsuite analyze`` run that wrote ``human`` (its summary.json) that change a
    recomputed human measure: the exclusions, and the prior of the Elo fit."""
    path = human.parent / "summary.json"
    try:
        opts = json.loads(path.read_text(encoding="utf-8")).get("options", {})
    except (OSError, ValueError, AttributeError):
        return {}
    keys = ("attention_fails", "keep_incomplete", "duplicates", "mushra_screening", "implausible_playback", "study",
            "elo_prior")
    return {k: opts[k] for k in keys if k in opts} if isinstance(opts, dict) else {}


def check_against_results(human, resampler, results_path) -> None:
    """InputError when the human table's values are not the ones recomputed from the results file."""
    source = human.attrs.get("source", "")
    if source == "plain":
        raise InputError("--results recomputes the measures of ratings.csv, likert_means.csv, elo.csv or "
                         "pairwise.csv of `evalsuite analyze`, not of a plain condition,value file",
                         path=human.attrs.get("path"))
    for (q, m), g in human.groupby(["question", "measure"], sort=False):
        point = resampler.point(source, q, m, list(g["condition"]))
        if point is None:
            raise InputError(f"cannot recompute {m!r}{' of ' + repr(q) if q else ''} from this file for the "
                             f"participant bootstrap (no such judgements)", path=results_path)
        for (c, v, line), p in zip(zip(g["condition"], g["value"], g["line"]), point):
            if math.isfinite(v) and not math.isclose(v, p, rel_tol=1e-6, abs_tol=1e-9):
                raise InputError(f"{m} of {c!r} is {v:g} here but {p:g} recomputed from {results_path}: not the "
                                 "results this table was computed from, or analysed with other exclusion options",
                                 path=human.attrs.get("path"), line=int(line), field=m)


@click.command()
@click.argument("scores", type=click.Path(dir_okay=False, path_type=pathlib.Path))
@click.argument("human", type=click.Path(dir_okay=False, path_type=pathlib.Path))
@click.option("-o", "--out", "out_dir", type=click.Path(file_okay=False, path_type=pathlib.Path),
              default=pathlib.Path("correlations"), show_default=True, help="Folder for the tables and figures.")
@click.option("--measure", "measures", multiple=True,
              help="Human measure(s) to use where the file has several: median, mean (ratings.csv), elo, "
                   "win_rate (elo.csv); comma-separated or repeated. Default: all of the file's.")
@click.option("--question", "questions", multiple=True, help="Only these questions / scales (default: all).")
@click.option("--metric", "metrics", multiple=True,
              help="Only these metrics (default: all); for a condition,value SCORES file, the metric's name.")
@click.option("--results", "results", type=click.Path(dir_okay=False, path_type=pathlib.Path), default=None,
              help="The study's results.csv (or battles CSV): adds CIs from resampling participants.")
@click.option("--per-segment", "per_sequence", type=click.Path(dir_okay=False, path_type=pathlib.Path), default=None,
              help="per_sequence.csv of `evalsuite score` (needs --results): also correlate the metrics with the "
                   "human measure segment by segment (correlations_per_segment.csv, mean over segments with a CI).")
@click.option("--bootstrap", "n_boot", type=click.IntRange(0), default=1000, show_default=True,
              help="Bootstrap resamples (conditions; participants with --results); 0 = no CIs.")
@click.option("--seed", type=int, default=42, show_default=True, help="Seed of the bootstrap.")
@click.option("--alpha", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.05,
              show_default=True, help="1 - CI level.")
@click.option("--rename", "renames", multiple=True, metavar="SCORE=HUMAN",
              help="Condition SCORE of the scores is HUMAN in the human judgements (repeatable).")
@click.option("--exclude", "excluded", multiple=True, help="Leave these conditions out (comma-separated or repeated).")
@click.option("--shared-only", is_flag=True,
              help="Correlate the conditions both inputs have instead of stopping on a difference.")
@click.option("--human-lower-better", is_flag=True,
              help="The human values are better when lower (e.g. a rank in a plain CSV); sets 'agrees'.")
@click.option("--natural", default=None, metavar="NAME",
              help="The natural condition (as named in HUMAN): adds |metric - NAME| for every 'closer to natural' "
                   "metric, which has an expected sign.")
@click.option("--mismatch-suffix", default=":mismatched", show_default=True,
              help="X vs X + this suffix is a matched-vs-mismatched comparison: left out of win rates.")
@click.option("--no-figures", is_flag=True, help="Tables only.")
@click.option("-v", "--verbose", is_flag=True,
              help="Print every row's note; by default one line per kind of note (count and examples), all of "
                   "them in OUT/notes.csv.")
def correlate(scores, human, out_dir, measures, questions, metrics, results, per_sequence, n_boot, seed, alpha, renames, excluded,
              shared_only, human_lower_better, natural, mismatch_suffix, no_figures, verbose):
    """Correlate objective metrics (SCORES) with human judgements (HUMAN) across conditions.

    SCORES: summary.csv of `evalsuite score`, or a condition,metric,value or condition,value
    CSV. HUMAN: ratings.csv, likert_means.csv, elo.csv or pairwise.csv of `evalsuite analyze`,
    or a condition,value CSV (published numbers). For every metric and human measure: n,
    Spearman's rho and Kendall's tau-b with their p-values (exact, over every ordering of the
    conditions, up to 8 conditions; t / normal approximation above), percentile bootstrap CIs
    over conditions (and over participants with --results), and whether the sign agrees with
    the metric's direction. Writes correlations.csv/.md/.tex and figures/scatter_<metric>.png.

    \b
    Example:
      evalsuite score -r natural=data/NA data/SysA data/SysB data/SysC -o scores/
      evalsuite analyze results.csv -o analysis/
      evalsuite correlate scores/summary.csv analysis/ratings.csv --measure median \\
          --rename natural=NA --results results.csv -o correlations/
    """
    from evalsuite.analysis.correlate.bootstrap import ParticipantResampler
    from evalsuite.analysis.correlate.io import read_human, read_scores
    from evalsuite.analysis.correlate.output import display_table, group_notes, write_notes, write_outputs
    from evalsuite.analysis.correlate.table import add_distance_to_natural
    from evalsuite.analysis.correlate.table import correlate as run

    metric_names = _names(metrics)
    s = read_scores(scores)
    if s.attrs.get("plain"):
        if len(metric_names) > 1:
            raise InputError("a condition,value file holds one metric: give --metric once (its name)", path=scores)
        if metric_names:
            s["metric"] = metric_names[0]
    elif metric_names:
        unknown = [m for m in metric_names if m not in set(s["metric"])]
        if unknown:
            raise InputError(f"no metric {', '.join(map(repr, unknown))}; it has: {', '.join(dict.fromkeys(s['metric']))}",
                             path=scores, field="metric")
        s = s[s["metric"].isin(metric_names)]
    h = read_human(human, _names(measures), _names(questions), mismatch_suffix)
    source = h.attrs["source"]
    mapping = _renames(renames)
    s = s.assign(condition=s["condition"].map(lambda c: mapping.get(c, c)))
    dupes = s[s.duplicated(["metric", "condition"], keep=False)]
    if not dupes.empty:
        raise InputError(f"--rename makes two conditions {dupes['condition'].iloc[0]!r} for metric "
                         f"{dupes['metric'].iloc[0]!r}", path=scores)
    if natural:  # before --exclude: the natural condition may be left out of the correlation
        s.attrs.update(path=str(scores))
        s = add_distance_to_natural(s, natural)
    drop = set(_names(excluded))
    unknown_drop = sorted(drop - set(s["condition"]) - set(h["condition"]))
    if unknown_drop:
        raise InputError(f"--exclude: no condition {', '.join(unknown_drop)} in either input")
    s = s[~s["condition"].isin(drop)]
    h = h[~h["condition"].isin(drop)]
    s.attrs.update(path=str(scores), source="scores")
    h.attrs.update(path=str(human), source=source)
    resampler = None
    if per_sequence is not None and results is None:
        raise InputError("--per-segment needs --results (the judgements of each segment come from the results.csv)")
    if results is not None:
        opts = _analysis_options(human)
        resampler = ParticipantResampler.from_results(results, mismatch_suffix=mismatch_suffix, **opts)
        check_against_results(h, resampler, results)
    notes: list[str] = []
    row_notes: list[tuple[str, str, str, str]] = []
    table = run(s, h, n_boot=n_boot, seed=seed, alpha=alpha, participants=resampler, shared_only=shared_only,
                human_higher=not human_lower_better, notes=notes, row_notes=row_notes)
    for n in notes:
        click.echo(f"warning: {n}")
    write_outputs(table, s, h, out_dir, alpha=alpha, figures=not no_figures)
    if per_sequence is not None and resampler is not None:
        _write_per_segment(per_sequence, resampler.data, mapping, drop, out_dir, n_boot=n_boot, seed=seed,
                           alpha=alpha, mismatch_suffix=mismatch_suffix)
    shown = display_table(table, alpha)
    cols = [c for c in shown.columns if c not in ("p (rho)", "p (tau_b)", "p from", "note")]
    widths = {c: max(len(c), *(len(str(v)) for v in shown[c])) for c in cols}
    click.echo("  ".join(c.ljust(widths[c]) for c in cols))
    for _, r in shown.iterrows():
        click.echo("  ".join(str(r[c]).ljust(widths[c]) for c in cols).rstrip())
    notes_file = write_notes(row_notes, out_dir / "notes.csv")
    if verbose:
        for _, metric, measure, text in row_notes:
            click.echo(f"note: {metric} / {measure}: {text}")
    else:
        for line in group_notes(row_notes):
            click.echo(f"note: {line}")
    if notes_file is not None:
        click.echo(f"All {len(row_notes)} notes: {notes_file}")
    click.echo(f"Wrote {out_dir / 'correlations.csv'} (.md, .tex)" + ("" if no_figures else " and figures/"))



def _write_per_segment(path, results, mapping, drop, out_dir, *, n_boot, seed, alpha, mismatch_suffix):
    import pandas as pd

    from evalsuite.analysis.correlate.segments import human_by_segment, per_segment

    seq = pd.read_csv(path, dtype=str, keep_default_na=False)
    missing = [c for c in ("condition", "sequence", "metric", "value") if c not in seq.columns]
    if missing:
        raise InputError(f"missing column(s) {', '.join(missing)}; expected the per_sequence.csv of `evalsuite score` "
                         "(condition, sequence, metric, value)", path=path, line=1)
    seq["condition"] = seq["condition"].map(lambda c: mapping.get(c, c))
    seq = seq[~seq["condition"].isin(drop)]
    table = per_segment(seq, human_by_segment(results, mismatch_suffix), n_boot=n_boot, seed=seed, alpha=alpha)
    if table.empty:
        raise InputError("no segment has both per-sequence metric values and judgements of 3 or more conditions "
                         "(the sequence names of per_sequence.csv must be the segment ids of the results)", path=path)
    out_dir.mkdir(parents=True, exist_ok=True)
    table.to_csv(out_dir / "correlations_per_segment.csv", index=False)
    means = table[table["segment"] == "(mean)"]
    for _, r in means.iterrows():
        click.echo(f"per segment: {r['metric']} / {r['question']}: mean rho {r['spearman_rho']:.3f} over {r['n']} "
                   f"segments [{r['spearman_ci_low']:.3f}, {r['spearman_ci_high']:.3f}]")
    click.echo(f"Wrote {out_dir / 'correlations_per_segment.csv'}")
