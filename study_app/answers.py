"""Validation of what a participant's browser sends, and attention-check scoring.

Every endpoint payload goes through these functions; anything unexpected raises
:class:`PayloadError` (answered with HTTP 422 and the message), never a KeyError.
"""
from __future__ import annotations

import re

from study_app.definition import (PAIRWISE_ANSWERS, PAIRWISE_EXPECTED_RE, Study,
                                  mushra_check_passes)
from study_app.errors import StudyDefinitionError
from study_app.headphones import correct_choice

TOKEN_RE = re.compile(r"^[A-Za-z0-9_-]{8,64}$")
EVENT_KINDS = ("play", "pause", "seeked", "ended", "choice", "reload", "hidden", "visible", "resize")
MAX_EVENTS = 2000


class PayloadError(ValueError):
    pass


def _require_dict(value, what):
    if not isinstance(value, dict):
        raise PayloadError(f"{what}: expected an object")
    return value


def _only_keys(obj: dict, allowed, what):
    extra = sorted(set(obj) - set(allowed))
    if extra:
        raise PayloadError(f"{what}: unexpected field {extra[0]!r}")


def _int(value, lo, hi, what):
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise PayloadError(f"{what}: expected an integer in {lo}..{hi}")
    return value


def parse_token(value) -> str:
    if not isinstance(value, str) or not TOKEN_RE.match(value):
        raise PayloadError("token: expected 8-64 characters of letters, digits, '_' or '-'")
    return value


def parse_events(value, n_slots: int) -> list[dict]:
    if value is None:
        return []
    if not isinstance(value, list) or len(value) > MAX_EVENTS:
        raise PayloadError(f"events: expected a list of at most {MAX_EVENTS} events")
    out = []
    for i, e in enumerate(value):
        what = f"events[{i}]"
        _require_dict(e, what)
        _only_keys(e, ("id", "kind", "slot", "t", "ms", "detail"), what)
        if not isinstance(e.get("id"), str) or not TOKEN_RE.match(e["id"]):
            raise PayloadError(f"{what}.id: expected 8-64 characters of letters, digits, '_' or '-'")
        if e.get("kind") not in EVENT_KINDS:
            raise PayloadError(f"{what}.kind: expected one of {', '.join(EVENT_KINDS)}")
        slot = e.get("slot")
        if slot is not None:
            _int(slot, 0, max(n_slots - 1, 0), f"{what}.slot")
        for key in ("t", "ms"):
            v = e.get(key)
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))
                                  or not -1 <= v <= 1e13):
                raise PayloadError(f"{what}.{key}: expected a number")
        detail = e.get("detail", "")
        if not isinstance(detail, str) or len(detail) > 200:
            raise PayloadError(f"{what}.detail: expected a string of at most 200 characters")
        out.append({"id": e["id"], "kind": e["kind"], "slot": slot, "t": e.get("t"),
                    "ms": e.get("ms"), "detail": detail})
    return out


def n_slots(page: dict) -> int:
    return {"pairwise": 2, "mushra": len(page.get("slots", [])), "likert": 1,
            "headphone_check": len(page.get("trials", []))}.get(page["type"], 0)


def parse_answer(study: Study, page: dict, answer) -> dict:
    """Validated answer data for a plan page (raises :class:`PayloadError`)."""
    answer = _require_dict(answer, "answer")
    ptype = page["type"]
    if ptype == "consent":
        cfg = study.page(page["page"]).cfg
        _only_keys(answer, ("agree", "website"), "answer")
        if answer.get("agree") is not True:
            raise PayloadError("answer.agree: you must agree to take part to continue")
        website = answer.get("website", "")
        if not isinstance(website, str) or len(website) > 500:
            raise PayloadError("answer.website: expected a string")
        return {"agree": True, "honeypot": bool(website.strip()) and cfg["honeypot"]}
    if ptype == "instructions":
        _only_keys(answer, (), "answer")
        return {}
    if ptype == "questionnaire":
        return {"responses": _questionnaire(study.page(page["page"]).cfg["questions"], answer)}
    if ptype == "headphone_check":
        _only_keys(answer, ("choices",), "answer")
        choices, n = answer.get("choices"), len(page["trials"])
        if not isinstance(choices, list) or len(choices) != n:
            raise PayloadError(f"answer.choices: expected a list of {n} answers (1, 2 or 3)")
        choices = [_int(c, 1, 3, f"answer.choices[{i}]") for i, c in enumerate(choices)]
        correct = sum(c == correct_choice(o) for c, o in zip(choices, page["trials"]))
        return {"choices": choices, "correct": correct,
                "passed": correct >= study.page(page["page"]).cfg["pass"]}
    block = study.page(page["block"]).cfg
    if ptype == "pairwise":
        _only_keys(answer, ("choices", "reasons"), "answer")
        choices = _require_dict(answer.get("choices"), "answer.choices")
        allowed = PAIRWISE_ANSWERS[block["levels"]]
        qids = [q["id"] for q in block["questions"]]
        _only_keys(choices, qids, "answer.choices")
        for qid in qids:
            if choices.get(qid) not in allowed:
                raise PayloadError(f"answer.choices.{qid}: expected one of {', '.join(allowed)}")
        reasons = answer.get("reasons", [])
        reason_ids = {r["id"] for r in block["reasons"]}
        if not isinstance(reasons, list) or any(r not in reason_ids for r in reasons):
            raise PayloadError("answer.reasons: expected a list of reason ids of this page")
        if block["reasons_required"] and not reasons and any(c != "equal" for c in choices.values()):
            raise PayloadError("answer.reasons: please tick at least one reason for your preference")
        return {"choices": {q: choices[q] for q in qids}, "reasons": sorted(set(reasons))}
    if ptype == "mushra":
        _only_keys(answer, ("ratings",), "answer")
        ratings = answer.get("ratings")
        n = len(page["slots"])
        if not isinstance(ratings, list) or len(ratings) != n:
            raise PayloadError(f"answer.ratings: expected a list of {n} ratings")
        return {"ratings": [_int(r, 0, 100, f"answer.ratings[{i}]") for i, r in enumerate(ratings)]}
    if ptype == "likert":
        _only_keys(answer, ("ratings",), "answer")
        ratings = _require_dict(answer.get("ratings"), "answer.ratings")
        ids = [s["id"] for s in block["statements"]]
        _only_keys(ratings, ids, "answer.ratings")
        return {"ratings": {sid: _int(ratings.get(sid), 1, block["points"], f"answer.ratings.{sid}")
                            for sid in ids}}
    raise PayloadError(f"pages of type {ptype} take no answer")


def _questionnaire(questions, answer):
    _only_keys(answer, [q["id"] for q in questions], "answer")
    out = {}
    for q in questions:
        what = f"answer.{q['id']}"
        v = answer.get(q["id"])
        if v is None or v == "":
            if q["required"]:
                raise PayloadError(f"{what}: this question needs an answer")
            out[q["id"]] = None
            continue
        if q["type"] == "number":
            if isinstance(v, str):
                try:
                    v = float(v) if "." in v else int(v)
                except ValueError:
                    raise PayloadError(f"{what}: expected a number") from None
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise PayloadError(f"{what}: expected a number")
            if (q["min"] is not None and v < q["min"]) or (q["max"] is not None and v > q["max"]):
                raise PayloadError(f"{what}: expected a number in {q['min']}..{q['max']}")
        elif q["type"] == "choice":
            if v not in q["options"]:
                raise PayloadError(f"{what}: expected one of the options")
        else:
            if not isinstance(v, str) or len(v) > q["max_length"]:
                raise PayloadError(f"{what}: expected text of at most {q['max_length']} characters")
        out[q["id"]] = v
    return out


# ------------------------------------------------------------------------ attention checks

def pairwise_expected_screen(expected: str, position_check: str) -> tuple[str, str]:
    """(side, strength) an attentive participant picks; side in left/right/equal."""
    m = PAIRWISE_EXPECTED_RE.match(expected)
    if not m:
        raise StudyDefinitionError(f"bad pairwise attention expectation {expected!r}")
    word, strength = m.group(1), m.group(3) or ""
    other = "right" if position_check == "left" else "left"
    side = {"this": position_check, "other": other}.get(word, word)
    return side, strength


def screen_side(choice: str) -> tuple[str, str]:
    """'left_strong' -> ('left', 'strong'); 'equal' -> ('equal', '')."""
    side, _, strength = choice.partition("_")
    return side, strength


def score_attention(study: Study, page: dict, data: dict):
    """True/False for attention-check pages, None otherwise."""
    if not page.get("check"):
        return None
    by_file = study.manifest.by_file()
    block = study.page(page["block"]).cfg
    if page["type"] == "pairwise":
        expected = by_file[page["a"]].expected
        side, strength = pairwise_expected_screen(expected, page["position_a"])
        for choice in data["choices"].values():
            got_side, got_strength = screen_side(choice)
            if got_side != side or (strength and got_strength != strength):
                return False
        return True
    if page["type"] == "mushra":
        slot = page["check_slot"]
        expected = by_file[page["slots"][slot]].expected
        return mushra_check_passes(expected, data["ratings"][slot], block["bands"], block["tolerance"])
    expected = int(by_file[page["stimulus"]].expected)
    return all(v == expected for v in data["ratings"].values())
