"""The synthetic speaker: files and layout, real espeak-ng speech at the stated word times, motion and
labels, the oracle (exact reproduction, other seeds, switches), determinism and speed."""
from __future__ import annotations

import csv
import hashlib
import json
import pathlib
import subprocess
import time

import numpy as np
import pytest
from click.testing import CliRunner

from evalsuite.audio import read_wav
from evalsuite.cli import main
from evalsuite.motion.bvh_writer import format_bvh
from evalsuite.motion.io import load_motion
from evalsuite.motion.presets import resolve_joints
from evalsuite.synth import (
    KINDS,
    PHASES,
    Layout,
    MotionParams,
    emphasis_from_audio,
    keyword_class,
    read_synth_corpus,
    segment_oracle,
    synthesize_corpus,
)
from evalsuite.synth.speech import Voice, trim_silence

# espeak-ng is required (scripts/install-system-packages installs it); without it the synthesiser raises a
# clear InputError, so these tests fail instead of hiding a missing install step.


@pytest.fixture(scope="module")
def corpus_dir(tmp_path_factory) -> pathlib.Path:
    root = tmp_path_factory.mktemp("synth") / "corpus"
    synthesize_corpus(root, 2.0, seed=0, layout=Layout(segment_s=10.0), progress=False)
    return root


def _tree_hashes(root: pathlib.Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


def test_layout_files_and_corpus_json(corpus_dir):
    meta = json.loads((corpus_dir / "corpus.json").read_text())
    assert meta["format"] == "evalsuite-synthetic-speaker" and meta["format_version"] == 1
    assert meta["seed"] == 0 and meta["fps"] == 30.0 and meta["espeak_ng"].startswith("eSpeak NG")
    assert set(meta["keyword_classes"]) == {"up", "wide", "self", "point", "negation"}
    assert meta["model"]["params"]["baton_deg"] > 0 and meta["model"]["phases"] == list(PHASES)
    segs = meta["segments"]
    assert len(segs) == 16                     # 2 minutes in segments of 6.5-10.7 s (segment_s = 10)
    assert sorted(s for ids in meta["splits"].values() for s in ids) == sorted(segs)
    assert all(len(meta["splits"][k]) >= 1 for k in ("train", "val", "test"))
    for seg_id, info in segs.items():
        base = corpus_dir / {"train": "trn", "val": "val", "test": "tst"}[info["split"]] / "main-agent"
        for sub, ext in (("wav", "wav"), ("bvh", "bvh"), ("tsv", "tsv"), ("labels", "csv")):
            assert (base / sub / f"{seg_id}.{ext}").is_file()
        assert 6.0 <= info["duration"] <= 12.0
    # sentences are disjoint across splits (and unique within the corpus)
    by_split = {k: {t for s in ids for t in segs[s]["sentences"]} for k, ids in meta["splits"].items()}
    assert not (by_split["train"] & by_split["val"]) and not (by_split["train"] & by_split["test"])
    assert not (by_split["val"] & by_split["test"])
    corpus = read_synth_corpus(corpus_dir)
    assert len(corpus) == 16 and corpus.speakers == ("synth01",)
    assert {s.split for s in corpus} == {"train", "val", "test"}


def test_speech_is_espeak_at_the_word_times(corpus_dir):
    corpus = read_synth_corpus(corpus_dir)
    meta = corpus.meta
    voice = Voice(**meta["voice"])
    for seg in corpus:
        x, rate = read_wav(seg.audio)
        x = x[:, 0]
        words = seg.transcript.words
        # the word count matches the transcript and corpus.json's sentences
        assert len(words) == meta["segments"][seg.id]["n_words"]
        assert len(words) == sum(len(s.replace(",", "").split()) for s in meta["segments"][seg.id]["sentences"])
        inside = np.zeros(len(x), dtype=bool)
        for w in words:
            a, b = int(round(w.start * rate)), int(round(w.end * rate))
            rms = np.sqrt(np.mean(x[a:b] ** 2))
            assert rms > 0.01, (seg.id, w)     # speech inside every word
            inside[a:b] = True
        assert np.sqrt(np.mean(x[~inside] ** 2)) < 1e-4   # silence between words and in pauses
    # the samples of a word are espeak-ng's own output for it, trimmed: run it again and compare
    seg = corpus.segments[0]
    x, rate = read_wav(seg.audio, raw=True)
    emphasised = set(meta["segments"][seg.id]["emphasis"])
    for i in (0, sorted(emphasised)[0]):
        w = seg.transcript.words[i]
        e = i in emphasised
        out = subprocess.run(["espeak-ng", "-w", "/dev/stdout", "-v", voice.voice, "-s", str(voice.rate), "-a",
                              str(voice.emphasis_amplitude if e else voice.amplitude), "-p",
                              str(voice.emphasis_pitch if e else voice.pitch), w.text],
                             capture_output=True, check=True).stdout
        pcm = np.frombuffer(out[out.find(b"data") + 8:], dtype="<i2")
        clip = trim_silence(pcm, rate, voice.trim_threshold, voice.trim_margin_s)
        a = int(round(w.start * rate))
        assert np.array_equal(x[a:a + len(clip), 0], clip)
        assert abs((a + len(clip)) / rate - w.end) < 1e-5


def test_emphasis_is_louder_and_recoverable_from_audio(corpus_dir):
    corpus = read_synth_corpus(corpus_dir)
    hits = total = 0
    for seg in corpus:
        x, rate = read_wav(seg.audio)
        flags = [i in set(seg.meta["emphasis"]) for i in range(len(seg.transcript))]
        guess = emphasis_from_audio(x, rate, seg.transcript)
        hits += sum(a == b for a, b in zip(flags, guess))
        total += len(flags)
    assert hits / total > 0.9


def test_motion_skeleton_labels_and_plausible_positions(corpus_dir):
    corpus = read_synth_corpus(corpus_dir)
    seen_phases, seen_kinds = set(), set()
    for seg in corpus:
        m = seg.load_motion()
        assert m.fps == 30.0 and m.is_hierarchical
        assert m.n_frames == round(seg.duration * 30)
        resolve_joints("genea2020_upper", m.joint_names)          # the named presets apply
        with open(seg.labels, newline="") as fh:
            rows = list(csv.DictReader(fh))
        assert [int(r["frame"]) for r in rows] == list(range(m.n_frames))
        for r in rows:
            assert r["phase"] in PHASES and r["kind"] in KINDS
            assert (r["kind"] == "none") == (r["keyword"] == "") == (r["phase"] == "rest")
            if r["kind"] not in ("none", "beat"):
                assert keyword_class(r["keyword"]) == r["kind"]
        seen_phases |= {r["phase"] for r in rows}
        seen_kinds |= {r["kind"] for r in rows}
        pos = m.positions()
        names = m.joint_names
        head, hips = pos[:, names.index("Head")], pos[:, names.index("Hips")]
        for hand in ("RightHand", "LeftHand"):
            h = pos[:, names.index(hand)]
            assert (h[:, 1] > hips[:, 1] - 15).all() and (h[:, 1] < head[:, 1] + 45).all()   # cm
            assert (np.linalg.norm(h - pos[:, names.index(hand.replace("Hand", "Arm"))], axis=1) <= 53.01).all()
    assert seen_phases == set(PHASES)
    assert {"beat", "up", "wide", "self", "point", "negation"} <= seen_kinds


def test_wrists_move_more_while_speaking_and_rest_in_long_pauses(corpus_dir):
    corpus = read_synth_corpus(corpus_dir)
    speaking, pauses = [], []
    for seg in corpus:
        m = seg.load_motion()
        pos = m.positions()[:, [m.joint_index("RightHand"), m.joint_index("LeftHand")]]
        speed = np.linalg.norm(np.gradient(pos, axis=0), axis=2).mean(axis=1) * m.fps
        t = np.arange(m.n_frames) / m.fps
        gap = np.full(m.n_frames, np.inf)            # distance (s) to the nearest word
        for w in seg.transcript.words:
            gap = np.minimum(gap, np.clip(np.maximum(w.start - t, t - w.end), 0, None))
        speaking.append(speed[gap == 0])
        pauses.append(speed[gap > 0.4])
    # measured on this corpus: about 39 cm/s while speaking, 4.5 cm/s more than 0.4 s away from any word
    assert np.mean(np.concatenate(speaking)) > 4.0 * np.mean(np.concatenate(pauses))


def test_the_oracle_reproduces_the_corpus_exactly(corpus_dir):
    corpus = read_synth_corpus(corpus_dir)
    for seg in corpus:
        motion, labels = segment_oracle(corpus, seg.id)
        text = format_bvh(motion.skeleton, motion.values, 1.0 / motion.fps)
        assert text == seg.motion.read_text()
        assert labels.to_csv() == seg.labels.read_text()
        other, other_labels = segment_oracle(corpus, seg.id, seed=123)
        assert other.n_frames == motion.n_frames
        assert not np.allclose(other.values, motion.values)    # another performance of the same speech


def test_switches_of_the_known_truth_benchmark(corpus_dir):
    corpus = read_synth_corpus(corpus_dir)
    params = MotionParams.from_dict(corpus.meta["model"]["params"])
    seg = max(corpus, key=lambda s: s.duration)
    base, lab = segment_oracle(corpus, seg.id)
    _, no_beats = segment_oracle(corpus, seg.id, params=params.replace(beats=False))
    assert "beat" in set(lab.kind) and "beat" not in set(no_beats.kind)
    _, no_sem = segment_oracle(corpus, seg.id, params=params.replace(semantic=False))
    assert set(no_sem.kind) <= {"none", "beat"}
    # an offset delays the same performance: labels shift by exactly that many frames
    _, late = segment_oracle(corpus, seg.id, params=params.replace(offset_s=0.6))
    assert np.mean(late.phase[18:] == lab.phase[:-18]) > 0.99
    # the amplitude scales the excursion of the hands from rest
    half, _ = segment_oracle(corpus, seg.id, params=params.replace(amplitude=0.5))
    rest, _ = segment_oracle(corpus, seg.id, params=params.replace(beats=False, semantic=False))
    hand = base.joint_index("RightHand")
    full_dev = np.abs(base.positions()[:, hand] - rest.positions()[:, hand]).mean()
    half_dev = np.abs(half.positions()[:, hand] - rest.positions()[:, hand]).mean()
    assert 0.3 * full_dev < half_dev < 0.7 * full_dev


def test_one_seed_gives_byte_identical_files(tmp_path, corpus_dir):
    again = tmp_path / "again"
    synthesize_corpus(again, 2.0, seed=0, layout=Layout(segment_s=10.0), progress=False)
    assert _tree_hashes(again) == _tree_hashes(corpus_dir)
    other = tmp_path / "other"
    synthesize_corpus(other, 2.0, seed=1, layout=Layout(segment_s=10.0), progress=False)
    assert _tree_hashes(other) != _tree_hashes(corpus_dir)


def test_command_writes_a_corpus_and_refuses_a_full_folder(tmp_path):
    out = tmp_path / "c"
    runner = CliRunner()
    res = runner.invoke(main, ["corpus", "synth", "-o", str(out), "--minutes", "0.5", "--seed", "3",
                               "--segment-seconds", "10"])
    assert res.exit_code == 0, res.output
    assert "Wrote 4 segments" in res.output
    assert load_motion(next(out.rglob("*.bvh"))).fps == 30.0
    res = runner.invoke(main, ["corpus", "synth", "-o", str(out), "--minutes", "0.5", "--quiet"])
    assert res.exit_code == 1 and "not empty" in res.output


@pytest.mark.slow
def test_ten_minutes_in_under_a_minute(tmp_path):
    t0 = time.perf_counter()
    meta = synthesize_corpus(tmp_path / "c10", 10.0, seed=0, progress=False)
    elapsed = time.perf_counter() - t0
    assert elapsed < 60.0
    assert sum(s["duration"] for s in meta["segments"].values()) >= 9.5 * 60




def test_rebound_batons_go_out_and_back_within_each_syllable_and_old_corpora_keep_alternate():
    from evalsuite.corpus.types import Transcript, Word
    from evalsuite.synth.body import channel_index
    from evalsuite.synth.model import oracle_motion

    # one word of two syllables, cut at 0.25 s: no gesture unit (not emphasised, not a keyword)
    transcript = Transcript([Word("garden", 0.5, 1.0)])
    params = MotionParams(fps=100.0, sway_deg=0.0, breath_deg=0.0)
    onsets = [[0.0, 0.25]]
    m, _ = oracle_motion(transcript, 2.0, seed=1, params=params, onsets=onsets)
    alt, _ = oracle_motion(transcript, 2.0, seed=1, params=params.replace(baton="alternate"), onsets=onsets)
    col = channel_index(m.skeleton, "RightForeArm", "Yrotation")
    start = 0.5 + params.baton_lag_s
    at = {t: int(round(t * 100)) for t in (start, start + 0.125, start + 0.25, start + 0.375, start + 0.5)}
    rebound = m.values[:, col] - m.values[at[start], col]     # from the resting angle
    # out at the middle of each syllable, back to the starting angle at its end: the direction of every
    # flick is the same, whatever came before
    assert rebound[at[start + 0.125]] > 3.0 and rebound[at[start + 0.375]] > 3.0
    assert abs(rebound[at[start + 0.25]]) < 1e-6 and abs(rebound[at[start + 0.5]]) < 1e-6
    # the earlier form: up on the first syllable, down on the second
    a = alt.values[:, col] - alt.values[at[start], col]
    assert a[at[start + 0.25]] > 3.0 and a[at[start + 0.5]] < -3.0
    # a corpus.json written before the field existed is read as the alternate form
    old = {k: v for k, v in MotionParams().to_dict().items() if k not in ("baton", "baton_apex")}
    assert MotionParams.from_dict(old).baton == "alternate"
    assert MotionParams.from_dict(MotionParams().to_dict()).baton == "rebound"
    with pytest.raises(ValueError, match="baton must be"):
        MotionParams(baton="circle")
