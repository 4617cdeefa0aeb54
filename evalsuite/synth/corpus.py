"""Writing a synthetic-speaker corpus: :func:`synthesize_corpus`.

Per segment (about ``segment_s`` seconds of several sentences): sentences from the grammar (unique across
the whole corpus, so splits share no sentence), emphasis flags, espeak-ng speech laid out word by word
(gaps of ``word_gap_s`` between words, ``phrase_pause_s`` at commas, ``sentence_pause_s`` between
sentences and now and then a ``long_pause_s`` in which the speaker returns to rest), and the motion
model's performance of it (:func:`evalsuite.synth.model.oracle_motion` with the segment's own
motion seed). Everything is seeded: one seed gives byte-identical files on one machine.
"""
from __future__ import annotations

import json
import pathlib
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from evalsuite.audio import write_wav
from evalsuite.corpus.types import Transcript, Word
from evalsuite.errors import InputError
from evalsuite.motion.bvh_writer import format_bvh
from evalsuite.synth.grammar import KEYWORD_CLASSES, LEXICON, choose_emphasis, make_sentence
from evalsuite.synth.layout import FORMAT, FORMAT_VERSION, SPLIT_DIRS, format_tsv, segment_paths
from evalsuite.synth.model import oracle_motion
from evalsuite.synth.params import KINDS, PHASES, MotionParams
from evalsuite.synth.skeletons import SKELETONS, retarget, smplx_rotations
from evalsuite.synth.speech import Voice, WordBank, espeak_version

__all__ = ["Layout", "synthesize_corpus", "assign_splits"]


@dataclass(frozen=True)
class Layout:
    """How sentences become a segment's timeline (seconds; pairs are uniform ranges)."""

    segment_s: float = 20.0
    lead_s: tuple[float, float] = (0.3, 0.6)
    word_gap_s: tuple[float, float] = (0.03, 0.09)
    phrase_pause_s: tuple[float, float] = (0.25, 0.45)
    sentence_pause_s: tuple[float, float] = (0.5, 1.0)
    long_pause_p: float = 0.2
    long_pause_s: tuple[float, float] = (1.6, 2.6)
    tail_s: float = 0.5
    emphasis_rate: float = 0.25


def assign_splits(n: int, rng: np.random.Generator, val: float = 0.1, test: float = 0.1) -> list[str]:
    """Split names for ``n`` segments: a seeded permutation, at least one val and one test segment when n >= 3,
    and two test segments when n >= 8 (conditions such as ``mismatched`` need two)."""
    n_val = max(1 if n >= 3 else 0, int(round(val * n)))
    n_test = max(2 if n >= 8 else 1 if n >= 3 else 0, int(round(test * n)))
    names = ["val"] * n_val + ["test"] * n_test + ["train"] * (n - n_val - n_test)
    return [names[i] for i in rng.permutation(n)]


def _u(rng: np.random.Generator, pair: tuple[float, float]) -> float:
    return float(rng.uniform(pair[0], pair[1]))


def _sentences(rng: np.random.Generator, n: int, used: set[str], emphasis_rate: float) -> list[tuple[list[str], list[bool], list[int]]]:
    """``n`` new sentences: words, emphasis flags and the number of words of each phrase."""
    out: list[tuple[list[str], list[bool], list[int]]] = []
    tries = 0
    while len(out) < n:
        s = make_sentence(rng)
        tries += 1
        if s.text in used:
            if tries > 200 * n + 1000:
                raise InputError("the grammar has run out of new sentences for a corpus this long")
            continue
        used.add(s.text)
        words = s.words
        out.append((words, choose_emphasis(words, rng, emphasis_rate), [len(p) for p in s]))
    return out


def _segment_audio(sentences: list[tuple[list[str], list[bool], list[int]]], bank: WordBank, layout: Layout,
                   rng: np.random.Generator) -> tuple[np.ndarray, Transcript, list[bool], list[str], float]:
    """Lay out sentences until ``segment_s``: int16 samples, transcript, emphasis, sentence texts, duration."""
    rate = bank.rate or 22050
    pieces: list[np.ndarray] = []
    pos = int(round(_u(rng, layout.lead_s) * rate))
    pieces.append(np.zeros(pos, dtype=np.int16))
    words: list[Word] = []
    flags: list[bool] = []
    texts: list[str] = []
    for k, (sent, emph, phrase_lens) in enumerate(sentences):
        spoken = sum(len(bank[(w, e)]) for w, e in zip(sent, emph)) / rate + 0.06 * len(sent) + 0.8
        if k and pos / rate + spoken > layout.segment_s and pos / rate > 0.6 * layout.segment_s:
            break           # the next sentence (with its pause) would not fit, and the segment is long enough
        if k:
            pause = _u(rng, layout.long_pause_s) if rng.random() < layout.long_pause_p else _u(rng, layout.sentence_pause_s)
            pieces.append(np.zeros(int(round(pause * rate)), dtype=np.int16))
            pos += len(pieces[-1])
        ends = set(np.cumsum(phrase_lens)[:-1].tolist())
        for i, (w, e) in enumerate(zip(sent, emph)):
            if i:
                gap = _u(rng, layout.phrase_pause_s) if i in ends else _u(rng, layout.word_gap_s)
                pieces.append(np.zeros(int(round(gap * rate)), dtype=np.int16))
                pos += len(pieces[-1])
            clip = bank[(w, e)]
            words.append(Word(w, round(pos / rate, 6), round((pos + len(clip)) / rate, 6)))
            flags.append(e)
            pieces.append(clip)
            pos += len(clip)
        texts.append(" ".join(sent))
    pieces.append(np.zeros(int(round(layout.tail_s * rate)), dtype=np.int16))
    audio = np.concatenate(pieces)
    return audio, Transcript(tuple(words)), flags, texts, len(audio) / rate


def _word_onsets(audio: np.ndarray, rate: int, transcript: Transcript) -> list[list[float]]:
    """Acoustic onsets in each word (s after its start, 4 decimals): the spectral-flux onsets of the segment's
    speech (:func:`evalsuite.metrics.beats.audio_onsets`, what beat alignment measures) that fall in it."""
    from evalsuite.metrics.beats import audio_onsets

    on = audio_onsets(audio / 32768.0, rate)
    return [[round(float(o - w.start), 4) for o in on if w.start <= o < w.end] for w in transcript.words]


def _write_motion(path: pathlib.Path, motion: Any, skeleton: str, fps: float) -> None:
    """The segment's motion on ``skeleton``: BVH, or SMPL-X rotations (``<id>.npz`` in the same folder)."""
    if skeleton == "smplx":
        from evalsuite.motion.smplx import SmplxData, write_smplx

        poses, trans = smplx_rotations(motion)
        write_smplx(path.with_suffix(".npz"), SmplxData(poses, trans, np.zeros(0), model="smplx2020",
                                                         gender="neutral", fps=fps))
        return
    m = retarget(motion, skeleton)
    path.write_text(format_bvh(m.skeleton, m.values, 1.0 / fps), encoding="utf-8", newline="\n")


def synthesize_corpus(out_dir: str | pathlib.Path, minutes: float, seed: int = 0, *, layout: Layout | None = None,
                      voice: Voice | None = None, params: MotionParams | None = None, speaker: str = "synth01",
                      jobs: int = 2, progress: bool = True, skeleton: str = "genea2020") -> dict[str, Any]:
    """Write a synthetic-speaker corpus of about ``minutes`` minutes to ``out_dir``; returns ``corpus.json``'s
    content. See docs/corpus.md § The synthetic speaker for the model and the files. ``skeleton``: the speaker's
    own (``genea2020``) or another one (:mod:`evalsuite.synth.skeletons`)."""
    from tqdm import tqdm

    layout, voice, params = layout or Layout(), voice or Voice(), params or MotionParams()
    if not minutes > 0:
        raise InputError(f"minutes must be positive, got {minutes!r}", field="minutes")
    if skeleton not in SKELETONS:
        raise InputError(f"unknown skeleton {skeleton!r}; expected one of {', '.join(SKELETONS)}", field="--skeleton")
    root = pathlib.Path(out_dir)
    if root.exists() and any(root.iterdir()):
        raise InputError("the output folder exists and is not empty", path=root)
    n_seg = max(3, int(round(minutes * 60.0 / (layout.segment_s - 2.5))))   # segments average segment_s - 2.5 s
    splits = assign_splits(n_seg, np.random.default_rng([seed, 1]))
    text_rng = np.random.default_rng([seed, 0])
    used: set[str] = set()
    per_seg = int(np.ceil(layout.segment_s / 2.0)) + 2     # sentences take > 2 s each with their pauses
    pools = [_sentences(text_rng, per_seg, used, layout.emphasis_rate) for _ in range(n_seg)]
    bank = WordBank(voice, jobs)
    bank.add((w, e) for pool in pools for sent, emph, _ in pool for w, e in zip(sent, emph))
    meta: dict[str, Any] = {
        "format": FORMAT, "format_version": FORMAT_VERSION, "seed": int(seed), "minutes": float(minutes),
        "speaker": speaker, "fps": params.fps, "sample_rate": bank.rate, "espeak_ng": espeak_version(),
        "voice": asdict(voice), "layout": {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(layout).items()},
        "model": {"name": "evalsuite.synth.model", "version": 1, "params": params.to_dict(),
                  "phases": list(PHASES), "kinds": list(KINDS)},
        "keyword_classes": {c: list(ws) for c, ws in KEYWORD_CLASSES.items()},
        "lexicon": {k: list(v) for k, v in LEXICON.items()},
        "split_dirs": SPLIT_DIRS, "splits": {s: [] for s in SPLIT_DIRS}, "segments": {},
    }
    if skeleton != "genea2020":
        meta["skeleton"] = skeleton
    for idx in tqdm(range(n_seg), desc="synthetic speaker", unit="segment", disable=not progress):
        seg_id, split = f"seg_{idx:03d}", splits[idx]
        rng = np.random.default_rng([seed, 2, idx])
        audio, transcript, flags, texts, duration = _segment_audio(pools[idx], bank, layout, rng)
        motion_seed = int(np.random.SeedSequence([seed, 3, idx]).generate_state(1)[0])
        onsets = _word_onsets(audio.astype(np.float64), int(bank.rate or 22050), transcript)
        motion, labels = oracle_motion(transcript, duration, motion_seed, flags, params, name=seg_id, onsets=onsets)
        paths = segment_paths(root, split, seg_id)
        for p in paths.values():
            p.parent.mkdir(parents=True, exist_ok=True)
        write_wav(paths["wav"], audio.astype(np.float64) / 32768.0, int(bank.rate or 22050))
        _write_motion(paths["bvh"], motion, skeleton, params.fps)
        paths["tsv"].write_text(format_tsv(transcript), encoding="utf-8", newline="\n")
        paths["labels"].write_text(labels.to_csv(), encoding="utf-8", newline="\n")
        meta["splits"][split].append(seg_id)
        meta["segments"][seg_id] = {"split": split, "duration": duration, "n_frames": motion.n_frames,
                                    "motion_seed": motion_seed, "n_words": len(transcript),
                                    "emphasis": [i for i, f in enumerate(flags) if f], "onsets": onsets,
                                    "sentences": texts}
    for split, ids in meta["splits"].items():  # GENEA 2023's metadata.csv: the speaker of each recording
        if ids:
            rows = "".join(f"{i},{speaker},False,,\n" for i in ids)
            (root / SPLIT_DIRS[split] / "metadata.csv").write_text(
                "prefix,main-agent_id,main-agent_has_fingers,interloctr_id,interloctr_has_fingers\n" + rows,
                encoding="utf-8", newline="\n")
    (root / "corpus.json").write_text(json.dumps(meta, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return meta
