"""Session policy, pure (no database, no Flask): what happens to a session after an answer.

:func:`after_answer` takes the session's counters and the answer's :class:`~study_app.pages.Outcome` and
returns the :class:`Transition`: the next page, the updated counters, and whether the session ends
(``finished`` on reaching the page that completes it; ``failed`` for a filled-in honeypot, a reason the
page kind gives such as a failed headphone screening, or too many failed attention checks) and whether its
plan is released for someone else (a failed participant's data is excluded, so by default their plan is
handed out again).
"""
from __future__ import annotations

from dataclasses import dataclass

from study_app.pages import Outcome, get_kind

__all__ = ["SessionState", "Transition", "Rules", "after_answer", "plan_after_end"]


@dataclass(frozen=True)
class SessionState:
    current_page: int
    passed_checks: int = 0
    failed_checks: int = 0


@dataclass(frozen=True)
class Rules:
    max_failed_attention_checks: int = 2
    release_failed: bool = True
    reservation_minutes: float = 100.0
    # Interaction-log caps: events beyond them are not stored (docs/study_app.md, section 6).
    events_per_page: int = 1000
    events_per_session: int = 10000

    @classmethod
    def of(cls, study) -> Rules:
        return cls(study.max_failed_attention_checks, study.release_failed, study.reservation_minutes)


@dataclass(frozen=True)
class Transition:
    current_page: int
    passed_checks: int
    failed_checks: int
    status: str = "active"              # "active" | "finished" | "failed"
    end_reason: str | None = None       # completed | honeypot | attention_checks | a kind's reason
    honeypot: bool = False

    @property
    def ended(self) -> bool:
        return self.status != "active"


def after_answer(state: SessionState, outcome: Outcome, pages: list[dict], rules: Rules) -> Transition:
    """The session after the answer to page ``state.current_page`` (see the module docstring)."""
    passed = state.passed_checks + (outcome.attention is True)
    failed = state.failed_checks + (outcome.attention is False)
    nxt = state.current_page + 1
    status, reason = "active", None
    if outcome.honeypot:
        status, reason = "failed", "honeypot"
    elif outcome.end_reason:
        status, reason = "failed", outcome.end_reason
    elif failed >= rules.max_failed_attention_checks:
        status, reason = "failed", "attention_checks"
    elif nxt < len(pages) and get_kind(pages[nxt]["type"]).position == "last":
        status, reason = "finished", "completed"
    return Transition(current_page=nxt, passed_checks=passed, failed_checks=failed, status=status,
                      end_reason=reason, honeypot=outcome.honeypot)


def plan_after_end(status: str, rules: Rules, reason: str | None = None) -> str:
    """``used`` (kept with the session) or ``free`` (handed out again) for a plan whose session ended; a
    participant who did not consent answered nothing, so theirs is always handed out again."""
    if reason == "no_consent":
        return "free"
    return "used" if status == "finished" or not rules.release_failed else "free"
