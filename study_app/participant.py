"""Participant blueprint: entry from a crowd platform, pages, answers, autosave, events.

A participant's browser holds the ids of its own sessions in the signed session cookie;
every ``/s/<sid>/...`` request for a session not in that list is refused (403). Page HTML
and JSON carry slot numbers and labels only: conditions and file names stay on the server.
"""
from __future__ import annotations

import hashlib
import hmac
import re
import secrets
import urllib.parse
from functools import partial

from flask import Blueprint, abort, current_app, jsonify, redirect, render_template, request, session, url_for

from study_app.adaptive import assign_pair
from study_app.answers import n_slots, parse_events
from study_app.context import get_store, get_study
from study_app.media_signed import drop_session_links, video_urls
from study_app.operations import decline_without_plan, mark_if_pilot
from study_app.outcomes import code_for
from study_app.pages import get_kind
from study_app.payload import PayloadError, parse_json_object
from study_app.security import address_group
from study_app.storage import SubmitStatus
from study_app.submission import parse_answer_body, validate_submission

bp = Blueprint("participant", __name__)

PARAM_RE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")
# Platform ids (docs/study_app.md, section 5): Prolific participant and study ids are 24 hexadecimal
# characters (MongoDB object ids); MTurk worker ids are "A" and upper-case letters or digits, assignment and
# HIT ids upper-case letters or digits (the MTurk API's patterns, at most 64 characters).
PLATFORM_ID_RE = {
    ("prolific", "PROLIFIC_PID"): re.compile(r"^[0-9a-fA-F]{24}$"),
    ("prolific", "STUDY_ID"): re.compile(r"^[0-9a-fA-F]{24}$"),
    ("prolific", "SESSION_ID"): PARAM_RE,
    ("mturk", "workerId"): re.compile(r"^A[A-Z0-9]{1,63}$"),
    ("mturk", "assignmentId"): re.compile(r"^[A-Z0-9]{1,64}$"),
    ("mturk", "hitId"): re.compile(r"^[A-Z0-9]{1,64}$"),
}
MOBILE_RE = re.compile(r"Mobi|Android|iPhone|iPad|iPod|Tablet|Silk|Kindle", re.I)
MTURK_PREVIEW = "ASSIGNMENT_ID_NOT_AVAILABLE"
MTURK_SUBMIT_HOSTS = ("www.mturk.com", "workersandbox.mturk.com")


_study, _store = get_study, get_store


def _message(title, message, code=200, **extra):
    return render_template("message.html", title=title, message=message, **extra), code


def _own(sid: str):
    """Refuse any session this browser did not start (or resume via its platform id)."""
    if not isinstance(sid, str) or sid not in session.get("sids", []):
        abort(403)


# The platform field that identifies one attempt (the same on every link of that attempt).
ATTEMPT_FIELD = {"prolific": "SESSION_ID", "mturk": "assignmentId"}


def _may_resume(sess, platform_data: dict) -> bool:
    """This browser holds the session, or brings the same platform attempt id."""
    if sess.id in session.get("sids", []):
        return True
    field = ATTEMPT_FIELD.get(sess.platform)
    if field is None:       # anonymous: the participant id came from this browser's own cookie
        return True
    return bool(platform_data.get(field)) and (sess.platform_data or {}).get(field) == platform_data.get(field)


def _remember(sid: str):
    sids = [s for s in session.get("sids", []) if s != sid][-9:]
    session["sids"] = sids + [sid]
    session.permanent = True


@bp.route("/")
def index():
    return _message(_study().title, "Please open this study with the link you were given.")


@bp.route("/start/<study_id>")
def start(study_id):
    study = _study()
    if study_id != study.id:
        abort(404)
    args = request.args
    ua = request.headers.get("User-Agent", "")
    if study.block_mobile and MOBILE_RE.search(ua):
        return _message("Please use a computer",
                        "This study needs a desktop or laptop computer with a large screen. "
                        "Please return to it from a computer.", 403)
    platform_data = {}
    if study.platform == "prolific":
        names = ("PROLIFIC_PID", "STUDY_ID", "SESSION_ID")
        values = {n: args.get(n, "") for n in names}
        bad = [n for n in names if not PLATFORM_ID_RE[study.platform, n].match(values[n])]
        if bad:
            return _message("Link incomplete", "Please open this study from Prolific (the link lacks "
                            f"a valid {bad[0]}).", 400)
        values["PROLIFIC_PID"], values["STUDY_ID"] = values["PROLIFIC_PID"].lower(), values["STUDY_ID"].lower()
        if study.prolific_study_id and values["STUDY_ID"] != study.prolific_study_id.lower():
            return _message("Wrong study", "This link belongs to another Prolific study.", 400)
        participant, platform_data = values["PROLIFIC_PID"], values
    elif study.platform == "mturk":
        assignment = args.get("assignmentId", "")
        if assignment == MTURK_PREVIEW:
            return render_template("preview.html", study=study)
        names = ("workerId", "assignmentId", "hitId")
        values = {n: args.get(n, "") for n in names}
        bad = [n for n in names if not PLATFORM_ID_RE[study.platform, n].match(values[n])]
        submit_to = args.get("turkSubmitTo", "")
        parsed = urllib.parse.urlparse(submit_to)
        if bad or parsed.scheme != "https" or parsed.hostname not in MTURK_SUBMIT_HOSTS:
            what = bad[0] if bad else "turkSubmitTo"
            return _message("Link incomplete", f"Please open this HIT from MTurk (invalid {what}).", 400)
        values["turkSubmitTo"] = f"https://{parsed.hostname}"
        participant, platform_data = values["workerId"], values
    else:
        participant = session.get(f"anon_{study.id}")
        if not participant:
            participant = "anon-" + secrets.token_hex(8)
            session[f"anon_{study.id}"] = participant
            session.permanent = True
    address = client_key()
    sess, state = _store().start_session(study, participant, study.platform, platform_data, ua, address)
    if state == "throttled":
        current_app.logger.warning("study %s: refused a new session for participant %s: address limit "
                                   "(%d new sessions in %g minutes) reached", study.id, participant,
                                   study.new_sessions_per_address, study.new_sessions_window_minutes)
        wait = _store().retry_after(study, address)
        page, code = _message("Too many new sessions", "Too many participants have started this study from "
                              "your network in a short time. Please try again later.", 429)
        return page, code, {"Retry-After": str(wait)}
    if sess is None:
        return _full()
    if state == "created":
        mark_if_pilot(_store(), study, sess.id)        # pilot mode: kept out of the export by default
    if state == "existing":
        if sess.status != "active" and _may_resume(sess, platform_data):
            # Re-opening the link after the end (same browser or same platform attempt): the outcome's
            # code and the return link again.
            _remember(sess.id)
            return _ended(sess)
        if sess.status == "finished":
            return _message("Already completed", "You have already completed this study. You can "
                            "take part only once.", 409)
        if sess.status == "failed":
            return _message("Cannot continue", "You cannot take part in this study anymore.", 409)
        if sess.status == "expired":
            return _message("Time expired", "Your place in this study has expired and the study "
                            "cannot be started again.", 409)
        if not study.resume and sess.plan_id is not None:      # (without a plan it has not started yet)
            return _message("Already started", "You have already started this study; it cannot be "
                            "started again.", 409)
        if not _may_resume(sess, platform_data):
            # A participant id alone never opens an existing session: the browser must hold it (its
            # cookie) or bring the same platform session (Prolific SESSION_ID, MTurk assignmentId).
            current_app.logger.warning("study %s: refused to resume session %s of participant %s from "
                                       "another browser without its platform session id", study.id, sess.id,
                                       participant)
            return _message("Already in progress", "This study is already in progress in another browser "
                            "or tab for this participant id. Please continue it there.", 409)
    _remember(sess.id)
    return redirect(url_for("participant.page", sid=sess.id))


@bp.route("/s/<sid>/")
def page(sid):
    _own(sid)
    study, store = _study(), _store()
    loaded = store.view_current_page(sid)
    if loaded is None:
        abort(404)
    sess, pages, view, played = loaded
    if sess.status != "active":
        return _ended(sess)
    if sess.plan_id is None and not store.has_free_plan(study.id):
        return _full()
    index = sess.current_page
    spec = assign_pair(store, study, sid, index, pages[index])     # an adaptive pairwise page: its pair now
    data = _page_data(study, spec, index, len(pages), sid)
    data.update(draft=view.draft or {}, played=sorted(s for s in played["play"] if s is not None),
                ended=sorted(s for s in played["ended"] if s is not None))
    kind = get_kind(spec["type"])
    return render_template("page.html", study=study, spec=spec, data=data, page=_page_cfg(study, spec),
                           index=index, total=len(pages), kind_template=kind.template_name,
                           kind_script=kind.script)


def _page_cfg(study, spec):
    return study.page(spec.get("block") or spec["page"]).cfg


def _page_data(study, spec, index, total, sid) -> dict:
    """What the browser needs for one page: never a condition or file name."""
    data = {"type": spec["type"], "index": index, "total": total,
            "answer_url": url_for("participant.answer", sid=sid, index=index),
            "draft_url": url_for("participant.draft", sid=sid, index=index),
            "events_url": url_for("participant.events", sid=sid, index=index),
            "require_full_playback": study.require_full_playback,
            "min_width": study.min_width}
    kind = get_kind(spec["type"])
    data["done_word"] = kind.done_word
    data["videos"] = video_urls(study, kind, spec, sid, index)
    data.update(kind.page_data(study, spec, _page_cfg(study, spec)))
    return data


def _full():
    return _message("Study full", "All places in this study are taken at the moment. Please "
                    "return the task and try again later.", 503)


def client_key() -> str:
    """A keyed hash of the client's address, an IPv6 address's /64 (the per-address limit stores no address)."""
    if "X-Forwarded-For" in request.headers and not current_app.config.get("TRUSTED_PROXIES_SET"):
        current_app.config["TRUSTED_PROXIES_SET"] = True      # warn once per process
        current_app.logger.warning("requests carry X-Forwarded-For but no proxy is trusted: every client "
                                   "shares the proxy's address for the per-address limit (set "
                                   "EVALSUITE_TRUSTED_PROXIES, docs/study_app.md section 9)")
    key = current_app.config["SECRET_KEY"].encode()
    group = address_group(request.remote_addr)       # IPv6: its /64
    return hmac.new(key, f"address|{group}".encode(), hashlib.sha256).hexdigest()[:32]


def _ended(sess):
    """The page of a session that has ended: its outcome's code (:mod:`study_app.outcomes`), the link back to
    Prolific with that code, or MTurk's submit form carrying it."""
    study = _study()
    oc = code_for(study, sess.status, sess.end_reason)
    code = oc.code if oc else ""
    link = study.completion_url(code) if study.platform == "prolific" and code else ""
    mturk = sess.platform_data if study.platform == "mturk" and code else None
    if sess.status == "finished":
        return render_template("finish.html", study=study, code=code, link=link, mturk=mturk,
                               text=study.pages[-1].cfg["text"], redirect_seconds=study.redirect_seconds)
    outcome = oc.outcome if oc else ""
    return render_template("failed.html", study=study, code=code, link=link, mturk=mturk, outcome=outcome,
                           reason=sess.end_reason), (410 if sess.status == "expired" else 200)


def _json_body() -> dict:
    return parse_json_object(request.get_data(cache=True))


@bp.route("/s/<sid>/answer/<int:index>", methods=["POST"])
def answer(sid, index):
    """Store the answer to page ``index`` (the body: :mod:`study_app.submission`)."""
    _own(sid)
    study, store = _study(), _store()
    try:
        body = parse_answer_body(_json_body())
    except PayloadError as exc:
        return jsonify(error=str(exc)), 422

    try:
        status, ans, sess = store.submit(sid, index, body.token, partial(validate_submission, study, index, body))
    except PayloadError as exc:
        return jsonify(error=str(exc)), 422
    if status is SubmitStatus.MISSING:
        return jsonify(error="this session does not exist (any more); open the study link again"), 404
    nxt = url_for("participant.page", sid=sid)
    if status is SubmitStatus.FULL and index == 0 and body.answer == {"agree": False}:
        # "I do not agree" while every plan is taken: the participant still leaves with the no-consent code
        decline_without_plan(store, sid)
        return jsonify(status="stored", next=nxt, session_status="failed")
    if status is SubmitStatus.FULL:
        return jsonify(error="All places in this study are taken at the moment. Please return the task and "
                       "try again later.", next=nxt), 409
    if status is SubmitStatus.AHEAD:
        return jsonify(error="this page is not open yet; answer the current page first", next=nxt), 409
    if status is SubmitStatus.CONFLICT:
        # another tab or window of this session answered the page first (or the session ended there): the
        # stored answer is kept; ``stale`` tells the page to warn and load the current page
        return jsonify(error="this page was already answered in another tab or window; the answer given "
                       "there is kept", next=nxt, stale=True, current_page=sess.current_page,
                       session_status=sess.status), 409
    if status is SubmitStatus.STORED and sess.status != "active":
        drop_session_links(sid)         # its signed video URLs stop working now (nginx: 404)
    extra = {}
    if ans is not None and ans.events_dropped:
        extra["events_dropped"] = ans.events_dropped
        extra["warning"] = _cap_message(_store().rules)
    return jsonify(status=status.value, next=nxt, session_status=sess.status, **extra)


def _cap_message(rules, which: str = "") -> str:
    what = {"page": f"of this page is full (at most {rules.events_per_page} events per page",
            "session": f"of this session is full (at most {rules.events_per_session} events per session"}.get(
        which, f"is full (at most {rules.events_per_page} events per page and {rules.events_per_session} per "
        "session")
    return f"the interaction log {what}, play/ended and the others each); further events are not recorded"


@bp.route("/s/<sid>/draft/<int:index>", methods=["POST"])
def draft(sid, index):
    _own(sid)
    try:
        body = _json_body()
        d = body.get("draft")
        if set(body) - {"draft"} or not isinstance(d, dict) or len(str(d)) > 20000:
            raise PayloadError("expected {\"draft\": {...}} of at most 20000 characters")
        _check_draft(d)
    except PayloadError as exc:
        return jsonify(error=str(exc)), 422
    ok = _store().save_draft(sid, index, d)
    return (jsonify(saved=True), 200) if ok else (jsonify(error="not the current page", stale=True,
                                                           next=url_for("participant.page", sid=sid)), 409)


def _check_draft(d, depth=0):
    """Drafts are plain JSON of limited depth: strings, numbers, booleans, lists, objects."""
    if depth > 4:
        raise PayloadError("draft too deeply nested")
    items = d.items() if isinstance(d, dict) else enumerate(d) if isinstance(d, list) else ()
    for k, v in items:
        if isinstance(k, str) and len(k) > 64:
            raise PayloadError("draft key too long")
        if isinstance(v, (dict, list)):
            _check_draft(v, depth + 1)
        elif not (v is None or isinstance(v, (str, int, float, bool))) or (isinstance(v, str) and len(v) > 2000):
            raise PayloadError("draft values must be short strings, numbers or booleans")


@bp.route("/s/<sid>/events/<int:index>", methods=["POST"])
def events(sid, index):
    _own(sid)
    store = _store()
    sess, pages = store.load(sid)
    if sess is None or not 0 <= index <= min(sess.current_page, len(pages) - 1):
        abort(404)
    if sess.status != "active":
        return jsonify(error=f"this session has ended ({sess.status}); events are no longer recorded"), 409
    try:
        body = _json_body()
        if set(body) - {"events"}:
            raise PayloadError("expected {\"events\": [...]}")
        evs = parse_events(body.get("events"), n_slots(pages[index]))
    except PayloadError as exc:
        return jsonify(error=str(exc)), 422
    dropped, which = store.log_events(sid, index, evs)
    if dropped:
        return jsonify(error=_cap_message(store.rules, which), logged=len(evs) - dropped, dropped=dropped), 413
    return jsonify(logged=len(evs))
