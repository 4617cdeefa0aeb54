"""The oracle condition on a corpus segment, and emphasis for transcripts that come without it.

Emphasis is not in the GENEA TSV (kept standard); a synthetic corpus stores it in ``corpus.json``
(``segments.<id>.emphasis``: indices of emphasised words) with each segment's motion seed, so
:func:`segment_oracle` reproduces the corpus's motion exactly. For other transcripts,
:func:`emphasis_from_audio` re-derives it from the speech: a word is emphasised when its RMS is more
than ``ratio`` times the median word RMS of the segment (the synthetic speaker's emphasised words are
spoken at amplitude 170 against 90, about 1.9 times louder).
"""
from __future__ import annotations

import pathlib

import numpy as np

from evalsuite.corpus.synth.layout import read_synth_corpus
from evalsuite.corpus.synth.model import FrameLabels, oracle_motion
from evalsuite.corpus.synth.params import MotionParams
from evalsuite.corpus.types import Corpus, Transcript
from evalsuite.motion.motion import Motion

__all__ = ["segment_oracle", "emphasis_from_audio"]


def emphasis_from_audio(signal: np.ndarray, rate: int, transcript: Transcript, ratio: float = 1.4) -> list[bool]:
    """Emphasis flags from the loudness of each word: RMS over the word's span > ``ratio`` x median."""
    x = np.asarray(signal, dtype=np.float64)
    x = x.mean(axis=1) if x.ndim == 2 else x
    rms = []
    for w in transcript.words:
        seg = x[int(round(w.start * rate)): max(int(round(w.end * rate)), int(round(w.start * rate)) + 1)]
        rms.append(float(np.sqrt(np.mean(seg ** 2))) if seg.size else 0.0)
    if not rms:
        return []
    med = float(np.median(rms))
    return [r > ratio * med for r in rms]


def segment_oracle(corpus: Corpus | str | pathlib.Path, segment_id: str, seed: int | None = None,
                   params: MotionParams | None = None) -> tuple[Motion, FrameLabels]:
    """The model's performance of one corpus segment: with ``seed=None`` the segment's own motion seed (the
    corpus's motion, exactly), else another performance. ``params`` default to the corpus's model
    parameters (switches included: ``params.replace(offset_s=0.3)``)."""
    from evalsuite.corpus.synth.layout import read_meta

    if not isinstance(corpus, Corpus):
        corpus = read_synth_corpus(corpus)
    seg = corpus.get(segment_id)
    meta = corpus.meta if corpus.meta.get("model") else read_meta(corpus.root)
    p = params or MotionParams.from_dict(meta["model"]["params"])
    transcript = seg.transcript
    assert transcript is not None
    info = meta["segments"][segment_id]       # corpus.json is the source, whichever reader made the Corpus
    emphasised = set(info["emphasis"])
    flags = [i in emphasised for i in range(len(transcript))]
    s = int(info["motion_seed"]) if seed is None else int(seed)
    duration = float(info["n_frames"]) / p.fps
    onsets = info.get("onsets")
    return oracle_motion(transcript, duration, s, flags, p, name=segment_id, onsets=onsets)
