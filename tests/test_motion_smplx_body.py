"""evalsuite.motion.smplx_body: J(β), forward kinematics, modes, caching and the missing-model message.

The reference here is written from the definitions, frame by frame and joint by joint: Rodrigues' formula for
each axis-angle, 4x4 homogeneous transforms chained along the parent table, J = J_regressor · (v_template +
shapedirs · β) with explicit sums."""
from __future__ import annotations

import math

import numpy as np
import pytest
from smplx_helpers import fake_smplx_model, write_fake_beat2_recording

from evalsuite.errors import InputError
from evalsuite.motion.smplx import read_smplx
from evalsuite.motion.smplx_body import (
    MODEL_ENV,
    SmplxModelMissing,
    load_body_model,
    resolve_model_path,
    rest_joints,
    smplx_positions,
)
from evalsuite.motion.smplx_layout import SMPLX_PARENTS


def _rodrigues(v):
    theta = math.sqrt(v[0] ** 2 + v[1] ** 2 + v[2] ** 2)
    if theta < 1e-12:
        return np.eye(3)
    k = [v[0] / theta, v[1] / theta, v[2] / theta]
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(theta) * kx + (1.0 - math.cos(theta)) * (kx @ kx)


def _reference_rest(model_file, betas, expression=None):
    with np.load(model_file) as m:
        v, sd, jr = m["v_template"], m["shapedirs"], m["J_regressor"]
    n_shape = 300 if sd.shape[2] >= 300 else sd.shape[2] // 2
    joints = np.zeros((55, 3))
    for j in range(55):
        for i in range(v.shape[0]):
            if jr[j, i] == 0.0:
                continue
            vert = v[i] + sd[i, :, :len(betas)] @ np.asarray(betas, dtype=float)
            if expression is not None:
                vert = vert + sd[i, :, n_shape:n_shape + len(expression)] @ expression
            joints[j] += jr[j, i] * vert
    return joints


def _reference_frame(rotvecs, rest, trans):
    transforms = []
    for j, p in enumerate(SMPLX_PARENTS):
        local = np.eye(4)
        local[:3, :3] = _rodrigues(rotvecs[j])
        local[:3, 3] = rest[j] - (rest[p] if p >= 0 else 0.0)
        transforms.append(local if p < 0 else transforms[p] @ local)
    return np.array([t[:3, 3] + trans for t in transforms])


@pytest.fixture()
def model(tmp_path):
    return fake_smplx_model(tmp_path / "SMPLX_FAKE.npz", n_betas=300, n_verts=120, seed=3)


def test_rest_joints_follow_the_regression(model, tmp_path):
    betas = np.random.default_rng(1).normal(size=300)
    assert np.allclose(rest_joints(model, betas), _reference_rest(model, betas), atol=1e-12)
    assert np.allclose(rest_joints(model, betas[:16]), _reference_rest(model, betas[:16]), atol=1e-12)
    assert np.allclose(rest_joints(model, np.zeros(0)), _reference_rest(model, []), atol=1e-12)


def test_full_positions_equal_the_chain_of_transforms(model, tmp_path):
    path = write_fake_beat2_recording(tmp_path / "rec.npz", n_frames=6, n_expr=100, seed=5)
    data = read_smplx(path)
    got = smplx_positions(data, model, mode="full")
    assert got.shape == (6, 55, 3)
    for t in range(6):
        rest = _reference_rest(model, data.betas, data.expressions[t])
        want = _reference_frame(data.rotvecs[t], rest, data.trans[t])
        assert np.abs(got[t] - want).max() < 1e-6


def test_leaderboard_positions_zero_orientation_translation_jaw_eyes_and_take_the_given_betas(model, tmp_path):
    data = read_smplx(write_fake_beat2_recording(tmp_path / "rec.npz", n_frames=4, seed=8))
    gt_betas = np.random.default_rng(9).normal(size=300)
    got = smplx_positions(data, model, mode="leaderboard", betas=gt_betas)
    rest = _reference_rest(model, gt_betas)
    for t in range(4):
        rot = data.rotvecs[t].copy()
        rot[[0, 22, 23, 24]] = 0.0
        want = _reference_frame(rot, rest, np.zeros(3))
        assert np.abs(got[t] - want).max() < 1e-6
    assert np.allclose(got[:, 0], rest[0])       # the pelvis stays at its rest place
    own = smplx_positions(data, model, mode="leaderboard")
    assert np.abs(own - got).max() > 1e-4        # the betas given are the ones used


def test_rest_joints_are_cached_in_memory_and_on_disk(model, tmp_path):
    betas = np.linspace(-1.0, 1.0, 300)
    first = rest_joints(model, betas, cache_dir=tmp_path / "cache")
    files = list((tmp_path / "cache").glob("smplx_rest_joints_*.npy"))
    assert len(files) == 1 and np.array_equal(np.load(files[0]), first)
    first[0, 0] = 99.0                            # callers get copies
    assert rest_joints(model, betas)[0, 0] != 99.0


def test_without_a_model_the_message_is_one_line(tmp_path, monkeypatch):
    monkeypatch.delenv(MODEL_ENV, raising=False)
    data = read_smplx(write_fake_beat2_recording(tmp_path / "rec.npz", n_frames=3))
    with pytest.raises(SmplxModelMissing) as info:
        smplx_positions(data, None)
    message = str(info.value)
    assert "\n" not in message
    assert "--smplx-model" in message and MODEL_ENV in message and "https://smpl-x.is.tue.mpg.de" in message
    with pytest.raises(InputError, match="no such SMPL-X model file"):
        resolve_model_path(tmp_path / "nope.npz")


def test_environment_variable_names_the_model(model, tmp_path, monkeypatch):
    monkeypatch.setenv(MODEL_ENV, str(model))
    assert resolve_model_path(None) == model
    data = read_smplx(write_fake_beat2_recording(tmp_path / "rec.npz", n_frames=3))
    assert np.array_equal(smplx_positions(data, None), smplx_positions(data, model))


def test_wrong_model_files_are_refused(tmp_path):
    good = fake_smplx_model(tmp_path / "m.npz", n_betas=10, n_verts=50)
    with np.load(good) as m:
        arrays = {k: m[k] for k in m.files}
    cases = {
        "missing key 'J_regressor'": {k: v for k, v in arrays.items() if k != "J_regressor"},
        r"J_regressor: found shape \(52, 50\); expected \(55, 50\) \(an SMPL-H": dict(
            arrays, J_regressor=arrays["J_regressor"][:52]),
        r"shapedirs: found shape \(50, 20\)": dict(arrays, shapedirs=arrays["shapedirs"][:, 0]),
        "kintree_table: .*SMPL-X parent table": dict(arrays, kintree_table=arrays["kintree_table"][:, ::-1]),
        "J_regressor: holds pickled Python objects": dict(arrays, J_regressor=np.array([{"sparse": 1}], dtype=object)),
    }
    for i, (pattern, content) in enumerate(cases.items()):
        path = tmp_path / f"bad{i}.npz"
        np.savez(path, **content)
        with pytest.raises(InputError, match=pattern):
            load_body_model(path)
    pkl = tmp_path / "SMPLX_NEUTRAL.pkl"
    pkl.write_bytes(b"x")
    with pytest.raises(InputError, match="pickled SMPL-X model files are not read"):
        load_body_model(pkl)
    with pytest.raises(InputError, match="300 betas but this model has 10 shape components"):
        rest_joints(good, np.zeros(300))


def test_long_recordings_in_blocks(model, tmp_path):
    from evalsuite.motion.smplx_body import smplx_fk

    data = read_smplx(write_fake_beat2_recording(tmp_path / "rec.npz", n_frames=3000, seed=2))
    pos = smplx_positions(data, model, mode="leaderboard")
    assert pos.shape == (3000, 55, 3) and np.isfinite(pos).all()
    rest = rest_joints(model, data.betas)
    per_frame = rest + np.random.default_rng(0).normal(0.0, 0.01, (3000, 55, 3))
    for r in (rest, per_frame):
        whole = smplx_fk(data.rotvecs, r, data.trans, block_frames=4096)
        assert np.array_equal(whole, smplx_fk(data.rotvecs, r, data.trans, block_frames=7))
    t = 1234
    want = _reference_frame(data.rotvecs[t], per_frame[t], data.trans[t])
    assert np.abs(smplx_fk(data.rotvecs, per_frame, data.trans, block_frames=100)[t] - want).max() < 1e-9


def test_smplx_motion_positions_offsets_and_bvh_round_trip(model, tmp_path, monkeypatch):
    from evalsuite.motion import load_motion, save_motion
    from evalsuite.motion.motion import Motion
    from evalsuite.motion.smplx_motion import SmplxMotion

    monkeypatch.delenv(MODEL_ENV, raising=False)
    path = write_fake_beat2_recording(tmp_path / "rec.npz", n_frames=30, n_expr=0, seed=4)
    motion = load_motion(path, smplx_model=model)
    assert isinstance(motion, SmplxMotion) and motion.has_positions
    want = smplx_positions(read_smplx(path), model)
    assert np.abs(motion.positions() - want).max() < 1e-9
    # the skeleton's OFFSETs are J(beta): plain BVH forward kinematics of the Euler channels gives the same
    assert np.abs(Motion.positions(motion) - want).max() < 1e-9
    save_motion(motion, tmp_path / "rec.bvh")
    back = load_motion(tmp_path / "rec.bvh")
    order = [back.joint_names.index(n) for n in motion.joint_names]   # BVH lists joints depth first
    assert sorted(back.joint_names) == sorted(motion.joint_names) and back.fps == 30.0
    assert np.abs(back.positions()[:, order] - want).max() < 1e-6
    board = load_motion(path, smplx_model=model, positions="leaderboard")
    save_motion(board, tmp_path / "board.bvh")
    want_board = smplx_positions(read_smplx(path), model, mode="leaderboard")
    assert np.abs(load_motion(tmp_path / "board.bvh").positions()[:, order] - want_board).max() < 1e-6


def test_smplx_motion_without_a_model_has_rotations_but_no_positions(tmp_path, monkeypatch):
    from evalsuite.motion import load_motion, save_motion

    monkeypatch.delenv(MODEL_ENV, raising=False)
    path = write_fake_beat2_recording(tmp_path / "rec.npz", n_frames=5)
    motion = load_motion(path)
    assert motion.local_rotations().shape == (5, 55, 3, 3)
    for action in (motion.positions, lambda: save_motion(motion, tmp_path / "x.bvh"),
                   lambda: save_motion(motion, tmp_path / "x.npy")):
        with pytest.raises(SmplxModelMissing) as info:
            action()
        assert "\n" not in str(info.value) and "--smplx-model" in str(info.value)
    assert not (tmp_path / "x.bvh").exists()
    assert "need --smplx-model" in motion.summary()["positions"]


@pytest.mark.parametrize("mode", ["full", "leaderboard"])
def test_selected_joints_keep_the_positions_mode(model, tmp_path, monkeypatch, mode):
    from evalsuite.motion import load_motion, ops

    monkeypatch.delenv(MODEL_ENV, raising=False)
    path = write_fake_beat2_recording(tmp_path / "rec.npz", n_frames=8, n_expr=0, seed=6)
    names = ["pelvis", "spine1", "spine2", "spine3", "neck", "head", "jaw"]
    part = ops.select_joints(load_motion(path, smplx_model=model, positions=mode), names)
    want = smplx_positions(read_smplx(path), model, mode=mode)[:, [0, 3, 6, 9, 12, 15, 22]]
    assert part.joint_names == names and np.abs(part.positions() - want).max() < 1e-9
    assert np.abs(ops.cut(part, 0.0, 0.1).positions() - want[:3]).max() < 1e-9
    bare = ops.select_joints(load_motion(path), names)
    with pytest.raises(SmplxModelMissing):
        bare.positions()
