"""``evalsuite analyze``: statistics, figures and a report from a study's results."""
from __future__ import annotations

import pathlib

import click

from evalsuite.analysis.presets import PRESETS, preset_values
from evalsuite.errors import InputError


def _attention(value):
    if isinstance(value, int):
        return value
    if str(value).strip().lower() == "any":
        return 1
    try:
        k = int(value)
    except ValueError:
        raise click.BadParameter(f"{value!r}: expected a count >= 1 or 'any'") from None
    if k < 1:
        raise click.BadParameter(f"{value!r}: expected a count >= 1 or 'any'")
    return k


def _playback(value):
    text = str(value).strip().lower()
    if text == "off":
        return 0
    if not text.isdigit():
        raise click.BadParameter(f"{value!r}: expected a count of pages (0 or 'off': no exclusion)")
    return int(text)


@click.command()
@click.argument("results", type=click.Path(dir_okay=False, path_type=pathlib.Path))
@click.option("-o", "--out", "out_dir", type=click.Path(file_okay=False, path_type=pathlib.Path),
              default=pathlib.Path("analysis"), show_default=True, help="Folder for tables, figures and report.html.")
@click.option("--study", default=None, help="Analyse only this study id (needed when the file holds several).")
@click.option("--tie-policy", type=click.Choice(["exclude", "split", "half"]), default="exclude", show_default=True,
              help="Pairwise ties: left out of the test (sign test), split equally between A and B, "
                   "or counted as half a win each.")
@click.option("--ci", "ci_method", type=click.Choice(["clopper-pearson", "wilson"]), default="clopper-pearson",
              show_default=True, help="CI of a preference in ci_low/ci_high (both are in pairwise.csv).")
@click.option("--holm-per-question", is_flag=True,
              help="Holm-Bonferroni within each question instead of across the whole study.")
@click.option("--alpha", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.05,
              show_default=True, help="Significance level and 1 - CI level.")
@click.option("--attention-fails", default="2", show_default=True, callback=lambda c, p, v: _attention(v),
              help="Exclude a session that failed at least this many attention checks ('any' = 1).")
@click.option("--keep-incomplete", is_flag=True, help="Keep sessions with status 'incomplete' (failed ones never).")
@click.option("--duplicates", type=click.Choice(["keep-first", "drop-all"]), default="keep-first",
              show_default=True, help="A participant id with several sessions: keep the earliest or drop all.")
@click.option("--mushra-screening/--no-mushra-screening", default=False, show_default=True,
              help="BS.1534-3 post-screening: exclude a session rating the hidden reference < 90 on > 15% of its "
                   "items. A listening-test rule, off for gesture studies (natural motion is no ceiling); "
                   "the output says how many sessions it would exclude. --preset mushra-itu turns it on.")
@click.option("--implausible-playback", default="1", show_default=True, callback=lambda c, p, v: _playback(v),
              help="Exclude a session with at least this many pages the study server flagged playback_implausible "
                   "(a video never fetched, or answered faster than the clips last); 'off' = 0 = keep them.")
@click.option("--zero-method", type=click.Choice(["wilcox", "pratt", "zsplit"]), default="wilcox",
              show_default=True, help="Wilcoxon handling of equal paired ratings.")
@click.option("--bootstrap", "n_boot", type=click.IntRange(0), default=1000, show_default=True,
              help="Participant-bootstrap rounds for Elo CIs (0 = none).")
@click.option("--seed", type=int, default=42, show_default=True, help="Seed of the bootstrap.")
@click.option("--elo-prior", type=click.FloatRange(0, 1e6), default=0.1, show_default=True,
              help="Virtual ties per compared pair in the Bradley-Terry fit (a penalty that keeps a condition "
                   "that never wins finite); 0 = plain maximum likelihood, the GENEA Leaderboard's estimate.")
@click.option("--preset", type=click.Choice(sorted(PRESETS)), default=None,
              help="Reproduce a published procedure; 'leaderboard': Elo prior 0, 10000 participant-bootstrap "
                   "rounds drawn as the Leaderboard draws them (seed 42), exclusion on any failed attention "
                   "check, ties as half wins; 'mushra-itu': BS.1534-3 post-screening of assessors on the hidden "
                   "reference. Options given explicitly override it.")
@click.option("--mismatch-suffix", default=":mismatched", show_default=True,
              help="Condition X + this suffix is X's mismatched stimulus (matched/mismatched designs).")
@click.option("--no-figures", is_flag=True, help="Tables only (faster).")
@click.option("--blind", is_flag=True, help="Replace condition names by stable codes in every output; "
                                             "the folder stays blind until --reveal.")
@click.option("--reveal", is_flag=True, help="End a blind analysis: real names, plus blind_key.csv (code -> name).")
@click.option("--scores", type=click.Path(dir_okay=False, path_type=pathlib.Path), default=None,
              help="summary.csv of `evalsuite score`: adds a 'Metrics vs humans' section and correlations.csv "
                   "(see `evalsuite correlate`).")
@click.pass_context
def analyze(ctx, results, out_dir, study, tie_policy, ci_method, holm_per_question, alpha, attention_fails,
            keep_incomplete, duplicates, mushra_screening, implausible_playback, zero_method, n_boot, seed,
            elo_prior, preset, mismatch_suffix, no_figures, blind, reveal, scores=None):
    """Analyse RESULTS (a study's results.csv or a battles CSV).

    Applies the exclusion rules, then runs the tests that fit the data: pairwise
    preferences (binomial test, Clopper-Pearson/Wilson CIs, Holm), matched vs mismatched
    (Barnard), Bradley-Terry/Elo with participant bootstrap, 0-100 ratings (medians,
    Wilcoxon signed-rank, Holm, significance matrix) and Likert scales (Cronbach's alpha,
    ANOVA, t-tests). Writes CSV/Markdown/LaTeX tables, PNG figures and report.html to OUT.
    """
    from evalsuite.analysis.pipeline import AnalysisOptions
    from evalsuite.analysis.pipeline import analyze as run

    if not results.is_file():
        raise InputError("file not found (expected a results.csv or battles CSV)", path=results)
    if scores is not None:
        from evalsuite.analysis.correlate.io import read_scores

        read_scores(scores)  # a malformed file stops here, before any statistic is computed
    given = {"tie_policy": tie_policy, "attention_fails": attention_fails, "n_boot": n_boot, "seed": seed,
             "elo_prior": elo_prior, "mushra_screening": mushra_screening}
    values = dict(given)
    for name, value in preset_values(preset).items():
        if name not in given or ctx.get_parameter_source(name) == click.core.ParameterSource.DEFAULT:
            values[name] = value
    opts = AnalysisOptions(ci_method=ci_method, holm_scope="question" if holm_per_question else "study",
                           alpha=alpha, keep_incomplete=keep_incomplete, duplicates=duplicates,
                           implausible_playback=implausible_playback,
                           zero_method=zero_method, mismatch_suffix=mismatch_suffix, study=study,
                           figures=not no_figures, preset=preset, scores=str(scores) if scores else None,
                           **values)
    run(results, out_dir, opts, blind=blind, reveal=reveal, echo=click.echo)
