"""The built-in conditions on SMPL-X motion (a BEAT2 corpus): the GENEA Leaderboard's make_synthetic_baseline.py
formulas on axis-angle, checked against the formulas written out here, and SMPL-X files out with the other keys
carried over."""
from __future__ import annotations

import numpy as np
import pytest
from corpus_helpers import wav
from scipy.spatial.transform import Rotation

from evalsuite.corpus import load_corpus
from evalsuite.generators import GeneratorError, find_generator
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import derive_seed, generate

TAKES = ("2_scott_0_1_1", "2_scott_0_2_2", "4_lawrence_0_3_3", "4_lawrence_0_4_4")
N = 90  # 3 s at 30 fps


@pytest.fixture(scope="module")
def requests(tmp_path_factory):
    root = tmp_path_factory.mktemp("beat2") / "beat_english_v2.0.0"
    for k, stem in enumerate(TAKES):
        rng = np.random.default_rng(k)
        wav(root / "wave16k" / f"{stem}.wav", N / 30)
        (root / "smplxflame_30").mkdir(parents=True, exist_ok=True)
        np.savez(root / "smplxflame_30" / f"{stem}.npz", poses=rng.normal(0, 0.3, (N, 165)).astype(np.float32),
                 trans=rng.normal(0, 0.1, (N, 3)).astype(np.float32), betas=rng.normal(size=300).astype(np.float32),
                 expressions=rng.normal(size=(N, 100)).astype(np.float32), model="smplx2020", gender="neutral",
                 mocap_frame_rate=np.array(30), note=np.array(f"take {k}"))
    return requests_from_corpus(load_corpus(root), "all", 30.0)


def _src(req):
    return dict(np.load(req.segment.motion))


def _run(name, requests, out, **kw):
    run = generate(find_generator(name), requests, out, progress=False, **kw)
    return {r["segment"]: dict(np.load(out / r["file"])) for r in run.files}, run


def _rng(req, seed=0):
    return np.random.default_rng(derive_seed(seed, req.segment_id, 0))


def _same_other_keys(out, src, but=("poses",)):
    assert list(out) == list(src)  # the same keys in the same order
    for key in src:
        assert out[key].dtype == src[key].dtype, key
        if key not in but:
            np.testing.assert_array_equal(out[key], src[key], err_msg=key)


def test_natural_writes_the_recorded_smplx_file_unchanged(requests, tmp_path):
    out, _ = _run("natural", requests, tmp_path)
    for req in requests:
        _same_other_keys(out[req.segment_id], _src(req), but=())


def test_gaussian_noise_adds_sigma_002_to_every_value(requests, tmp_path):
    out, run = _run("gaussian_noise", requests, tmp_path, seed=3)
    assert all(r["file"].endswith(".npz") for r in run.files)
    for req in requests:
        src, got = _src(req), out[req.segment_id]
        _same_other_keys(got, src)
        want = src["poses"].astype(np.float64) + _rng(req, 3).normal(0, 0.02, (N, 165))
        np.testing.assert_allclose(got["poses"], want.astype(np.float32), atol=1e-7)
        assert 0.018 < float(np.std(got["poses"].astype(np.float64) - src["poses"])) < 0.022


def test_attenuated_pulls_80_percent_to_the_files_mean(requests, tmp_path):
    out, _ = _run("attenuated", requests, tmp_path)
    for req in requests:
        src, got = _src(req), out[req.segment_id]
        _same_other_keys(got, src)
        p = src["poses"].astype(np.float64)
        np.testing.assert_allclose(got["poses"], (0.2 * p + 0.8 * p.mean(axis=0)).astype(np.float32), atol=1e-7)


def test_fluctuation_is_one_sine_per_sample_and_spares_the_global_orientation(requests, tmp_path):
    out, _ = _run("fluctuation", requests, tmp_path, seed=1)
    t = np.arange(N)
    for req in requests:
        src, got = _src(req), out[req.segment_id]
        _same_other_keys(got, src)
        phase = _rng(req, 1).uniform(0, 2 * np.pi)
        want = src["poses"].astype(np.float64) + 0.05 * np.sin(2 * np.pi * 0.2 * t + phase)[:, None]
        want[:, :3] = src["poses"][:, :3]
        np.testing.assert_allclose(got["poses"], want.astype(np.float32), atol=1e-7)
        diff = got["poses"].astype(np.float64) - src["poses"]
        assert np.all(diff[:, :3] == 0) and np.allclose(diff[:, 3:], diff[:, 3:4], atol=1e-6)


def test_fixing_holds_18_of_all_55_joints_at_frame_0(requests, tmp_path):
    out, _ = _run("fixing", requests, tmp_path, seed=2)
    for req in requests:
        src, got = _src(req), out[req.segment_id]
        _same_other_keys(got, src)
        joints = set(_rng(req, 2).choice(55, size=18, replace=False).tolist())
        rot, orig = got["poses"].reshape(N, 55, 3), src["poses"].reshape(N, 55, 3)
        held = {j for j in range(55) if np.all(rot[:, j] == orig[0, j])}
        assert held == joints
        others = sorted(set(range(55)) - joints)
        np.testing.assert_array_equal(rot[:, others], orig[:, others])


def test_mismatched_takes_the_donors_poses_and_trans_and_keeps_the_rest(requests, tmp_path):
    out, run = _run("mismatched", requests, tmp_path, seed=5)
    by_id = {r.segment_id: r for r in requests}
    for row in run.files:
        donor = row["meta"]["motion_from"]
        assert donor != row["segment"]
        src, got, don = _src(by_id[row["segment"]]), out[row["segment"]], _src(by_id[donor])
        _same_other_keys(got, src, but=("poses", "trans"))
        np.testing.assert_array_equal(got["poses"], don["poses"])
        np.testing.assert_array_equal(got["trans"], don["trans"])


def test_mean_pose_holds_the_per_joint_rotation_mean(requests, tmp_path):
    out, _ = _run("mean_pose", requests, tmp_path)
    poses = np.concatenate([_src(r)["poses"] for r in requests]).astype(np.float64).reshape(-1, 55, 3)
    for req in requests:
        got = out[req.segment_id]
        assert np.all(got["poses"] == got["poses"][:1]) and np.all(got["trans"] == got["trans"][:1])
        np.testing.assert_array_equal(got["betas"], _src(req)["betas"])
    mean = out[requests[0].segment_id]["poses"][0].reshape(55, 3)
    for j in (0, 12, 40):  # chordal L2 mean: the top eigenvector of the sum of q q^T (sign-free)
        q = Rotation.from_rotvec(poses[:, j]).as_quat()
        top = np.linalg.eigh(q.T @ q)[1][:, -1]
        np.testing.assert_allclose(np.abs(Rotation.from_rotvec(mean[j]).as_quat() @ top), 1.0, atol=1e-5)


def test_random_segments_write_smplx_made_of_other_segments(requests, tmp_path):
    out, _ = _run("random_segments", requests, tmp_path, seed=4)
    for req in requests:
        src, got = _src(req), out[req.segment_id]
        _same_other_keys(got, src, but=("poses", "trans", "expressions"))
        assert got["poses"].shape == (N, 165) and np.isfinite(got["poses"]).all()
        first = got["poses"][0]
        others = np.concatenate([_src(r)["poses"] for r in requests if r is not req])
        assert np.min(np.abs(others - first).max(axis=1)) < 1e-6  # the first frame is another segment's frame
        assert np.min(np.abs(src["poses"] - first).max(axis=1)) > 1e-3


def test_smplx_conditions_refuse_another_frame_rate_and_post_processing(requests, tmp_path):
    at_60 = requests_from_corpus(load_corpus(requests[0].segment.motion.parent.parent), "all", 60.0)
    with pytest.raises(GeneratorError, match=r"is at 30 fps but 60 fps were asked for; SMPL-X conditions keep the "
                                             r"source's rate \(generate with --fps 30\)"):
        generate(find_generator("attenuated"), at_60, tmp_path / "a", progress=False)
    from evalsuite.generators.runner import PostProcess

    with pytest.raises(GeneratorError, match=r"post-processing filters work on BVH or positions motion, not on SMPL-X"):
        generate(find_generator("attenuated"), requests, tmp_path / "b", progress=False,
                 post=[PostProcess("moving_average", (("window", 5),))])
