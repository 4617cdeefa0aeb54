"""study_app.derived: audio-mismatched clips (the GENEA Leaderboard's design) and video-only copies for muted
pairwise blocks, their balance over the plans and the errors a study author sees."""
from __future__ import annotations

import re
import subprocess
from collections import Counter

import pytest
from av_helpers import decode_audio, dominant_hz, ffmpeg, make_av_stimuli, tone_hz

from study_app import derived
from study_app.definition import load_study
from study_app.design import balance_report, build_plans, read_plans, write_plans
from study_app.errors import StudyDefinitionError

CONDITIONS = ["SYSA", "SYSB"]
SEGMENTS = ["s1", "s2", "s3", "s4"]
SPEAKERS = {"s1": "anna", "s2": "anna", "s3": "ben", "s4": "ben"}
LENGTHS = [1.0, 1.5, 0.6, 1.2]

STUDY = """\
id: align
stimuli: stim/manifest.csv
sessions: {sessions}
seed: 5
pages:
  - type: pairwise
    id: align
    conditions: [SYSA, SYSB]
    audio_mismatch: true
    speakers: {speakers}
    levels: 5
    questions: [{{id: alignment, text: "Which video's motion fits its speech better?"}}]
    pages: 4
  - type: pairwise
    id: realism
    conditions: [SYSA, SYSB]
    muted: true
    questions: [{{id: realism, text: "In which video does the character move more like a real person?"}}]
    pages: 2
  - {{type: finish, id: finish}}
"""


@pytest.fixture(scope="module")
def stim(tmp_path_factory):
    folder = tmp_path_factory.mktemp("av") / "stim"
    # clips (and their speech) of different lengths: a longer donor's speech is cut, a shorter one's padded
    make_av_stimuli(folder, CONDITIONS, SEGMENTS, seconds=LENGTHS)
    return folder


def _study(tmp_path, stim, sessions=4, speakers=None, extra=""):
    (tmp_path / "stim").symlink_to(stim, target_is_directory=True)
    text = STUDY.format(sessions=sessions, speakers=speakers or SPEAKERS)
    path = tmp_path / "study.yaml"
    path.write_text(text.replace("    pages: 2\n", "    pages: 2\n" + extra) if extra else text)
    return path


def _video_bytes(path) -> bytes:
    """The encoded video stream, as stored (a copy keeps every byte)."""
    return subprocess.run([ffmpeg(), "-nostdin", "-v", "error", "-i", str(path), "-map", "0:v:0", "-c", "copy",
                           "-f", "h264", "-"], capture_output=True, check=True).stdout


def test_audio_mismatched_clip_is_the_same_video_with_another_segments_speech_of_the_speaker(tmp_path, stim):
    study = load_study(_study(tmp_path, stim))
    made = derived.write_derived(study.manifest, progress=False)
    clips = {f: c for f, c in study.manifest.derived.items() if c.audio}
    assert sorted(made) == sorted(study.manifest.derived) and len(clips) == len(CONDITIONS) * len(SEGMENTS)
    by_file = study.manifest.by_file()
    donors = Counter()
    for name, clip in clips.items():
        own, stim_ = by_file[clip.video], clip.stimulus
        assert stim_.segment == own.segment and stim_.condition == own.condition and stim_.audio_mismatched
        assert stim_.audio_segment != own.segment and SPEAKERS[stim_.audio_segment] == SPEAKERS[own.segment]
        donors[(stim_.condition, stim_.audio_segment)] += 1
        assert _video_bytes(stim / name) == _video_bytes(stim / clip.video)      # video copied, not re-encoded
        sound = decode_audio(stim / name)
        assert abs(len(sound) / 16000 - LENGTHS[SEGMENTS.index(own.segment)]) < 0.08  # cut / padded to the clip
        assert abs(dominant_hz(sound) - tone_hz(SEGMENTS.index(stim_.audio_segment))) < 20
    assert set(donors.values()) == {1}                                           # each segment donates once
    assert derived.write_derived(study.manifest, progress=False) == []           # up to date: nothing redone


def test_each_speech_segment_is_heard_matched_and_mismatched_equally_often_and_sides_balance(tmp_path, stim):
    study = load_study(_study(tmp_path, stim, sessions=6))
    plans = build_plans(study)
    counts = derived.audio_balance(plans, study.manifest.by_file(), {"align"}.__contains__)
    # 6 sessions x 4 pages = 24 pages = 3 per (condition, segment)
    assert {k: v for k, v in counts.items()} == {("align", s, r): 6 for s in SEGMENTS
                                                  for r in ("matched", "mismatched")}
    pairs = balance_report(plans, study)["pairs"]
    for c in CONDITIONS:
        assert pairs[("align", c, f"{c}:audio_mismatched", "left")] == 6
        assert pairs[("align", c, f"{c}:audio_mismatched", "right")] == 6
    lines = derived.audio_balance_lines(plans, study)
    assert lines == ["audio mismatch align: speech heard matched / mismatched: s1 6/6, s2 6/6, s3 6/6, s4 6/6"]


def test_muted_pairs_serve_video_only_copies(tmp_path, stim):
    study = load_study(_study(tmp_path, stim))
    plans = build_plans(study)
    realism = [p for plan in plans["plans"] for p in plan["pages"] if p.get("block") == "realism"]
    silent = study.page("realism").cfg["silent"]
    assert len(silent) == len(CONDITIONS) * len(SEGMENTS)
    by_file = study.manifest.by_file()
    for p in realism:
        for f in (p["a"], p["b"]):
            assert f in silent.values() and by_file[f].silent and by_file[f].condition in CONDITIONS
    derived.write_derived(study.manifest, progress=False)
    for src, copy in silent.items():
        assert derived.has_audio(stim / src) and not derived.has_audio(stim / copy)
        assert _video_bytes(stim / copy) == _video_bytes(stim / src)
        assert len(decode_audio(stim / copy)) == 0


def test_a_muted_page_naming_a_clip_with_sound_serves_its_video_only_copy(tmp_path, stim):
    from study_app.pages import get_kind

    study = load_study(_study(tmp_path, stim))
    silent = study.page("realism").cfg["silent"]
    src = sorted(silent)[:2]
    spec = {"type": "pairwise", "block": "realism", "a": src[0], "b": src[1], "position_a": "right"}
    kind = get_kind("pairwise")
    assert [kind.media(study, spec, k).file for k in (0, 1)] == [silent[src[1]], silent[src[0]]]
    spec["block"] = "align"
    assert [kind.media(study, spec, k).file for k in (0, 1)] == [src[1], src[0]]


def test_serving_refuses_plans_whose_derived_clips_are_missing(tmp_path, stim):
    study = load_study(_study(tmp_path, stim))
    path = write_plans(build_plans(study), tmp_path / "plans.json")
    missing = [f for f in study.manifest.derived if (stim / f).exists()]
    for f in missing:
        (stim / f).unlink()
    with pytest.raises(StudyDefinitionError, match="run `evalsuite study build` again"):
        read_plans(path, study)
    derived.write_derived(study.manifest, progress=False)
    assert read_plans(path, study)["study"] == "align"


@pytest.mark.parametrize("speakers, extra, message", [
    ({"s1": "anna", "s2": "anna", "s3": "ben", "s4": "carl"}, "", "speaker 'ben' has only one segment (s3)"),
    ({"s1": "anna", "s2": "anna", "s3": "ben"}, "", "no speaker for segment(s) s4"),
    ("[anna]", "", "expected a mapping segment: speaker"),
    (None, "    speakers: {s1: a, s2: a}\n", "pages[1].speakers: only used with audio_mismatch"),
])
def test_speaker_errors_name_the_field(tmp_path, stim, speakers, extra, message):
    with pytest.raises(StudyDefinitionError, match=re.escape(message)):
        load_study(_study(tmp_path, stim, speakers=speakers, extra=extra))


def test_one_speaker_for_every_segment_and_design_conflicts(tmp_path, stim):
    study = load_study(_study(tmp_path, stim, speakers="narrator"))
    donors = {c.stimulus.audio_segment for c in study.manifest.derived.values() if c.audio}
    assert donors == set(SEGMENTS)
    text = (tmp_path / "study.yaml").read_text()
    for add, message in (("    muted: true\n", "pages[0].muted: not with audio_mismatch"),
                         ("    mismatched: true\n", "pages[0].audio_mismatch: not with mismatched")):
        (tmp_path / "study.yaml").write_text(text.replace("    audio_mismatch: true\n", "    audio_mismatch: true\n" + add, 1))
        with pytest.raises(StudyDefinitionError, match=re.escape(message)):
            load_study(tmp_path / "study.yaml")


def test_a_donor_without_sound_is_an_error_naming_its_line(tmp_path):
    from study_app.samples import make_sample_stimuli

    make_sample_stimuli(tmp_path / "stim", CONDITIONS, SEGMENTS)      # video only
    path = tmp_path / "study.yaml"
    path.write_text(STUDY.format(sessions=2, speakers=SPEAKERS))
    study = load_study(path)
    with pytest.raises(StudyDefinitionError, match=r"manifest.csv:\d+: file: '.*' has no sound; an audio_mismatch"):
        derived.write_derived(study.manifest, progress=False)


def test_an_audio_attention_check_in_a_muted_pair_block_is_refused(tmp_path):
    make_av_stimuli(tmp_path / "stim", CONDITIONS, SEGMENTS, attention=[("s1", "this", "distorted_audio")])
    path = tmp_path / "study.yaml"
    path.write_text(STUDY.format(sessions=2, speakers=SPEAKERS).replace("    pages: 2\n", "    pages: 2\n"
                                                                         "    attention_checks: [1]\n"))
    with pytest.raises(StudyDefinitionError, match=r"pages\[1\].attention_checks: .* needs sound, but block "
                                                   r"'realism' is muted"):
        load_study(path)
    path.write_text(path.read_text().replace("    muted: true\n", ""))
    assert load_study(path).page("realism").cfg["attention_checks"] == [1]


def test_practice_of_an_audio_mismatch_block_uses_its_segments(tmp_path, stim):
    path = _study(tmp_path, stim)
    text = path.read_text()

    def with_practice(practice_segment, block_segments):
        path.write_text(text.replace("  - type: pairwise\n    id: align\n",
                                     f"  - {{type: training, id: practice, of: align, segments: [{practice_segment}]}}\n"
                                     f"  - type: pairwise\n    id: align\n    segments: [{block_segments}]\n", 1))
        return load_study(path)

    study = with_practice("s1", "s1, s2, s3, s4")
    practice = [p for plan in build_plans(study)["plans"] for p in plan["pages"] if p.get("training")]
    assert practice and all(study.manifest.by_file()[p["b"]].audio_mismatched for p in practice)
    with pytest.raises(StudyDefinitionError, match=r"pages\[0\].segments\[0\]: segment 's1' is not one of 'align'"):
        with_practice("s1", "s3, s4")


def test_power_and_prereg_know_the_audio_mismatch_design(tmp_path, stim):
    from study_app.planning import block_plans
    from study_app.prereg import prereg_markdown

    study = load_study(_study(tmp_path, stim, sessions=6))
    plans = build_plans(study)
    align = next(r for r in block_plans(study, plans) if r["block"] == "align")
    assert align["pairs"] == [("SYSA", "SYSA:audio_mismatched"), ("SYSB", "SYSB:audio_mismatched")]
    assert align["per_session"] == 2.0            # 4 pages per session, half for each system
    text = prereg_markdown(study, plans)
    assert "the same motion with another segment's speech of the same speaker" in text
    assert "audio mismatch: per system the share preferring the video with its own speech" in text


def test_the_demo_study_on_clips_with_sound_is_served_as_built(tmp_path):
    from study_app import demo
    from study_app.design import default_plans_path

    make_av_stimuli(tmp_path / "render" / "stimuli", ["natural", "baseline", "system"], ["seg01", "seg02", "seg03"],
                    seconds=0.5)
    demo.run(tmp_path, lambda *a: None)
    study = load_study(tmp_path / "study" / "study.yaml")
    plans = read_plans(default_plans_path(study), study)          # the derived clips exist
    by_file = study.manifest.by_file()
    shown = [p for plan in plans["plans"] for p in plan["pages"] if p["type"] == "pairwise"]
    assert shown and all(by_file[p["a"]].silent and by_file[p["b"]].silent for p in shown)


def test_derangement_moves_every_element():
    import random

    rng = random.Random(1)
    for n in (2, 3, 7):
        for _ in range(50):
            p = derangement_of(rng, n)
            assert sorted(p) == list(range(n)) and all(p[i] != i for i in range(n))
    with pytest.raises(ValueError):
        derived.derangement(rng, 1)


def derangement_of(rng, n):
    return derived.derangement(rng, n)
