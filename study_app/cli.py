"""``evalsuite study``: build session plans, serve a study, export its results."""
from __future__ import annotations

import os
import pathlib
import secrets

import click

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
    """Validate STUDY_FILE and write its balanced session plans."""
    from study_app.definition import load_study
    from study_app.design import balance_report, build_plans, default_plans_path, position_spread, write_plans

    st = load_study(study_file)
    plans = build_plans(st)
    path = write_plans(plans, out or default_plans_path(st))
    click.echo(f"{len(plans['plans'])} session plans for study {st.id!r} -> {path}")
    report = balance_report(plans, st)
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
               for block, d in sorted(position_spread(report[key]).items())]
    if spreads:
        click.echo("orders, largest distance of a count from equal (0: exact, up to 1: equal within one): "
                   + ", ".join(f"{what} {block} {d:.2g}" for what, block, d in spreads))
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
@click.option("--host", default="127.0.0.1", show_default=True)
@click.option("--port", default=5000, show_default=True, type=int)
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
def export(study_file, db, instance, out, raw):
    """Export the answers of STUDY_FILE to results.csv (and raw JSON)."""
    from study_app.definition import load_study
    from study_app.export import raw_json_chunks, result_rows, results_csv
    from study_app.storage import Store, make_engine

    st = load_study(study_file)
    store = Store(make_engine(_db_url(study_file, instance, db)))
    dump = store.dump(st.id)
    pathlib.Path(out).write_text(results_csv(st, dump))
    click.echo(f"{len(result_rows(st, dump))} judgements from {len(dump['sessions'])} sessions -> {out}")
    if raw:
        with open(raw, "w", encoding="utf-8") as fh:
            fh.writelines(raw_json_chunks(st, dump))
        click.echo(f"raw JSON -> {raw}")


@study.command("admin-token")
def admin_token():
    """Print a fresh random admin token (pass it to `serve --admin-token`)."""
    click.echo(secrets.token_urlsafe(24))
