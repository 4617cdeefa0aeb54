"""The `evalsuite` command: --help/--version, info, convert, demo, clean errors."""
from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest
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


@pytest.mark.parametrize("src_ext, dst_ext", [(".bvh", ".bvh"), (".bvh", ".npz"), (".npz", ".csv"), (".csv", ".npy"),
                                              (".npy", ".npz")])
def test_convert_start_end_cuts_every_format_by_seconds(tmp_path, src_ext, dst_ext):
    walk = evalsuite.load_motion(sample_path("walk01"))  # 101 frames @ 24 fps
    src = tmp_path / f"in{src_ext}"
    if src_ext == ".bvh":
        src = sample_path("walk01")
    else:
        evalsuite.save_motion(walk, src)
    out = tmp_path / f"out{dst_ext}"
    extra = ["--input-fps", "24"] if src_ext == ".npy" else []
    res = run("convert", src, out, "--start", "1", "--end", "2.5", *extra)
    assert res.exit_code == 0, res.output
    assert "36 frames @ 24 fps" in res.output
    cut = evalsuite.load_motion(out, fps=24.0 if dst_ext == ".npy" else None, joint_names=walk.joint_names
                                if dst_ext == ".npy" else None)
    assert cut.n_frames == 36  # frames round(1 * 24) = 24 up to, not including, round(2.5 * 24) = 60
    np.testing.assert_allclose(cut.positions(), walk.positions()[24:60], atol=1e-4)
    if dst_ext == ".bvh":
        np.testing.assert_allclose(cut.values, walk.values[24:60], atol=1e-4)


def test_convert_start_or_end_alone_and_the_cut_comes_before_resampling(tmp_path):
    walk = evalsuite.load_motion(sample_path("walk01"))
    assert run("convert", sample_path("walk01"), tmp_path / "a.npz", "--start", "3.5").exit_code == 0
    with np.load(tmp_path / "a.npz") as data:
        np.testing.assert_allclose(data["positions"], walk.positions()[84:], atol=1e-9)
    assert run("convert", sample_path("walk01"), tmp_path / "b.npz", "--end", "0.5").exit_code == 0
    with np.load(tmp_path / "b.npz") as data:
        assert data["positions"].shape[0] == 12
    # seconds are the input's: at 24 fps frame 24 (1 s) is kept, then every second frame at 12 fps
    assert run("convert", sample_path("walk01"), tmp_path / "c.npz", "--start", "1", "--end", "2",
               "--fps", "12").exit_code == 0
    with np.load(tmp_path / "c.npz") as data:
        np.testing.assert_allclose(data["positions"], walk.positions()[24:48:2], atol=1e-6)
    # the end of the file itself (4.20833 s) and a value rounding to it are within the file
    assert run("convert", sample_path("walk01"), tmp_path / "d.npz", "--start", "4", "--end", "4.21").exit_code == 0


@pytest.mark.parametrize("args, message", [
    (["--start", "2", "--end", "1"], "cut 2 s to 1 s is empty: the end must come after the start"),
    (["--start", "1", "--end", "1"], "cut 1 s to 1 s is empty"),
    (["--start", "-1", "--end", "1"], "cut -1 s to 1 s: the start must be 0 s or later"),
    (["--start", "5"], "cut 5 s to the end starts outside the motion, which lasts 4.20833 s (101 frames @ 24 fps)"),
    (["--end", "5"], "cut 0 s to 5 s ends outside the motion, which lasts 4.20833 s (101 frames @ 24 fps)"),
    (["--start", "1", "--end", "1.01"], "cut 1 s to 1.01 s holds no frame at 24 fps"),
    (["--start", "nan"], "cut nan s to the end: start and end must be finite numbers of seconds"),
])
def test_convert_start_end_refuses_bad_cuts_in_one_line(tmp_path, args, message):
    out = tmp_path / "x.npz"
    res = CliRunner().invoke(main, ["convert", str(sample_path("walk01")), str(out), *args])
    assert res.exit_code == 1
    assert f"Error: {sample_path('walk01')}: {message}" in res.output
    assert len(res.output.strip().splitlines()) == 1
    assert not out.exists()


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


def test_info_and_convert_on_smplx(tmp_path, monkeypatch):
    sys.path.insert(0, str(pathlib.Path(__file__).parent))
    from smplx_helpers import fake_smplx_model, write_fake_beat2_recording

    from evalsuite.motion.io import load_motion
    from evalsuite.motion.smplx import read_smplx
    from evalsuite.motion.smplx_body import MODEL_ENV, smplx_positions

    monkeypatch.setenv(MODEL_ENV, "")        # restored after the test (the option sets it)
    rec = write_fake_beat2_recording(tmp_path / "2_scott_0_1_1.npz", n_frames=45, n_expr=0)
    model = fake_smplx_model(tmp_path / "model.npz", n_betas=300, n_verts=80)
    res = run("info", rec)
    assert res.exit_code == 0, res.output
    for text in ("smplx", "45", "1.500 s", "betas", "300", "neutral", "smplx2020",
                 "need --smplx-model or EVALSUITE_SMPLX_MODEL"):
        assert text in res.output
    data = json.loads(run("info", rec, "--json", "--smplx-model", model).output)
    assert data["format"] == "smplx" and data["positions"].startswith("available (full mode")
    assert os.environ[MODEL_ENV] == ""       # --smplx-model set it for the command only
    res = run("convert", rec, tmp_path / "x.bvh")
    assert res.exit_code == 1 and "--smplx-model" in res.output and "smpl-x.is.tue.mpg.de" in res.output
    assert len(res.output.strip().splitlines()) == 1
    for mode in ("full", "leaderboard"):
        res = run("convert", rec, tmp_path / f"{mode}.npy", "--smplx-model", model, "--positions", mode)
        assert res.exit_code == 0, res.output
        want = smplx_positions(read_smplx(rec), model, mode=mode)
        got = np.load(tmp_path / f"{mode}.npy")
        assert got.shape == (45, 55, 3) and np.abs(got - want).max() < 1e-12
    assert run("convert", rec, tmp_path / "x.bvh", "--smplx-model", model).exit_code == 0
    back = load_motion(tmp_path / "x.bvh")
    order = [back.joint_names.index(n) for n in load_motion(rec).joint_names]
    assert np.abs(back.positions()[:, order] - smplx_positions(read_smplx(rec), model)).max() < 1e-6
    assert run("convert", rec, tmp_path / "cut.npz", "--start", "0.5").exit_code == 0
    assert read_smplx(tmp_path / "cut.npz").n_frames == 30
