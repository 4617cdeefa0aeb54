"""Building generation requests: from a corpus split, or from one utterance without a corpus."""
from __future__ import annotations

import pathlib
from collections.abc import Sequence

from evalsuite.corpus.types import Corpus, Transcript
from evalsuite.errors import InputError
from evalsuite.generators.contract import GenerationRequest

__all__ = ["requests_from_corpus", "request_for_audio", "audio_duration"]


def audio_duration(path: str | pathlib.Path) -> float:
    """Duration in seconds of a WAV file (from its sample count and rate)."""
    from evalsuite.audio import read_wav

    samples, rate = read_wav(path)
    return len(samples) / float(rate)


def requests_from_corpus(corpus: Corpus, split: str | Sequence[str], fps: float, *,
                         segments: Sequence[str] | None = None) -> list[GenerationRequest]:
    """One request per segment of ``split`` (optionally only ``segments``), seed 0 (the runner derives the
    real seeds). The duration is the segment's (its audio's, when it has audio)."""
    if not fps > 0:
        raise InputError(f"fps must be positive, got {fps}", field="--fps")
    chosen = corpus.split(split)
    if segments:
        wanted = set(segments)
        missing = sorted(wanted - {s.id for s in chosen})
        if missing:
            raise InputError(f"no segment(s) {', '.join(missing)} in split {split}", path=corpus.root)
        chosen = tuple(s for s in chosen if s.id in wanted)
    out = []
    for s in chosen:
        duration = s.duration
        if duration is None and s.audio is not None:
            duration = audio_duration(s.audio)
        if duration is None:
            raise InputError(f"segment {s.id!r} has neither audio nor a known duration", path=corpus.root)
        out.append(GenerationRequest(segment_id=s.id, duration=float(duration), fps=float(fps), seed=0,
                                     audio=s.audio, transcript=s.transcript, speaker=s.speaker,
                                     interlocutor=s.interlocutor, segment=s))
    return out


def request_for_audio(audio: str | pathlib.Path, fps: float, transcript: Transcript | None = None,
                      segment_id: str | None = None) -> GenerationRequest:
    """A request for one utterance: its WAV (duration from the file) and optional transcript."""
    path = pathlib.Path(audio)
    return GenerationRequest(segment_id=segment_id or path.stem, duration=audio_duration(path), fps=float(fps),
                             seed=0, audio=path, transcript=transcript)
