"""Rotations, operations, filters and positions files."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import evalsuite
from evalsuite.errors import InputError, MotionError
from evalsuite.motion import filters, ops, rotations
from evalsuite.motion.presets import GENEA2020_UPPER
from evalsuite.motion.samples import sample_path
from evalsuite.motion.synthetic import synthetic_motion


@pytest.fixture(scope="module")
def walk():
    return evalsuite.load_motion(sample_path("walk01"))


@pytest.fixture(scope="module")
def humanoid():
    return synthetic_motion(n_joints=30, fps=30, seconds=2, seed=3)


# --- rotations ------------------------------------------------------------------------------

@pytest.mark.parametrize("axes", ["XYZ", "ZXY", "YZX", "ZYX", "XZY", "YXZ", "ZXZ", "X", "YX"])
def test_euler_to_matrix_matches_scipy_intrinsic(axes):
    rng = np.random.default_rng(0)
    angles = rng.uniform(-180, 180, size=(50, len(axes)))
    ours = rotations.euler_to_matrix(angles, axes)
    ref = Rotation.from_euler(axes, angles, degrees=True).as_matrix()
    np.testing.assert_allclose(ours, ref, atol=1e-12)


def test_representation_round_trips():
    rng = np.random.default_rng(1)
    mats = Rotation.random(100, random_state=2).as_matrix().reshape(10, 10, 3, 3)
    np.testing.assert_allclose(rotations.quaternion_to_matrix(rotations.matrix_to_quaternion(mats)), mats, atol=1e-12)
    np.testing.assert_allclose(rotations.expmap_to_matrix(rotations.matrix_to_expmap(mats)), mats, atol=1e-12)
    np.testing.assert_allclose(rotations.sixd_to_matrix(rotations.matrix_to_6d(mats)), mats, atol=1e-12)
    eul = rotations.matrix_to_euler(mats, "ZXY")
    np.testing.assert_allclose(rotations.euler_to_matrix(eul, "ZXY"), mats, atol=1e-12)
    # 6D of a noisy matrix still gives a proper rotation (Gram-Schmidt)
    noisy = rotations.sixd_to_matrix(rotations.matrix_to_6d(mats) + rng.normal(0, 0.01, (10, 10, 6)))
    np.testing.assert_allclose(noisy @ np.swapaxes(noisy, -1, -2), np.broadcast_to(np.eye(3), noisy.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(noisy), 1.0, atol=1e-12)


def test_slerp_midpoint_and_endpoints():
    q0 = Rotation.from_euler("Z", 0, degrees=True).as_quat()
    q1 = Rotation.from_euler("Z", 90, degrees=True).as_quat()
    mid = rotations.quaternion_slerp(q0, q1, 0.5)
    np.testing.assert_allclose(Rotation.from_quat(mid).as_euler("ZXY", degrees=True), [45, 0, 0], atol=1e-9)
    np.testing.assert_allclose(rotations.quaternion_slerp(q0, -q1, 1.0), q1, atol=1e-12)  # shorter arc


# --- joint selection ------------------------------------------------------------------------

def test_select_preset_on_genea_named_skeleton(humanoid):
    upper = ops.select_joints(humanoid, "genea2020_upper")
    assert upper.joint_names == GENEA2020_UPPER
    assert not upper.is_hierarchical  # the preset leaves out the root
    np.testing.assert_array_equal(upper.positions(), humanoid.positions()[:, [humanoid.joint_index(n)
                                                                              for n in GENEA2020_UPPER]])
    # Spine's parent Hips is gone: it becomes a root; Spine1's parent is Spine.
    assert upper.parents[0] == -1
    assert upper.joint_names[upper.parents[1]] == "Spine"


def test_drop_subtree_keeps_bvh_and_world_positions(humanoid):
    fingers = [n for n in humanoid.joint_names if "Hand" in n and n not in ("RightHand", "LeftHand")]
    pruned = ops.drop_joints(humanoid, fingers)
    assert pruned.is_hierarchical
    kept = [humanoid.joint_index(n) for n in pruned.joint_names]
    np.testing.assert_allclose(pruned.positions(), humanoid.positions()[:, kept], atol=1e-9)
    assert "RightHand_End" in pruned.skeleton.end_site_names  # the hand keeps a bone to draw


def test_unknown_joint_names_are_listed(walk):
    with pytest.raises(MotionError, match="'Nope'.*it has: Hips"):
        ops.select_joints(walk, ["Hips", "Nope"])


# --- resampling, cutting, centering ---------------------------------------------------------

def test_resample_integer_ratio_keeps_frames(humanoid):
    down = ops.resample(humanoid, 15)
    assert down.fps == 15
    assert down.n_frames == 30
    np.testing.assert_allclose(down.positions(), humanoid.positions()[::2], atol=1e-9)


def test_resample_up_and_back_is_identity(walk):
    up = ops.resample(walk, 48)
    assert up.n_frames == 2 * walk.n_frames - 1
    np.testing.assert_allclose(ops.resample(up, 24).positions(), walk.positions(), atol=1e-9)


def test_resample_uses_slerp_for_rotations():
    motion = synthetic_motion(n_joints=20, fps=10, seconds=1, seed=0)
    values = motion.values.copy()
    values[:, 3:] = 0.0
    values[:, 3] = np.arange(len(values)) * 40.0  # root Z rotation 0, 40, 80, ... degrees
    motion = motion.with_values(values)
    up = ops.resample(motion, 20)
    # Halfway between 0 and 40 degrees about Z is 20 degrees.
    np.testing.assert_allclose(up.values[1, 3], 20.0, atol=1e-9)
    np.testing.assert_allclose(up.values[1, 0:3], (values[0, 0:3] + values[1, 0:3]) / 2, atol=1e-12)


def test_resample_positions_motion_linear():
    pos = np.zeros((3, 1, 3))
    pos[:, 0, 0] = [0.0, 1.0, 4.0]
    m = evalsuite.Motion.from_positions(pos, ["a"], fps=10)
    up = ops.resample(m, 20)
    np.testing.assert_allclose(up.positions()[:, 0, 0], [0.0, 0.5, 1.0, 2.5, 4.0])


def test_cut_by_time(walk):
    part = ops.cut(walk, 1.0, 2.0)
    assert part.n_frames == 24
    np.testing.assert_allclose(part.positions(), walk.positions()[24:48])
    with pytest.raises(MotionError, match="outside the motion"):
        ops.cut(walk, 10.0, 11.0)


def test_cut_past_the_end_is_clipped_or_refused(walk):
    assert ops.cut(walk, 4.0, 60.0).n_frames == walk.n_frames - 96  # renderers cut many files to one span
    with pytest.raises(MotionError, match=r"cut 4 s to 60 s ends outside the motion, which lasts 4.20833 s"):
        ops.cut(walk, 4.0, 60.0, past_end=False)
    assert ops.cut(walk, 4.0, 4.21, past_end=False).n_frames == 5  # rounds to the last frame's end


@pytest.mark.parametrize("axes", ["xz", "xyz"])
def test_center_on_root(walk, axes):
    centred = ops.center(walk, axes=axes)
    assert centred.is_hierarchical
    idx = ["xyz".index(a) for a in axes]
    np.testing.assert_allclose(centred.positions()[:, 0, idx], 0.0, atol=1e-9)
    rel = walk.positions() - walk.positions()[:, :1]
    np.testing.assert_allclose(centred.positions() - centred.positions()[:, :1], rel, atol=1e-9)


# --- filters --------------------------------------------------------------------------------

def test_moving_average_of_a_line_is_the_line_inside():
    x = np.arange(20, dtype=float)[:, None]
    np.testing.assert_allclose(filters.moving_average(x, 5)[2:-2], x[2:-2])


def test_savgol_keeps_cubics():
    t = np.linspace(0, 1, 40)[:, None]
    x = 3 * t ** 3 - t
    np.testing.assert_allclose(filters.savgol(x, 9, 3), x, atol=1e-12)


def test_one_euro_removes_jitter_and_follows_steps():
    rng = np.random.default_rng(0)
    clean = np.repeat([0.0, 10.0], 100)[:, None]
    noisy = clean + rng.normal(0, 0.5, clean.shape)
    out = filters.one_euro(noisy, fps=60, min_cutoff=1.0, beta=0.5)
    assert np.std(out[50:100] - clean[50:100]) < 0.5 * np.std(noisy[50:100] - clean[50:100])
    assert abs(out[-1, 0] - 10.0) < 1.0


def test_smooth_bvh_unwraps_angles(walk):
    values = walk.values.copy()
    values[:, 3] = np.where(np.arange(len(values)) % 2 == 0, 179.0, -179.0)  # +-179 is a 2 degree wiggle
    smoothed = filters.smooth(walk.with_values(values), "moving_average")
    assert smoothed.is_hierarchical
    assert np.all(np.abs(np.abs(smoothed.values[5:-5, 3]) - 180.0) < 2.0)  # not averaged towards 0


# --- positions files ------------------------------------------------------------------------

def test_npz_npy_csv_round_trips(walk, tmp_path):
    pos = walk.positions(end_sites=True)
    names = walk.position_names(end_sites=True)
    evalsuite.save_motion(walk, tmp_path / "w.npz", end_sites=True)
    m = evalsuite.load_motion(tmp_path / "w.npz")
    assert m.joint_names == names
    assert m.fps == 24
    np.testing.assert_array_equal(m.positions(), pos)
    evalsuite.save_motion(walk, tmp_path / "w.csv")
    c = evalsuite.load_motion(tmp_path / "w.csv")
    assert c.joint_names == walk.joint_names
    assert c.fps == 24
    np.testing.assert_allclose(c.positions(), walk.positions(), atol=1e-6)
    evalsuite.save_motion(walk, tmp_path / "w.npy")
    with pytest.raises(InputError, match="give fps"):
        evalsuite.load_motion(tmp_path / "w.npy")
    n = evalsuite.load_motion(tmp_path / "w.npy", fps=24, joint_names=walk.joint_names)
    np.testing.assert_array_equal(n.positions(), walk.positions())


def test_genea_style_flat_npy(walk, tmp_path):
    flat = walk.positions().reshape(walk.n_frames, -1)
    np.save(tmp_path / "flat.npy", flat)
    m = evalsuite.load_motion(tmp_path / "flat.npy", fps=24)
    assert m.joint_names[0] == "joint0"
    assert m.n_joints == 19
    np.testing.assert_array_equal(m.positions(), walk.positions())
    with pytest.raises(InputError, match="3 joint names given but the array has 19 joints"):
        evalsuite.load_motion(tmp_path / "flat.npy", fps=24, joint_names=["a", "b", "c"])


@pytest.mark.parametrize("content,message", [
    (b"not a zip", "not a readable .npz"),
])
def test_bad_npz(tmp_path, content, message):
    (tmp_path / "bad.npz").write_bytes(content)
    with pytest.raises(InputError, match=message):
        evalsuite.load_motion(tmp_path / "bad.npz")


def test_bad_positions_csv_names_row_and_column(tmp_path):
    (tmp_path / "p.csv").write_text("time,a.x,a.y,a.z\n0,1,2,3\n0.1,1,oops,3\n")
    with pytest.raises(InputError) as info:
        evalsuite.load_motion(tmp_path / "p.csv")
    assert info.value.line == 3
    assert info.value.field == "a.y"
    assert "oops" in str(info.value)
    (tmp_path / "q.csv").write_text("a.x,a.y\n1,2\n")
    with pytest.raises(InputError, match="3 columns per joint"):
        evalsuite.load_motion(tmp_path / "q.csv", fps=30)


def test_nan_positions_rejected(tmp_path):
    arr = np.zeros((4, 2, 3))
    arr[2, 1, 0] = np.nan
    np.save(tmp_path / "n.npy", arr)
    with pytest.raises(InputError, match="frame 2, joint 'joint1'"):
        evalsuite.load_motion(tmp_path / "n.npy", fps=30)


def test_fps_mismatch_for_bvh_is_refused(tmp_path):
    with pytest.raises(InputError, match="file says 24"):
        evalsuite.load_motion(sample_path("walk01"), fps=30)
