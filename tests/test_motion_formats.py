"""evalsuite.motion.formats: the motion format registry that load_motion dispatches through."""
from __future__ import annotations

import numpy as np
import pytest
from smplx_helpers import write_fake_beat2_recording

from evalsuite.errors import InputError, UnknownNameError
from evalsuite.motion import load_motion
from evalsuite.motion.formats import (
    MOTION_FORMATS,
    MotionFormat,
    motion_format_for,
    motion_suffixes,
    register_motion_format,
)
from evalsuite.motion.io import list_motion_files
from evalsuite.motion.motion import Motion


def test_builtin_formats_and_detection(tmp_path):
    assert MOTION_FORMATS.names()[:3] == ["bvh", "smplx", "positions"]
    assert set(motion_suffixes()) >= {".bvh", ".npz", ".npy", ".csv"}
    smplx = write_fake_beat2_recording(tmp_path / "a.npz", n_frames=3)
    positions = tmp_path / "b.npz"
    np.savez(positions, positions=np.zeros((3, 1, 3)), fps=np.float64(30))
    assert motion_format_for(smplx).name == "smplx"
    assert motion_format_for(positions).name == "positions"
    assert motion_format_for(tmp_path / "c.npy").name == "positions"
    assert motion_format_for(tmp_path / "d.BVH").name == "bvh"
    with pytest.raises(InputError, match=r"unknown motion file type '\.txt'; expected one of \.bvh"):
        motion_format_for(tmp_path / "e.txt")
    with pytest.raises(UnknownNameError, match="unknown motion format 'smplh'.*Did you mean 'smplx'"):
        load_motion(smplx, format="smplh")


def test_a_registered_format_is_loaded_and_listed(tmp_path):
    def load(path, *, fps=None, **_):
        arr = np.loadtxt(path, ndmin=2)
        return Motion.from_positions(arr.reshape(len(arr), -1, 3), ["a"], fps or 10.0, name=path.stem)

    register_motion_format(MotionFormat("xyz", (".xyz",), load, description="x y z per line"))
    try:
        (tmp_path / "one.xyz").write_text("0 1 2\n3 4 5\n")
        motion = load_motion(tmp_path / "one.xyz")
        assert motion.n_frames == 2 and motion.fps == 10.0 and motion.positions()[1, 0, 2] == 5.0
        assert list(list_motion_files(tmp_path)) == ["one"]
        with pytest.raises(ValueError, match="registered already"):
            register_motion_format(MotionFormat("xyz", (".xyz",), load))
    finally:
        MOTION_FORMATS.unregister("xyz")
    assert ".xyz" not in motion_suffixes()
