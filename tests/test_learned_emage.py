"""Tests for evalsuite.learned.emage_aeskconv (EMAGE's AESKConv FGD encoder, written anew)."""
from __future__ import annotations

import numpy as np
import pytest
import torch
from click.testing import CliRunner

from evalsuite.errors import InputError
from evalsuite.learned import emage_aeskconv as ea

# The published AESKConv_240_100.bin layout (after removing "module."), worked out from the architecture:
# 55 edges x 6 ch -> pool to 35 edges x 6 -> pool to 20 edges x 6 -> 20 x 12 -> 20 chains x 12 = 240.
ENCODER_SHAPES = {}
for _i, (_cin, _cout, _pool) in enumerate([(330, 330, (210, 330)), (210, 210, (120, 210)),
                                           (120, 240, None), (240, 240, None)]):
    _p = f"encoder.layers.{_i}.0."
    ENCODER_SHAPES.update({
        _p + "residual.0.weight": (_cout, _cin, 4), _p + "residual.0.bias": (_cout,),
        _p + "residual.0.mask": (_cout, _cin, 4), _p + "residual.1.weight": (_cout,),
        _p + "residual.1.bias": (_cout,), _p + "shortcut.weight": (_cout, _cin, 1),
        _p + "shortcut.bias": (_cout,), _p + "shortcut.mask": (_cout, _cin, 1)})
    if _pool:
        ENCODER_SHAPES[_p + "common.0.weight"] = _pool
OTHER_SHAPES = {"fc_mu.weight": (240, 240), "fc_mu.bias": (240,), "fc_logvar.weight": (240, 240),
                "fc_logvar.bias": (240,)}
for _k in (0, 1):
    for _c in (0, 2):
        OTHER_SHAPES[f"decoder.main.{_k}.model.{_c}.weight"] = (240, 240, 3)
        OTHER_SHAPES[f"decoder.main.{_k}.model.{_c}.bias"] = (240,)
for _k, _shape in [(3, (240, 240, 3)), (6, (240, 240, 3)), (9, (240, 240, 3)), (12, (330, 240, 3)),
                   (14, (330, 330, 3))]:
    OTHER_SHAPES[f"decoder.main.{_k}.weight"] = _shape
    OTHER_SHAPES[f"decoder.main.{_k}.bias"] = (_shape[0],)
PUBLISHED = {**ENCODER_SHAPES, **OTHER_SHAPES}


def random_checkpoint(path, seed=0, prefix="module."):
    """A .bin like the published one: {'model_state': {'module.'+key: tensor}}, random weights, real masks/pools."""
    g = torch.Generator().manual_seed(seed)
    real = ea.AESKConv().state_dict()
    state = {}
    for k, shape in PUBLISHED.items():
        if k.endswith("mask") or k.endswith("common.0.weight"):
            state[prefix + k] = real[k].clone()
        else:
            state[prefix + k] = torch.randn(shape, generator=g) * 0.2
    torch.save({"model_state": state, "epoch": 100}, path)
    return {k[len(prefix):]: v for k, v in state.items()}


def test_published_key_names_and_shapes():
    assert ea.expected_shapes() == PUBLISHED
    # one entry checked against the code that made the checkpoint: the first conv sees 55 edges x 6 channels
    assert PUBLISHED["encoder.layers.0.0.residual.0.weight"] == (330, 330, 4)


def test_topology_facts():
    edges = ea.skeleton_edges()
    assert edges[0] == (0, 55) and edges[1] == (0, 1) and len(edges) == 55
    near = ea.edge_neighbours(edges)
    # left_knee (edge 4 = hip->knee): itself, pelvis-hip (1), knee-ankle (7), 2 hops: other pelvis edges, foot
    assert near[4] == [0, 1, 2, 3, 4, 7, 10]
    groups, _ = ea.pooling_groups(edges, last=False)
    assert len(groups) == 35 and [0] in groups


def numpy_forward(state, x):
    """Independent float64 numpy version of the encoder on (T, 330) using the state dict's tensors."""
    s = {k: v.double().numpy() for k, v in state.items()}
    h = x.T.astype(np.float64)  # (C, T)
    for i in range(4):
        p = f"encoder.layers.{i}.0."
        w = s[p + "residual.0.weight"] * s[p + "residual.0.mask"]
        hp = np.pad(h, ((0, 0), (1, 1)))
        t_out = (hp.shape[1] - 4) // 2 + 1
        conv = np.stack([np.einsum("oik,ik->o", w, hp[:, 2 * t:2 * t + 4]) for t in range(t_out)], 1)
        conv += s[p + "residual.0.bias"][:, None]
        c = conv.shape[0]
        grp = conv.reshape(10, c // 10, -1)
        mu = grp.mean(axis=(1, 2), keepdims=True)
        var = grp.var(axis=(1, 2), keepdims=True)
        gn = ((grp - mu) / np.sqrt(var + 1e-5)).reshape(c, -1)
        gn = gn * s[p + "residual.1.weight"][:, None] + s[p + "residual.1.bias"][:, None]
        ws = (s[p + "shortcut.weight"] * s[p + "shortcut.mask"])[:, :, 0]
        short = ws @ h[:, ::2] + s[p + "shortcut.bias"][:, None]
        out = gn + short
        if p + "common.0.weight" in s:
            out = s[p + "common.0.weight"] @ out
        h = np.tanh(out)
    return h.T


def test_import_load_strict_and_forward_matches_numpy(tmp_path):
    state = random_checkpoint(tmp_path / "AESKConv_240_100.bin")
    result = CliRunner().invoke(__import__("evalsuite.learned.cli", fromlist=["fgd"]).fgd,
                                ["import-emage", str(tmp_path / "AESKConv_240_100.bin"), "-o", str(tmp_path / "m.pt")])
    assert result.exit_code == 0, result.output
    model, meta = ea.load_emage_model(tmp_path / "m.pt")
    assert len(meta["source_sha256"]) == 64 and "first two rows" in meta["input"]
    rng = np.random.default_rng(1)
    x = ea.axis_angle_to_rot6d(rng.normal(scale=0.5, size=(70, 165)))
    z = ea.aeskconv_latents(model, x)
    assert z.shape == (4, 240) and z.dtype == np.float32
    ref = numpy_forward(state, x[:64])
    assert np.allclose(z, ref, rtol=1e-4, atol=1e-4 * np.abs(ref).max())


def test_rot6d_is_first_two_rows_of_rodrigues():
    rng = np.random.default_rng(2)
    aa = rng.normal(size=(3, 6))
    out = ea.axis_angle_to_rot6d(aa)
    assert out.shape == (3, 12)
    r = aa[1, 3:]
    theta = np.linalg.norm(r)
    k = r / theta
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    rot = np.eye(3) + np.sin(theta) * kx + (1 - np.cos(theta)) * kx @ kx
    assert np.allclose(out[1, 6:], np.concatenate([rot[0], rot[1]]))


def test_wrong_checkpoints_give_precise_errors(tmp_path):
    state = random_checkpoint(tmp_path / "a.bin", prefix="")
    missing = dict(state)
    del missing["fc_mu.bias"]
    torch.save({"model_state": missing}, tmp_path / "b.bin")
    with pytest.raises(InputError, match="key 'fc_mu.bias' missing"):
        ea.import_emage(tmp_path / "b.bin", tmp_path / "o.pt")
    bad = dict(state)
    bad["encoder.layers.1.0.shortcut.bias"] = torch.zeros(7)
    torch.save({"model_state": bad}, tmp_path / "c.bin")
    with pytest.raises(InputError, match=r"shortcut.bias' has shape \(7,\), expected \(210,\)"):
        ea.import_emage(tmp_path / "c.bin", tmp_path / "o.pt")
    with pytest.raises(InputError, match="at least 32 frames"):
        ea.aeskconv_latents(ea.AESKConv().eval(), np.zeros((31, 330)))


def test_score_uses_imported_model_on_smplx_motion(tmp_path):
    from evalsuite.learned.fgd import score_fgd
    from evalsuite.learned.modelfile import load_model
    from evalsuite.motion import load_motion
    from tests.smplx_helpers import write_fake_beat2_recording

    random_checkpoint(tmp_path / "ck.bin")
    ea.import_emage(tmp_path / "ck.bin", tmp_path / "m.pt")
    model = load_model(tmp_path / "m.pt")
    assert model.window == 32 and model.fps == 30.0 and len(model.content_hash) == 64
    path = write_fake_beat2_recording(tmp_path / "a.npz", n_frames=75, seed=3)
    motion = load_motion(path)
    feats = model.features(motion)
    direct = ea.aeskconv_latents(ea.load_emage_model(tmp_path / "m.pt")[0],
                                 ea.axis_angle_to_rot6d(motion.smplx.poses))
    assert feats.shape == (4, 240) and np.allclose(feats, direct)
    with pytest.raises(InputError, match="expects 30 fps"):
        model.features(load_motion(write_fake_beat2_recording(tmp_path / "b.npz", n_frames=75, fps=60)))
    ref = {f"s{i}": load_motion(write_fake_beat2_recording(tmp_path / f"r{i}.npz", n_frames=320, seed=i))
           for i in range(3)}
    cond = {f"s{i}": load_motion(write_fake_beat2_recording(tmp_path / f"c{i}.npz", n_frames=320, seed=10 + i))
            for i in range(3)}
    rows = score_fgd(tmp_path / "m.pt", ref, {"same": ref, "other": cond}, raw=False, n_bootstrap=0)
    by = {r["condition"]: r for r in rows if r["metric"] == "fgd"}
    assert by["same"]["value"] == pytest.approx(0.0, abs=1e-6) and by["other"]["value"] > 0
    assert by["other"]["n_windows_reference"] == 60 and by["other"]["model_hash"] == model.content_hash


def test_fgd_score_command_reads_the_imported_model(tmp_path):
    from evalsuite.learned.cli import fgd
    from tests.smplx_helpers import write_fake_beat2_recording

    random_checkpoint(tmp_path / "ck.bin")
    ea.import_emage(tmp_path / "ck.bin", tmp_path / "m.pt")
    for side, seed in (("nat", 0), ("sys", 10)):
        (tmp_path / side).mkdir()
        for i in range(3):
            write_fake_beat2_recording(tmp_path / side / f"s{i}.npz", n_frames=96, seed=seed + i)
    result = CliRunner().invoke(fgd, ["score", str(tmp_path / "m.pt"), str(tmp_path / "nat"), str(tmp_path / "sys"),
                                      "--bootstrap", "0"])
    assert result.exit_code == 0, result.output
    assert "| sys | fgd |" in result.output


def test_pickled_checkpoint_needs_unsafe_pickle(tmp_path):
    import argparse

    state = random_checkpoint(tmp_path / "a.bin", prefix="")
    torch.save({"model_state": state, "args": argparse.Namespace(vae_length=240)}, tmp_path / "p.bin")
    with pytest.raises(InputError, match="--unsafe-pickle"):
        ea.import_emage(tmp_path / "p.bin", tmp_path / "o.pt")
    ea.import_emage(tmp_path / "p.bin", tmp_path / "o.pt", allow_pickle=True)
    assert ea.load_emage_model(tmp_path / "o.pt")[1]["source_file"] == "p.bin"
