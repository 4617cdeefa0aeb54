"""Outcome codes: one completion code per way a session can end, each with the review action it should
trigger on the crowd platform (Prolific's completion codes carry actions; on MTurk the code is sent with the
HIT and the requester reviews by it).

The outcomes and the session ends they cover:

========================  ===============================================  ==========================
outcome                   a session that ended with                        default action
========================  ===============================================  ==========================
``completed``             status finished                                  ``AUTOMATICALLY_APPROVE``
``no_consent``            "I do not agree" on the consent page             ``REQUEST_RETURN``
``screened_out``          the headphone check failed                       ``REQUEST_RETURN``
``attention_checks``      too many failed attention checks, or the         ``MANUALLY_REVIEW``
                          consent honeypot filled in
``timed_out``             status expired (the reservation ran out)         ``REQUEST_RETURN``
========================  ===============================================  ==========================

In the study definition::

    outcomes:
      completed: {code: C1A2B3, action: AUTOMATICALLY_APPROVE}
      no_consent: NOCONSENT1            # a code alone takes the default action
      attention_checks: {code: ATTN99, action: REJECT}

``completion_code`` is the shorthand for ``outcomes.completed`` and ``failure_code`` for every other outcome
that ``outcomes`` does not name.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from study_app.schema import Checker, describe

__all__ = ["OUTCOMES", "ACTIONS", "DEFAULT_ACTIONS", "OutcomeCode", "load_outcomes", "outcome_of", "code_for"]

OUTCOMES = ("completed", "no_consent", "screened_out", "attention_checks", "timed_out")
# Prolific's completion-code actions evalsuite knows; REJECT is carried out by the review export and the API
# client (set such a code to "manually review" in Prolific).
ACTIONS = ("AUTOMATICALLY_APPROVE", "MANUALLY_REVIEW", "REQUEST_RETURN", "REJECT")
DEFAULT_ACTIONS = {"completed": "AUTOMATICALLY_APPROVE", "no_consent": "REQUEST_RETURN",
                   "screened_out": "REQUEST_RETURN", "attention_checks": "MANUALLY_REVIEW",
                   "timed_out": "REQUEST_RETURN"}
CODE_RE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")
# session end_reason -> outcome (a page kind's own failure reasons are screenings)
_REASONS = {"completed": "completed", "no_consent": "no_consent", "headphone_check": "screened_out",
            "attention_checks": "attention_checks", "honeypot": "attention_checks"}


@dataclass(frozen=True)
class OutcomeCode:
    outcome: str
    code: str           # "" when the study has none for this outcome (the participant is asked to return)
    action: str


def load_outcomes(chk: Checker, data: dict, completion_code: str, failure_code: str) -> dict[str, OutcomeCode]:
    """Every outcome's code and action from the definition's ``outcomes`` mapping and the shorthands."""
    given = chk.get(data, "outcomes", "", dict, default={})
    odd = [k for k in given if k not in OUTCOMES]
    if odd:
        chk.fail(f"outcomes.{odd[0]}", f"unknown outcome; expected one of {', '.join(OUTCOMES)}")
    if completion_code and "completed" in given:
        chk.fail("outcomes.completed", "given twice (also as completion_code); expected one of them")
    out: dict[str, OutcomeCode] = {}
    for name in OUTCOMES:
        where = f"outcomes.{name}"
        value: Any = given.get(name)
        code, action = (completion_code if name == "completed" else failure_code), DEFAULT_ACTIONS[name]
        if isinstance(value, str):
            code = value
        elif isinstance(value, dict):
            chk.unknown_keys(value, ("code", "action"), where)
            code = chk.get(value, "code", where, str, required=True, expected="the completion code")
            action = chk.get(value, "action", where, str, default=action)
        elif value is not None:
            chk.fail(where, f"expected a code or a mapping with code and action, got {describe(value)}")
        if code and not CODE_RE.match(code):
            chk.fail(where if value is not None else ("completion_code" if name == "completed" else "failure_code"),
                     f"expected letters, digits, '_' or '-' (at most 64), got {code!r}")
        if action not in ACTIONS:
            chk.fail(f"{where}.action", f"expected one of {', '.join(ACTIONS)}, got {action!r}")
        out[name] = OutcomeCode(name, code, action)
    done = out["completed"].code
    for name, oc in out.items():
        if name != "completed" and done and oc.code == done:
            field = f"outcomes.{name}" if name in given else "failure_code"
            chk.fail(field, f"the same code as completed ({done!r}); expected a different code, or a participant "
                     "who did not complete would be paid as one who did")
    return out


def outcome_of(status: str, end_reason: str | None) -> str | None:
    """The outcome of a session that has ended (None while it is active)."""
    if status == "finished":
        return "completed"
    if status == "expired":
        return "timed_out"
    if status == "failed":
        return _REASONS.get(end_reason or "", "screened_out")
    return None


def code_for(study: Any, status: str, end_reason: str | None) -> OutcomeCode | None:
    """The outcome code a session with this status and end reason gets (None while active)."""
    outcome = outcome_of(status, end_reason)
    if outcome is None:
        return None
    outcomes = getattr(study, "outcomes", None) or {}
    if outcome in outcomes:
        return outcomes[outcome]
    code = study.completion_code if outcome == "completed" else study.failure_code
    return OutcomeCode(outcome, code, DEFAULT_ACTIONS[outcome])
