"""Operations on a running study, shared by the admin page and ``evalsuite study ...``: release a reserved
plan, add plans (top-up), exclude a session, pilot mode, forget a participant (GDPR), and the exports that
leave pilot and excluded sessions out, replace participant ids by keyed hashes, or list each submission's
review decision for Prolific. Every function is one transaction on the :class:`~study_app.storage.Store`;
given the server's signed-URL ``links`` (:func:`study_app.media_signed.links_of`), those that end a session or
delete it also remove its links, and :func:`prune_links` removes those of every session that has ended."""
from __future__ import annotations

import csv
import dataclasses
import hashlib
import hmac
import io
import logging
from types import SimpleNamespace
from typing import Any

from sqlalchemy import delete, func, select, update

from study_app.design import build_plans
from study_app.errors import StudyStateError
from study_app.media_signed import Links, remove_session_links
from study_app.media_signed import prune_links as prune_folder
from study_app.model import Study
from study_app.outcomes import code_for
from study_app.storage import Base, ParticipantSession, Plan, SessionMark, Store, StudyFlag, utcnow

__all__ = ["release_plan", "topup", "exclude", "set_pilot", "pilot_mode", "mark_if_pilot", "forget",
           "decline_without_plan", "marks", "ended_sessions", "prune_links",
           "export_dump", "pseudonym", "pseudonym_key", "PLATFORM_ID_FIELDS", "review_rows", "review_csv", "REVIEW_COLUMNS"]

log = logging.getLogger("study_app.operations")
# platform_data fields that identify a person or their submission (pseudonymised in exports)
PLATFORM_ID_FIELDS = ("PROLIFIC_PID", "SESSION_ID", "workerId", "assignmentId")


def _session(db, study: Study, key: str) -> ParticipantSession:
    """A session of the study by its session id or participant id."""
    sess = db.scalars(select(ParticipantSession).where(
        ParticipantSession.study == study.id,
        (ParticipantSession.id == key) | (ParticipantSession.participant == key))).first()
    if sess is None:
        raise StudyStateError(f"no session or participant {key!r} in study {study.id!r}", field="session")
    return sess


def _pages(db, store: Store, sess: ParticipantSession) -> list[dict]:
    """The pages a session was shown: its plan's (kept after the plan is released), else the entry pages."""
    pages = db.scalar(select(Plan.pages).where(Plan.id == sess.plan_id)) if sess.plan_id is not None else None
    return pages if pages is not None else (store.entry_pages or [])


def _drop_links(links: Links | None, sid: str, pages: list[dict]) -> None:
    if links is not None and sid:
        n = remove_session_links(links, sid, pages)
        log.info("session %s: %d signed-URL links removed", sid, n)


def release_plan(store: Store, study: Study, plan_key: str, links: Links | None = None) -> str:
    """Hand a reserved plan out again now (its participant left without the reservation expiring): the
    session holding it ends as ``expired`` (reason ``released``). Returns that session's id."""
    with store.Session.begin() as db:
        plan = db.scalars(select(Plan).where(Plan.study == study.id, Plan.key == plan_key)).first()
        if plan is None:
            raise StudyStateError(f"no plan {plan_key!r} in study {study.id!r}", field="plan")
        if plan.status != "reserved":
            raise StudyStateError(f"plan {plan_key!r} is {plan.status}, not reserved; only a reserved plan "
                                  "can be released", field="plan")
        sid = plan.session_id or ""
        sess = db.get(ParticipantSession, sid) if sid else None
        if sess is not None and sess.status == "active":
            sess.status, sess.end_reason, sess.finished_at = "expired", "released", utcnow()
        plan.status, plan.session_id, plan.reserved_until = "free", None, None
        plan.times_released += 1
        pages = plan.pages
    _drop_links(links, sid, pages)
    log.info("study %s: plan %s released by the researcher (session %s)", study.id, plan_key, sid)
    return sid


def topup(store: Store, study: Study, n: int) -> list[str]:
    """Add ``n`` plans to the running study without rebuilding: a new balanced batch built with the
    study's design for ``n`` sessions (seed ``study.seed + batch``), keys ``topup<batch>-plan-XXXX``,
    handed out after the plans already there. Returns the new keys."""
    if not 1 <= n <= 5000:
        raise StudyStateError(f"expected 1 to 5000 plans, got {n}", field="n")
    with store.Session.begin() as db:
        flag = db.get(StudyFlag, (study.id, "topups"))
        batch = int(flag.value) + 1 if flag is not None else 1
        plans = build_plans(dataclasses.replace(study, sessions=n, seed=study.seed + batch))["plans"]
        last = db.scalar(select(func.max(Plan.position)).where(Plan.study == study.id))
        keys = [f"topup{batch}-{p['key']}" for p in plans]
        for i, (key, p) in enumerate(zip(keys, plans)):
            db.add(Plan(study=study.id, key=key, position=(last if last is not None else -1) + 1 + i,
                        pages=p["pages"]))
        if flag is None:
            db.add(StudyFlag(study=study.id, name="topups", value=str(batch)))
        else:
            flag.value = str(batch)
    log.info("study %s: %d plans added (top-up batch %d)", study.id, n, batch)
    return keys


def exclude(store: Store, study: Study, key: str, reason: str, undo: bool = False, links: Links | None = None) -> str:
    """Exclude a session (by session or participant id) from the export, with the reason (and remove its
    links); ``undo`` takes the exclusion back. Returns the session id."""
    reason = (reason or "").strip()
    if not undo and not reason:
        raise StudyStateError("expected a reason for the exclusion", field="reason")
    with store.Session.begin() as db:
        sess = _session(db, study, key)
        mark = db.get(SessionMark, sess.id) or SessionMark(session_id=sess.id, pilot=False)
        mark.excluded, mark.reason, mark.marked_at = not undo, "" if undo else reason[:500], utcnow()
        db.add(mark)
        sid, pages = sess.id, _pages(db, store, sess)
    if not undo:
        _drop_links(links, sid, pages)
    log.info("study %s: session %s %s%s", study.id, sid, "included again" if undo else "excluded: ",
             "" if undo else reason)
    return sid


def set_pilot(store: Store, study: Study, on: bool) -> None:
    """Pilot mode: while on, every new session is a pilot session (kept out of the export by default)."""
    with store.Session.begin() as db:
        flag = db.get(StudyFlag, (study.id, "pilot"))
        if flag is None:
            db.add(StudyFlag(study=study.id, name="pilot", value="1" if on else "0"))
        else:
            flag.value = "1" if on else "0"
    log.info("study %s: pilot mode %s", study.id, "on" if on else "off")


def pilot_mode(store: Store, study: Study) -> bool:
    with store.ReadSession() as db:
        flag = db.get(StudyFlag, (study.id, "pilot"))
        return flag is not None and flag.value == "1"


def mark_if_pilot(store: Store, study: Study, session_id: str) -> bool:
    """Mark a new session as a pilot session when pilot mode is on (called when a session is created)."""
    if not pilot_mode(store, study):
        return False
    with store.Session.begin() as db:
        if db.get(SessionMark, session_id) is None:
            db.add(SessionMark(session_id=session_id, pilot=True))
    return True


def decline_without_plan(store: Store, session_id: str) -> None:
    """End a session that declined consent before it held a plan (every plan was taken): ``failed`` with
    reason ``no_consent``, so the participant gets the no-consent code rather than "study full"."""
    with store.Session.begin() as db:
        sess = db.get(ParticipantSession, session_id)
        if sess is not None and sess.status == "active" and sess.plan_id is None:
            sess.status, sess.end_reason, sess.finished_at = "failed", "no_consent", utcnow()


def marks(store: Store, study: Study) -> dict[str, SessionMark]:
    """Session id -> its mark (pilot, excluded, reason)."""
    with store.ReadSession() as db:
        rows = db.scalars(select(SessionMark).join(ParticipantSession, SessionMark.session_id == ParticipantSession.id)
                          .where(ParticipantSession.study == study.id)).all()
        return {m.session_id: m for m in rows}


def _rowcount(result: Any) -> int:
    return int(getattr(result, "rowcount", 0) or 0)


def forget(store: Store, study: Study, participant: str, links: Links | None = None) -> int:
    """Delete everything stored about one participant (a GDPR erasure request): every row of every table
    that names their session or participant id, and their signed-URL ``links``; their plan is handed out
    again. Logs one line with a hash of the id (not the id). Returns the number of rows deleted."""
    deleted = 0
    store.media_log.flush()             # no buffered media request may come back after the deletion
    with store.Session.begin() as db:
        sess = _session(db, study, participant)
        sid, pid, pages = sess.id, sess.participant, _pages(db, store, sess)
        db.execute(update(Plan).where(Plan.session_id == sid).values(
            status="free", session_id=None, reserved_until=None, times_released=Plan.times_released + 1))
        for table in reversed(Base.metadata.sorted_tables):
            if table.name == ParticipantSession.__tablename__:
                continue
            if "session_id" in table.c:
                deleted += _rowcount(db.execute(delete(table).where(table.c.session_id == sid)))
        deleted += _rowcount(db.execute(delete(ParticipantSession).where(ParticipantSession.id == sid)))
    _drop_links(links, sid, pages)
    log.warning("study %s: participant %s forgotten on request: %d rows deleted", study.id,
                hashlib.sha256(pid.encode()).hexdigest()[:12], deleted)
    return deleted


def ended_sessions(store: Store, study: Study) -> list[tuple[str, list[dict]]]:
    """(session id, pages) of every session that is no longer active: ended (finished, failed, expired;
    reservations that ran out are expired first) or excluded."""
    with store.Session.begin() as db:
        store.release_expired(db, study.id, utcnow())
    with store.ReadSession() as db:
        rows = db.execute(select(ParticipantSession.id, Plan.pages).outerjoin(
            Plan, Plan.id == ParticipantSession.plan_id).outerjoin(
            SessionMark, SessionMark.session_id == ParticipantSession.id).where(
            ParticipantSession.study == study.id,
            (ParticipantSession.status != "active") | (SessionMark.excluded.is_(True)))).all()
    return [(sid, pages if pages is not None else (store.entry_pages or [])) for sid, pages in rows]


def prune_links(store: Store, study: Study, links: Links) -> int:
    """Remove the signed-URL links of every session that is no longer active (:func:`ended_sessions`);
    an active session's links stay. Returns how many were removed."""
    n = prune_folder(links, ended_sessions(store, study))
    log.info("study %s: %d signed-URL links of ended sessions removed", study.id, n)
    return n


def pseudonym_key(secret: str) -> bytes:
    """The pseudonymisation key derived from a secret (the server's SECRET_KEY or ``--key``): the same
    secret gives the same pseudonyms in every export, and without it they cannot be reversed by trying ids."""
    return hmac.new(secret.encode(), b"evalsuite-pseudonym", hashlib.sha256).digest()


def pseudonym(key: bytes, value: str) -> str:
    """The keyed hash that replaces a participant or platform id: HMAC-SHA256(key, value), 24 hex digits."""
    return "p-" + hmac.new(key, value.encode(), hashlib.sha256).hexdigest()[:24]


def export_dump(store: Store, study: Study, *, include_pilot: bool = False, include_excluded: bool = False,
                pseudonym_key: bytes | None = None) -> dict:
    """The store's dump for an export: pilot and excluded sessions left out unless asked for, and with a
    ``pseudonym_key`` every participant id and platform id replaced by :func:`pseudonym`."""
    dump = store.dump(study.id)
    by_session = marks(store, study)
    drop = {sid for sid, m in by_session.items()
            if (m.pilot and not include_pilot) or (m.excluded and not include_excluded)}
    sessions: list[Any] = []
    for s in dump["sessions"]:
        if s.id in drop:
            continue
        copy = SimpleNamespace(**{c.key: getattr(s, c.key) for c in ParticipantSession.__table__.columns})
        if pseudonym_key is not None:
            copy.participant = pseudonym(pseudonym_key, s.participant)
            copy.platform_data = {k: (pseudonym(pseudonym_key, v) if k in PLATFORM_ID_FIELDS and v else v)
                                  for k, v in (s.platform_data or {}).items()}
        sessions.append(copy)
    events = dump["events"]
    out = dict(dump, sessions=sessions, answers=[a for a in dump["answers"] if a.session_id not in drop],
               events=(e for e in events if e.session_id not in drop))
    out["marks"] = {sid: m for sid, m in by_session.items() if sid not in drop}
    return out


REVIEW_COLUMNS = ("participant_id", "submission_id", "outcome", "code", "action", "reason")
_WHY = {"completed": "completed the study", "no_consent": "did not consent",
        "screened_out": "screened out by the headphone check", "timed_out": "the time limit ran out"}


def review_rows(study: Study, dump: dict) -> list[dict]:
    """One row per ended session for the platform's review: the participant and submission ids, the
    outcome, its code and action (:mod:`study_app.outcomes`) and the reason. An excluded session is
    ``MANUALLY_REVIEW`` with the exclusion's reason; pilot sessions are whatever ``dump`` holds."""
    rows = []
    by_session = dump.get("marks", {})
    for s in dump["sessions"]:
        oc = code_for(study, s.status, s.end_reason)
        if oc is None:
            continue
        data = s.platform_data or {}
        reason = _WHY.get(oc.outcome) or (f"failed {s.failed_checks} attention checks" if s.end_reason ==
                                          "attention_checks" else f"ended early ({s.end_reason})")
        action = oc.action
        mark = by_session.get(s.id)
        if mark is not None and mark.excluded:
            action, reason = "MANUALLY_REVIEW", f"excluded: {mark.reason}"
        rows.append({"participant_id": s.participant, "submission_id": data.get("SESSION_ID")
                     or data.get("assignmentId") or "", "outcome": oc.outcome, "code": oc.code,
                     "action": action, "reason": reason})
    return rows


def review_csv(study: Study, dump: dict) -> str:
    """:func:`review_rows` as CSV (Prolific's bulk approve takes the participant_id column of the
    AUTOMATICALLY_APPROVE rows; bulk reject and request return take the ids with the reason)."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=REVIEW_COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(review_rows(study, dump))
    return buf.getvalue()
