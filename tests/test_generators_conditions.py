"""Built-in conditions against their definitions (GENEA designs and the Leaderboard's synthetic baselines)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from evalsuite.generators import GeneratorError, find_generator
from evalsuite.generators.checking import tiny_corpus
from evalsuite.generators.requests import requests_from_corpus
from evalsuite.generators.runner import generate
from evalsuite.motion.io import load_motion
from evalsuite.motion.joint_rotations import rotation_joints


@pytest.fixture(scope="module")
def corpus(tmp_path_factory):
    return tiny_corpus(tmp_path_factory.mktemp("tiny"), n_segments=6, seconds=5.0)


@pytest.fixture(scope="module")
def requests(corpus):
    return requests_from_corpus(corpus, "all", 30.0)


def _run(name, requests, out, **kw):
    run = generate(find_generator(name), requests, out, progress=False, **kw)
    return {r["segment"] if kw.get("samples", 1) == 1 else (r["segment"], r["sample"]): load_motion(out / r["file"])
            for r in run.files}, run


def _natural(requests):
    return {r.segment_id: load_motion(r.segment.motion) for r in requests}


def _rotvecs(motion):
    return np.stack([Rotation.from_euler(axes.upper(), motion.values[:, cols], degrees=True).as_rotvec()
                     for _, cols, axes in rotation_joints(motion)], axis=1)


def test_natural_is_the_recorded_motion(requests, tmp_path):
    out, _ = _run("natural", requests, tmp_path)
    nat = _natural(requests)
    for sid, m in out.items():
        np.testing.assert_allclose(m.values, nat[sid].values, atol=1e-6)


def test_mismatched_never_keeps_own_motion_and_is_reproducible(requests, tmp_path):
    out, run = _run("mismatched", requests, tmp_path / "a", seed=7)
    again, _ = _run("mismatched", requests, tmp_path / "b", seed=7)
    nat = _natural(requests)
    for sid, m in out.items():
        assert not np.allclose(m.values, nat[sid].values[: m.n_frames], atol=1e-3), sid
        donor = next(r["meta"]["motion_from"] for r in run.files if r["segment"] == sid)
        assert donor != sid
        np.testing.assert_allclose(m.values, nat[donor].values[: m.n_frames], atol=1e-6)
        np.testing.assert_array_equal(m.values, again[sid].values)


def test_mean_pose_has_zero_velocity(requests, tmp_path):
    out, _ = _run("mean_pose", requests, tmp_path)
    for m in out.values():
        assert np.abs(np.diff(m.positions(), axis=0)).max() == 0.0
    # it is the mean of the rotations: the mean rotation's distance to the frames is minimal in the chordal sense
    first = next(iter(out.values()))
    nat = _natural(requests)
    allv = np.concatenate([m.values for m in nat.values()])
    j, cols, axes = rotation_joints(first)[3]
    expected = Rotation.from_euler(axes.upper(), allv[:, cols], degrees=True).mean()
    got = Rotation.from_euler(axes.upper(), first.values[0, cols], degrees=True)
    assert (expected.inv() * got).magnitude() < 1e-6


def test_random_segments_have_no_jump_larger_than_natural_motion(requests, tmp_path):
    out, _ = _run("random_segments", requests, tmp_path, seed=3)
    nat = _natural(requests)
    natural_step = max(np.linalg.norm(np.diff(m.positions(), axis=0), axis=-1).max() for m in nat.values())
    for sid, m in out.items():
        step = np.linalg.norm(np.diff(m.positions(), axis=0), axis=-1).max()
        assert step <= natural_step * 1.05, (sid, step, natural_step)
        assert m.n_frames == 150


def test_gaussian_noise_matches_its_definition(requests, tmp_path):
    out, _ = _run("gaussian_noise", requests, tmp_path, seed=1)
    nat = _natural(requests)
    res = np.concatenate([(_rotvecs(m) - _rotvecs(nat[sid])).ravel() for sid, m in out.items()])
    assert abs(res.std() - 0.02) < 0.001
    assert abs(res.mean()) < 0.001


def test_attenuated_matches_its_definition(requests, tmp_path):
    out, _ = _run("attenuated", requests, tmp_path)
    for sid, m in _natural(requests).items():
        rv = _rotvecs(m)
        expected = 0.2 * rv + 0.8 * rv.mean(axis=0, keepdims=True)
        np.testing.assert_allclose(_rotvecs(out[sid]), expected, atol=1e-5)


def test_fluctuation_matches_its_definition(requests, tmp_path):
    out, _ = _run("fluctuation", requests, tmp_path, seed=2)
    for sid, m in _natural(requests).items():
        res = _rotvecs(out[sid]) - _rotvecs(m)
        assert np.abs(res[:, 0]).max() < 1e-5                 # the root joint is left alone
        body = res[:, 1:]
        assert abs(np.abs(body).max() - 0.05) < 0.002           # amplitude 0.05 rad
        np.testing.assert_allclose(body[5:], body[:-5], atol=1e-5)   # 0.2 cycles per frame: period 5 frames


def test_fixing_matches_its_definition(requests, tmp_path):
    out, _ = _run("fixing", requests, tmp_path, seed=2)
    for sid, m in _natural(requests).items():
        rv, got = _rotvecs(m), _rotvecs(out[sid])
        held = [r for r in range(rv.shape[1]) if np.abs(got[:, r] - got[:1, r]).max() < 1e-6]
        assert len(held) == round(rv.shape[1] * 18 / 55)
        assert 0 not in held
        for r in held:
            np.testing.assert_allclose(got[:, r], np.repeat(rv[:1, r], len(rv), axis=0), atol=1e-5)
        free = [r for r in range(rv.shape[1]) if r not in held]
        np.testing.assert_allclose(got[:, free], rv[:, free], atol=1e-5)


def test_smoothed_applies_the_filter_and_operators_chain(requests, tmp_path):
    noisy, _ = _run("gaussian_noise", requests, tmp_path / "noisy", seed=1)
    smooth, _ = _run("smoothed", requests, tmp_path / "smooth", config={"of": str(tmp_path / "noisy"),
                                                                        "method": "savgol", "window": 9, "order": 3})
    for sid in noisy:
        jerk = lambda m: np.abs(np.diff(m.positions(), 3, axis=0)).mean()  # noqa: E731
        assert jerk(smooth[sid]) < 0.5 * jerk(noisy[sid])


def test_precomputed_reads_a_folder_and_hashes_it(requests, tmp_path):
    _run("natural", requests, tmp_path / "nat")
    out, run = _run("precomputed", requests, tmp_path / "pre", config={"dir": str(tmp_path / "nat")})
    assert run.files[0]["meta"]["source_sha256"]
    partial = tmp_path / "partial"
    partial.mkdir()
    (partial / "seg01.bvh").write_bytes((tmp_path / "nat" / "seg01.bvh").read_bytes())
    with pytest.raises(GeneratorError, match="no file for segment 'seg00' in .*partial"):
        _run("precomputed", requests, tmp_path / "pre2", config={"dir": str(partial)})
