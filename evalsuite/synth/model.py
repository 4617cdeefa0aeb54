"""The synthetic speaker's procedural motion model, and the oracle: the same model run on any transcript.

Given words with times and emphasis flags, a seed and :class:`MotionParams`, :func:`oracle_motion`

1. **plans gesture units** (:func:`plan_gestures`): a keyword of a class (grammar.KEYWORD_CLASSES) gets its
   semantic gesture with probability ``semantic_p``, an emphasised ordinary word a beat with probability
   ``beat_p``. A beat's stroke (``beat_stroke_s``) ends ``lag`` after the word's onset, a semantic stroke
   (``semantic_stroke_s``; a head shake: ``shake_cycles`` at ``shake_hz``) starts ``lag`` after it; before
   the stroke comes the preparation (``prep_s``); after it a hold (beats: ``beat_hold_s``; semantic: until
   ``semantic_hold_s`` after the keyword's end) and a retraction (``retract_s``) to rest of each arm whose
   next unit leaves it free for ``retract_s + rest_gap_s`` (otherwise the arm holds until its next
   preparation). Arm units are sequential: a unit whose stroke would start less than ``min_prep_s`` after
   the previous unit's hold ends is dropped (a beat gives way to a semantic gesture). Negation is a head
   shake: it uses no arm and never conflicts.
2. **renders** the units as keyframe tracks of arm poses (body.POSES) with minimum-jerk transitions, adds
   *batons* (on each syllable the forearms flick out to ``baton_deg/2`` x gain x min(1.5, syllable
   duration / 0.2 s) at ``baton_apex`` of the syllable and back by its end (``baton="rebound"``, the two
   movement phases of a beat); ``baton="alternate"``, the model before 0.2, flicks up on one syllable and
   down on the next; minimum-jerk profiles, lagged ``baton_lag_s``: wrist speed follows speech and stops
   at syllable onsets), nods on emphasised words, head shakes, breathing and sway,
   and labels each frame with the phase, gesture kind and keyword of the unit it belongs to.

Every random number is drawn in a fixed order whatever the switches, so the switches change only what
they name: the same seed with ``offset_s=0.6`` is the same performance 0.6 s late.
"""
from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from evalsuite.corpus.types import Transcript
from evalsuite.motion.motion import Motion
from evalsuite.synth.body import ARM_CHANNELS, Track, arm_pose, channel_index, upper_body_skeleton
from evalsuite.synth.grammar import keyword_class
from evalsuite.synth.params import MotionParams

__all__ = ["Unit", "FrameLabels", "plan_gestures", "oracle_motion", "syllable_onsets"]

_ARM_KINDS = {"beat": "beat", "up": "up", "wide": "wide", "self": "self", "point": "point"}
_N_DRAWS = 9  # random numbers per word, always drawn


@dataclass
class Unit:
    """One gesture unit: kind, trigger word, arms used ('R', 'L', 'RL'; '' for the head), phase times."""

    kind: str
    keyword: str
    word: int
    arms: str
    prep_start: float
    stroke_start: float
    stroke_end: float
    hold_end: float
    retract_s: float
    amplitude: float
    end: float = 0.0          # end of the retraction (or of the hold, when the next unit follows on)
    retracts: bool = True
    retract_arms: str = ""    # the arms that return to rest after the hold


@dataclass
class FrameLabels:
    """Per-frame labels: ``phase`` (rest, preparation, stroke, hold, retraction), ``kind`` (none, beat, up,
    wide, self, point, negation) and the ``keyword`` that triggered the gesture ('' for none)."""

    phase: np.ndarray
    kind: np.ndarray
    keyword: np.ndarray

    def to_csv(self) -> str:
        rows = ["frame,phase,kind,keyword"]
        rows += [f"{i},{p},{k},{w}" for i, (p, k, w) in enumerate(zip(self.phase, self.kind, self.keyword))]
        return "\n".join(rows) + "\n"


def _uniform(u: float, rng_pair: tuple[float, float]) -> float:
    return rng_pair[0] + u * (rng_pair[1] - rng_pair[0])


def plan_gestures(transcript: Transcript, emphasis: list[bool], params: MotionParams,
                  draws: np.ndarray) -> list[Unit]:
    """Gesture units of a transcript; ``draws`` is ``(n_words, 9)`` uniform numbers (see the module doc)."""
    p = params
    units: list[Unit] = []
    for i, (w, emph) in enumerate(zip(transcript.words, emphasis)):
        u = draws[i]
        cls = keyword_class(w.text)
        if cls is not None:
            if not (p.semantic and u[0] < p.semantic_p):
                continue
            kind, lag, stroke = cls, _uniform(u[1], p.semantic_lag_s), _uniform(u[2], p.semantic_stroke_s)
        elif emph:
            if not (p.beats and u[0] < p.beat_p):
                continue
            kind, lag, stroke = "beat", _uniform(u[1], p.beat_lag_s), _uniform(u[2], p.beat_stroke_s)
        else:
            continue
        hands = "R" if u[6] < p.hands_p[0] else ("L" if u[6] < p.hands_p[0] + p.hands_p[1] else "RL")
        arms = {"wide": "RL", "negation": ""}.get(kind, hands)
        onset = w.start + p.offset_s
        stroke_end = onset + lag            # a beat's stroke ends on the emphasised syllable
        if kind != "beat":                  # a semantic stroke starts with its keyword (a shake: no arm)
            stroke = p.shake_cycles / p.shake_hz if kind == "negation" else stroke
            stroke_end = onset + lag + stroke
        hold = _uniform(u[4], p.beat_hold_s) if kind == "beat" else (
            w.end + p.offset_s + _uniform(u[4], p.semantic_hold_s) - stroke_end)
        units.append(Unit(kind, w.text, i, arms, stroke_end - stroke - _uniform(u[3], p.prep_s),
                          stroke_end - stroke, stroke_end, stroke_end + max(hold, 0.05),
                          _uniform(u[5], p.retract_s), _uniform(u[7], p.gesture_amplitude) * p.amplitude))
    kept: list[Unit] = []
    shakes = [u for u in units if u.kind == "negation"]      # the head is free: shakes never conflict
    for unit in (u for u in units if u.kind != "negation"):
        while kept and unit.stroke_start < kept[-1].hold_end + p.min_prep_s:
            if unit.kind != "beat" and kept[-1].kind == "beat":
                kept.pop()          # a semantic gesture wins over a beat
                continue
            break
        if kept and unit.stroke_start < kept[-1].hold_end + p.min_prep_s:
            continue
        if kept:
            unit.prep_start = max(unit.prep_start, kept[-1].hold_end)
        kept.append(unit)
    for unit in shakes:
        unit.end = unit.hold_end
    for k, unit in enumerate(kept):
        # an arm retracts when its next unit leaves it free long enough; otherwise it holds until then
        for arm in unit.arms:
            nxt_arm = next((v for v in kept[k + 1:] if arm in v.arms), None)
            if nxt_arm is None or nxt_arm.prep_start - unit.hold_end >= unit.retract_s + p.rest_gap_s:
                unit.retract_arms += arm
        unit.retracts = bool(unit.retract_arms)
        nxt = kept[k + 1] if k + 1 < len(kept) else None
        unit.end = unit.hold_end + unit.retract_s if unit.retracts else (nxt.prep_start if nxt else unit.hold_end)
    return sorted(kept + shakes, key=lambda u: u.stroke_start)


def _arm_tracks(units: list[Unit], params: MotionParams) -> dict[str, Track]:
    tracks = {s: Track(arm_pose("rest", s)) for s in ("Right", "Left")}
    for unit in units:
        for side in ("Right", "Left"):
            if side[0] not in unit.arms:
                continue
            tr, rest = tracks[side], arm_pose("rest", side)
            a = unit.amplitude
            if unit.kind == "beat":
                ready = rest + a * (arm_pose("ready", side) - rest)
                target = rest + a * (arm_pose("beat", side) - rest)
            else:
                target = rest + a * (arm_pose(unit.kind, side) - rest)
                ready = rest + 0.45 * (target - rest)
            tr.hold(unit.prep_start)
            tr.key(unit.stroke_start, ready)
            tr.key(unit.stroke_end, target)
            tr.key(unit.hold_end, target)
            if side[0] in unit.retract_arms:
                tr.key(unit.hold_end + unit.retract_s, rest)
    return tracks


def _labels(units: list[Unit], t: np.ndarray) -> FrameLabels:
    n = len(t)
    phase = np.full(n, "rest", dtype=object)
    kind = np.full(n, "none", dtype=object)
    keyword = np.full(n, "", dtype=object)
    for unit in sorted(units, key=lambda u: u.kind == "negation"):     # arm gestures first, then head shakes
        stops = ((unit.prep_start, "preparation"), (unit.stroke_start, "stroke"), (unit.stroke_end, "hold"),
                 (unit.hold_end, "retraction" if unit.retracts else "hold"), (unit.end, None))
        for (a, name), (b, _) in zip(stops[:-1], stops[1:]):
            sel = (t >= a) & (t < b)
            if unit.kind == "negation":  # a head shake labels the frames where the arms rest or hold
                sel &= (phase == "rest") | (phase == "hold")
            phase[sel], kind[sel], keyword[sel] = name, unit.kind, unit.keyword
    return FrameLabels(phase.astype(str), kind.astype(str), keyword.astype(str))


def _bump(t: np.ndarray, start: float, length: float) -> np.ndarray:
    s = (t - start) / max(length, 1e-3)
    return np.where((s > 0) & (s < 1), np.sin(np.pi * np.clip(s, 0, 1)) ** 2, 0.0)


def syllable_onsets(transcript: Transcript) -> list[list[float]]:
    """Estimated onsets (s after the word's start) of each word's syllables, for transcripts whose audio
    onsets are unknown: ``k * d / n`` for ``k < n``, n = the number of vowel groups of the word."""
    out = []
    for w in transcript.words:
        n = max(1, len(re.findall(r"[aeiouy]+", w.text.lower().rstrip("e")) or [w.text]))
        out.append([round(k * w.duration / n, 4) for k in range(n)])
    return out


def oracle_motion(transcript: Transcript, duration: float, seed: int, emphasis: list[bool] | None = None,
                  params: MotionParams | None = None, name: str | None = None,
                  onsets: list[list[float]] | None = None) -> tuple[Motion, FrameLabels]:
    """The speaker model's motion for ``transcript`` (``duration`` s at ``params.fps``) and its labels.

    ``emphasis``: one flag per word (default: none emphasised). ``onsets``: per word, the times (s after
    its start) of the acoustic onsets in it, where one baton flick ends and the next begins (default:
    :func:`syllable_onsets`; a synthetic corpus stores the onsets of its speech). With a segment's own motion seed and
    emphasis (corpus.json) this reproduces the corpus's motion exactly; another seed gives another
    performance of the same speech.
    """
    p = params or MotionParams()
    flags = list(emphasis) if emphasis is not None else [False] * len(transcript)
    if len(flags) != len(transcript):
        raise ValueError(f"emphasis has {len(flags)} flags for {len(transcript)} words")
    syl = onsets if onsets is not None else syllable_onsets(transcript)
    if len(syl) != len(transcript):
        raise ValueError(f"onsets has {len(syl)} entries for {len(transcript)} words")
    rng = np.random.default_rng(seed)
    idle = rng.uniform(size=12)
    draws = rng.uniform(size=(len(transcript), _N_DRAWS))
    units = plan_gestures(transcript, flags, p, draws)
    sk = upper_body_skeleton()
    n = int(round(duration * p.fps))
    t = np.arange(n) / p.fps
    values = np.zeros((n, sk.n_channels))
    values[:, channel_index(sk, "Hips", "Yposition")] = sk.offsets[0, 1]
    for side, tr in _arm_tracks([u for u in units if u.arms], p).items():
        vals = tr.sample(t)
        for c, (joint, ch) in enumerate(ARM_CHANNELS):
            values[:, channel_index(sk, side + joint, ch)] = vals[:, c]
    # batons: on every syllable the forearms flick (elbow flexion, minimum-jerk, out and back, or
    # alternately up and down), so wrist speed follows the speech and stops at syllable onsets;
    # nods on emphasised words
    baton = Track(np.zeros(1))
    nod = np.zeros(n)
    up = False
    if p.beats:
        for i, (w, emph) in enumerate(zip(transcript.words, flags)):
            gain = (p.emphasis_gain if emph else 1.0) * (0.7 + 0.6 * draws[i, 8])
            start = w.start + p.offset_s + p.baton_lag_s
            cuts = [0.0] + [float(o) for o in syl[i] if p.min_syllable_s <= o <= w.duration - p.min_syllable_s]
            cuts.append(w.duration)
            baton.hold(start)
            for a, b in zip(cuts[:-1], cuts[1:]):
                size = p.baton_deg * gain * min(1.5, (b - a) / 0.2)   # about the same speed on every syllable
                if p.baton == "rebound":    # out to size/2 and back within the syllable
                    baton.key(start + a + p.baton_apex * (b - a), np.array([size / 2]))
                    baton.key(start + b, np.array([0.0]))
                else:                       # "alternate": up on one syllable, down on the next
                    up = not up
                    baton.key(start + b, np.array([size / 2 if up else -size / 2]))
            if emph:
                nod += p.nod_deg * _bump(t, start, 0.35)
    flick = baton.sample(t)[:, 0] * p.amplitude
    values[:, channel_index(sk, "RightForeArm", "Yrotation")] += flick
    values[:, channel_index(sk, "LeftForeArm", "Yrotation")] -= 0.7 * flick
    values[:, channel_index(sk, "RightHand", "Zrotation")] += flick
    values[:, channel_index(sk, "Neck", "Xrotation")] += p.amplitude * nod
    for unit in units:
        if unit.kind == "negation":
            span = unit.stroke_end - unit.stroke_start
            env = _bump(t, unit.stroke_start - 0.1, span + 0.2) ** 0.5
            values[:, channel_index(sk, "Head", "Yrotation")] += (
                p.shake_deg * unit.amplitude * env * np.sin(2 * np.pi * p.shake_hz * (t - unit.stroke_start)))
    # breathing and sway (not speech-driven)
    breath = 2 * np.pi * _uniform(idle[0], p.breath_hz) * t + 2 * np.pi * idle[1]
    values[:, channel_index(sk, "Spine2", "Xrotation")] += p.breath_deg * np.sin(breath)
    values[:, channel_index(sk, "RightShoulder", "Zrotation")] += 0.8 * p.breath_deg * np.sin(breath)
    values[:, channel_index(sk, "LeftShoulder", "Zrotation")] -= 0.8 * p.breath_deg * np.sin(breath)
    for k, (joint, ch) in enumerate((("Spine", "Zrotation"), ("Spine", "Yrotation"), ("Spine1", "Xrotation"),
                                     ("Neck", "Yrotation"), ("Neck", "Zrotation"))):
        f = _uniform(idle[2 + k], p.sway_hz)
        values[:, channel_index(sk, joint, ch)] += p.sway_deg * np.sin(2 * np.pi * f * t + 2 * np.pi * idle[7 + k])
    motion = Motion(sk, values, p.fps, name=name)
    return motion, _labels(units, t)
