"""evalsuite.motion.smplx and smplx_layout: reading, writing and detecting SMPL-X .npz files."""
from __future__ import annotations

import zipfile

import numpy as np
import pytest
from smplx_helpers import fake_poses, write_fake_beat2_recording

from evalsuite.errors import InputError
from evalsuite.motion.smplx import SmplxData, is_smplx_npz, read_smplx, write_smplx
from evalsuite.motion.smplx_layout import SMPLH_JOINTS, SMPLX_JOINT_NAMES, SMPLX_PARENTS


def _arrays(path):
    with np.load(path, allow_pickle=False) as npz:
        return {k: npz[k] for k in npz.files}


def test_layout_is_the_smplx_order_and_tree():
    assert len(SMPLX_JOINT_NAMES) == len(SMPLX_PARENTS) == 55
    assert SMPLX_JOINT_NAMES[:3] == ("pelvis", "left_hip", "right_hip")
    assert SMPLX_JOINT_NAMES[22:25] == ("jaw", "left_eye_smplhf", "right_eye_smplhf")
    assert SMPLX_JOINT_NAMES[25] == "left_index1" and SMPLX_JOINT_NAMES[39] == "left_thumb3"
    assert SMPLX_JOINT_NAMES[40] == "right_index1" and SMPLX_JOINT_NAMES[54] == "right_thumb3"
    name = dict(enumerate(SMPLX_JOINT_NAMES))
    parent_of = {name[j]: (name[p] if p >= 0 else None) for j, p in enumerate(SMPLX_PARENTS)}
    assert parent_of["pelvis"] is None
    assert parent_of["head"] == "neck" and parent_of["jaw"] == "head" and parent_of["right_eye_smplhf"] == "head"
    assert parent_of["left_wrist"] == "left_elbow" and parent_of["left_thumb1"] == "left_wrist"
    assert parent_of["right_pinky3"] == "right_pinky2" and parent_of["right_index1"] == "right_wrist"
    assert parent_of["left_collar"] == "spine3" and parent_of["neck"] == "spine3"


def test_read_beat2_file(tmp_path):
    path = write_fake_beat2_recording(tmp_path / "2_scott_0_1_1.npz", n_frames=45, fps=30)
    data = read_smplx(path)
    raw = _arrays(path)
    assert data.poses.shape == (45, 165) and data.poses.dtype == np.float64
    assert np.array_equal(data.poses, raw["poses"]) and np.array_equal(data.trans, raw["trans"])
    assert data.betas.shape == (300,) and data.expressions is not None and data.expressions.shape == (45, 100)
    assert (data.model, data.gender, data.fps) == ("smplx2020", "neutral", 30.0)
    assert data.duration == pytest.approx(1.5)
    assert np.array_equal(data.rotvecs[:, 20], raw["poses"][:, 60:63])
    assert is_smplx_npz(path)


def test_amass_frame_rate_key_and_optional_keys(tmp_path):
    path = tmp_path / "amass.npz"
    np.savez(path, poses=fake_poses(10), mocap_framerate=np.array(120.0))
    data = read_smplx(path)
    assert data.fps == 120.0 and data.trans.shape == (10, 3) and not data.trans.any()
    assert data.betas.shape == (0,) and data.expressions is None and data.model == ""


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_write_back_is_exact(tmp_path, dtype):
    src = write_fake_beat2_recording(tmp_path / "a.npz", n_frames=20, dtype=dtype)
    extra_src = tmp_path / "b.npz"
    np.savez(extra_src, **dict(_arrays(src), note=np.arange(4, dtype=np.int16)))
    dst = tmp_path / "out.npz"
    write_smplx(dst, read_smplx(extra_src))
    before, after = _arrays(extra_src), _arrays(dst)
    assert list(before) == list(after)
    for key in before:
        assert before[key].dtype == after[key].dtype, key
        assert before[key].shape == after[key].shape, key
        assert before[key].tobytes() == after[key].tobytes(), key


def test_156_wide_smplh_layout_is_read_and_written_back(tmp_path):
    full = fake_poses(12).reshape(12, 55, 3)
    narrow = full[:, list(SMPLH_JOINTS)].reshape(12, 156)
    path = tmp_path / "smplh.npz"
    np.savez(path, poses=narrow, trans=np.zeros((12, 3)), mocap_frame_rate=np.array(30))
    data = read_smplx(path)
    rot = data.rotvecs
    assert not rot[:, 22:25].any()
    assert np.array_equal(rot[:, :22], full[:, :22]) and np.array_equal(rot[:, 25:], full[:, 25:])
    write_smplx(tmp_path / "back.npz", data)
    assert _arrays(tmp_path / "back.npz")["poses"].tobytes() == narrow.tobytes()
    data.poses[:, 22 * 3] = 0.1
    with pytest.raises(InputError, match="156 wide"):
        write_smplx(tmp_path / "bad.npz", data)


def test_three_dimensional_poses_are_read(tmp_path):
    poses = fake_poses(8)
    path = tmp_path / "p3.npz"
    np.savez(path, poses=poses.reshape(8, 55, 3), mocap_frame_rate=np.array(30))
    assert np.array_equal(read_smplx(path).poses, poses)


def test_data_made_in_code_is_written_with_the_beat2_keys(tmp_path):
    data = SmplxData(fake_poses(5), np.zeros((5, 3)), np.ones(10), None, "smplx2020", "neutral", 30.0)
    write_smplx(tmp_path / "new.npz", data)
    raw = _arrays(tmp_path / "new.npz")
    assert sorted(raw) == ["betas", "gender", "mocap_frame_rate", "model", "poses", "trans"]
    assert raw["mocap_frame_rate"].item() == 30
    back = read_smplx(tmp_path / "new.npz")
    assert np.array_equal(back.poses, data.poses) and back.model == "smplx2020"


def _save(path, **overrides):
    arrays = {"poses": fake_poses(6), "trans": np.zeros((6, 3)), "betas": np.zeros(10),
              "mocap_frame_rate": np.array(30)}
    arrays.update(overrides)
    np.savez(path, **{k: v for k, v in arrays.items() if v is not None})
    return path


@pytest.mark.parametrize("overrides, pattern", [
    ({"poses": None}, r"missing key 'poses'"),
    ({"mocap_frame_rate": None}, r"no frame rate: expected a key 'mocap_frame_rate'"),
    ({"poses": np.zeros((6, 72))}, r"poses: found shape \(6, 72\); expected \(T, 165\)"),
    ({"poses": np.zeros((6, 55, 4))}, r"poses: found shape \(6, 55, 4\)"),
    ({"poses": np.zeros((6, 165), dtype=np.int64)}, r"poses: expected floating-point numbers, found dtype int64"),
    ({"poses": np.zeros((0, 165))}, r"poses: no frames"),
    ({"trans": np.zeros((5, 3))}, r"trans: found shape \(5, 3\); expected \(6, 3\)"),
    ({"betas": np.zeros((2, 10))}, r"betas: found shape \(2, 10\); expected \(B,\)"),
    ({"expressions": np.zeros((4, 100))}, r"expressions: found shape \(4, 100\); expected \(6, E\)"),
    ({"mocap_frame_rate": np.array(0.0)}, r"mocap_frame_rate: expected one positive number"),
    ({"mocap_framerate": np.array(60.0)}, r"disagree"),
    ({"gender": np.array([1, 2])}, r"gender: expected one text value"),
])
def test_bad_files_give_precise_errors(tmp_path, overrides, pattern):
    path = _save(tmp_path / "bad.npz", **overrides)
    with pytest.raises(InputError, match=pattern) as info:
        read_smplx(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_nan_is_an_error_or_zero_when_asked(tmp_path):
    poses = fake_poses(6)
    poses[3, 20 * 3 + 1] = np.nan
    path = _save(tmp_path / "nan.npz", poses=poses)
    with pytest.raises(InputError, match=r"poses: NaN at frame 3, joint 'left_wrist'.*nan='zero'"):
        read_smplx(path)
    data = read_smplx(path, nan="zero")
    assert data.poses[3, 61] == 0.0 and np.isfinite(data.poses).all()
    poses[3, 61] = np.inf
    with pytest.raises(InputError, match="infinite value at frame 3"):
        read_smplx(_save(tmp_path / "inf.npz", poses=poses), nan="zero")


def test_pickled_objects_and_broken_archives_are_refused(tmp_path):
    path = _save(tmp_path / "obj.npz", gender=np.array([{"a": 1}], dtype=object))
    with pytest.raises(InputError, match="gender: holds pickled Python objects"):
        read_smplx(path)
    broken = tmp_path / "broken.npz"
    broken.write_bytes(b"not a zip")
    with pytest.raises(InputError, match="not a readable .npz archive"):
        read_smplx(broken)
    assert not is_smplx_npz(broken)


def test_detection_looks_for_poses(tmp_path):
    positions = tmp_path / "positions.npz"
    np.savez(positions, positions=np.zeros((3, 2, 3)), fps=np.float64(30))
    assert not is_smplx_npz(positions)
    assert not is_smplx_npz(tmp_path / "missing.npz")
    with zipfile.ZipFile(tmp_path / "z.npz", "w") as zf:
        zf.writestr("poses.npy", b"")
    assert is_smplx_npz(tmp_path / "z.npz")


def test_load_motion_gives_a_rotation_motion_with_the_recording(tmp_path):
    from scipy.spatial.transform import Rotation

    from evalsuite.motion import load_motion
    from evalsuite.motion.motion import Motion
    from evalsuite.motion.smplx_motion import SmplxMotion

    path = write_fake_beat2_recording(tmp_path / "2_scott_0_1_1.npz", n_frames=20, fps=30)
    motion = load_motion(path)
    assert isinstance(motion, SmplxMotion) and motion.is_hierarchical
    assert motion.joint_names == list(SMPLX_JOINT_NAMES) and list(motion.parents) == list(SMPLX_PARENTS)
    assert (motion.fps, motion.n_frames, motion.name) == (30.0, 20, "2_scott_0_1_1")
    assert np.array_equal(motion.smplx.poses, _arrays(path)["poses"])
    exact = Rotation.from_rotvec(motion.smplx.poses.reshape(-1, 3)).as_matrix().reshape(20, 55, 3, 3)
    assert np.allclose(motion.local_rotations(), exact, atol=1e-12)
    assert np.allclose(Motion.local_rotations(motion), exact, atol=1e-9)   # the Euler channels agree
    assert np.allclose(motion.values[:, :3], motion.smplx.trans)            # root channels: trans (no model)
    summary = motion.summary()
    assert summary["format"] == "smplx" and summary["betas"] == 300 and summary["gender"] == "neutral"
    with pytest.raises(InputError, match="fps 25 was given but the file says 30"):
        load_motion(path, fps=25)


def test_operations_keep_the_smplx_recording(tmp_path):
    from evalsuite.motion import load_motion, ops, save_motion
    from evalsuite.motion.smplx_motion import SmplxMotion

    path = write_fake_beat2_recording(tmp_path / "rec.npz", n_frames=60, fps=30)
    motion = load_motion(path)
    cut = ops.cut(motion, 0.5, 1.5)
    assert isinstance(cut, SmplxMotion) and cut.n_frames == 30
    assert np.allclose(cut.smplx.poses, motion.smplx.poses[15:45], atol=1e-9)
    assert np.allclose(cut.smplx.trans, motion.smplx.trans[15:45], atol=1e-12)
    assert cut.smplx.expressions is None
    half = ops.resample(motion, 15)
    assert isinstance(half, SmplxMotion) and half.fps == 15 and half.smplx.fps == 15
    save_motion(cut, tmp_path / "cut.npz")
    again = read_smplx(tmp_path / "cut.npz")
    assert again.n_frames == 30 and again.fps == 30 and again.model == "smplx2020"
    assert not isinstance(ops.select_joints(motion, "pelvis,spine1"), SmplxMotion)


def test_positions_npz_still_loads_as_positions(tmp_path):
    from evalsuite.motion import load_motion
    from evalsuite.motion.smplx_motion import SmplxMotion

    path = tmp_path / "pos.npz"
    np.savez(path, positions=np.zeros((4, 2, 3)), joint_names=np.array(["a", "b"]), fps=np.float64(25))
    motion = load_motion(path)
    assert not isinstance(motion, SmplxMotion) and motion.joint_names == ["a", "b"] and motion.fps == 25
