"""evalsuite.synth.skeletons: `evalsuite corpus synth --skeleton genea2020|genea2023|beat|smplx` writes the same
performance on another skeleton (joint names, hierarchy, offsets), or as SMPL-X rotations."""
from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.motion.io import load_motion
from evalsuite.motion.presets import GENEA2023
from evalsuite.motion.smplx import read_smplx
from evalsuite.motion.smplx_layout import SMPLX_JOINT_NAMES


def _synth(root: pathlib.Path, skeleton: str | None) -> pathlib.Path:
    args = ["corpus", "synth", "-o", str(root), "--minutes", "0.3", "--segment-seconds", "6", "--seed", "3", "--quiet"]
    res = CliRunner().invoke(main, args + (["--skeleton", skeleton] if skeleton else []))
    assert res.exit_code == 0, res.output
    return root


@pytest.fixture(scope="module")
def corpora(tmp_path_factory) -> dict[str, pathlib.Path]:
    base = tmp_path_factory.mktemp("skeletons")
    return {name: _synth(base / name, None if name == "default" else name)
            for name in ("default", "genea2023", "beat", "smplx")}


def _first(root: pathlib.Path, ext: str = "bvh") -> pathlib.Path:
    return sorted((root / "trn" / "main-agent" / "bvh").glob(f"*.{ext}"))[0]


def test_default_skeleton_is_the_speakers_own(corpora):
    motion = load_motion(_first(corpora["default"]))
    assert motion.joint_names[:2] == ["Hips", "Spine"] and len(motion.joint_names) == 16
    assert "skeleton" not in json.loads((corpora["default"] / "corpus.json").read_text())


@pytest.mark.parametrize("skeleton, wrists", [("genea2023", ("b_r_wrist", "b_l_wrist")),
                                              ("beat", ("RightHand", "LeftHand"))])
def test_bvh_skeletons_carry_the_same_performance(corpora, skeleton, wrists):
    own = load_motion(_first(corpora["default"]))
    other = load_motion(_first(corpora[skeleton]))
    assert json.loads((corpora[skeleton] / "corpus.json").read_text())["skeleton"] == skeleton
    if skeleton == "genea2023":
        assert other.joint_names == GENEA2023            # the 56 joints in the FGD scripts' order, fingers included
        parent = other.skeleton.parents[other.joint_index("b_r_index1")]
        assert other.joint_names[parent] == "b_r_wrist"
    else:
        assert {"HeadEnd", "RightHandIndex1", "RightHandThumb4", "LeftToeBase"} <= set(other.joint_names)
    assert other.n_frames == own.n_frames
    p_own, p_other = own.positions(), other.positions()
    for own_name, name in zip(("RightHand", "LeftHand"), wrists):   # bone lengths kept: the wrists move alike
        assert np.allclose(p_own[:, own.joint_index(own_name)], p_other[:, other.joint_index(name)], atol=1e-6)


def test_smplx_skeleton_writes_rotations(corpora):
    own = load_motion(_first(corpora["default"]))
    data = read_smplx(_first(corpora["smplx"], "npz"))
    assert data.poses.shape == (own.n_frames, 165) and data.fps == pytest.approx(own.fps)
    assert data.betas.size == 0                               # rotations only: no body shape
    from scipy.spatial.transform import Rotation

    sk = own.skeleton
    col = int(sk.channel_starts[sk.index("RightForeArm")])
    elbow = Rotation.from_euler("ZXY", own.values[:, col:col + 3], degrees=True).as_rotvec()
    j = SMPLX_JOINT_NAMES.index("right_elbow")
    assert np.allclose(data.poses[:, 3 * j:3 * j + 3], elbow, atol=1e-6)
    assert np.allclose(data.poses[:, 3 * SMPLX_JOINT_NAMES.index("left_knee"):][:, :3], 0.0)


def test_unknown_skeleton_is_refused(tmp_path):
    res = CliRunner().invoke(main, ["corpus", "synth", "-o", str(tmp_path / "x"), "--skeleton", "trinity"])
    assert res.exit_code != 0 and "genea2023" in res.output
