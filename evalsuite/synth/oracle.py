"""The oracle condition on a corpus segment, and emphasis for transcripts that come without it.

Emphasis is not in the GENEA TSV (kept standard); a synthetic corpus stores it in ``corpus.json``
(``segments.<id>.emphasis``: indices of emphasised words) with each segment's motion seed, so
:func:`segment_oracle` reproduces the corpus's motion exactly. For other transcripts,
:func:`emphasis_from_audio` re-derives it from the speech: a word is emphasised when its RMS is more
than ``ratio`` times the median word RMS of the segment (the synthetic speaker's emphasised words are
spoken at amplitude 170 against 90, about 1.9 times louder).
"""
from __future__ import annotations

import dataclasses
import pathlib
from typing import Any

import numpy as np

from evalsuite.corpus.types import Corpus, Transcript
from evalsuite.motion.motion import Motion
from evalsuite.synth.layout import read_meta, read_synth_corpus
from evalsuite.synth.model import FrameLabels, oracle_motion
from evalsuite.synth.params import MotionParams

__all__ = ["segment_oracle", "causal_mean_positions", "emphasis_from_audio"]


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


def _performance_inputs(corpus: Corpus, meta: dict, segment_id: str,
                        params: MotionParams | None) -> tuple[Transcript, list[bool], float, Any, MotionParams, int]:
    """What :func:`oracle_motion` needs for one segment: transcript, emphasis flags, duration (s), syllable
    onsets, the model's parameters and the segment's own motion seed (corpus.json is the source, whichever
    reader made the Corpus)."""
    p = params or MotionParams.from_dict(meta["model"]["params"])
    transcript = corpus.get(segment_id).transcript
    assert transcript is not None
    info = meta["segments"][segment_id]
    emphasised = set(info["emphasis"])
    flags = [i in emphasised for i in range(len(transcript))]
    return transcript, flags, float(info["n_frames"]) / p.fps, info.get("onsets"), p, int(info["motion_seed"])


def _meta(corpus: Corpus) -> dict:
    return corpus.meta if corpus.meta.get("model") else read_meta(corpus.root)


def segment_oracle(corpus: Corpus | str | pathlib.Path, segment_id: str, seed: int | None = None,
                   params: MotionParams | None = None) -> tuple[Motion, FrameLabels]:
    """The model's performance of one corpus segment: with ``seed=None`` the segment's own motion seed (the
    corpus's motion, exactly), else another performance. ``params`` default to the corpus's model
    parameters (switches included: ``params.replace(offset_s=0.3)``)."""
    if not isinstance(corpus, Corpus):
        corpus = read_synth_corpus(corpus)
    transcript, flags, duration, onsets, p, own_seed = _performance_inputs(corpus, _meta(corpus), segment_id, params)
    s = own_seed if seed is None else int(seed)
    return oracle_motion(transcript, duration, s, flags, p, name=segment_id, onsets=onsets)


def causal_mean_positions(corpus: Corpus, segment_id: str, k: int = 64, heard_after: float = 0.0,
                          seed: int = 0) -> Motion:
    """Estimated mean motion of one segment given only the speech heard so far: (n_frames, J, 3) world positions,
    as a positions :class:`Motion` at the corpus's rate.

    For each frame t, the words whose start + ``heard_after`` (s) is after t are not known yet: they are replaced
    by words drawn at random (with their emphasis) from the corpus's training transcripts, and the frame is the
    mean over ``k`` performances (motion seeds drawn too) of such speech. Word timings and syllable onsets stay the
    segment's. The mean of performances of the segment's own transcript estimates E[motion | whole speech]
    (:func:`segment_oracle`); this one E[motion_t | words begun by t]: what a causal model can reach, estimated, not
    a strict bound (it is told when the coming words start, which is generous, and it does not know the grammar,
    where a keyword may come, which a model can learn).
    """
    if k < 1:
        raise ValueError(f"k must be at least 1, got {k}")
    meta = _meta(corpus)
    transcript, flags, _, onsets, p, _ = _performance_inputs(corpus, meta, segment_id, None)
    vocabulary: list[tuple[str, bool]] = []      # (word, emphasised) of every training transcript
    for other in corpus.split("train"):
        emphasised = set(meta["segments"][other.id]["emphasis"])
        vocabulary += [(w.text, i in emphasised) for i, w in enumerate(other.transcript.words if other.transcript else ())]
    if not vocabulary:
        raise ValueError("the corpus's training split has no words to draw the coming words from")
    rng = np.random.default_rng(seed)
    words = transcript.words
    n = int(meta["segments"][segment_id]["n_frames"])
    heard = np.searchsorted(np.array([w.start for w in words]) + heard_after, np.arange(n) / p.fps, side="right")
    positions: np.ndarray | None = None
    first: Motion | None = None
    for n_heard in np.unique(heard):
        frames = np.nonzero(heard == n_heard)[0]
        total = np.zeros(())   # broadcasts to the frames' (F, J, 3) positions
        for _ in range(k):
            drawn = [vocabulary[j] for j in rng.integers(len(vocabulary), size=len(words) - n_heard)]
            said = list(words[:n_heard]) + [dataclasses.replace(w, text=text) for w, (text, _) in
                                            zip(words[n_heard:], drawn)]
            emph = flags[:n_heard] + [e for _, e in drawn]
            # up to the interval's last frame only: a frame's pose does not depend on the duration after it
            motion, _ = oracle_motion(Transcript(tuple(said)), (frames[-1] + 1) / p.fps, int(rng.integers(2 ** 31)),
                                      emph, p, name=segment_id, onsets=onsets)
            total = total + motion.positions()[frames]
            first = motion if first is None else first
        if positions is None:
            positions = np.zeros((n,) + total.shape[1:])
        positions[frames] = total / k
    assert positions is not None and first is not None
    return Motion.from_positions(positions, first.joint_names, first.fps, first.parents, name=segment_id)
