"""Tiny corpus fixtures written at test time: WAVs (evalsuite.audio.write_wav), BVHs (synthetic motion and
evalsuite's BVH writer) and transcripts, in each layout evalsuite reads. No real data."""
from __future__ import annotations

import csv
import json
import pathlib

import numpy as np

from evalsuite.audio import write_wav
from evalsuite.corpus.transcripts import write_transcript
from evalsuite.corpus.types import Transcript, Word
from evalsuite.motion.bvh_writer import write_bvh
from evalsuite.motion.synthetic import synthetic_motion

WORDS = Transcript((Word("deep", 0.2, 0.5), Word("learning", 0.6, 1.1), Word("is", 1.2, 1.4)))


def wav(path: pathlib.Path, seconds: float, rate: int = 16000, channels: int = 1,
        voiced: tuple[float, float] | None = None) -> pathlib.Path:
    """A tone inside ``voiced`` (default: the whole file), silence outside."""
    path.parent.mkdir(parents=True, exist_ok=True)
    n = int(round(seconds * rate))
    t = np.arange(n) / rate
    x = 0.3 * np.sin(2 * np.pi * 220 * t)
    if voiced is not None:
        x[(t < voiced[0]) | (t >= voiced[1])] = 0.0
    write_wav(path, np.repeat(x[:, None], channels, axis=1), rate)
    return path


def bvh(path: pathlib.Path, seconds: float, fps: float = 30.0, seed: int = 0) -> pathlib.Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    m = synthetic_motion(n_joints=20, fps=fps, seconds=seconds, seed=seed)
    write_bvh(path, m.skeleton, m.values, 1.0 / fps)
    return path


def transcript(path: pathlib.Path, words: Transcript = WORDS) -> pathlib.Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    write_transcript(words, path)
    return path


def genea2020(root: pathlib.Path, n: int = 2) -> pathlib.Path:
    for k in range(1, n + 1):
        name = f"Recording_{k:03d}"
        wav(root / "Audio" / f"{name}.wav", 2.0 + k, rate=44100)
        bvh(root / "Motion" / f"{name}.bvh", 2.0 + k, fps=60)
        transcript(root / "Transcripts" / f"{name}.json")
    return root


def genea2023(root: pathlib.Path, *, dyadic: bool = True, year: int = 2023) -> pathlib.Path:
    """trn with two recordings (speakers 1 and 2), val with one, tst without main-agent motion."""
    agents = ("main-agent", "interloctr") if dyadic else ("",)
    meta_rows = {"trn": [("000", "01", "02"), ("001", "02", "01")], "val": [("000", "03", "01")],
                 "tst": [("000", "01", "03")]}
    for split, rows in meta_rows.items():
        # 2023: metadata.csv with a header; 2022: trn_2022_v1_metadata.csv without (fname, fingers, speaker)
        name = "metadata.csv" if dyadic else f"{split}_{year}_v1_metadata.csv"
        with open(_mk(root / split / name), "w", newline="") as fh:
            w = csv.writer(fh)
            if dyadic:
                w.writerow(["prefix", "main-agent_id", "main-agent_has_fingers", "interloctr_id",
                            "interloctr_has_fingers"])
            for sid, main, other in rows:
                prefix = f"{split}_{year}_v0_{sid}"
                w.writerow([prefix, main, "finger_incl", other, "finger_excl"] if dyadic
                           else [prefix, "finger_incl" if main != "02" else "finger_excl", main])
                for agent in agents:
                    base = root / split / agent if agent else root / split
                    stem = f"{prefix}_{agent}" if agent else prefix
                    wav(base / "wav" / f"{stem}.wav", 3.0)
                    if not (split == "tst" and agent != "interloctr"):
                        bvh(base / "bvh" / f"{stem}.bvh", 3.0)
                    transcript(base / "tsv" / f"{stem}.tsv")
    return root


def synth(root: pathlib.Path) -> pathlib.Path:
    genea2023(root)
    (root / "corpus.json").write_text(json.dumps({"model": "synthetic speaker v1", "seed": 7}))
    lab = _mk(root / "trn" / "main-agent" / "labels" / "trn_2023_v0_000.csv")
    lab.write_text("frame,phase,kind,keyword\n0,rest,,\n1,stroke,beat,\n")
    return root


def beat(root: pathlib.Path, table: bool = True) -> pathlib.Path:
    takes = [("1_wayne_0_1_1", "1"), ("1_wayne_0_2_2", "1"), ("2_scott_0_1_1", "2")]
    for stem, spk in takes:
        wav(root / spk / f"{stem}.wav", 2.0)
        bvh(root / spk / f"{stem}.bvh", 2.0, fps=120)
        transcript(root / spk / f"{stem}.TextGrid")
        (root / spk / f"{stem}.json").write_text('{"names": ["browDownLeft"], "frames": []}')  # facial, not words
        (root / spk / f"{stem}.txt").write_text("semantic labels, not a transcript\n")
    if table:
        (root / "train_test_split.csv").write_text("id,type\n1_wayne_0_1_1,train\n1_wayne_0_2_2,val\n"
                                                   "2_scott_0_1_1,test\n")
    return root


def zeggs(root: pathlib.Path) -> pathlib.Path:
    for stem in ("001_Neutral_0_x_1_0", "002_Happy_0_x_1_0"):
        wav(root / f"{stem}.wav", 2.0, rate=48000, channels=2)
        bvh(root / f"{stem}.bvh", 2.0, fps=60)
    return root


def folder(root: pathlib.Path) -> pathlib.Path:
    wav(root / "a.wav", 2.0)
    bvh(root / "a.bvh", 2.0)
    transcript(root / "a.tsv")
    wav(root / "b.wav", 2.5, voiced=(0.5, 2.0))
    bvh(root / "b.bvh", 2.5)
    (root / "b.txt").write_text("Deep learning is fun.\n")
    (root / "splits.csv").write_text("segment,split,speaker\na,train,alice\nb,test,bob\n")
    return root


def _mk(path: pathlib.Path) -> pathlib.Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    return path
