"""The render step of `evalsuite demo`, on the bundled samples (no condition folders)."""
from __future__ import annotations

import csv

import imageio.v3
import imageio_ffmpeg
import yaml

from renderers.demo import find_conditions, run


def test_demo_step_renders_a_comparison_and_a_study_stimuli_set(tmp_path):
    lines = []
    run(tmp_path, lines.append)
    compare = tmp_path / "render" / "compare.mp4"
    frames, seconds = imageio_ffmpeg.count_frames_and_secs(str(compare))
    assert frames == 90
    assert abs(seconds - 3.0) < 1e-6
    assert (tmp_path / "render" / "compare.png").is_file()
    # the mannequin by default: it stands on a floor (the stick figure has none)
    still = imageio.v3.imread(tmp_path / "render" / "compare.png")
    assert still[-3].astype(int).sum(axis=1).min() < 3 * 240
    assert yaml.safe_load((tmp_path / "render" / "stimuli.yaml").read_text())["render"]["style"] == "mannequin"
    with open(tmp_path / "render" / "stimuli" / "manifest.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    conditions, segments = find_conditions(tmp_path)
    assert segments == ["sample"]
    assert sum(r["kind"] == "stimulus" for r in rows) == len(conditions)
    assert sorted(r["check"] for r in rows if r["kind"] == "attention") == \
        ["distorted_audio", "distorted_video", "instruction"]
    for r in rows:
        assert (tmp_path / "render" / "stimuli" / r["file"]).is_file()
    assert any("side-by-side" in line for line in lines)


def test_demo_uses_condition_folders_when_an_earlier_step_wrote_them(tmp_path):
    for cond in ("smoothed", "natural", "static"):
        folder = tmp_path / "conditions" / cond
        folder.mkdir(parents=True)
        for seg in ("seg00", "seg01"):
            (folder / f"{seg}.bvh").write_text("placeholder")
    conditions, segments = find_conditions(tmp_path)
    assert list(conditions) == ["natural", "static", "smoothed"]
    assert segments == ["seg00", "seg01"]
