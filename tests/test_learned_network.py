"""The encoder is laid out like the reference extractors: their checkpoints load by name and give
the same features as the reference network's computation (written out here with torch.nn.functional)."""
from __future__ import annotations

import numpy as np
import pytest
import torch
import torch.nn.functional as F
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.learned.modelfile import encode_windows, load_model
from evalsuite.learned.network import Architecture, EmbeddingNet
from evalsuite.motion.presets import PRESETS


def genea2023_layout(pose_dim: int, window: int) -> dict[str, tuple]:
    """Parameter names and shapes of the GENEA 2023 EmbeddingNet (evaluation_metric/embedding_net.py),
    written out from the reference code, not from evalsuite's network."""
    flat = {30: 320, 60: 800, 90: 1280, 120: 1760}[window]
    spec: dict[str, tuple] = {}

    def bn(prefix, n):
        for p in ("weight", "bias", "running_mean", "running_var"):
            spec[f"{prefix}.{p}"] = (n,)
        spec[f"{prefix}.num_batches_tracked"] = ()

    def lin(prefix, n_in, n_out):
        spec[f"{prefix}.weight"] = (n_out, n_in)
        spec[f"{prefix}.bias"] = (n_out,)

    spec["pose_encoder.net.0.0.weight"] = (128, pose_dim, 3)
    spec["pose_encoder.net.0.0.bias"] = (128,)
    bn("pose_encoder.net.0.1", 128)
    spec["pose_encoder.net.1.0.weight"] = (64, 128, 3)
    spec["pose_encoder.net.1.0.bias"] = (64,)
    bn("pose_encoder.net.1.1", 64)
    spec["pose_encoder.net.2.0.weight"] = (64, 64, 4)
    spec["pose_encoder.net.2.0.bias"] = (64,)
    bn("pose_encoder.net.2.1", 64)
    spec["pose_encoder.net.3.weight"] = (32, 64, 3)
    spec["pose_encoder.net.3.bias"] = (32,)
    lin("pose_encoder.out_net.0", flat, 256)
    bn("pose_encoder.out_net.1", 256)
    lin("pose_encoder.out_net.3", 256, 128)
    bn("pose_encoder.out_net.4", 128)
    lin("pose_encoder.out_net.6", 128, 32)
    lin("decoder.pre_net.0", 32, 64)
    bn("decoder.pre_net.1", 64)
    lin("decoder.pre_net.3", 64, 4 * window)
    spec["decoder.net.0.weight"] = (4, 32, 3)  # ConvTranspose1d: (in, out, k)
    spec["decoder.net.0.bias"] = (32,)
    bn("decoder.net.1", 32)
    spec["decoder.net.3.weight"] = (32, 32, 3)
    spec["decoder.net.3.bias"] = (32,)
    bn("decoder.net.4", 32)
    spec["decoder.net.6.weight"] = (32, 32, 3)
    spec["decoder.net.6.bias"] = (32,)
    spec["decoder.net.7.weight"] = (pose_dim, 32, 3)
    spec["decoder.net.7.bias"] = (pose_dim,)
    return spec


def random_state(spec: dict, seed: int) -> dict:
    g = torch.Generator().manual_seed(seed)
    state = {}
    for name, shape in spec.items():
        if name.endswith("num_batches_tracked"):
            state[name] = torch.tensor(7)
        elif name.endswith("running_var"):
            state[name] = torch.rand(shape, generator=g) + 0.5
        else:
            state[name] = torch.randn(shape, generator=g) * 0.2
    return state


def reference_features(sd: dict, x: np.ndarray, fc_mu: bool = False) -> np.ndarray:
    """The reference PoseEncoderConv forward in eval mode, with its quirk nn.LeakyReLU(True) = slope 1."""
    def bn(h, p):
        return F.batch_norm(h, sd[f"{p}.running_mean"], sd[f"{p}.running_var"], sd[f"{p}.weight"],
                            sd[f"{p}.bias"], training=False, eps=1e-5)

    h = torch.from_numpy(x.astype(np.float32)).transpose(1, 2)
    for i, stride in ((0, 1), (1, 1), (2, 2)):
        h = F.conv1d(h, sd[f"pose_encoder.net.{i}.0.weight"], sd[f"pose_encoder.net.{i}.0.bias"], stride=stride)
        h = F.leaky_relu(bn(h, f"pose_encoder.net.{i}.1"), 0.2)
    h = F.conv1d(h, sd["pose_encoder.net.3.weight"], sd["pose_encoder.net.3.bias"]).flatten(1)
    h = F.linear(h, sd["pose_encoder.out_net.0.weight"], sd["pose_encoder.out_net.0.bias"])
    h = F.leaky_relu(bn(h, "pose_encoder.out_net.1"), 1.0)
    h = F.linear(h, sd["pose_encoder.out_net.3.weight"], sd["pose_encoder.out_net.3.bias"])
    h = F.leaky_relu(bn(h, "pose_encoder.out_net.4"), 1.0)
    h = F.linear(h, sd["pose_encoder.out_net.6.weight"], sd["pose_encoder.out_net.6.bias"])
    if fc_mu:
        h = F.linear(h, sd["pose_encoder.fc_mu.weight"], sd["pose_encoder.fc_mu.bias"])
    return h.detach().numpy().astype(np.float64)


@pytest.mark.parametrize("window", [30, 120])
def test_evalsuite_network_has_the_genea2023_parameter_names_and_shapes(window):
    net = EmbeddingNet(Architecture(pose_dim=168, window=window))
    ours = {k: tuple(v.shape) for k, v in net.state_dict().items()}
    assert ours == genea2023_layout(168, window)


def test_genea2023_layout_checkpoint_imports_by_name_and_matches_reference_features(tmp_path):
    spec = genea2023_layout(168, 30)
    state = random_state(spec, seed=1)
    ckpt = tmp_path / "model_checkpoint_30.bin"
    torch.save({"pose_dim": 168, "n_frames": 30, "gen_dict": state}, ckpt)
    rng = np.random.default_rng(0)
    mean = rng.normal(100.0, 50.0, 168)
    std = rng.uniform(1.0, 30.0, 168)
    stats = tmp_path / "stats.npz"
    np.savez(stats, mean=mean, std=std)
    out = tmp_path / "genea2023.pt"
    result = CliRunner().invoke(main, ["fgd", "import-genea", str(ckpt), "--stats", str(stats),
                                       "--joints", "genea2023", "-o", str(out)])
    assert result.exit_code == 0, result.output
    model = load_model(out)
    assert model.joints == PRESETS["genea2023"]
    assert model.representation["convention"] == "pymo"
    assert (model.window, model.stride, model.window_rule) == (30, 15, "genea")
    assert model.content_hash in result.output
    # Parameters arrive unchanged under the same names.
    for name, tensor in model.net.state_dict().items():
        assert torch.equal(tensor, state[name]), name
    raw = rng.normal(100.0, 40.0, size=(50, 30, 168))
    normalised = (raw - mean) / std
    expected = reference_features(state, normalised)
    np.testing.assert_allclose(encode_windows(model, normalised, normalized=True), expected, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(encode_windows(out, raw), expected, rtol=1e-5, atol=1e-5)
    # The slope-1 quirk matters: a slope-0.2 activation would give other features.
    assert not np.allclose(expected, _features_with_fc_slope(state, normalised, 0.2), atol=1e-3)


def _features_with_fc_slope(state, x, slope):
    net = EmbeddingNet(Architecture(pose_dim=168, window=30, fc_slope=slope))
    net.load_state_dict(state)
    with torch.inference_mode():
        return net.eval().pose_encoder(torch.from_numpy(x.astype(np.float32))).numpy()


def test_yoon_bone_direction_checkpoint_with_fc_mu_head(tmp_path):
    pose_dim, window = 27, 34
    net = EmbeddingNet(Architecture(pose_dim=pose_dim, window=window, conv_channels=(32, 64), variational_head=True))
    state = random_state({k: tuple(v.shape) for k, v in net.state_dict().items()}, seed=2)
    assert state["pose_encoder.out_net.0.weight"].shape == (256, 384)  # Yoon et al.: 384 for 34 frames
    assert state["decoder.pre_net.3.weight"].shape == (136, 64)
    ckpt = tmp_path / "yoon.bin"
    torch.save({"pose_dim": pose_dim, "gen_dict": state}, ckpt)
    mean_dir = np.random.default_rng(1).normal(size=27)
    stats = tmp_path / "stats.npy"
    np.save(stats, np.stack([mean_dir, np.ones(27)]))
    joints = [f"j{i}" for i in range(10)]
    out = tmp_path / "yoon.pt"
    result = CliRunner().invoke(main, ["fgd", "import-genea", str(ckpt), "--stats", str(stats), "--joints",
                                       ",".join(joints), "--representation", "bone_directions", "--fps", "15",
                                       "--stride", "10", "-o", str(out)])
    assert result.exit_code == 0, result.output
    model = load_model(out)
    assert model.arch.variational_head
    assert model.window == 34
    assert model.fps == 15.0
    assert model.representation["bones"][3] == ["j1", "j4"]
    x = np.random.default_rng(3).normal(size=(8, 34, 27))
    np.testing.assert_allclose(model.encode(x, normalized=True), reference_features(state, x, fc_mu=True),
                               rtol=1e-5, atol=1e-5)


def test_import_rejects_checkpoints_that_do_not_fit(tmp_path):
    state = random_state(genea2023_layout(168, 30), seed=0)
    stats = tmp_path / "s.npz"
    np.savez(stats, mean=np.zeros(168), std=np.ones(168))
    bad = dict(state)
    bad.pop("pose_encoder.out_net.6.weight")
    ckpt = tmp_path / "bad.bin"
    torch.save({"pose_dim": 168, "n_frames": 30, "gen_dict": bad}, ckpt)
    r = CliRunner().invoke(main, ["fgd", "import-genea", str(ckpt), "--stats", str(stats), "--joints", "genea2023",
                                  "-o", str(tmp_path / "x.pt")])
    assert r.exit_code == 1
    assert "out_net.6.weight" in r.output
    assert "Traceback" not in r.output
    good = tmp_path / "good.bin"
    torch.save({"pose_dim": 168, "n_frames": 30, "gen_dict": state}, good)
    r = CliRunner().invoke(main, ["fgd", "import-genea", str(good), "--stats", str(stats), "--joints",
                                  "genea2023_upper", "-o", str(tmp_path / "x.pt")])
    assert r.exit_code == 1
    assert "168 values per frame" in r.output
    np.savez(stats, mean=np.zeros(168), std=np.zeros(168))
    with pytest.raises(InputError, match="non-positive"):
        from evalsuite.learned.genea import import_checkpoint

        import_checkpoint(good, joints="genea2023", stats=stats)
