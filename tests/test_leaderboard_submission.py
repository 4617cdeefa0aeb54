"""validate-submission: a good submission passes, and each class of broken submission is caught with a message
naming the file, what is wrong and what was expected."""
from __future__ import annotations

import json
import pathlib
import zipfile

import numpy as np
import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.leaderboard.submission import validate_submission, video_id_of

IDS = {"2_scott_0_103_103": 90, "4_lawrence_0_3_3": 120}


def _recording(path: pathlib.Path, frames: int, seed: int = 0, **override) -> None:
    rng = np.random.default_rng(seed)
    data = {"poses": rng.normal(0, 0.2, (frames, 165)), "trans": rng.normal(0, 0.01, (frames, 3)),
            "betas": np.zeros(300), "expressions": np.zeros((frames, 100)), "model": np.array("smplx2020"),
            "gender": np.array("neutral"), "mocap_frame_rate": np.array(30)}
    data.update(override)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, **{k: v for k, v in data.items() if v is not None})


@pytest.fixture
def dirs(tmp_path):
    gt, sub = tmp_path / "gt", tmp_path / "sub"
    for vid, n in IDS.items():
        _recording(gt / f"{vid}.npz", n)
        for k in (1, 2, 3):
            _recording(sub / f"{vid}_{k}.npz", n, seed=k)
    return gt, sub


def _codes(report):
    return {(p.file, p.severity, p.code) for p in report.problems}


def test_a_good_submission_passes_with_no_problem(dirs):
    gt, sub = dirs
    report = validate_submission(sub, gt)
    assert report.ok and report.problems == []
    assert (report.files, report.recordings) == (6, 2)
    assert report.samples == {"2_scott_0_103_103": 3, "4_lawrence_0_3_3": 3}
    result = CliRunner().invoke(main, ["validate-submission", str(sub), "--against", str(gt), "--no-progress"])
    assert result.exit_code == 0, result.output
    assert "OK: no errors, 0 warnings" in result.output and "3 x2" in result.output


def test_names_are_grouped_by_the_first_five_tokens():
    assert video_id_of("2_scott_0_103_103_sample_10") == "2_scott_0_103_103"
    assert video_id_of("2_scott_0_103") is None


@pytest.mark.parametrize("case, file, code, message", [
    ("short_name", "2_scott_0.npz", "name", "fewer than five '_'-separated tokens"),
    ("unknown", "9_nobody_0_1_1_1.npz", "unknown_recording", "9_nobody_0_1_1 is not a recording"),
    ("missing", "4_lawrence_0_3_3_*.npz", "missing_recording", "no file for 4_lawrence_0_3_3"),
    ("count", "2_scott_0_103_103_*.npz", "sample_count", "2 samples"),
    ("no_poses", "2_scott_0_103_103_1.npz", "keys", "no 'poses' array"),
    ("shape", "2_scott_0_103_103_1.npz", "shape", "poses has shape (90, 55, 3) (flatten the joints"),
    ("width", "2_scott_0_103_103_1.npz", "shape", "156 = SMPL-X without jaw and eyes"),
    ("dtype", "2_scott_0_103_103_1.npz", "dtype", "poses has dtype int64"),
    ("fps", "2_scott_0_103_103_1.npz", "fps", "mocap_frame_rate is 60"),
    ("nan", "2_scott_0_103_103_1.npz", "nan", "poses has 1 NaN values (first at frame 5, column 7 = joint 2 from 0)"),
    ("inf", "2_scott_0_103_103_1.npz", "inf", "trans has 1 infinite values (first at frame 3)"),
    ("trans_length", "2_scott_0_103_103_1.npz", "trans_length", "trans has 80 frames but poses 90"),
    ("length", "2_scott_0_103_103_1.npz", "length", "85 frames (2.83 s) but the ground truth has 90 (3.00 s)"),
    ("unreadable", "2_scott_0_103_103_1.npz", "unreadable", "cannot read the file as .npz"),
    ("pickle", "2_scott_0_103_103_1.npz", "unreadable_key", "'poses' cannot be read without pickle"),
    ("empty", "(submission)", "no_files", "no .npz files"),
])
def test_each_class_of_broken_submission_is_an_error(dirs, case, file, code, message):
    gt, sub = dirs
    target = sub / "2_scott_0_103_103_1.npz"
    poses = np.random.default_rng(1).normal(0, 0.2, (90, 165))
    if case == "short_name":
        target.rename(sub / "2_scott_0.npz")
    elif case == "unknown":
        _recording(sub / "9_nobody_0_1_1_1.npz", 90)
    elif case == "missing":
        for p in sub.glob("4_lawrence*"):
            p.unlink()
    elif case == "count":
        target.unlink()
    elif case == "no_poses":
        _recording(target, 90, poses=None)
    elif case == "shape":
        _recording(target, 90, poses=poses.reshape(90, 55, 3))
    elif case == "width":
        _recording(target, 90, poses=poses[:, :156])
    elif case == "dtype":
        _recording(target, 90, poses=np.zeros((90, 165), dtype=np.int64))
    elif case == "fps":
        _recording(target, 90, mocap_frame_rate=np.array(60))
    elif case == "nan":
        poses[5, 7] = np.nan
        _recording(target, 90, poses=poses)
    elif case == "inf":
        trans = np.zeros((90, 3))
        trans[3, 1] = np.inf
        _recording(target, 90, trans=trans)
    elif case == "trans_length":
        _recording(target, 90, trans=np.zeros((80, 3)))
    elif case == "length":
        _recording(target, 85)
    elif case == "unreadable":
        target.write_bytes(b"PK\x03\x04 truncated")
    elif case == "pickle":
        _recording(target, 90, poses=np.array([poses], dtype=object))
    elif case == "empty":
        for p in sub.iterdir():
            p.unlink()
    report = validate_submission(sub, gt)
    assert not report.ok
    hits = [p for p in report.errors if (p.file, p.code) == (file, code)]
    assert hits and message in hits[0].message, report.problems
    assert hits[0].expected
    result = CliRunner().invoke(main, ["validate-submission", str(sub), "--against", str(gt), "--json"])
    assert result.exit_code == 1
    data = json.loads(result.output)
    assert not data["ok"] and {"file": file, "severity": "error", "code": code} in [
        {k: p[k] for k in ("file", "severity", "code")} for p in data["problems"]]


def test_lengths_state_both_tolerances(dirs):
    gt, sub = dirs
    _recording(sub / "2_scott_0_103_103_1.npz", 89)  # 1 frame short: within 2 % of 90 (1 frame)
    assert validate_submission(sub, gt).ok
    _recording(sub / "2_scott_0_103_103_1.npz", 60)  # a third short: an error, and the organisers warn too
    report = validate_submission(sub, gt)
    assert ("2_scott_0_103_103_1.npz", "error", "length") in _codes(report)
    assert ("2_scott_0_103_103_1.npz", "warning", "length_leaderboard") in _codes(report)
    assert validate_submission(sub, gt, length_tolerance=0.5).ok  # looser: only the organisers' warning stays
    text = CliRunner().invoke(main, ["validate-submission", str(sub), "--against", str(gt), "--no-progress"]).output
    assert "an error beyond 2 % of the ground truth's frames (at least 1)" in text
    assert "the organisers' script warns beyond 20 %" in text
    assert "expected: 90 frames, within 1 (2 % of the ground truth, at least 1)" in text


def test_warnings_alone_do_not_fail(dirs):
    gt, sub = dirs
    for p in sub.glob("*_2.npz"):
        p.unlink()
    for p in sub.glob("*_3.npz"):
        p.unlink()
    _recording(sub / "4_lawrence_0_3_3_1.npz", 120, betas=None, expressions=None)
    (sub / "README.txt").write_text("our system")
    report = validate_submission(sub, gt)
    assert report.ok
    assert _codes(report) == {("(submission)", "warning", "single_sample"), ("README.txt", "warning", "ignored"),
                              ("4_lawrence_0_3_3_1.npz", "warning", "optional_keys")}
    assert "no betas, expressions" in report.warnings[-1].message or any(
        "no betas, expressions" in p.message for p in report.warnings)


def test_sample_numbers_of_different_widths_warn_about_text_order(dirs):
    gt, sub = dirs
    for vid, n in IDS.items():
        for k in range(4, 11):
            _recording(sub / f"{vid}_{k}.npz", n, seed=k)
    report = validate_submission(sub, gt)
    assert report.ok
    order = [p for p in report.warnings if p.code == "sample_order"]
    assert len(order) == 2 and "_10 comes before _2" in order[0].message


def test_the_ground_truth_may_be_a_beat2_language_folder(dirs, tmp_path):
    _, sub = dirs
    beat2 = tmp_path / "beat_english_v2.0.0"
    for vid, n in {**IDS, "1_wayne_0_1_1": 60}.items():
        _recording(beat2 / "smplxflame_30" / f"{vid}.npz", n)
    (beat2 / "train_test_split.csv").write_text("id,type\n2_scott_0_103_103,test\n4_lawrence_0_3_3,test\n"
                                                "1_wayne_0_1_1,train\n")
    assert validate_submission(sub, beat2).ok  # the training recording is not expected
    with pytest.raises(InputError, match=r"no such submission folder"):
        validate_submission(tmp_path / "nope", beat2)
    (tmp_path / "empty_gt").mkdir()
    with pytest.raises(InputError, match=r"empty_gt: no ground-truth \.npz files"):
        validate_submission(sub, tmp_path / "empty_gt")
    assert zipfile.is_zipfile(sub / "2_scott_0_103_103_1.npz")
