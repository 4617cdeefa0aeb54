"""What the admin page shows about participants while a study runs: one row per participant (to approve
or reject crowd submissions) and the "this video does not play" reports counted per stimulus.

Read-only queries on the store: sessions, their plans, first-view records and the ``unplayable`` events
only (never the whole interaction log), so the admin page and its JSON stay fast on a large study.
"""
from __future__ import annotations

import datetime as dt
from collections import defaultdict
from typing import Any

from sqlalchemy import func, select

from study_app.model import Study
from study_app.pages import get_kind
from study_app.storage import Answer, Event, PageView, ParticipantSession, Plan, Store

__all__ = ["REPORT_EVENT", "participant_rows", "unplayable_reports", "status_counts", "duration"]

REPORT_EVENT = "unplayable"     # the event kind a participant's "does not play" report is stored as


def _iso(t: dt.datetime | None) -> str:
    return t.isoformat(timespec="seconds") + "Z" if t is not None else ""


def duration(seconds: int | None) -> str:
    """``3725`` -> ``1 h 02 min``; ``65`` -> ``1 min 05 s``; None -> ``""``."""
    if seconds is None:
        return ""
    h, rest = divmod(int(seconds), 3600)
    m, s = divmod(rest, 60)
    if h:
        return f"{h} h {m:02d} min"
    return f"{m} min {s:02d} s" if m else f"{s} s"


def _plans(db: Any, plan_ids: set) -> dict[int, list]:
    ids = [i for i in plan_ids if i is not None]
    if not ids:
        return {}
    return {p.id: p.pages for p in db.scalars(select(Plan).where(Plan.id.in_(ids)))}


def _reports(db: Any, study_id: str) -> list[tuple[str, int, int | None, dt.datetime]]:
    """(session, page index, slot, time) of every distinct report (a repeated click counts once)."""
    rows = db.execute(
        select(Event.session_id, Event.page_index, Event.slot, func.max(Event.server_time))
        .join(ParticipantSession, Event.session_id == ParticipantSession.id)
        .where(ParticipantSession.study == study_id, Event.kind == REPORT_EVENT)
        .group_by(Event.session_id, Event.page_index, Event.slot))
    return [(s, p, slot, t) for s, p, slot, t in rows]


def status_counts(store: Store, study: Study) -> dict[str, int]:
    with store.ReadSession() as db:
        rows = db.execute(select(ParticipantSession.status, func.count())
                          .where(ParticipantSession.study == study.id).group_by(ParticipantSession.status))
        return {status: int(n) for status, n in rows}


def participant_rows(store: Store, study: Study, now: dt.datetime) -> list[dict]:
    """One row per participant session, oldest first: id, platform, status, current page, time spent
    (first view to last activity), attention checks passed/failed and "does not play" reports."""
    with store.ReadSession() as db:
        sessions = db.scalars(select(ParticipantSession).where(ParticipantSession.study == study.id)
                              .order_by(ParticipantSession.created_at)).all()
        plans = _plans(db, {s.plan_id for s in sessions})
        activity = {sid: (first, max(x for x in (shown, drafted) if x is not None))
                    for sid, first, shown, drafted in db.execute(
                        select(PageView.session_id, func.min(PageView.shown_at), func.max(PageView.shown_at),
                               func.max(PageView.draft_at))
                        .join(ParticipantSession, PageView.session_id == ParticipantSession.id)
                        .where(ParticipantSession.study == study.id).group_by(PageView.session_id))}
        reports: dict[str, int] = defaultdict(int)
        for sid, _page, _slot, _t in _reports(db, study.id):
            reports[sid] += 1
    rows = []
    for s in sessions:
        pages = plans.get(s.plan_id) if s.plan_id is not None else None
        total = len(pages) if pages else 0
        if s.status == "finished":
            where = "finished"
        elif pages and 0 <= s.current_page < total:
            spec = pages[s.current_page]
            where = f"{s.current_page + 1} of {total}: {spec.get('block') or spec['page']} ({spec['type']})"
        else:
            where = "not started"
        first, last_view = activity.get(s.id, (None, None))
        start = min(x for x in (s.created_at, first) if x is not None)
        last = max(x for x in (s.updated_at, last_view, s.finished_at) if x is not None)
        rows.append({
            "participant": s.participant, "session": s.id, "platform": s.platform,
            "status": s.status, "end_reason": s.end_reason or "",
            "current_page": s.current_page, "pages": total, "where": where,
            "started_at": _iso(start), "last_active_at": _iso(last),
            "seconds": max(0, int((last - start).total_seconds())),
            "time_spent": duration(max(0, int((last - start).total_seconds()))),
            "idle": duration(max(0, int((now - last).total_seconds()))) if s.status == "active" else "",
            "passed_checks": s.passed_checks, "failed_checks": s.failed_checks,
            "reports": reports.get(s.id, 0), "honeypot": bool(s.honeypot),
        })
    return rows


def unplayable_reports(store: Store, study: Study) -> list[dict]:
    """Per stimulus: how many "does not play" reports name it (a report for every video of a page counts
    for each of them) and from how many participants; most reported first."""
    with store.ReadSession() as db:
        reports = _reports(db, study.id)
        owners = {sid: (participant, plan_id) for sid, participant, plan_id in db.execute(
            select(ParticipantSession.id, ParticipantSession.participant, ParticipantSession.plan_id)
            .where(ParticipantSession.id.in_({r[0] for r in reports})))} if reports else {}
        plans = _plans(db, {plan_id for _p, plan_id in owners.values()})
    by_file = study.manifest.by_file()
    counts: dict[str, dict] = {}
    for sid, index, slot, when in reports:
        participant, plan_id = owners.get(sid, ("", None))
        pages = plans.get(plan_id) if plan_id is not None else None
        if not pages or not 0 <= index < len(pages):
            continue
        spec = pages[index]
        kind = get_kind(spec["type"])
        slots = range(kind.n_slots(spec)) if slot is None else [slot]
        for k in slots:
            if not 0 <= k < kind.n_slots(spec):
                continue
            media = kind.media(study, spec, k)
            key = media.file or f"{spec['page']}: generated {kind.media_word} {k + 1}"
            stim = by_file.get(media.file or "")
            entry = counts.setdefault(key, {
                "file": key, "condition": (stim.condition or "attention_check") if stim else "",
                "segment": stim.segment if stim else "", "kind": stim.kind if stim else "generated",
                "reports": 0, "participants": set(), "pages": set(), "last_reported_at": when})
            entry["reports"] += 1
            entry["participants"].add(participant)
            entry["pages"].add(spec.get("block") or spec["page"])
            entry["last_reported_at"] = max(entry["last_reported_at"], when)
    out = []
    for e in counts.values():
        out.append({**e, "participants": len(e["participants"]), "pages": ", ".join(sorted(e["pages"])),
                    "last_reported_at": _iso(e["last_reported_at"])})
    return sorted(out, key=lambda e: (-e["reports"], e["file"]))


def answer_count(store: Store, study: Study) -> int:
    """Answers stored for the study (counted in SQL)."""
    with store.ReadSession() as db:
        return int(db.scalar(select(func.count(Answer.id)).join(
            ParticipantSession, Answer.session_id == ParticipantSession.id)
            .where(ParticipantSession.study == study.id)) or 0)


def plan_counts(store: Store, study: Study, now: dt.datetime) -> dict[str, int]:
    """Plans by status, a reservation past its time counted as ``reserved (expired)``."""
    with store.ReadSession() as db:
        rows = db.execute(select(Plan.status, Plan.reserved_until).where(Plan.study == study.id)).all()
    out: dict[str, int] = {}
    for status, until in rows:
        key = "reserved (expired)" if status == "reserved" and until is not None and until < now else status
        out[key] = out.get(key, 0) + 1
    return out
