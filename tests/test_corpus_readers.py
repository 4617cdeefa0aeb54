"""Corpus layouts: each fixture folder loads with the right pairing; missing audio, duration mismatches and
ambiguous layouts give precise errors; seeded splits."""
from __future__ import annotations

import shutil

import pytest
from corpus_helpers import beat, bvh, folder, genea2020, genea2023, synth, transcript, wav, zeggs

from evalsuite.corpus import detect_layout, load_corpus, read_splits, split_corpus, write_splits
from evalsuite.corpus.readers import motion_info, wav_info
from evalsuite.errors import InputError


def test_genea2020_pairs_audio_motion_and_json_transcripts_by_recording(tmp_path):
    root = genea2020(tmp_path / "g20")
    c = load_corpus(root)
    assert c.layout == "genea2020" and [s.id for s in c] == ["Recording_001", "Recording_002"]
    s = c.get("Recording_002")
    assert (s.audio.name, s.motion.name, s.transcript.source.endswith("Transcripts/Recording_002.json")) == \
        ("Recording_002.wav", "Recording_002.bvh", True)
    assert s.duration == pytest.approx(4.0) and s.meta["motion_fps"] == 60 and s.meta["audio_rate"] == 44100
    assert [w.text for w in s.transcript.words] == ["deep", "learning", "is"]


def test_genea2020_split_folders(tmp_path):
    genea2020(tmp_path / "rel" / "Training_data")
    (tmp_path / "rel" / "Test_data" / "Audio").mkdir(parents=True)
    wav(tmp_path / "rel" / "Test_data" / "Audio" / "TestSeq001.wav", 2.0)
    c = load_corpus(tmp_path / "rel")
    assert {s.id: s.split for s in c} == {"Training_data/Recording_001": "train",
                                         "Training_data/Recording_002": "train", "Test_data/TestSeq001": "test"}
    assert c.get("Test_data/TestSeq001").meta["missing"] == ["transcript", "motion"]


def test_genea2023_pairs_main_agent_and_interlocutor_with_metadata(tmp_path):
    c = load_corpus(genea2023(tmp_path / "g23"))
    assert c.layout == "genea2023"
    assert {s.id: (s.split, s.speaker) for s in c} == {
        "trn_2023_v0_000": ("train", "01"), "trn_2023_v0_001": ("train", "02"),
        "val_2023_v0_000": ("val", "03"), "tst_2023_v0_000": ("test", "01")}
    s = c.get("trn_2023_v0_001")
    assert s.audio.name == "trn_2023_v0_001_main-agent.wav" and s.motion.name == "trn_2023_v0_001_main-agent.bvh"
    assert s.transcript.source.endswith("main-agent/tsv/trn_2023_v0_001_main-agent.tsv")
    assert s.interlocutor.audio.name == "trn_2023_v0_001_interloctr.wav"
    assert s.interlocutor.motion.name == "trn_2023_v0_001_interloctr.bvh"
    assert len(s.interlocutor.transcript) == 3
    assert s.meta["finger_incl"] is True and s.meta["interlocutor_finger_incl"] is False
    assert s.meta["interlocutor_speaker"] == "01"
    assert c.get("tst_2023_v0_000").motion is None and c.meta["missing"] == {"motion": 1}


def test_genea2022_is_the_monadic_layout_with_its_metadata(tmp_path):
    c = load_corpus(genea2023(tmp_path / "g22", dyadic=False, year=2022))
    assert c.layout == "genea2022" and len(c) == 4
    s = c.get("val_2022_v0_000")
    assert (s.split, s.speaker, s.interlocutor, s.meta["finger_incl"]) == ("val", "03", None, True)
    assert s.audio.name == "val_2022_v0_000.wav"
    assert (c.get("trn_2022_v0_001").speaker, c.get("trn_2022_v0_001").meta["finger_incl"]) == ("02", False)


def _move_metadata_to_the_root(root):
    """One metadata.csv for all splits at the corpus root, the per-split ones removed."""
    lines = []
    for split in ("trn", "val", "tst"):
        header, *rows = (root / split / "metadata.csv").read_text().splitlines()
        (root / split / "metadata.csv").unlink()
        lines += rows
    (root / "metadata.csv").write_text("\n".join([header, *lines]) + "\n")


def test_genea2023_metadata_at_the_root_gives_the_speakers(tmp_path):
    root = genea2023(tmp_path / "g23")
    split_wise = load_corpus(root)
    assert split_wise.meta["metadata_files"] == ["trn/metadata.csv", "tst/metadata.csv", "val/metadata.csv"]
    _move_metadata_to_the_root(root)
    c = load_corpus(root)
    assert c.meta["metadata_files"] == ["metadata.csv"] and c.speakers == split_wise.speakers == ("01", "02", "03")
    assert {s.id: (s.speaker, s.meta["finger_incl"], s.meta["interlocutor_speaker"]) for s in c} == \
        {s.id: (s.speaker, s.meta["finger_incl"], s.meta["interlocutor_speaker"]) for s in split_wise}


def test_genea_metadata_that_cannot_be_understood_is_an_error_naming_the_file(tmp_path):
    root = genea2023(tmp_path / "g23")
    meta = root / "trn" / "metadata.csv"
    good = meta.read_text()
    meta.write_text("take,role,fingers_ok,speaker\ntrn_2023_v0_000,main-agent,1,01\n")
    with pytest.raises(InputError, match=r"metadata\.csv:1: cannot read the columns take, role, fingers_ok, speaker: "
                                         r"expected GENEA 2023's header prefix, main-agent_id"):
        load_corpus(root)
    meta.write_text("prefix,main-agent_has_fingers\ntrn_2023_v0_000,fingers_incl\n")
    with pytest.raises(InputError, match="no speaker column"):
        load_corpus(root)
    meta.write_text(good.replace("finger_excl", "no_fingers", 1))
    with pytest.raises(InputError, match=r"metadata\.csv:2.*'no_fingers' is not a finger flag"):
        load_corpus(root)
    meta.write_text(good.replace("_v0_", "_v1_"))  # the recordings of another release
    (root / "val" / "metadata.csv").unlink()
    (root / "tst" / "metadata.csv").unlink()
    with pytest.raises(InputError, match=r"no recording of trn/metadata\.csv \(e\.g\. trn_2023_v1_000\) is in the "
                                         r"corpus \(e\.g\. trn_2023_v0_000\)"):
        load_corpus(root)
    meta.write_text(good)
    (root / "metadata.csv").write_text(good.replace(",01,", ",07,", 1))
    with pytest.raises(InputError, match="trn_2023_v0_000 is also in another metadata file with other values"):
        load_corpus(root)
    f = folder(tmp_path / "plain")
    (f / "metadata.csv").write_text("segment,speaker\na,1\n")
    with pytest.raises(InputError, match="metadata.csv is read in the GENEA layouts only.*splits.csv"):
        load_corpus(f)


def test_genea2023_empty_tsv_is_an_empty_transcript_as_in_the_real_data(tmp_path):
    root = genea2023(tmp_path / "g23")
    (root / "trn" / "main-agent" / "tsv" / "trn_2023_v0_001_main-agent.tsv").write_text("")
    assert len(load_corpus(root).get("trn_2023_v0_001").transcript) == 0


def test_synthetic_speaker_output_brings_corpus_json_and_labels(tmp_path):
    c = load_corpus(synth(tmp_path / "syn"))
    assert c.layout == "genea2023"
    assert c.meta["corpus_json"] == {"model": "synthetic speaker v1", "seed": 7} and c.meta["seed"] == 7
    assert c.get("trn_2023_v0_000").labels.name == "trn_2023_v0_000.csv"
    assert c.get("trn_2023_v0_001").labels is None


def test_beat_takes_speakers_from_names_and_splits_from_the_table(tmp_path):
    c = load_corpus(beat(tmp_path / "beat"))
    assert c.layout == "beat"
    assert {s.id: (s.speaker, s.split, s.meta["speaker_name"]) for s in c} == {
        "1_wayne_0_1_1": ("1", "train", "wayne"), "1_wayne_0_2_2": ("1", "val", "wayne"),
        "2_scott_0_1_1": ("2", "test", "scott")}
    s = c.get("2_scott_0_1_1")
    assert s.motion.name == "2_scott_0_1_1.bvh" and s.meta["motion_fps"] == 120
    assert s.transcript.source.endswith("2_scott_0_1_1.TextGrid") and len(s.transcript) == 3


def test_zeggs_has_no_transcripts_and_says_so(tmp_path):
    c = load_corpus(zeggs(tmp_path / "zeggs"))
    assert c.layout == "zeggs" and c.meta["missing"] == {"transcript": 2}
    s = c.get("002_Happy_0_x_1_0")
    assert s.transcript is None and s.meta["style"] == "Happy" and s.meta["audio_channels"] == 2
    assert s.meta["missing"] == ["transcript"]


def test_plain_folder_matches_by_stem_and_reads_splits_csv(tmp_path):
    c = load_corpus(folder(tmp_path / "f"))
    assert c.layout == "folder"
    assert {s.id: (s.split, s.speaker) for s in c} == {"a": ("train", "alice"), "b": ("test", "bob")}
    b = c.get("b")
    assert b.transcript.estimated and [w.text for w in b.transcript.words] == ["Deep", "learning", "is", "fun."]
    assert b.transcript.words[0].start == pytest.approx(0.5, abs=0.021)
    assert not c.get("a").transcript.estimated


def test_missing_audio_is_an_error_naming_the_motion_and_the_expected_file(tmp_path):
    root = genea2023(tmp_path / "g23")
    (root / "val" / "main-agent" / "wav" / "val_2023_v0_000_main-agent.wav").unlink()
    with pytest.raises(InputError, match=r"val_2023_v0_000_main-agent\.wav: motion "
                                         r"val/main-agent/bvh/val_2023_v0_000_main-agent\.bvh has no audio file; "
                                         r"expected its audio at val/main-agent/wav/val_2023_v0_000_main-agent\.wav"):
        load_corpus(root)
    root = folder(tmp_path / "f")
    (root / "a.wav").unlink()
    with pytest.raises(InputError, match=r"a\.wav: motion a\.bvh has no audio file; expected its audio at a\.wav"):
        load_corpus(root)


def test_duration_mismatch_is_an_error_by_default_and_reported_under_warn_or_skip(tmp_path):
    root = genea2020(tmp_path / "g20")
    bvh(root / "Motion" / "Recording_001.bvh", 5.0, fps=60)  # the audio lasts 3 s
    with pytest.raises(InputError, match=r"Recording_001\.wav: segment 'Recording_001': audio Audio/Recording_001\.wav "
                                         r"lasts 3\.000 s but motion Motion/Recording_001\.bvh lasts 5\.000 s; expected "
                                         r"them to agree within 0\.500 s \(max\(0\.5 s, 2 %\)\)"):
        load_corpus(root)
    with pytest.warns(UserWarning, match="lasts 5.000 s"):
        c = load_corpus(root, on_mismatch="warn")
    assert len(c) == 2 and c.get("Recording_001").meta["mismatch"]["motion_duration"] == pytest.approx(5.0)
    c = load_corpus(root, on_mismatch="skip")
    assert [s.id for s in c] == ["Recording_002"] and c.meta["skipped"] == ["Recording_001"]
    assert c.meta["mismatches"][0]["audio_duration"] == pytest.approx(3.0)
    assert len(load_corpus(root, tolerance=2.5)) == 2


def test_small_differences_within_the_tolerance_load_silently(tmp_path):
    root = tmp_path / "f"
    wav(root / "long.wav", 100.0, rate=8000)
    bvh(root / "long.bvh", 101.9, fps=10)  # 1.9 s < 2 % of 101.9 s
    assert load_corpus(root).get("long").meta["motion_duration"] == pytest.approx(101.9)


def test_headers_give_durations_without_loading(tmp_path):
    info = wav_info(wav(tmp_path / "a.wav", 1.5, rate=22050, channels=2))
    assert (info.rate, info.channels, info.duration) == (22050, 2, pytest.approx(1.5))
    m = motion_info(bvh(tmp_path / "a.bvh", 2.0, fps=30))
    assert (m.fps, m.frames, m.duration) == (30.0, 60, pytest.approx(2.0))
    (tmp_path / "bad.wav").write_bytes(b"RIFX0000WAVE")
    with pytest.raises(InputError, match=r"bad\.wav: not a WAV file: expected a RIFF/WAVE header"):
        wav_info(tmp_path / "bad.wav")


def test_layout_detection_is_explicit_about_ambiguity_and_unknown_folders(tmp_path):
    root = genea2023(tmp_path / "both")
    transcript(root / "1_wayne_0_1_1.TextGrid")
    with pytest.raises(InputError, match=r"looks like several layouts \(genea2023, beat\); name one with load_corpus\(..., layout=NAME\)"):
        detect_layout(root)
    assert load_corpus(root, layout="genea2023").layout == "genea2023"
    (tmp_path / "empty").mkdir()
    (tmp_path / "empty" / "notes.md").write_text("hi")
    with pytest.raises(InputError, match=r"empty: unknown corpus layout: no layout recognises this folder. Known "
                                         r"layouts: genea2020: GENEA 2020"):
        load_corpus(tmp_path / "empty")
    with pytest.raises(InputError, match=r"layout: unknown layout 'trinity'; known: beat, beat2, folder, genea2020"):
        load_corpus(root, layout="trinity")


def test_a_malformed_transcript_inside_a_corpus_names_its_file_and_line(tmp_path):
    root = genea2023(tmp_path / "g23")
    bad = root / "val" / "interloctr" / "tsv" / "val_2023_v0_000_interloctr.tsv"
    bad.write_text("0.1\t0.2\thi\n0.3\tsoon\tthere\n")
    with pytest.raises(InputError, match=r"val_2023_v0_000_interloctr\.tsv:2: end \(field 2\): expected a time"):
        load_corpus(root)


def test_split_corpus_is_seeded_and_keeps_speakers_disjoint(tmp_path):
    root = tmp_path / "many"
    for k in range(12):
        wav(root / f"s{k:02d}.wav", 1.0 + k % 3, rate=8000)
    (root / "splits.csv").write_text("segment,split,speaker\n" + "".join(
        f"s{k:02d},train,spk{k % 6}\n" for k in range(12)))
    c = load_corpus(root)
    a, b = split_corpus(c, val=0.2, test=0.2, seed=5), split_corpus(c, val=0.2, test=0.2, seed=5)
    assert [s.split for s in a] == [s.split for s in b]
    assert {s.split for s in a} == {"train", "val", "test"} and a.meta["split"]["speakers_disjoint"]
    per_speaker = {}
    for s in a:
        per_speaker.setdefault(s.speaker, set()).add(s.split)
    assert all(len(v) == 1 for v in per_speaker.values())
    others = {tuple(s.split for s in split_corpus(c, val=0.2, test=0.2, seed=k)) for k in range(6)}
    assert len(others) > 1  # the seed matters
    seg = split_corpus(c, val=0.25, test=0.25, seed=1, by="segment")
    assert not seg.meta["split"]["speakers_disjoint"]
    write_splits(a, tmp_path / "splits.csv")
    assert read_splits(tmp_path / "splits.csv") == {s.id: s.split for s in a}


def test_split_corpus_with_one_speaker_splits_segments(tmp_path):
    c = load_corpus(zeggs(tmp_path / "z"))
    d = split_corpus(c, val=0.0, test=0.5, seed=0)
    assert sorted(s.split for s in d) == ["test", "train"] and not d.meta["split"]["speakers_disjoint"]
    with pytest.raises(InputError, match=r"val: val must be a fraction in \[0, 1\)"):
        split_corpus(c, val=1.5)


def test_a_new_layout_is_one_registered_function(tmp_path):
    from evalsuite.corpus.readers import LAYOUTS, register_layout

    @register_layout("one_take", detect=lambda root: (root / "take.marker").exists(), description="one take")
    def read_one_take(root, b):
        b.add("take", audio=root / "speech.wav", motion=None, speaker="me")

    try:
        root = tmp_path / "one"
        wav(root / "speech.wav", 1.0)
        (root / "take.marker").write_text("")
        c = load_corpus(root)
        assert c.layout == "one_take" and c.get("take").speaker == "me"
    finally:
        LAYOUTS.pop("one_take")
    shutil.rmtree(tmp_path / "one")


def test_positions_motion_durations_from_array_headers(tmp_path):
    import numpy as np

    root = tmp_path / "pos"
    wav(root / "a.wav", 2.0)
    np.savez(root / "a.npz", positions=np.zeros((60, 4, 3)), fps=np.array(30.0))
    wav(root / "b.wav", 2.0)
    np.save(root / "b.npy", np.zeros((20, 12)))
    c = load_corpus(root, motion_fps=10)
    assert c.get("a").meta["motion_duration"] == pytest.approx(2.0)
    assert (c.get("b").meta["motion_frames"], c.get("b").meta["motion_duration"]) == (20, pytest.approx(2.0))
    np.save(root / "b.npy", np.zeros((50, 12)))
    with pytest.raises(InputError, match=r"motion b\.npy lasts 5\.000 s"):
        load_corpus(root, motion_fps=10)
    assert load_corpus(root).get("b").meta["motion_duration"] is None  # no rate: duration unknown


def test_beat2_folders_with_smplx_npz_motion(tmp_path):
    import numpy as np

    root = tmp_path / "beat_english_v2.0.0"
    for stem in ("2_scott_0_1_1", "4_lawrence_0_3_3"):
        wav(root / "wave16k" / f"{stem}.wav", 2.0)
        transcript(root / "textgrid" / f"{stem}.TextGrid")
        (root / "smplxflame_30").mkdir(parents=True, exist_ok=True)
        np.savez(root / "smplxflame_30" / f"{stem}.npz", poses=np.zeros((60, 165)), trans=np.zeros((60, 3)),
                 mocap_frame_rate=np.array(30))
    (root / "train_test_split.csv").write_text("id,type\n2_scott_0_1_1,train\n4_lawrence_0_3_3,test\n")
    c = load_corpus(root)
    assert c.layout == "beat2" and {s.id: (s.speaker, s.split) for s in c} == {
        "2_scott_0_1_1": ("2", "train"), "4_lawrence_0_3_3": ("4", "test")}
    s = c.get("4_lawrence_0_3_3")
    assert s.motion.parent.name == "smplxflame_30" and s.meta["motion_duration"] == pytest.approx(2.0)


def test_the_interlocutor_streams_durations_are_checked_too(tmp_path):
    root = genea2023(tmp_path / "g23")
    bvh(root / "val" / "interloctr" / "bvh" / "val_2023_v0_000_interloctr.bvh", 6.0)
    with pytest.raises(InputError, match=r"segment 'val_2023_v0_000 \(interlocutor\)': audio "
                                         r"val/interloctr/wav/val_2023_v0_000_interloctr\.wav lasts 3\.000 s but motion "
                                         r"val/interloctr/bvh/val_2023_v0_000_interloctr\.bvh lasts 6\.000 s"):
        load_corpus(root)
    c = load_corpus(root, on_mismatch="skip")
    assert "val_2023_v0_000" not in {s.id for s in c} and c.meta["skipped"] == ["val_2023_v0_000"]


@pytest.mark.parametrize("durations, val, test", [((0.1, 0.1, 10.0), 0.1, 0.5), ((10.0, 0.1, 0.1), 0.4, 0.1),
                                                  ((1.0, 1.0, 1.0, 1.0), 0.45, 0.45)])
def test_every_split_asked_for_gets_a_speaker_whatever_the_durations(tmp_path, durations, val, test):
    root = tmp_path / "few"
    for k, d in enumerate(durations):
        wav(root / f"s{k}.wav", d, rate=8000)
    (root / "splits.csv").write_text("segment,split,speaker\n" + "".join(f"s{k},train,p{k}\n"
                                                                        for k in range(len(durations))))
    c = load_corpus(root)
    for seed in range(8):
        d = split_corpus(c, val=val, test=test, seed=seed)
        assert {s.split for s in d} == {"train", "val", "test"} and d.meta["split"]["speakers_disjoint"]
