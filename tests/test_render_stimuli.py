"""Batch stimuli: blinded names, the manifest, skipping up-to-date videos, local processes and
dask workers, attention checks that differ measurably from their source."""
from __future__ import annotations

import csv
import os
import re

import imageio_ffmpeg
import numpy as np
import pytest
import yaml
from click.testing import CliRunner
from render_helpers import RATE, decode, waving_motion

from evalsuite.cli import main
from evalsuite.motion.io import save_motion
from renderers.attention import make_attention_check
from renderers.audio import decode_audio, speech_like_audio, write_wav
from renderers.render import render_video
from renderers.scene import RenderSettings
from renderers.stimuli import MANIFEST_COLUMNS, blinded_name, build_stimuli, file_sha256, load_config, plan

CONDITIONS = {"natural": 15.0, "baseline": 45.0}


def make_project(root, segments=("seg01", "seg02"), seconds=1.0, checks=True, width=96, height=72):
    for k, seg in enumerate(segments):
        for cond, amp in CONDITIONS.items():
            folder = root / "motion" / cond
            folder.mkdir(parents=True, exist_ok=True)
            save_motion(waving_motion(seconds, 30.0, amplitude=amp + 5 * k, shift=(3.0 * k, 0, 0)),
                        folder / f"{seg}.npz")
        (root / "audio").mkdir(exist_ok=True)
        write_wav(root / "audio" / f"{seg}.wav", speech_like_audio(seconds, RATE, seed=k), RATE)
    cfg = {"output": "out", "segments": list(segments),
           "conditions": {c: f"motion/{c}/{{segment}}.npz" for c in CONDITIONS},
           "audio": "audio/{segment}.wav",
           "render": {"width": width, "height": height}}
    if checks:
        cfg["attention_checks"] = [
            {"check": "instruction", "segment": segments[0], "condition": "natural",
             "text": "Attention: please select the left video", "appear_s": 0.4},
            {"check": "distorted_audio", "segment": segments[0], "condition": "baseline"},
            {"check": "distorted_video", "segment": segments[-1], "condition": "natural", "expected": "other"},
        ]
    path = root / "stimuli.yaml"
    path.write_text(yaml.safe_dump(cfg))
    return path


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_batch_writes_blinded_videos_and_manifest_and_skips_up_to_date(tmp_path):
    config = make_project(tmp_path)
    result = build_stimuli(config, echo=lambda *a: None)
    manifest = tmp_path / "out" / "manifest.csv"
    rows = read_rows(manifest)
    assert list(rows[0]) == MANIFEST_COLUMNS
    assert result["rendered"] == 7
    assert result["skipped"] == 0
    assert len(rows) == 7
    stim = [r for r in rows if r["kind"] == "stimulus"]
    att = [r for r in rows if r["kind"] == "attention"]
    assert {(r["condition"], r["segment"]) for r in stim} == {(c, s) for c in CONDITIONS for s in ("seg01", "seg02")}
    assert {r["check"]: r["expected"] for r in att} == {"instruction": "left", "distorted_audio": "bad",
                                                         "distorted_video": "other"}
    for r in rows:
        video = tmp_path / "out" / r["file"]
        assert file_sha256(video) == r["sha256"]
        assert int(r["n_frames"]) == 30
        assert r["fps"] == "30"
        assert (r["width"], r["height"]) == ("96", "72")
        assert imageio_ffmpeg.count_frames_and_secs(str(video))[0] == 30
    # The study app (issue 6) accepts this manifest, including its blinding check.
    from study_app.definition import load_manifest

    assert len(load_manifest(manifest).stimuli) == 7

    mtimes = {r["file"]: os.stat(tmp_path / "out" / r["file"]).st_mtime_ns for r in rows}
    again = build_stimuli(config, echo=lambda *a: None)
    assert again["rendered"] == 0
    assert again["skipped"] == 7
    assert {r["file"]: os.stat(tmp_path / "out" / r["file"]).st_mtime_ns for r in rows} == mtimes
    assert read_rows(manifest) == rows

    # Changing one motion re-renders that segment (its shared camera changes) and its checks.
    save_motion(waving_motion(1.0, 30.0, amplitude=80.0), tmp_path / "motion" / "baseline" / "seg02.npz")
    third = build_stimuli(config, echo=lambda *a: None)
    assert third["rendered"] == 3 and third["skipped"] == 4   # 2 conditions of seg02 + the check made from one
    # A damaged video is re-rendered even though its inputs did not change.
    first = tmp_path / "out" / rows[0]["file"]
    first.write_bytes(b"broken")
    assert build_stimuli(config, echo=lambda *a: None)["rendered"] == 1


def test_blinded_names_reveal_nothing(tmp_path):
    config = make_project(tmp_path, checks=False)
    jobs, _ = plan(load_config(config))
    names = [j["file"] for j in jobs]
    assert len(set(names)) == len(names)
    for j in jobs:
        assert re.fullmatch(r"v[0-9a-f]{12}\.mp4", j["file"])
        for word in list(CONDITIONS) + ["seg01", "seg02", "stimulus"]:
            assert word not in j["file"]
    # Stable for one key (re-runs keep names), unrelated under another key.
    assert [j["file"] for j in plan(load_config(config))[0]] == names
    other = [blinded_name(b"another key", list(CONDITIONS), "stimulus", j["condition"], j["segment"]) for j in jobs]
    assert not set(other) & set(names)
    # A name that would contain a condition name is never produced.
    assert "bad" not in blinded_name(b"k", ["bad", "fed", "ace", "cafe", "add"] + [f"{i:x}" * 3 for i in range(16)],
                                     "x")
    # The key is private to the output folder, not derivable from the config.
    assert (tmp_path / "out" / ".blinding-key").is_file()


def test_conditions_of_one_segment_share_the_camera(tmp_path):
    config = make_project(tmp_path, checks=False)
    jobs, _ = plan(load_config(config))
    by_seg = {}
    for j in jobs:
        by_seg.setdefault(j["segment"], []).append(j["view"])
    for views in by_seg.values():
        assert all(v == views[0] for v in views)
    assert by_seg["seg01"][0] != by_seg["seg02"][0]
    # ... and the camera frames both conditions: the widest arm swing fits in the picture.
    from renderers.scene import View

    cam = View.from_dict(by_seg["seg01"][0]).camera
    for cond, amp in CONDITIONS.items():
        uv = cam.project(waving_motion(1.0, 30.0, amplitude=amp).positions().reshape(-1, 3))
        assert np.all((uv >= 0) & (uv <= [96, 72]))


@pytest.mark.slow
def test_jobs_processes_and_dask_cluster_render_the_same_manifest(tmp_path):
    config = make_project(tmp_path, segments=("seg01",), seconds=0.5, checks=False, width=64, height=48)
    res = CliRunner().invoke(main, ["render", "stimuli", str(config), "--jobs", "2"])
    assert res.exit_code == 0, res.output
    assert "2 rendered, 0 up to date" in res.output
    rows = read_rows(tmp_path / "out" / "manifest.csv")
    assert len(rows) == 2

    import distributed  # part of the [test] extra
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        res = CliRunner().invoke(main, ["render", "stimuli", str(config), "--dask", cluster.scheduler_address,
                                        "--force"])
    assert res.exit_code == 0, res.output
    assert "2 rendered" in res.output
    again = read_rows(tmp_path / "out" / "manifest.csv")
    # same names, same inputs; the encoder is deterministic, so the very same files
    assert [(r["file"], r["input_hash"], r["sha256"]) for r in again] == \
        [(r["file"], r["input_hash"], r["sha256"]) for r in rows]


@pytest.fixture(scope="module")
def source_video(tmp_path_factory):
    root = tmp_path_factory.mktemp("src")
    wav = root / "s.wav"
    write_wav(wav, speech_like_audio(1.0, RATE), RATE)
    out = root / "src.mp4"
    render_video([waving_motion(1.0, 30.0)], out, RenderSettings(width=160, height=120), audio=wav)
    return out


def test_distorted_video_differs_measurably_from_its_source(source_video, tmp_path):
    out = tmp_path / "dv.mp4"
    make_attention_check(source_video, out, "distorted_video")
    _, src = decode(source_video)
    _, dst = decode(out)
    assert dst.shape == src.shape
    diff = np.abs(dst.astype(float) - src.astype(float)).mean(axis=(1, 2, 3))
    assert diff.min() > 30, "every frame is heavily distorted"
    a, _ = decode_audio(source_video, RATE)
    b, _ = decode_audio(out, RATE)
    n = min(len(a), len(b))
    assert np.corrcoef(a[:n, 0], b[:n, 0])[0, 1] > 0.95, "the audio is left alone"


def test_distorted_audio_differs_measurably_from_its_source(source_video, tmp_path):
    out = tmp_path / "da.mp4"
    make_attention_check(source_video, out, "distorted_audio")
    a, _ = decode_audio(source_video, RATE)
    b, _ = decode_audio(out, RATE)
    assert abs(len(a) - len(b)) <= 1024
    n = min(len(a), len(b))
    assert abs(np.corrcoef(a[:n, 0], b[:n, 0])[0, 1]) < 0.3
    noise = b[:n, 0] - a[:n, 0]
    snr_db = 10 * np.log10(np.mean(a[:n, 0] ** 2) / np.mean(noise ** 2))
    assert snr_db < 0, "more distortion than signal"
    _, src = decode(source_video)
    _, dst = decode(out)
    assert np.abs(dst.astype(float) - src.astype(float)).mean() < 2, "the picture is left alone"


def test_instruction_appears_a_few_seconds_in(source_video, tmp_path):
    out = tmp_path / "ins.mp4"
    info = make_attention_check(source_video, out, "instruction", text="Attention: please rate this video 73",
                                appear_s=0.5)
    assert info["appear_s"] == 0.4    # a 1 s clip: at 40% of it
    _, src = decode(source_video)
    _, dst = decode(out)
    diff = np.abs(dst.astype(float) - src.astype(float)).mean(axis=(1, 2, 3))
    first = int(np.ceil(0.4 * 30))
    assert diff[:first].max() < 2
    assert diff[first:].min() > 15
    # the box is red: in the middle rows of a late frame, red dominates
    mid = dst[-1, 50:70, 20:140].astype(int)
    assert (mid[..., 0] - mid[..., 2]).mean() > 60


def test_bad_config_is_a_clear_error(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump({"segments": ["a"], "conditions": {"x": "m/{segment}.bvh"},
                                    "render": {"width": 101}}))
    res = CliRunner().invoke(main, ["render", "stimuli", str(path)])
    assert res.exit_code == 1
    assert "Error:" in res.output
    assert "even" in res.output
    path.write_text(yaml.safe_dump({"segments": ["a"], "conditions": {"x": "m/{segment}.bvh"}}))
    res = CliRunner().invoke(main, ["render", "stimuli", str(path)])
    assert res.exit_code == 1
    assert "not found" in res.output
    assert "Traceback" not in res.output
    path.write_text(yaml.safe_dump({"segments": ["a"], "conditions": {"x": "m.bvh"},
                                    "attention_checks": [{"check": "loud"}]}))
    res = CliRunner().invoke(main, ["render", "stimuli", str(path)])
    assert res.exit_code == 1
    assert "attention_checks[0].check" in res.output


def test_attention_cli(source_video, tmp_path):
    out = tmp_path / "cli_att.mp4"
    res = CliRunner().invoke(main, ["render", "attention", str(source_video), "-o", str(out), "--check",
                                    "instruction", "--text", "Attention: please select the left video",
                                    "--appear", "0.2"])
    assert res.exit_code == 0, res.output
    assert imageio_ffmpeg.count_frames_and_secs(str(out))[0] == 30
    res = CliRunner().invoke(main, ["render", "attention", str(source_video), "-o", str(out), "--check", "loud"])
    assert res.exit_code == 2   # click rejects the choice
