"""HEMVIP session JSON exports as results.csv rows (format: ``docs/human-data.md``).

HEMVIP (webMUSHRA for video) posts one session object per participant: ``trials``, each with an ``id`` (the
page; HEMVIP names it after the speech segment), a ``type`` and ``responses`` ``[{"stimulus", "score"}, ...]``
(the stimulus keys are the condition ids). Its export is a JSON list of such objects, or of database records
that hold one under ``sessionJSON`` (object or JSON text); one object alone is read too. The participant is
``userId`` (added by HEMVIP's server), else the ``participant.response`` answer to a question named ``id`` or
``name``, else the session's position in the file. The study id is ``study=``, else the first session's
``testId``, else the file's name.

- rating pages (``video``, ``mushra``): one ``mushra`` row per stimulus, the 0-100 score;
- pairwise pages (``videopc``, ``pairwise``): one ``pairwise`` row; the first response's score is the
  preference for it (GENEA 2023: -2..2, 2 clearly better; GENEA 2022: true/false per side, both false a tie);
- attention checks (a stimulus key holding ``attn`` or ``_att_``: that stimulus on a rating page, the whole
  pairwise page), pairwise pages reported broken (score 99) and other page types are left out.
"""
from __future__ import annotations

import json
from typing import Any

import pandas as pd

from evalsuite.analysis.importers import Importer
from evalsuite.analysis.importers.common import fail, rows

RATING_TYPES = ("video", "mushra")
PAIRWISE_TYPES = ("videopc", "pairwise")


def _sessions(data: Any, path) -> list[dict]:
    items = data if isinstance(data, list) else [data]
    out = []
    for i, item in enumerate(items):
        if not isinstance(item, dict):
            fail(f"session {i + 1} is a {type(item).__name__}; expected a session object with 'trials'", path)
        inner = item.get("sessionJSON", item)
        if isinstance(inner, str):
            try:
                inner = json.loads(inner)
            except json.JSONDecodeError as exc:
                fail(f"session {i + 1}: sessionJSON is not JSON ({exc.msg})", path)
        if not isinstance(inner, dict) or not isinstance(inner.get("trials"), list):
            fail(f"session {i + 1} has no 'trials' list; expected HEMVIP's session JSON", path)
        inner = dict(inner)
        inner.setdefault("userId", item.get("userId", ""))
        out.append(inner)
    return out


def _participant(session: dict, index: int) -> str:
    if session.get("userId"):
        return str(session["userId"])
    part = session.get("participant") or {}
    names, answers = part.get("name") or [], part.get("response") or []
    for key in ("id", "name"):
        if key in names and names.index(key) < len(answers):
            return str(answers[names.index(key)])
    return f"session{index + 1}"


def _is_check(key: str) -> bool:
    return "attn" in key.lower() or "_att_" in key.lower()


def _pairwise_score(value: Any) -> float:
    if isinstance(value, bool):
        return 1.0 if value else 0.0
    return float(value)


def read(path, *, study: str | None = None, question: str | None = None) -> pd.DataFrame:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        fail("file not found (expected a HEMVIP JSON export)", path)
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        fail(f"not JSON ({exc}); expected a HEMVIP JSON export", path)
    records: list[dict] = []
    sessions = _sessions(data, path)
    for i, session in enumerate(sessions):
        who = _participant(session, i)
        sid = f"{who}#{i + 1}"
        q = question or str(session.get("question", "") or "") or "human-likeness"
        for t, trial in enumerate(session["trials"]):
            kind = str(trial.get("type", ""))
            resp = [r for r in trial.get("responses") or [] if isinstance(r, dict) and "stimulus" in r]
            page = str(trial.get("id", f"page{t + 1}"))
            if kind in RATING_TYPES:
                resp = [r for r in resp if not _is_check(str(r["stimulus"]))]
            if not resp or any(_is_check(str(r["stimulus"])) for r in resp):
                continue
            common = dict(participant=who, session=sid, page=page, segment=page, question=q)
            if kind in RATING_TYPES:
                for r in resp:
                    score = r.get("score")
                    if not isinstance(score, (int, float)) or isinstance(score, bool) or not 0 <= score <= 100:
                        fail(f"session {who!r}, page {page!r}: score {score!r} of {r['stimulus']!r}; expected a "
                             "number in 0..100", path, field="score")
                    records.append(dict(common, page_type="mushra", condition=str(r["stimulus"]),
                                        answer=f"{float(score):g}"))
            elif kind in PAIRWISE_TYPES:
                if len(resp) != 2:
                    fail(f"session {who!r}, page {page!r}: {len(resp)} responses on a pairwise page; expected 2",
                         path, field="responses")
                try:
                    first, second = (_pairwise_score(r.get("score")) for r in resp)
                except (TypeError, ValueError):
                    fail(f"session {who!r}, page {page!r}: pairwise scores {[r.get('score') for r in resp]!r}; "
                         "expected numbers -2..2 or true/false", path, field="score")
                if 99 in (first, second):
                    continue
                pref = first - second if isinstance(resp[0].get("score"), bool) else first
                answer = "a" if pref > 0 else "b" if pref < 0 else "tie"
                strength = "" if answer == "tie" or isinstance(resp[0].get("score"), bool) else (
                    "strong" if abs(pref) >= 2 else "weak")
                records.append(dict(common, page_type="pairwise", condition_a=str(resp[0]["stimulus"]),
                                    condition_b=str(resp[1]["stimulus"]), answer=answer, strength=strength))
    if not records:
        fail("no rating or pairwise pages with answers in the export", path)
    table = pd.DataFrame(records).fillna("")
    test_id = str(sessions[0].get("testId") or "")
    return rows(len(table), study or test_id or path.stem, **{c: table[c].to_numpy() for c in table.columns})


HEMVIP = Importer("hemvip", "HEMVIP (webMUSHRA) session JSON export", read)
