"""Admin blueprint: progress, attention-check failures, reservations and exports.

Access with the admin token given at start-up: either the login form (stores a flag in
the signed session cookie) or an ``Authorization: Bearer <token>`` header (scripts).
There is no default credential.
"""
from __future__ import annotations

from collections import Counter
from functools import wraps

from flask import (Blueprint, Response, abort, current_app, redirect, render_template, request,
                   session, url_for)

from study_app.app import check_token
from study_app.export import raw_json, result_rows, results_csv
from study_app.storage import utcnow

bp = Blueprint("admin", __name__)


def _authorised() -> bool:
    token = current_app.config["ADMIN_TOKEN"]
    header = request.headers.get("Authorization", "")
    if header.startswith("Bearer "):
        return check_token(header[7:].strip(), token)
    return session.get("admin") is True


def admin_required(view):
    @wraps(view)
    def wrapped(*args, **kwargs):
        if not _authorised():
            if request.headers.get("Authorization") or request.path.startswith("/admin/export"):
                abort(403)
            return redirect(url_for("admin.login"))
        return view(*args, **kwargs)
    return wrapped


@bp.route("/login", methods=["GET", "POST"])
def login():
    error = ""
    if request.method == "POST":
        given = request.form.get("token", "")
        if isinstance(given, str) and check_token(given, current_app.config["ADMIN_TOKEN"]):
            session.clear()
            session["admin"] = True
            return redirect(url_for("admin.overview"))
        error = "Wrong token."
    return render_template("admin_login.html", error=error), (403 if error else 200)


@bp.route("/logout", methods=["POST"])
def logout():
    session.pop("admin", None)
    return redirect(url_for("admin.login"))


@bp.route("/")
@admin_required
def overview():
    study, store = current_app.extensions["study"], current_app.extensions["store"]
    dump = store.dump(study.id)
    now = utcnow()
    statuses = Counter(s.status for s in dump["sessions"])
    rows = result_rows(study, dump)
    comparisons = Counter()
    for r in rows:
        if r["is_training"] or r["is_attention_check"]:
            continue
        if r["page_type"] == "pairwise":
            comparisons[(r["question"], f"{r['condition_a']} vs {r['condition_b']}")] += 1
        else:
            comparisons[(r["question"], r["condition"])] += 1
    failures = [s for s in dump["sessions"] if s.failed_checks or s.status == "failed"]
    plans = sorted(dump["plans"].values(), key=lambda p: p.position)
    plan_counts = Counter(p.status if not (p.status == "reserved" and p.reserved_until < now)
                          else "reserved (expired)" for p in plans)
    return render_template("admin.html", study=study, statuses=statuses, comparisons=sorted(comparisons.items()),
                           failures=failures, plans=plans, plan_counts=plan_counts,
                           n_answers=len(dump["answers"]), now=now)


@bp.route("/export/results.csv")
@admin_required
def export_csv():
    study, store = current_app.extensions["study"], current_app.extensions["store"]
    return Response(results_csv(study, store.dump(study.id)), mimetype="text/csv",
                    headers={"Content-Disposition": f'attachment; filename="{study.id}-results.csv"'})


@bp.route("/export/raw.json")
@admin_required
def export_json():
    study, store = current_app.extensions["study"], current_app.extensions["store"]
    return Response(raw_json(study, store.dump(study.id)), mimetype="application/json",
                    headers={"Content-Disposition": f'attachment; filename="{study.id}-raw.json"'})

