"""FGD: Fréchet oracles, the score_fgd contract, matching data to the model, bootstrap, determinism."""
from __future__ import annotations

import math

import numpy as np
import pytest
from learned_helpers import FPS, WINDOW, natural, trained
from scipy import linalg

from evalsuite.errors import InputError
from evalsuite.learned.fgd import ROW_KEYS, bootstrap_fd, raw_frechet_distance, score_fgd
from evalsuite.metrics.frechet import frechet_distance_samples
from evalsuite.motion import Motion
from evalsuite.motion.ops import resample


def _sqrtm_fd(x, y):
    """Textbook FD with scipy's sqrtm on the covariance product, as an independent check."""
    m1, m2 = x.mean(0), y.mean(0)
    s1, s2 = np.cov(x, rowvar=False), np.cov(y, rowvar=False)
    covmean = linalg.sqrtm(s1 @ s2).real
    return float((m1 - m2) @ (m1 - m2) + np.trace(s1 + s2 - 2 * covmean))


def test_fd_oracles_hold_for_gaussian_samples():
    rng = np.random.default_rng(0)
    d, n = 8, 200_000
    mu = rng.normal(size=d)
    x = rng.normal(size=(n, d))
    y = rng.normal(size=(n, d)) + mu
    assert raw_frechet_distance(x, y) == pytest.approx(mu @ mu, rel=0.01, abs=0.01)
    s1, s2 = 0.5, 2.0
    assert raw_frechet_distance(s1 * x, s2 * rng.normal(size=(n, d))) == pytest.approx(d * (s1 - s2) ** 2, rel=0.01)
    assert raw_frechet_distance(x, x) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("n_x, n_y, d", [(300, 250, 20), (40, 30, 90), (25, 60, 70)])
def test_raw_space_fd_equals_the_dense_computation(n_x, n_y, d):
    # Includes N < D (singular covariances), where raw-space FGD usually lives.
    rng = np.random.default_rng(n_x + d)
    x = rng.normal(size=(n_x, d)) @ rng.normal(size=(d, d)) * 0.3
    y = rng.normal(size=(n_y, d)) @ rng.normal(size=(d, d)) * 0.3 + 0.2
    with pytest.warns(Warning) if min(n_x, n_y) <= d else _nothing():
        dense = frechet_distance_samples(x, y)
    # The dense form takes square roots of round-off eigenvalues in the null space
    # (sqrt(1e-13) ~ 3e-7 each); the factored form never forms them: agreement to ~1e-7.
    assert raw_frechet_distance(x, y) == pytest.approx(dense, rel=1e-7, abs=1e-8)
    if n_x > d and n_y > d:
        assert dense == pytest.approx(_sqrtm_fd(x, y), rel=1e-6)


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_bootstrap_interval_is_seeded_and_covers_the_distance():
    rng = np.random.default_rng(1)
    ref = [rng.normal(size=(40, 4)) for _ in range(12)]
    cond = [rng.normal(size=(40, 4)) + 1.0 for _ in range(12)]
    value = frechet_distance_samples(np.concatenate(ref), np.concatenate(cond))
    for unit in ("sequence", "window"):
        low, high = bootstrap_fd(ref, cond, n_bootstrap=300, unit=unit, seed=5)
        assert low < value < high
        assert (low, high) == bootstrap_fd(ref, cond, n_bootstrap=300, unit=unit, seed=5)
    assert all(math.isnan(v) for v in bootstrap_fd(ref, cond, n_bootstrap=0))


def test_bootstrap_interval_contains_the_estimate_where_the_percentile_interval_does_not():
    """Natural vs natural at 5 sequences a side (the reviewer's `natural 0 [0.95, 712]`): every resample's FD
    lies above the estimate, so the percentile interval excludes it; the centred interval does not."""
    from evalsuite.learned.fgd import bootstrap_fd_samples

    rng = np.random.default_rng(2)
    ref = [rng.normal(size=(30, 8)) for _ in range(5)]
    cond = [rng.normal(size=(30, 8)) for _ in range(5)]
    value = frechet_distance_samples(np.concatenate(ref), np.concatenate(cond))
    samples = bootstrap_fd_samples(ref, cond, n_bootstrap=400, seed=1)
    assert np.percentile(samples, 2.5) > value            # the old interval would exclude its estimate
    low, high = bootstrap_fd(ref, cond, n_bootstrap=400, seed=1)
    assert low <= value <= high
    q_low, q_mid, q_high = np.percentile(samples, [2.5, 50, 97.5])
    assert (low, high) == pytest.approx((max(value - (q_mid - q_low), 0.0), value + (q_high - q_mid)), rel=1e-12)


def test_score_fgd_rows_follow_the_contract_and_count_windows():
    model = trained()
    nat = natural()
    names = sorted(nat)
    reference = {n: nat[n] for n in names[0::2]}
    other = {n: nat[n] for n in names[1::2]}
    noisy = {n: m.with_positions(m.positions() + np.random.default_rng(0).normal(0, 30.0, m.positions().shape))
             for n, m in other.items()}
    rows = score_fgd(model, reference, {"natural": other, "noisy": noisy}, n_bootstrap=200)
    assert [(r["condition"], r["metric"]) for r in rows] == [
        ("natural", "fgd"), ("natural", "fgd_raw"), ("noisy", "fgd"), ("noisy", "fgd_raw")]
    per_seq = (int(20 * FPS) - WINDOW) // (WINDOW // 2) + 1  # complete windows of a 20 s piece
    for r in rows:
        assert tuple(r) == ROW_KEYS
        assert r["model_hash"] == model.content_hash
        assert r["window"] == WINDOW
        assert r["n_windows_reference"] == r["n_windows_condition"] == 4 * per_seq
        assert r["value"] >= 0
    fgd = {r["condition"]: r for r in rows if r["metric"] == "fgd"}
    raw = {r["condition"]: r for r in rows if r["metric"] == "fgd_raw"}
    assert fgd["noisy"]["value"] > fgd["natural"]["value"]
    assert raw["noisy"]["value"] > raw["natural"]["value"]
    assert fgd["noisy"]["ci_low"] <= fgd["noisy"]["value"] <= fgd["noisy"]["ci_high"]
    # Near 0 the FD's small-sample bias dominates: resamples (with duplicates) sit above the point
    # estimate; the interval is moved onto the estimate and the bias reported beside it.
    assert 0 <= fgd["natural"]["ci_low"] <= fgd["natural"]["value"] <= fgd["natural"]["ci_high"]
    assert fgd["natural"]["ci_high"] < fgd["noisy"]["ci_low"]
    assert fgd["natural"]["bootstrap_bias"] > 0
    assert math.isnan(raw["natural"]["ci_low"])
    # Raw-space FGD is the FD of the flattened normalised windows, computed independently here.
    flat = [np.concatenate([model.normalize(model.windows(s[n])).reshape(-1, WINDOW * model.arch.pose_dim) for n in sorted(s)])
            for s in (reference, noisy)]
    with pytest.warns(Warning):
        assert raw["noisy"]["value"] == pytest.approx(frechet_distance_samples(*flat), rel=1e-6)
    # Scoring the reference against itself gives 0.
    (self_row,) = score_fgd(model, reference, {"self": reference}, raw=False, n_bootstrap=0)
    assert self_row["value"] == pytest.approx(0.0, abs=1e-9)


def test_motion_is_resampled_and_joints_selected_by_name_to_match_the_model():
    model = trained()
    nat = natural()
    name = sorted(nat)[0]
    m30 = nat[name]
    m60 = resample(m30, 60.0)
    assert m60.fps == 60.0
    # Back at 30 fps the model sees exactly the original frames (integer ratio).
    np.testing.assert_array_equal(model.windows(m60), model.windows(m30))
    # Joint order and extra joints do not matter: selection is by name.
    pos = m30.positions()
    order = np.random.default_rng(0).permutation(pos.shape[1])
    names = [m30.joint_names[i] for i in order]
    shuffled = Motion.from_positions(np.concatenate([pos[:, order], pos[:, :1] * 0], axis=1), names + ["extra"], 30.0)
    np.testing.assert_array_equal(model.features(shuffled), model.features(m30))


def test_data_that_cannot_match_the_model_is_a_clear_error():
    model = trained()
    m = natural()[sorted(natural())[0]]
    missing = Motion.from_positions(m.positions()[:, 1:], m.joint_names[1:], 30.0, name="armless")
    with pytest.raises(InputError, match=f"joints the motion does not have: {m.joint_names[0]}"):
        score_fgd(model, {"a": m}, {"c": {"armless": missing}})
    short = Motion.from_positions(m.positions()[: WINDOW - 1], m.joint_names, 30.0, name="tiny")
    with pytest.raises(InputError, match=rf"c/tiny: .*too short for one {WINDOW}-frame window"):
        score_fgd(model, {"a": m}, {"c": {"tiny": short}})
    with pytest.raises(InputError, match="no sequences"):
        score_fgd(model, {}, {"c": {"x": m}})


def _two_joint_bvh(path, n_frames=40):
    rng = np.random.default_rng(0)
    values = np.column_stack([rng.normal(0, 1, (n_frames, 3)), rng.normal(0, 10, (n_frames, 3)),
                              np.tile([1.0, 2.0, 3.0], (n_frames, 1)), rng.normal(0, 10, (n_frames, 3))])
    lines = ["HIERARCHY", "ROOT Hips", "{", "  OFFSET 0 0 0",
             "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation", "  JOINT Spine", "  {",
             "    OFFSET 0 10 0", "    CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation",
             "    End Site", "    {", "      OFFSET 0 10 0", "    }", "  }", "}", "MOTION", f"Frames: {n_frames}",
             "Frame Time: 0.0333333"]
    lines += [" ".join(f"{v:.6f}" for v in row) for row in values]
    path.write_text("\n".join(lines) + "\n")


def test_genea2023_style_models_apply_the_pymo_convention_to_bvh_input(tmp_path):
    from evalsuite import load_motion
    from evalsuite.learned.modelfile import FeatureModel, new_meta
    from evalsuite.learned.network import Architecture, EmbeddingNet
    from evalsuite.learned.presets import JOINT_PRESETS

    assert JOINT_PRESETS["genea2023"]["convention"] == "pymo"
    bvh = tmp_path / "two.bvh"
    _two_joint_bvh(bvh)
    arch = Architecture(pose_dim=6, window=20)
    rep = {"kind": "positions", "joints": ["Hips", "Spine"], "convention": "pymo"}
    model = FeatureModel(EmbeddingNet(arch), new_meta(arch, rep, 30.0, 10, "complete", {}, {}, 0), np.zeros(6),
                         np.ones(6))
    default = load_motion(bvh)  # joint position channels replace the OFFSET
    pymo = load_motion(bvh, convention="pymo")  # ... are added to it (PyMO, GENEA 2023)
    assert not np.allclose(default.positions(), pymo.positions())
    np.testing.assert_allclose(model.pose_vectors(default), pymo.positions().reshape(40, 6))


def test_batched_fd_equals_the_shared_frechet_function():
    from evalsuite.learned.fgd import batched_frechet_distance
    from evalsuite.metrics.frechet import frechet_distance

    rng = np.random.default_rng(4)
    b, d = 6, 5
    a1, a2 = rng.normal(size=(b, d, d)), rng.normal(size=(b, d, d))
    s1, s2 = a1 @ np.swapaxes(a1, 1, 2), a2 @ np.swapaxes(a2, 1, 2)
    s2[0] = s1[0]  # identical Gaussians: 0 after clipping
    m1, m2 = rng.normal(size=(b, d)), rng.normal(size=(b, d))
    m2[0] = m1[0]
    got = batched_frechet_distance(m1, s1, m2, s2)
    want = [frechet_distance(m1[i], s1[i], m2[i], s2[i]) for i in range(b)]
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10)
