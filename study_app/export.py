"""Export of stored answers: ``results.csv`` (docs/results_format.md) and a raw JSON dump.

One row per judgement. Pairwise answers are translated from the screen (left/right) to
A/B with the plan's ``position_a``; 5-level answers become ``a``/``b`` + ``weak``/``strong``.
For matched-vs-mismatched pairs A is the matched video and ``condition_b`` is the
condition name followed by ``:mismatched``. Attention-check stimuli use the manifest's
condition (or ``attention_check`` when it is empty). Consent/questionnaire answers are only
in the raw JSON.
"""
from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterator

from evalsuite.contracts import results as results_contract
from study_app.model import Study
from study_app.pages import get_kind
from study_app.playback import PlaybackCheck, check_playback, media_seconds

COLUMNS = list(results_contract.COLUMNS)


def _iso(t) -> str:
    return t.isoformat(timespec="milliseconds") + "Z" if t is not None else ""


def _session_status(status: str) -> str:
    return status if status in ("finished", "failed") else "incomplete"


def playback_of(study: Study, page: dict, ans, dump: dict) -> PlaybackCheck | None:
    """The server's judgement of playback on an answered page (:mod:`study_app.playback`); None without
    media. Clip durations are looked up for rating pages, and given by the kind for generated sounds."""
    kind = get_kind(page["type"])
    n = kind.n_slots(page)
    if not n:
        return None
    seconds: list[float | None] = []
    if kind.block:
        files = [kind.media(study, page, k).file for k in range(n)]
        seconds = [media_seconds(study, f) if f else None for f in files]
    else:
        seconds = [kind.generated_seconds(page, k) for k in range(n)]
    return check_playback(n, dump.get("media_requests", {}).get((ans.session_id, ans.page_index), set()),
                          seconds, ans.rt_ms, study.playback_min_fraction, study.require_full_playback,
                          dump.get("media_served", {}).get((ans.session_id, ans.page_index), {})
                          if "media_served" in dump else None)


def result_rows(study: Study, dump: dict) -> list[dict]:
    rows = []
    sessions = {s.id: s for s in dump["sessions"]}
    order = {s.id: i for i, s in enumerate(dump["sessions"])}
    for ans in sorted(dump["answers"], key=lambda a: (order[a.session_id], a.page_index)):
        sess = sessions[ans.session_id]
        page = dump["plans"][sess.plan_id].pages[ans.page_index] if sess.plan_id in dump["plans"] else None
        if page is None:
            continue
        kind = get_kind(page["type"])
        if not kind.block:
            continue   # consent and questionnaire answers are in the raw JSON only
        base = {"study": study.id, "participant": sess.participant, "platform": sess.platform,
                "session": sess.id, "session_status": _session_status(sess.status),
                "page": page["page"], "page_type": page["type"], "trial": ans.page_index,
                "segment": page["segment"], "rt_ms": ans.rt_ms,
                "is_training": int(bool(page.get("training"))), "is_attention_check": 0,
                "attention_expected": "", "attention_passed": "",
                "shown_at": _iso(ans.shown_at), "answered_at": _iso(ans.answered_at)}
        check = playback_of(study, page, ans, dump)
        base["playback_implausible"] = "" if check is None else int(check.implausible)
        base["playback_reason"] = "" if check is None else "; ".join(check.reasons)
        rows.extend(kind.export_rows(study, page, ans, base))
    for r in rows:
        for c in COLUMNS:
            r.setdefault(c, "")
    return rows


def results_csv(study: Study, dump: dict) -> str:
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    for row in result_rows(study, dump):
        writer.writerow(row)
    return buf.getvalue()


def _playback_json(study: Study, ans, dump: dict, sessions: dict) -> dict | None:
    sess = sessions.get(ans.session_id)
    plan = dump["plans"].get(sess.plan_id) if sess is not None else None
    check = playback_of(study, plan.pages[ans.page_index], ans, dump) if plan is not None else None
    if check is None:
        return None
    return {"implausible": check.implausible, "not_requested": list(check.not_requested), "min_ms": check.min_ms,
            "reasons": list(check.reasons)}


def raw_json_chunks(study: Study, dump: dict) -> Iterator[str]:
    """Everything stored for the study as JSON text in pieces: sessions (with platform ids), answers,
    plans and events. The interaction log is streamed from the database, one event at a time, so that an
    export never holds every event in memory."""
    def sess(s):
        return {"id": s.id, "participant": s.participant, "platform": s.platform,
                "platform_data": s.platform_data, "plan": dump["plans"][s.plan_id].key if s.plan_id in dump["plans"] else None,
                "status": s.status, "end_reason": s.end_reason, "current_page": s.current_page,
                "failed_checks": s.failed_checks, "passed_checks": s.passed_checks,
                "honeypot": s.honeypot, "user_agent": s.user_agent, "created_at": _iso(s.created_at),
                "finished_at": _iso(s.finished_at)}
    by_id = {s.id: s for s in dump["sessions"]}
    head = {
        "study": study.id,
        "embodiment": study.manifest.embodiment,
        "sessions": [sess(s) for s in dump["sessions"]],
        "answers": [{"session": a.session_id, "page_index": a.page_index, "page": a.page_id,
                     "submit_token": a.submit_token, "data": a.data,
                     "attention_passed": a.attention_passed, "rt_ms": a.rt_ms,
                     "client_rt_ms": a.client_rt_ms, "shown_at": _iso(a.shown_at),
                     "answered_at": _iso(a.answered_at), "playback": _playback_json(study, a, dump, by_id)}
                    for a in dump["answers"]],
        "plans": [{"key": p.key, "status": p.status, "session": p.session_id,
                   "reserved_until": _iso(p.reserved_until), "times_released": p.times_released,
                   "pages": p.pages} for p in sorted(dump["plans"].values(), key=lambda p: p.position)],
    }
    text = json.dumps(head, indent=1)
    yield text[:-2] + ',\n "events": ['
    sep = "\n  "
    for e in dump["events"]:
        yield sep + json.dumps({"session": e.session_id, "page_index": e.page_index, "kind": e.kind,
                                "slot": e.slot, "media_time": e.media_time, "client_ms": e.client_ms,
                                "detail": e.detail, "server_time": _iso(e.server_time)})
        sep = ",\n  "
    yield "\n ]\n}"
