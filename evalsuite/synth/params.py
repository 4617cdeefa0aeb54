"""Parameters of the synthetic speaker's motion model (all stored in ``corpus.json``).

Times are seconds, angles degrees; a pair ``(lo, hi)`` is a uniform random range drawn per gesture.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

__all__ = ["MotionParams", "PHASES", "KINDS"]

PHASES = ("rest", "preparation", "stroke", "hold", "retraction")
KINDS = ("none", "beat", "up", "wide", "self", "point", "negation")


@dataclass(frozen=True)
class MotionParams:
    """The procedural model's parameters (see docs/corpus.md § The synthetic speaker for the formulas).

    The last four are the switches of the known-truth benchmark: ``offset_s`` delays every speech-driven
    event (beats, batons, nods, semantic gestures) by that many seconds; ``beats`` / ``semantic`` turn
    beat gestures (with word batons and nods) / semantic gestures (with head shakes) off; ``amplitude``
    scales every gesture's excursion from the rest pose (idle motion is not scaled).
    """

    fps: float = 30.0
    beat_p: float = 0.85                          # an emphasised ordinary word gets a beat
    semantic_p: float = 0.9                       # a keyword gets its class's semantic gesture
    beat_lag_s: tuple[float, float] = (0.03, 0.09)        # stroke end after the emphasised word's onset
    semantic_lag_s: tuple[float, float] = (0.04, 0.11)   # stroke start after the keyword's onset
    beat_stroke_s: tuple[float, float] = (0.2, 0.26)
    semantic_stroke_s: tuple[float, float] = (0.5, 0.6)
    prep_s: tuple[float, float] = (0.5, 0.65)
    min_prep_s: float = 0.2                        # a unit needs this long after the previous hold
    beat_hold_s: tuple[float, float] = (0.1, 0.16)
    semantic_hold_s: tuple[float, float] = (0.38, 0.52)  # after the keyword's end
    retract_s: tuple[float, float] = (1.3, 1.5)
    rest_gap_s: float = 0.6                       # retract when the arm is free at least this long after retraction
    gesture_amplitude: tuple[float, float] = (0.75, 0.9)
    hands_p: tuple[float, float, float] = (0.9, 0.02, 0.08)     # right, left, both (beats, raise, point, chest)
    baton_deg: float = 14.0                       # elbow flick per syllable, x emphasis_gain when emphasised
    emphasis_gain: float = 1.8
    baton_lag_s: float = 0.04
    # "rebound": out and back within each syllable (a beat's two movement phases, McNeill 1992), so the
    # flick's direction is known from the syllable alone; "alternate" (corpora before 0.2.0): up on one
    # syllable, down on the next, a direction set by the count of syllables since the segment began
    baton: str = "rebound"
    baton_apex: float = 0.5                       # the flick's turning point, as a fraction of the syllable
    min_syllable_s: float = 0.08                  # onsets closer than this to a word's edges do not cut it
    nod_deg: float = 5.0
    shake_deg: float = 14.0
    shake_hz: float = 2.5
    shake_cycles: float = 2.0
    breath_hz: tuple[float, float] = (0.2, 0.3)
    breath_deg: float = 0.8
    sway_deg: float = 0.8
    sway_hz: tuple[float, float] = (0.04, 0.2)
    offset_s: float = 0.0
    beats: bool = True
    semantic: bool = True
    amplitude: float = 1.0

    def replace(self, **changes: Any) -> MotionParams:
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(self).items()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> MotionParams:
        names = {f.name for f in dataclasses.fields(cls)}
        values: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items() if k in names}
        values.setdefault("baton", "alternate")   # corpora written before the field existed
        return cls(**values)

    def __post_init__(self) -> None:
        if self.baton not in ("rebound", "alternate"):
            raise ValueError(f"baton must be 'rebound' or 'alternate', got {self.baton!r}")
        if not 0.0 < self.baton_apex < 1.0:
            raise ValueError(f"baton_apex must be between 0 and 1, got {self.baton_apex}")
