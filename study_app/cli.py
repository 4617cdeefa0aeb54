"""``evalsuite study``: build session plans, serve a study, export its results."""
from __future__ import annotations

import math
import os
import pathlib
import secrets

import click

from study_app.cli_ops import COMMANDS

DB_HELP = ("Database URL (SQLAlchemy): sqlite:///path.db or postgresql+psycopg://user@host/db. "
           "Default: SQLite study.db in the instance folder.")


def _instance_dir(study_path, instance):
    return pathlib.Path(instance) if instance else pathlib.Path(study_path).resolve().parent / "instance"


def _db_url(study_path, instance, db):
    if db:
        return db
    folder = _instance_dir(study_path, instance)
    folder.mkdir(parents=True, exist_ok=True)
    return f"sqlite:///{folder / 'study.db'}"


@click.group()
def study():
    """Crowd perceptual studies: build balanced session plans, serve them, export results.

    Typical use: `evalsuite study build study.yaml`, then
    `evalsuite study serve study.yaml --admin-token ...`, finally
    `evalsuite study export study.yaml -o results.csv`.
    """


@study.command()
@click.argument("study_file", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--out", type=click.Path(dir_okay=False),
              help="Plans JSON to write (default: <study id>.plans.json beside the definition).")
@click.option("--db", default=None, help="Also create the tables and store the plans in this "
              "database (needed before starting several gunicorn workers).")
def build(study_file, out, db):
    """Validate STUDY_FILE, write the clips it derives (audio-mismatched, video-only) and its balanced session
    plans."""
    from study_app import derived, design
    from study_app.definition import load_study

    st = load_study(study_file)
    made = derived.write_derived(st.manifest)     # audio-mismatched and video-only clips (study_app.derived)
    if made:
        click.echo(f"{len(made)} derived clip(s) written to {st.manifest.root / derived.DERIVED_FOLDER}")
    plans = design.build_plans(st)
    path = design.write_plans(plans, out or design.default_plans_path(st))
    click.echo(f"{len(plans['plans'])} session plans for study {st.id!r} -> {path}")
    for line in derived.audio_balance_lines(plans, st):
        click.echo(line)
    report = design.balance_report(plans, st)
    if report["pairs"]:
        click.echo("pairwise comparisons (block, A, B): times with A left / A right")
        keys = sorted({k[:3] for k in report["pairs"]})
        for k in keys:
            click.echo(f"  {k[0]}: {k[1]} vs {k[2]}: {report['pairs'][k + ('left',)]} / "
                       f"{report['pairs'][k + ('right',)]}")
    if report["mushra_slots"]:
        per_cond = {}
        for (block, cond, _slot), n in report["mushra_slots"].items():
            per_cond[(block, cond)] = per_cond.get((block, cond), 0) + n
        click.echo("mushra ratings per condition: " + ", ".join(
            f"{b}/{c}: {n}" for (b, c), n in sorted(per_cond.items())))
    spreads = [(what, block, d) for what, key in (("page positions", "page_positions"), ("mushra slots", "mushra_slots"),
                                                 ("pairwise sides", "pairs"))
               for block, d in sorted(design.position_spread(report[key]).items())]
    if spreads:
        click.echo("orders, largest distance of a count from equal (0: exact, up to 1: equal within one): "
                   + ", ".join(f"{what} {block} {d:.2g}" for what, block, d in spreads))
    uneven = design.size_spread(plans, st)
    if uneven:
        n_pages = sum(1 for p in plans["plans"] for page in p["pages"] if "block" in page)
        w = uneven[0]
        click.echo(f"warning: on {len(uneven)} of {n_pages} rating pages the video files differ in size by more than "
                   f"10% (largest: {w['ratio']:.1f}x on {w['plan']}/{w['page']}, {w['smallest']:,} to "
                   f"{w['largest']:,} bytes); a participant can tell the clips apart by size in the browser's network "
                   "panel: render the stimuli with equal_size: pad or cbr (docs/render.md)", err=True)
    if db:
        from study_app.storage import init_db, make_engine
        init_db(make_engine(db), st, plans)
        click.echo(f"database ready: {db}")


@study.command()
@click.argument("study_file", type=click.Path(exists=True, dir_okay=False))
@click.option("--db", default=None, help=DB_HELP)
@click.option("--instance", type=click.Path(file_okay=False), default=None,
              help="Folder for the default SQLite database and the generated cookie secret "
                   "(default: instance/ beside the study file).")
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to listen on.")
@click.option("--port", default=5000, show_default=True, type=int, help="Port to listen on.")
@click.option("--admin-token", envvar="EVALSUITE_ADMIN_TOKEN", required=True,
              help="Token for /admin (or env EVALSUITE_ADMIN_TOKEN); at least 12 characters. "
                   "`evalsuite study admin-token` makes one.")
@click.option("--secret-key", envvar="EVALSUITE_SECRET_KEY", default=None,
              help="Key signing cookies (env EVALSUITE_SECRET_KEY). Default: a random key kept "
                   "in the instance folder so sessions survive restarts.")
@click.option("--secure-cookies/--no-secure-cookies", default=None,
              help="Send cookies over HTTPS only (default: on unless serving on loopback).")
def serve(study_file, db, instance, host, port, admin_token, secret_key, secure_cookies):
    """Serve STUDY_FILE with Flask's development server (local use and pilots).

    For production use gunicorn with several workers and PostgreSQL (docs/study_app.md).
    """
    from study_app.app import create_app

    folder = _instance_dir(study_file, instance)
    folder.mkdir(parents=True, exist_ok=True)
    if not secret_key:
        key_file = folder / "secret_key"
        if not key_file.exists():
            key_file.write_text(secrets.token_urlsafe(32))
            os.chmod(key_file, 0o600)
        secret_key = key_file.read_text().strip()
    if secure_cookies is None:
        secure_cookies = host not in ("127.0.0.1", "localhost", "::1")
    url = _db_url(study_file, instance, db)
    app = create_app({"STUDY": study_file, "DATABASE_URL": url, "SECRET_KEY": secret_key,
                      "ADMIN_TOKEN": admin_token, "SESSION_COOKIE_SECURE": secure_cookies,
                      "INSTANCE_PATH": str(folder)})
    from study_app.context import study_of

    st = study_of(app)
    base = f"http://{host}:{port}"
    click.echo(f"study {st.id!r}, database {url}")
    click.echo(f"participant link: {base}/start/{st.id}" + (
        "?PROLIFIC_PID={{%PROLIFIC_PID%}}&STUDY_ID={{%STUDY_ID%}}&SESSION_ID={{%SESSION_ID%}}"
        if st.platform == "prolific" else ""))
    click.echo(f"admin: {base}/admin/")
    app.run(host=host, port=port, threaded=True, debug=False, use_reloader=False)


@study.command()
@click.argument("study_file", type=click.Path(exists=True, dir_okay=False))
@click.option("--db", default=None, help=DB_HELP)
@click.option("--instance", type=click.Path(file_okay=False), default=None,
              help="Folder of the default SQLite database.")
@click.option("-o", "--out", type=click.Path(dir_okay=False), default="results.csv",
              show_default=True, help="results.csv in the long format (docs/results_format.md).")
@click.option("--raw", type=click.Path(dir_okay=False), default=None,
              help="Also write everything stored (sessions, answers, events, plans) as JSON.")
@click.option("--pseudonymise", is_flag=True, help="Replace participant and platform ids by keyed hashes "
              "(HMAC-SHA256 with --key; the same key gives the same pseudonyms).")
@click.option("--key", envvar="EVALSUITE_SECRET_KEY", default=None,
              help="Secret of the pseudonyms (default: EVALSUITE_SECRET_KEY).")
@click.option("--include-pilot", is_flag=True, help="Keep pilot sessions (left out by default).")
@click.option("--include-excluded", is_flag=True, help="Keep excluded sessions (left out by default).")
def export(study_file, db, instance, out, raw, pseudonymise, key, include_pilot, include_excluded):
    """Export the answers of STUDY_FILE to results.csv (and raw JSON), without pilot and excluded sessions."""
    from study_app.definition import load_study
    from study_app.embodiment import describe_embodiment
    from study_app.export import raw_json_chunks, result_rows, results_csv
    from study_app.operations import export_dump, pseudonym_key
    from study_app.storage import Base, Store, make_engine

    if pseudonymise and not key:
        raise click.ClickException("--pseudonymise needs --key or EVALSUITE_SECRET_KEY")
    st = load_study(study_file)
    store = Store(make_engine(_db_url(study_file, instance, db)))
    Base.metadata.create_all(store.engine)
    dump = export_dump(store, st, include_pilot=include_pilot, include_excluded=include_excluded,
                       pseudonym_key=pseudonym_key(key) if pseudonymise else None)
    pathlib.Path(out).write_text(results_csv(st, dump))
    click.echo(f"{len(result_rows(st, dump))} judgements from {len(dump['sessions'])} sessions -> {out}")
    click.echo(f"stimuli: {describe_embodiment(st.manifest.embodiment)}")
    if raw:
        with open(raw, "w", encoding="utf-8") as fh:
            fh.writelines(raw_json_chunks(st, dump))
        click.echo(f"raw JSON -> {raw}")


for _command in COMMANDS:
    study.add_command(_command)


@study.command("admin-token")
def admin_token():
    """Print a fresh random admin token (pass it to `serve --admin-token`)."""
    click.echo(secrets.token_urlsafe(24))


DESIGNS = ("pairwise", "mushra", "likert")


@study.command()
@click.argument("study_file", required=False, type=click.Path(exists=True, dir_okay=False))
@click.option("--design", type=click.Choice(DESIGNS), default=None,
              help="Without STUDY_FILE: the test to plan (pairwise: exact binomial; mushra: Wilcoxon signed-rank; "
                   "likert: paired t-test, both by simulation).")
@click.option("--comparisons", type=click.IntRange(1, 10_000), default=1, show_default=True,
              help="Without STUDY_FILE: comparisons in the Holm family (planned at alpha / comparisons).")
@click.option("--preference", type=click.FloatRange(0, 1), default=0.65, show_default=True,
              help="Pairwise: the share of (non-tie) judgements expected for the better condition.")
@click.option("--ties", type=click.FloatRange(0, 0.95), default=0.0, show_default=True,
              help="Pairwise: the share of tie answers expected (left out of the test, so more judgements).")
@click.option("--difference", type=click.FloatRange(0, 100, min_open=True), default=10.0, show_default=True,
              help="MUSHRA: expected difference of two conditions, in rating points (0-100 scale).")
@click.option("--sd", type=click.FloatRange(0, 100, min_open=True), default=20.0, show_default=True,
              help="MUSHRA: standard deviation of one rating, in rating points.")
@click.option("--likert-difference", type=click.FloatRange(0, 10, min_open=True), default=0.5, show_default=True,
              help="Likert: expected difference of two conditions, in scale points.")
@click.option("--likert-sd", type=click.FloatRange(0, 10, min_open=True), default=1.0, show_default=True,
              help="Likert: standard deviation of one answer (and of a participant's offset), in scale points.")
@click.option("--points", type=click.IntRange(2, 11), default=7, show_default=True,
              help="Without STUDY_FILE, likert: points of the scale.")
@click.option("--statements", type=click.IntRange(1, 50), default=1, show_default=True,
              help="Without STUDY_FILE, likert: statements averaged into the scale score.")
@click.option("--alpha", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.05,
              show_default=True, help="Significance level of the study (before Holm).")
@click.option("--power", "target", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.8,
              show_default=True, help="Power to reach for each comparison.")
@click.option("--exclusion-rate", type=click.FloatRange(0, 0.95), default=0.0, show_default=True,
              help="With STUDY_FILE: share of sessions expected to be excluded (more participants).")
@click.option("--sims", type=click.IntRange(100, 100_000), default=1000, show_default=True,
              help="Simulated studies per sample size (MUSHRA, Likert).")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the simulations.")
def power(study_file, design, comparisons, preference, ties, difference, sd, likert_difference, likert_sd,
          points, statements, alpha, target, exclusion_rate, sims, seed):
    """How many judgements or participants reach a stated power for a stated effect.

    With STUDY_FILE: per rating block of the definition, the comparisons and Holm family, judgements per
    comparison needed, what one session gives (from its plans), participants needed and the power of the
    definition's `sessions`; the last line is the number of participants. Without it, for one --design: the
    last line is the number of judgements (pairwise), pages (mushra) or participants (likert) per comparison.

    \b
    evalsuite study power --design pairwise --preference 0.65 --comparisons 10 --alpha 0.05 --power 0.8
    evalsuite study power study.yaml --preference 0.65 --difference 8 --exclusion-rate 0.1
    """
    from evalsuite.analysis import power as pw
    from study_app.planning import Effects

    effects = Effects(preference=preference, ties=ties, difference=difference, sd=sd,
                      likert_difference=likert_difference, likert_sd=likert_sd, alpha=alpha, power=target,
                      exclusion_rate=exclusion_rate, sims=sims, seed=seed)
    try:
        if study_file:
            if design:
                raise click.UsageError("--design is for planning without a study definition; the definition "
                                       "says its designs")
            _power_of_study(study_file, effects)
            return
        if not design:
            raise click.UsageError("give a STUDY_FILE, or --design pairwise|mushra|likert")
        level = alpha / comparisons
        click.echo(f"{design}: {comparisons} comparison(s), planned at Holm's strictest step alpha/K = {level:.4g}, "
                   f"power {target:g}")
        if design == "pairwise":
            n, achieved = pw.pairwise_judgements(preference, alpha=alpha, power=target, comparisons=comparisons)
            needed = math.ceil(n / (1 - ties))
            click.echo(f"exact two-sided binomial test, preference {preference:g}: {n} judgements without ties "
                       f"(power {achieved:.3f})" + (f", {needed} with {ties:g} ties" if ties else ""))
            click.echo("judgements per comparison:")
        elif design == "mushra":
            needed, achieved = pw.smallest_n(lambda m: pw.mushra_power(m, difference, sd, level, sims=sims, seed=seed),
                                             target)
            click.echo(f"Wilcoxon signed-rank, difference {difference:g} points, SD {sd:g}: simulated power "
                       f"{achieved:.3f} ({sims} studies, seed {seed})")
            click.echo("pages rating both conditions, per comparison:")
        else:
            needed, achieved = pw.smallest_n(lambda m: pw.likert_power(
                m, likert_difference, likert_sd, level, points=points, statements=statements, sims=sims, seed=seed),
                target)
            click.echo(f"paired t-test, difference {likert_difference:g} of {points} points, SD {likert_sd:g}, "
                       f"{statements} statement(s): simulated power {achieved:.3f} ({sims} studies, seed {seed})")
            click.echo("participants rating both conditions, per comparison:")
        click.echo(str(needed))
    except ValueError as exc:
        raise click.ClickException(str(exc)) from None


def _power_of_study(study_file, effects) -> None:
    from study_app.definition import load_study
    from study_app.design import build_plans
    from study_app.planning import study_power

    st = load_study(study_file)
    rows = study_power(st, build_plans(st), effects)
    if not rows:
        raise click.ClickException("the study has no pairwise, mushra or likert block to plan")
    click.echo(f"study {st.id!r}: alpha {effects.alpha:g}, power {effects.power:g}, {st.sessions} planned sessions"
               + (f", {effects.exclusion_rate:g} expected to be excluded" if effects.exclusion_rate else ""))
    for r in rows:
        per = r["per_session"] * (1 - effects.exclusion_rate)
        click.echo(f"  {r['block']} ({r['design']}, {r['effect']}): {len(r['pairs'])} comparison(s) x "
                   f"{len(r['questions'])} {'scale' if r['design'] == 'likert' else 'question'}(s), family of "
                   f"{r['family']}, level {r['level']:.4g}; needs {r['needed']} {r['unit']} per comparison, a "
                   f"session gives {per:.3g} -> "
                   + (f"{r['participants']} participants" if r["participants"] else "no session shows one")
                   + f"; the planned sessions give {r['planned']:.0f} (power {r['achieved']:.2f})")
    need = [r["participants"] for r in rows if r["participants"]]
    if len(need) < len(rows):
        raise click.ClickException("a comparison of the study is never shown (see above); fix the design first")
    click.echo("participants needed (largest over the blocks):")
    click.echo(str(max(need)))


@study.command()
@click.argument("study_file", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--out", type=click.Path(dir_okay=False), default=None,
              help="Markdown file to write (default: <study id>.prereg.md beside the definition).")
@click.option("--preset", type=click.Choice(["leaderboard", "mushra-itu"]), default=None,
              help="The `evalsuite analyze --preset` the analysis will use (its settings go into the analysis plan).")
@click.option("--preference", type=click.FloatRange(0, 1), default=0.65, show_default=True,
              help="Pairwise effect for the sample-size rationale (see `study power`).")
@click.option("--difference", type=click.FloatRange(0, 100, min_open=True), default=10.0, show_default=True,
              help="MUSHRA effect in rating points for the sample-size rationale.")
@click.option("--exclusion-rate", type=click.FloatRange(0, 0.95), default=0.0, show_default=True,
              help="Share of sessions expected to be excluded, for the sample size.")
@click.option("--alpha", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.05,
              show_default=True, help="Significance level of the analysis.")
@click.option("--power", "target", type=click.FloatRange(0, 1, min_open=True, max_open=True), default=0.8,
              show_default=True, help="Power the sample size is planned for.")
def prereg(study_file, out, preset, preference, difference, exclusion_rate, alpha, target):
    """Write a pre-registration draft of STUDY_FILE (OSF Preregistration items, Markdown).

    Design, randomisation, sample size and stopping rule, variables, exclusion criteria and the analysis plan
    come from the definition, its plans, `study power` and `evalsuite analyze`'s settings; hypotheses, authors
    and what else only the researcher knows are marked TO COMPLETE.
    """
    from evalsuite.analysis.pipeline import AnalysisOptions
    from evalsuite.analysis.presets import preset_values
    from study_app.definition import load_study
    from study_app.design import build_plans
    from study_app.planning import Effects
    from study_app.prereg import prereg_markdown

    st = load_study(study_file)
    options = AnalysisOptions(alpha=alpha, preset=preset, **preset_values(preset))
    effects = Effects(preference=preference, difference=difference, exclusion_rate=exclusion_rate, alpha=alpha,
                      power=target)
    text = prereg_markdown(st, build_plans(st), options, effects)
    path = pathlib.Path(out) if out else st.path.with_name(f"{st.id}.prereg.md")
    path.write_text(text, encoding="utf-8")
    click.echo(f"pre-registration draft ({text.count('TO COMPLETE')} items to complete) -> {path}")
