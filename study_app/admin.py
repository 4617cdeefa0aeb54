"""Admin blueprint: progress, attention-check failures, reservations and exports.

Access with the admin token given at start-up: either the login form (stores a flag in
the signed session cookie) or an ``Authorization: Bearer <token>`` header (scripts).
There is no default credential.
"""
from __future__ import annotations

from collections import Counter

from flask import (
    Blueprint,
    Response,
    current_app,
    flash,
    get_flashed_messages,
    jsonify,
    redirect,
    render_template,
    request,
    session,
    url_for,
)

from study_app.adaptive import adaptive_status
from study_app.context import get_store, get_study
from study_app.embodiment import describe_embodiment
from study_app.errors import StudyStateError
from study_app.export import raw_json_chunks, result_rows, results_csv
from study_app.media_signed import links_of
from study_app.monitor import answer_count, participant_rows, plan_counts, status_counts, unplayable_reports
from study_app.operations import (
    exclude,
    export_dump,
    forget,
    pilot_mode,
    pseudonym_key,
    release_plan,
    review_csv,
    set_pilot,
    topup,
)
from study_app.pages import get_kind
from study_app.security import (
    address_group,
    admin_logins,
    admin_required,
    check_token,
    end_admin_session,
    start_admin_session,
)
from study_app.storage import utcnow

bp = Blueprint("admin", __name__)


@bp.route("/login", methods=["GET", "POST"])
def login():
    error = ""
    if request.method == "POST":
        address, logins = address_group(request.remote_addr), admin_logins()
        wait = logins.retry_after(address)
        if wait:
            resp = Response(render_template("admin_login.html", error="Too many wrong tokens from this address; "
                                            f"try again in {wait} s."), status=429)
            resp.headers["Retry-After"] = str(wait)
            return resp
        given = request.form.get("token", "")
        if isinstance(given, str) and check_token(given, current_app.config["ADMIN_TOKEN"]):
            logins.succeeded(address)
            session.clear()
            start_admin_session()
            return redirect(url_for("admin.overview"))
        logins.failed(address)
        error = "Wrong token."
    return render_template("admin_login.html", error=error), (403 if error else 200)


@bp.route("/logout", methods=["POST"])
def logout():
    end_admin_session()
    return redirect(url_for("admin.login"))


@bp.route("/")
@admin_required
def overview():
    study, store = get_study(), get_store()
    dump = store.dump(study.id)
    now = utcnow()
    statuses = Counter(s.status for s in dump["sessions"])
    rows = result_rows(study, dump)
    comparisons = Counter()
    for r in rows:
        if r["is_training"] or r["is_attention_check"]:
            continue
        comparisons[(r["question"], get_kind(r["page_type"]).comparison_label(r))] += 1
    failures = [s for s in dump["sessions"] if s.failed_checks or s.status == "failed"]
    plans = sorted(dump["plans"].values(), key=lambda p: p.position)
    plan_counts = Counter(p.status if not (p.status == "reserved" and p.reserved_until < now)
                          else "reserved (expired)" for p in plans)
    return render_template("admin.html", study=study, statuses=statuses, comparisons=sorted(comparisons.items()),
                           failures=failures, plans=plans, plan_counts=plan_counts,
                           n_answers=len(dump["answers"]), now=now,
                           participants=participant_rows(store, study, now),
                           reports=unplayable_reports(store, study), refresh_seconds=_refresh_seconds(),
                           pilot=pilot_mode(store, study), messages=get_flashed_messages(with_categories=True),
                           adaptive=adaptive_status(store, study),
                           embodiment=describe_embodiment(study.manifest.embodiment))


def _refresh_seconds() -> int:
    """How often the admin page polls status.json (``ADMIN_REFRESH_SECONDS``, default 15)."""
    return int(current_app.config.get("ADMIN_REFRESH_SECONDS", 15))


@bp.route("/status.json")
@admin_required
def status_json():
    """What the admin page refreshes by itself: session counts, the participant table and the
    "does not play" reports (admin token: the login cookie or ``Authorization: Bearer``)."""
    study, store = get_study(), get_store()
    now = utcnow()
    statuses = status_counts(store, study)
    return jsonify(study=study.id, generated_at=now.isoformat(timespec="seconds") + "Z",
                   refresh_seconds=_refresh_seconds(),
                   sessions={"started": sum(statuses.values()), **{k: statuses.get(k, 0) for k in
                                                                    ("active", "finished", "failed", "expired")}},
                   answers=answer_count(store, study), plans=plan_counts(store, study, now),
                   participants=participant_rows(store, study, now), reports=unplayable_reports(store, study),
                   adaptive=adaptive_status(store, study))


def _export_dump():
    """The dump for an export: ``?pilot=1`` and ``?excluded=1`` keep pilot and excluded sessions,
    ``?pseudonymise=1`` replaces participant ids by keyed hashes (:mod:`study_app.operations`)."""
    study, store = get_study(), get_store()
    key = pseudonym_key(current_app.config["SECRET_KEY"]) if request.args.get("pseudonymise") == "1" else None
    return study, export_dump(store, study, include_pilot=request.args.get("pilot") == "1",
                              include_excluded=request.args.get("excluded") == "1", pseudonym_key=key)


@bp.route("/export/results.csv")
@admin_required
def export_csv():
    study, dump = _export_dump()
    return Response(results_csv(study, dump), mimetype="text/csv",
                    headers={"Content-Disposition": f'attachment; filename="{study.id}-results.csv"'})


@bp.route("/export/raw.json")
@admin_required
def export_json():
    study, dump = _export_dump()
    # streamed: the interaction log is read from the database in batches while the response is sent
    return Response(raw_json_chunks(study, dump), mimetype="application/json",
                    headers={"Content-Disposition": f'attachment; filename="{study.id}-raw.json"'})


@bp.route("/export/review.csv")
@admin_required
def export_review():
    """Each ended submission's outcome, code, action and reason, for Prolific's bulk approve/reject."""
    study, dump = _export_dump()
    return Response(review_csv(study, dump), mimetype="text/csv",
                    headers={"Content-Disposition": f'attachment; filename="{study.id}-review.csv"'})


@bp.route("/op/<name>", methods=["POST"])
@admin_required
def operation(name):
    """The operations of the admin page's forms: release, topup, exclude, include, forget, pilot."""
    study, store, form = get_study(), get_store(), request.form
    links = links_of(current_app.config, study)         # signed-URL links go with the session's end
    try:
        if name == "release":
            release_plan(store, study, form.get("plan", ""), links=links)
            flash(f"plan {form.get('plan')} released", "ok")
        elif name == "topup":
            n = form.get("n", "")
            keys = topup(store, study, int(n) if n.isdigit() else 0)
            flash(f"{len(keys)} plans added", "ok")
        elif name in ("exclude", "include"):
            exclude(store, study, form.get("session", ""), form.get("reason", ""), undo=name == "include", links=links)
            flash(f"session {form.get('session')} {name}d", "ok")
        elif name == "forget":
            if form.get("confirm") != form.get("participant"):
                raise StudyStateError("type the participant id a second time to confirm", field="confirm")
            n = forget(store, study, form.get("participant", ""), links=links)
            flash(f"participant forgotten: {n} rows deleted", "ok")
        elif name == "pilot":
            set_pilot(store, study, form.get("on") == "1")
            flash(f"pilot mode {'on' if form.get('on') == '1' else 'off'}", "ok")
        else:
            return Response("unknown operation", status=404)
    except StudyStateError as exc:
        flash(str(exc), "error")
    return redirect(url_for("admin.overview"))
