"""Training: the sanity ordering, save/load bit-identity, determinism, the CLI end to end."""
from __future__ import annotations

import numpy as np
import pytest
import torch
from click.testing import CliRunner
from learned_helpers import FPS, WINDOW, natural, trained

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.learned.fgd import score_fgd
from evalsuite.learned.modelfile import load_model
from evalsuite.learned.sanity import check_model
from evalsuite.learned.training import train_model
from evalsuite.motion import save_motion


def test_briefly_trained_encoder_reproduces_the_sanity_ordering():
    result = check_model(trained(), natural(), seed=0)
    for check in result["checks"]:
        assert check["passed"], check
    rows = result["rows"]
    noise = [r["fgd"] for r in rows if r["perturbation"] == "gaussian noise"]
    jitter = [r["fgd"] for r in rows if r["perturbation"] == "temporal jitter"]
    assert noise == sorted(noise)
    assert jitter == sorted(jitter)
    assert rows[0]["fgd"] < min(noise[-1], jitter[-1], rows[-1]["fgd"])


def test_save_and_load_give_bit_identical_features(tmp_path):
    model = trained()
    path = tmp_path / "m.pt"
    digest = model.save(path)
    loaded = load_model(path)
    assert loaded.content_hash == digest == model.content_hash
    m = natural()["take00"]
    np.testing.assert_array_equal(loaded.features(m), model.features(m))
    assert loaded.meta["training"]["seed"] == 0
    assert loaded.meta["representation"]["joints"] == m.joint_names
    assert np.array_equal(loaded.mean, model.mean)
    assert np.array_equal(loaded.std, model.std)
    # A changed byte of the weights is detected.
    payload = torch.load(path, weights_only=True)
    payload["state_dict"]["pose_encoder.out_net.6.bias"][0] += 1e-3
    torch.save(payload, tmp_path / "tampered.pt")
    with pytest.raises(InputError, match="content hash mismatch"):
        load_model(tmp_path / "tampered.pt")


def test_same_seed_gives_the_same_model_and_fgd_twice():
    nat = natural()
    names = sorted(nat)
    ref, cond = {n: nat[n] for n in names[:4]}, {n: nat[n] for n in names[4:]}
    a = train_model(nat, joints="all", window=WINDOW, fps=FPS, epochs=2, seed=11, progress=False)
    b = train_model(nat, joints="all", window=WINDOW, fps=FPS, epochs=2, seed=11, progress=False)
    c = train_model(nat, joints="all", window=WINDOW, fps=FPS, epochs=2, seed=12, progress=False)
    assert a.content_hash == b.content_hash != c.content_hash
    for name, t in a.net.state_dict().items():
        assert torch.equal(t, b.net.state_dict()[name])
    fa = score_fgd(a, ref, {"c": cond}, raw=False, n_bootstrap=50, seed=1)
    fb = score_fgd(b, ref, {"c": cond}, raw=False, n_bootstrap=50, seed=1)
    assert fa == fb
    history = a.meta["training"]["history"]
    assert len(history) == 2
    assert all(np.isfinite(h["val_loss"]) for h in history)


def test_cli_train_info_check_score_end_to_end(tmp_path):
    nat_dir = tmp_path / "natural"
    gen_dir = tmp_path / "SYS_noisy"
    nat_dir.mkdir()
    gen_dir.mkdir()
    rng = np.random.default_rng(0)
    for name, m in natural().items():
        save_motion(m, nat_dir / f"{name}.bvh")
        noisy = m.with_positions(m.positions() + rng.normal(0, 30.0, m.positions().shape))
        save_motion(noisy, gen_dir / f"{name}.npz")
    model_path = tmp_path / "model.pt"
    runner = CliRunner()
    r = runner.invoke(main, ["fgd", "train", str(nat_dir), "--joints", "all", "--window", str(WINDOW), "--epochs",
                             "6", "--lr", "1e-3", "--seed", "0", "-o", str(model_path)])
    assert r.exit_code == 0, r.output
    assert "validation loss" in r.output
    assert "content hash" in r.output
    model = load_model(model_path)
    assert model.meta["training"]["data"][0]["file_sha256"] is not None
    r = runner.invoke(main, ["fgd", "info", str(model_path)])
    assert r.exit_code == 0
    assert model.short_hash in r.output
    assert "seed 0" in r.output
    r = runner.invoke(main, ["fgd", "check", str(model_path), str(nat_dir)])
    assert r.exit_code == 0, r.output
    assert "| gaussian noise |" in r.output
    assert "FAIL" not in r.output
    r = runner.invoke(main, ["fgd", "score", str(model_path), str(nat_dir), str(gen_dir), "--bootstrap", "100",
                             "--codes", "8", "--format", "csv", "-o", str(tmp_path / "fgd.csv")])
    assert r.exit_code == 0, r.output
    assert "warning: SYS_noisy: fgd: 8 sequence(s) on a side (fewer than 10)" in r.stderr  # the rule of `score`
    import pandas as pd

    table = pd.read_csv(tmp_path / "fgd.csv")
    assert set(table["metric"]) == {"fgd", "fgd_raw", "nsd_k1", "nsd_k2", "codebook_hellinger", "codebook_perplexity"}
    assert (table["model_hash"] == model.content_hash).all()
    fgd_row = table[(table.metric == "fgd") & (table.condition == "SYS_noisy")].iloc[0]
    assert fgd_row.value > 0
    assert fgd_row.ci_low <= fgd_row.value <= fgd_row.ci_high
    r = runner.invoke(main, ["fgd", "score", str(model_path), str(nat_dir), str(tmp_path / "nothing_here")])
    assert r.exit_code != 0
    assert "Traceback" not in r.output


def test_bone_direction_variant_trains_with_the_yoon_head():
    nat = dict(list(natural().items())[:3])
    model = train_model(nat, joints="genea2020_upper", window=WINDOW, fps=FPS, epochs=1, seed=0, progress=False,
                        representation="bone_directions", architecture="yoon2020")
    assert model.arch.variational_head
    assert model.arch.conv_channels == (32, 64)
    bones = model.representation["bones"]
    assert ["Spine", "Spine1"] in bones
    assert ["RightForeArm", "RightHand"] in bones
    assert len(bones) == 14
    assert model.arch.pose_dim == 42
    assert np.array_equal(model.std, np.ones(42))  # Yoon et al.: mean direction subtracted, no std
    vec = model.pose_vectors(nat["take00"]).reshape(-1, 14, 3)
    np.testing.assert_allclose(np.linalg.norm(vec, axis=-1), 1.0)
    assert model.features(nat["take00"]).shape == ((int(20 * FPS) - WINDOW) // (WINDOW // 2) + 1, 32)


def test_window_and_stride_are_configurable_and_the_genea_rule_is_kept():
    from evalsuite.learned.representation import window_starts

    model = trained()
    m = natural()["take00"]
    assert len(model.windows(m, stride=5)) == (int(20 * FPS) - WINDOW) // 5 + 1
    np.testing.assert_array_equal(window_starts(30, 30, 15, "complete"), [0])
    assert len(window_starts(30, 30, 15, "genea")) == 0  # range(0, T - n, stride): last window unused
    np.testing.assert_array_equal(window_starts(100, 30, 15, "genea"), [0, 15, 30, 45, 60])
    np.testing.assert_array_equal(window_starts(100, 30, 15, "complete"), [0, 15, 30, 45, 60])
    np.testing.assert_array_equal(window_starts(105, 30, 15, "genea"), [0, 15, 30, 45, 60])
    np.testing.assert_array_equal(window_starts(105, 30, 15, "complete"), [0, 15, 30, 45, 60, 75])


def test_a_still_joint_is_normalised_by_the_std_floor_not_its_own_tiny_std():
    # Training motion that keeps one joint still (micrometre jitter), as the synthetic speaker keeps its lower
    # spine: divided by its own std, a generated motion's 1 mm deviation there was ~10^4 standard deviations
    # and alone made FGD huge. Floored at 1 % of the largest std it counts like any small deviation.
    from evalsuite.motion.motion import Motion

    rng = np.random.default_rng(0)
    still = 1

    def with_still_joint(m, offset=0.0):
        pos = m.positions().copy()
        pos[:, still] = np.array([0.0, 100.0, 0.0]) + rng.normal(0.0, 1e-5, size=(len(pos), 3)) + offset
        return Motion.from_positions(pos, m.joint_names, m.fps, parents=m.skeleton.parents)

    nat = {n: with_still_joint(m) for n, m in natural().items()}
    model = train_model(nat, joints="all", window=WINDOW, fps=FPS, epochs=2, seed=0, progress=False)
    floor = 0.01 * model.std.max()
    column = 3 * model.meta["representation"]["joints"].index(natural()["take00"].joint_names[still])
    assert np.all(model.std[column: column + 3] == floor)
    assert model.meta["normalization"]["dims_at_std_floor"] >= 3
    names = sorted(nat)
    ref = {n: nat[n] for n in names[:4]}
    same = {n: nat[n] for n in names[4:]}
    shifted = {n: with_still_joint(natural()[n], offset=0.1) for n in names[4:]}  # 1 mm off, still joint only
    rows = score_fgd(model, ref, {"same": same, "shifted": shifted}, raw=False, n_bootstrap=20, seed=1)
    fgd = {r["condition"]: r["value"] for r in rows if r["metric"] == "fgd"}
    assert fgd["shifted"] < fgd["same"] + 5.0, fgd
