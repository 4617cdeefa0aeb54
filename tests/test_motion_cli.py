"""The `evalsuite` command: --help/--version, info, convert, demo, clean errors."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
from click.testing import CliRunner

import evalsuite
from evalsuite.cli import main
from evalsuite.motion.samples import sample_path


def run(*args):
    return CliRunner().invoke(main, list(map(str, args)), catch_exceptions=False)


def test_version_and_help():
    assert evalsuite.__version__ in run("--version").output
    out = run("--help").output
    for cmd in ("info", "convert", "demo"):
        assert cmd in out
    for cmd in ("info", "convert", "demo"):
        assert "Usage:" in run(cmd, "--help").output


def test_info_text_and_json():
    out = run("info", sample_path("walk01")).output
    assert "joints     19" in out
    assert "fps        24" in out
    assert "centimetres" in out
    data = json.loads(run("info", "--json", "--joints", sample_path("walk01")).output)
    assert data["frames"] == 101
    assert data["joint_list"][1]["parent"] == "Hips"


def test_convert_bvh_to_npz_with_options(tmp_path):
    out = tmp_path / "w.npz"
    res = run("convert", sample_path("walk01"), out, "--joints", "Hips,Spine,Spine1,Neck,Head", "--fps", "12",
              "--center", "xz", "--smooth", "savgol")
    assert res.exit_code == 0, res.output
    with np.load(out) as data:
        assert data["positions"].shape == (51, 5, 3)
        assert list(data["joint_names"]) == ["Hips", "Spine", "Spine1", "Neck", "Head"]
        assert float(data["fps"]) == 12.0


def test_convert_bvh_to_bvh_and_positions_to_bvh_refused(tmp_path):
    res = run("convert", sample_path("mocapbank"), tmp_path / "m.bvh", "--fps", "60")
    assert res.exit_code == 0
    assert evalsuite.load_motion(tmp_path / "m.bvh").n_frames == 909
    # positions (here written from the BVH) cannot become a BVH: the refusal names what to write instead
    assert run("convert", sample_path("walk01"), tmp_path / "walk.npz").exit_code == 0
    res = CliRunner().invoke(main, ["convert", str(tmp_path / "walk.npz"), str(tmp_path / "x.bvh")])
    assert res.exit_code == 1
    assert "holds positions only and cannot be written as BVH" in res.output
    assert "Traceback" not in res.output
    assert not (tmp_path / "x.bvh").exists()


def test_bad_file_gives_message_without_traceback(tmp_path):
    bad = tmp_path / "bad.bvh"
    bad.write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n}\n")
    proc = subprocess.run([sys.executable, "-m", "evalsuite", "info", str(bad)], capture_output=True, text=True)
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    assert f"Error: {bad}:5: expected a number for OFFSET z of joint 'Hips', found '}}'" in proc.stderr


def test_demo_motion_step_writes_positions(tmp_path):
    from evalsuite.motion.demo import run as motion_step

    lines = []
    (tmp_path / "demo").mkdir()
    motion_step(tmp_path / "demo", lines.append)
    assert any("walk01.bvh: 19 joints, 101 frames @ 24 fps" in line for line in lines)
    with np.load(tmp_path / "demo" / "positions" / "walk01.npz") as data:
        assert data["positions"].shape == (101, 24, 3)
