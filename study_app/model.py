"""The study's data model: stimuli of the manifest, definition pages, the study; and shared constants."""
from __future__ import annotations

import pathlib
import re
from dataclasses import dataclass, field

from evalsuite.contracts import manifest as manifest_contract

ID_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
PLATFORMS = ("prolific", "mturk", "anonymous")
MANIFEST_REQUIRED = manifest_contract.REQUIRED
MANIFEST_KINDS = manifest_contract.KINDS


@dataclass(frozen=True)
class Stimulus:
    """One row of the stimulus manifest: a blinded video file and what it shows."""

    file: str
    condition: str
    segment: str
    kind: str = "stimulus"          # "stimulus" or "attention"
    expected: str = ""              # attention checks: the answer an attentive participant gives
    motion_segment: str = ""        # mismatched stimuli: the segment the motion comes from
    block: str = ""                 # attention checks: restrict to this block id
    duration_s: float | None = None  # the clip's length (optional column; else read from the file)
    check: str = ""                 # attention checks: how it was made (``distorted_audio``, ``instruction``, ...)
    line: int = 0
    audio_segment: str = ""         # derived audio-mismatched clips: the segment the speech comes from
    silent: bool = False            # derived video-only clips (muted blocks): the file has no sound

    @property
    def audio_mismatched(self) -> bool:
        """Motion of ``segment`` with another segment's speech (:mod:`study_app.derived`)."""
        return bool(self.audio_segment) and self.audio_segment != self.segment

    @property
    def needs_sound(self) -> bool:
        """An attention check only sound reveals (nobody can pass it in a muted block)."""
        return self.kind == "attention" and self.check in manifest_contract.AUDIO_CHECKS

    @property
    def mismatched(self) -> bool:
        return bool(self.motion_segment) and self.motion_segment != self.segment


@dataclass(frozen=True)
class DerivedClip:
    """A clip ``study build`` makes from manifest clips (:mod:`study_app.derived`): the video stream of
    ``video`` (copied, not re-encoded) with the sound of ``audio`` (AAC, cut or padded to ``seconds``), or
    no sound when ``audio`` is empty."""

    stimulus: Stimulus
    video: str
    audio: str = ""
    seconds: float | None = None


@dataclass
class Manifest:
    path: pathlib.Path
    root: pathlib.Path              # folder the file names are relative to
    stimuli: list[Stimulus]
    sha256: str
    # file -> clip made by `study build` (audio-mismatched and video-only variants; study_app.derived)
    derived: dict[str, DerivedClip] = field(default_factory=dict)
    # embodiment column -> its distinct values over the rows that have it (contracts.manifest.EMBODIMENT)
    embodiment: dict[str, list[str]] = field(default_factory=dict)

    def by_file(self) -> dict[str, Stimulus]:
        """Every clip a plan can name: the manifest's rows and the derived clips."""
        out = {s.file: s for s in self.stimuli}
        out.update((f, d.stimulus) for f, d in self.derived.items())
        return out


@dataclass
class Page:
    """One entry of the definition's ``pages`` list (a block expands to several plan pages)."""

    id: str
    type: str
    cfg: dict = field(default_factory=dict)


@dataclass
class Study:
    id: str
    title: str
    path: pathlib.Path
    manifest: Manifest
    pages: list[Page]
    platform: str = "anonymous"
    sessions: int = 10
    seed: int = 0
    completion_code: str = ""
    failure_code: str = ""
    max_failed_attention_checks: int = 2
    reservation_minutes: float = 100.0
    require_full_playback: bool = True
    min_width: int = 1100
    block_mobile: bool = True
    resume: bool = True
    release_failed: bool = True
    prolific_study_id: str = ""
    redirect_seconds: int = 0
    # At most this many new sessions per client address within the window (0: no limit).
    new_sessions_per_address: int = 10
    new_sessions_window_minutes: float = 60.0
    # A page is flagged when its time is below this fraction of its longest clip (study_app.playback).
    playback_min_fraction: float = 1.0
    sha256: str = ""
    # outcome -> study_app.outcomes.OutcomeCode (code and review action per way a session ends)
    outcomes: dict = field(default_factory=dict)

    @property
    def blocks(self) -> dict[str, Page]:
        """Rating pages (``pairwise``, ``mushra``, ``likert``, ... every registered block kind) by id."""
        from study_app.pages import get_kind

        return {p.id: p for p in self.pages if get_kind(p.type).block}

    def kind_of(self, page: Page):
        """The registered page kind of a definition page (:mod:`study_app.pages`)."""
        from study_app.pages import get_kind

        return get_kind(page.type)

    def page(self, page_id: str) -> Page:
        for p in self.pages:
            if p.id == page_id:
                return p
        raise KeyError(page_id)

    @property
    def conditions(self) -> list[str]:
        """Every condition name a participant must never see (used by leak checks too)."""
        return sorted({s.condition for s in self.manifest.stimuli if s.kind == "stimulus"})

    def completion_url(self, code: str) -> str:
        return f"https://app.prolific.com/submissions/complete?cc={code}"
