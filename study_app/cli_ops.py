"""``evalsuite study release|topup|exclude|pilot|forget|prune-links|review-export|prolific-review|status``: the
operations on a running study (:mod:`study_app.operations`), from the command line, on the study's database
(and, with signed video URLs, the server's links folder: ``EVALSUITE_MEDIA_LINKS``)."""
from __future__ import annotations

import os
import pathlib

import click

__all__ = ["COMMANDS"]

DB_HELP = ("Database URL (SQLAlchemy): sqlite:///path.db or postgresql+psycopg://user@host/db. "
           "Default: SQLite study.db in the instance folder.")


def _study_store(study_file, instance, db):
    from study_app.definition import load_study
    from study_app.storage import Base, Store, make_engine

    folder = pathlib.Path(instance) if instance else pathlib.Path(study_file).resolve().parent / "instance"
    url = db or f"sqlite:///{folder / 'study.db'}"
    if not db and not (folder / "study.db").is_file():
        raise click.ClickException(f"no database at {folder / 'study.db'}; give --db or --instance")
    engine = make_engine(url)
    Base.metadata.create_all(engine)        # tables added since the study started (marks, flags)
    return load_study(study_file), Store(engine)


def _db_options(f):
    f = click.option("--instance", type=click.Path(file_okay=False), default=None,
                     help="Folder of the default SQLite database.")(f)
    f = click.option("--db", default=None, help=DB_HELP)(f)
    return click.argument("study_file", type=click.Path(exists=True, dir_okay=False))(f)


def _links_options(f):
    f = click.option("--secret-key", envvar="EVALSUITE_SECRET_KEY", default=None,
                     help="The server's SECRET_KEY, which names the links (env EVALSUITE_SECRET_KEY).")(f)
    return click.option("--links", "links_dir", envvar="EVALSUITE_MEDIA_LINKS", default=None,
                        type=click.Path(file_okay=False),
                        help="The server's folder of signed-URL links (env EVALSUITE_MEDIA_LINKS, set with "
                             "EVALSUITE_MEDIA_SERVER=nginx-signed); the session's links are removed too.")(f)


def _links(st, links_dir, secret_key):
    """The server's links (study_app.media_signed.Links), or None without a links folder."""
    from study_app.media_signed import links_of
    if not links_dir:
        return None
    if not secret_key:
        raise click.ClickException("--links needs --secret-key or EVALSUITE_SECRET_KEY (the server's, which "
                                   "names the links)")
    return links_of({"MEDIA_SERVER": "nginx-signed", "MEDIA_LINKS": links_dir, "SECRET_KEY": secret_key}, st)


def _run(fn, *args, **kwargs):
    from study_app.errors import StudyStateError
    try:
        return fn(*args, **kwargs)
    except StudyStateError as exc:
        raise click.ClickException(str(exc)) from None


@click.command()
@_db_options
@click.argument("plan")
@_links_options
def release(study_file, db, instance, plan, links_dir, secret_key):
    """Hand the reserved PLAN (e.g. plan-0003) out again now; its session ends as expired."""
    from study_app.operations import release_plan
    st, store = _study_store(study_file, instance, db)
    sid = _run(release_plan, store, st, plan, links=_links(st, links_dir, secret_key))
    click.echo(f"plan {plan} released (session {sid or 'none'})")


@click.command()
@_db_options
@click.argument("n", type=click.IntRange(1, 5000))
def topup(study_file, db, instance, n):
    """Add N plans to the running study without rebuilding (a new balanced batch, handed out last)."""
    from study_app.operations import topup as add
    st, store = _study_store(study_file, instance, db)
    keys = _run(add, store, st, n)
    click.echo(f"{len(keys)} plans added: {keys[0]} .. {keys[-1]}")


@click.command()
@_db_options
@click.argument("session")
@click.option("--reason", default="", help="Why the session is excluded (required unless --undo).")
@click.option("--undo", is_flag=True, help="Take an exclusion back.")
@_links_options
def exclude(study_file, db, instance, session, reason, undo, links_dir, secret_key):
    """Exclude SESSION (a session or participant id) from the export, with --reason."""
    from study_app.operations import exclude as mark
    st, store = _study_store(study_file, instance, db)
    sid = _run(mark, store, st, session, reason, undo=undo, links=_links(st, links_dir, secret_key))
    click.echo(f"session {sid} {'included again' if undo else 'excluded'}")


@click.command()
@_db_options
@click.argument("state", type=click.Choice(["on", "off", "status"]))
def pilot(study_file, db, instance, state):
    """Pilot mode on|off (new sessions are pilot sessions, kept out of exports by default) or its status."""
    from study_app.operations import pilot_mode, set_pilot
    st, store = _study_store(study_file, instance, db)
    if state != "status":
        set_pilot(store, st, state == "on")
    click.echo(f"pilot mode {'on' if pilot_mode(store, st) else 'off'}")


@click.command()
@_db_options
@click.argument("participant")
@click.option("--yes", is_flag=True, help="Do not ask for confirmation.")
@_links_options
def forget(study_file, db, instance, participant, yes, links_dir, secret_key):
    """Delete every row stored about PARTICIPANT (participant or session id), a GDPR erasure request, and
    the links of their signed video URLs."""
    from study_app.operations import forget as erase
    st, store = _study_store(study_file, instance, db)
    links = _links(st, links_dir, secret_key)
    if not yes:
        click.confirm(f"delete everything stored about {participant}? This cannot be undone", abort=True)
    n = _run(erase, store, st, participant, links=links)
    click.echo(f"{participant}: {n} rows deleted")


@click.command("prune-links")
@_db_options
@_links_options
def prune_links(study_file, db, instance, links_dir, secret_key):
    """Remove the signed-URL links (EVALSUITE_MEDIA_SERVER=nginx-signed) of every session that is no longer
    active: finished, failed, expired (reservations that ran out are expired now) or excluded. Active
    sessions keep theirs; the stimulus files are never touched. Safe to run at any time, e.g. hourly."""
    from study_app.operations import prune_links as prune
    st, store = _study_store(study_file, instance, db)
    links = _links(st, links_dir, secret_key)
    if links is None:
        raise click.ClickException("give the links folder: --links or EVALSUITE_MEDIA_LINKS")
    click.echo(f"{prune(store, st, links)} links of ended sessions removed from {links.folder}")


@click.command("review-export")
@_db_options
@click.option("-o", "--out", type=click.Path(dir_okay=False), default="review.csv", show_default=True,
              help="CSV: participant_id, submission_id, outcome, code, action, reason.")
@click.option("--include-pilot", is_flag=True, help="Keep pilot sessions.")
def review_export(study_file, db, instance, out, include_pilot):
    """Each ended submission's outcome and the review action for it (Prolific's bulk approve/reject)."""
    from study_app.operations import export_dump, review_csv, review_rows
    st, store = _study_store(study_file, instance, db)
    dump = export_dump(store, st, include_pilot=include_pilot, include_excluded=True)
    pathlib.Path(out).write_text(review_csv(st, dump))
    click.echo(f"{len(review_rows(st, dump))} submissions -> {out}")


@click.command("prolific-review")
@_db_options
@click.option("--token", default=None, help="Prolific API token (default: EVALSUITE_PROLIFIC_TOKEN).")
@click.option("--base-url", default=None, help="Prolific API address (default: Prolific's own).")
@click.option("--apply", "apply_", is_flag=True, help="Send the calls; without it, only print them.")
def prolific_review(study_file, db, instance, token, base_url, apply_):
    """Carry out the review export on Prolific: request returns and rejections per outcome (approvals
    happen by the completed code's action; MANUALLY_REVIEW rows are listed for you)."""
    from study_app.operations import export_dump, review_rows
    from study_app.prolific_api import DEFAULT_BASE_URL, ProlificClient, ProlificError
    st, store = _study_store(study_file, instance, db)
    rows = review_rows(st, export_dump(store, st, include_excluded=True))
    client = ProlificClient(token or os.environ.get("EVALSUITE_PROLIFIC_TOKEN", ""), base_url or DEFAULT_BASE_URL) \
        if apply_ else None
    for r in rows:
        what = {"REQUEST_RETURN": "request return", "REJECT": "reject", "AUTOMATICALLY_APPROVE": "approve",
                "MANUALLY_REVIEW": "review by hand"}[r["action"]]
        click.echo(f"{r['submission_id']}\t{r['participant_id']}\t{r['outcome']}\t{what}\t{r['reason']}")
        if client is None or not r["submission_id"]:
            continue
        try:
            if r["action"] == "REQUEST_RETURN":
                client.request_return(r["submission_id"], [r["reason"]])
            elif r["action"] == "REJECT":
                client.reject(r["submission_id"], f"Your submission was rejected because you {r['reason']}. "
                              "The study asked for this in its instructions; please contact us if you think this "
                              "is a mistake.", "FAILED_CHECK")
        except ProlificError as exc:
            raise click.ClickException(str(exc)) from None


@click.command()
@_db_options
def status(study_file, db, instance):
    """Sessions by status and, for each adaptive pairwise block, its votes, estimated order and whether the
    ranking has separated (the study may stop; study_app.adaptive)."""
    from study_app.adaptive import adaptive_status
    from study_app.monitor import answer_count, status_counts
    st, store = _study_store(study_file, instance, db)
    counts = status_counts(store, st)
    click.echo(f"sessions: {sum(counts.values())} started, " + ", ".join(
        f"{counts.get(k, 0)} {k}" for k in ("active", "finished", "failed", "expired")) +
        f"; {answer_count(store, st)} answers")
    for a in adaptive_status(store, st):
        order = " > ".join(f"{c} ({e})" for c, e in zip(a["order"], a["elo"]))
        verdict = ("ranking separated: the study may stop" if a["done"] else
                   f"{a['separated']} of {a['neighbours']} neighbouring pairs separated: not separated yet")
        click.echo(f"{a['block']}: {a['votes']} votes; {order}; {verdict}")


COMMANDS = [release, topup, exclude, pilot, forget, prune_links, review_export, prolific_review, status]
