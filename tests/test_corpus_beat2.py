"""The beat2 corpus layout: BEAT2 language folders (smplxflame_30, wave16k, textgrid, sem, train_test_split.csv),
speaker ids from the names, betas from the motion, and what `evalsuite corpus info` shows of them."""
from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest
from click.testing import CliRunner
from corpus_helpers import transcript, wav

from evalsuite.cli import main
from evalsuite.corpus import detect_layout, load_corpus
from evalsuite.errors import InputError

TAKES = {"2_scott_0_1_1": ("train", 2.0), "2_scott_0_2_2": ("test", 3.0), "4_lawrence_0_3_3": ("val", 2.0)}


def _betas(speaker: str) -> np.ndarray:
    return np.random.default_rng(int(speaker)).normal(size=300)


def beat2_language(root: pathlib.Path, takes=TAKES, sem: bool = True) -> pathlib.Path:
    for stem, (_, seconds) in takes.items():
        n = int(round(seconds * 30))
        wav(root / "wave16k" / f"{stem}.wav", seconds)
        transcript(root / "textgrid" / f"{stem}.TextGrid")
        (root / "smplxflame_30").mkdir(parents=True, exist_ok=True)
        np.savez(root / "smplxflame_30" / f"{stem}.npz", poses=np.zeros((n, 165)), trans=np.zeros((n, 3)),
                 betas=_betas(stem.split("_")[0]), expressions=np.zeros((n, 100)), model="smplx2020",
                 gender="neutral", mocap_frame_rate=np.array(30))
        if sem:
            (root / "sem").mkdir(exist_ok=True)
            (root / "sem" / f"{stem}.txt").write_text("01_beat_align\t0.5\t1.0\t0.5\t0.1\t\n")
    (root / "text").mkdir(exist_ok=True)
    (root / "train_test_split.csv").write_text("id,type\n" + "".join(f"{k},{v[0]}\n" for k, v in takes.items()))
    return root


def test_a_language_folder_reads_speakers_splits_betas_sem_and_transcripts(tmp_path):
    root = beat2_language(tmp_path / "beat_english_v2.0.0")
    assert detect_layout(root) == "beat2"
    c = load_corpus(root)
    assert c.layout == "beat2"
    assert {s.id: (s.speaker, s.split, s.meta["speaker_name"], s.meta["language"]) for s in c} == {
        "2_scott_0_1_1": ("2", "train", "scott", "english"), "2_scott_0_2_2": ("2", "test", "scott", "english"),
        "4_lawrence_0_3_3": ("4", "val", "lawrence", "english")}
    s = c.get("2_scott_0_2_2")
    assert s.motion == root / "smplxflame_30" / "2_scott_0_2_2.npz" and s.audio.parent.name == "wave16k"
    assert s.meta["motion_fps"] == 30 and s.duration == pytest.approx(3.0)
    assert s.transcript is not None and s.transcript.source.endswith("textgrid/2_scott_0_2_2.TextGrid")
    assert s.meta["sem"] == root / "sem" / "2_scott_0_2_2.txt"
    np.testing.assert_array_equal(s.meta["betas"], _betas("2"))
    assert s.meta["betas"].dtype == np.float64
    assert [x.id for x in c.split("test")] == ["2_scott_0_2_2"]
    assert c.meta["beat2"] == {"languages": {"english": 3}, "sem_files": 3,
                               "betas": {"2": {"files": 2, "n_betas": [300], "distinct": 1},
                                         "4": {"files": 1, "n_betas": [300], "distinct": 1}}}


def test_a_folder_of_languages_prefixes_ids_with_the_language_folder(tmp_path):
    beat2_language(tmp_path / "BEAT2" / "beat_english_v2.0.0")
    beat2_language(tmp_path / "BEAT2" / "beat_chinese_v2.0.0", {"11_zhao_0_1_1": ("train", 2.0)}, sem=False)
    c = load_corpus(tmp_path / "BEAT2")
    assert c.layout == "beat2" and len(c) == 4
    seg = c.get("beat_chinese_v2.0.0/11_zhao_0_1_1")
    assert (seg.speaker, seg.meta["language"], "sem" in seg.meta) == ("11", "chinese", False)
    assert c.meta["beat2"]["languages"] == {"chinese": 1, "english": 3} and c.meta["beat2"]["sem_files"] == 3
    assert c.meta["split_tables"] == ["beat_chinese_v2.0.0/train_test_split.csv",
                                      "beat_english_v2.0.0/train_test_split.csv"]


def test_missing_audio_and_mismatched_durations_are_reported(tmp_path):
    root = beat2_language(tmp_path / "beat_english_v2.0.0")
    (root / "wave16k" / "4_lawrence_0_3_3.wav").unlink()
    with pytest.raises(InputError, match=r"motion smplxflame_30/4_lawrence_0_3_3\.npz has no audio file; expected "
                                         r"its audio at wave16k/4_lawrence_0_3_3\.wav"):
        load_corpus(root)
    wav(root / "wave16k" / "4_lawrence_0_3_3.wav", 9.0)
    with pytest.raises(InputError, match=r"lasts 9\.000 s but motion smplxflame_30/4_lawrence_0_3_3\.npz lasts "
                                         r"2\.000 s"):
        load_corpus(root)


def test_corpus_info_shows_languages_sem_and_betas(tmp_path):
    root = beat2_language(tmp_path / "beat_english_v2.0.0")
    np.savez(root / "smplxflame_30" / "2_scott_0_2_2.npz", poses=np.zeros((90, 165)), trans=np.zeros((90, 3)),
             betas=np.ones(10), mocap_frame_rate=np.array(30))
    r = CliRunner().invoke(main, ["corpus", "info", str(root)])
    assert r.exit_code == 0, r.output
    lines = r.output.splitlines()
    assert "layout:     beat2" in lines
    assert "languages:  english (3 segments)" in lines
    assert "sem:        3 segments with semantic relevance annotations (sem/*.txt)" in lines
    assert "betas:      2: [10, 300] betas, 2 different; 4: 300 betas" in lines
    assert "motion:     30 fps x3" in lines and "speakers:   2 (2, 4)" in lines
    data = json.loads(CliRunner().invoke(main, ["corpus", "info", str(root), "--json"]).output)
    assert data["layout"] == "beat2" and data["beat2"]["betas"]["4"] == {"files": 1, "n_betas": [300], "distinct": 1}
    assert data["splits"]["test"]["segments"] == 1
