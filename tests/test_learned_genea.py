"""evalsuite.learned.genea and genea_stats: the official GENEA FGD normalisation vectors as --stats presets."""
from __future__ import annotations

import numpy as np
import pytest
import torch
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.learned.genea import read_stats, stats_preset
from evalsuite.learned.genea_stats import STATS_PRESETS
from evalsuite.learned.modelfile import load_model
from evalsuite.learned.network import Architecture, EmbeddingNet
from evalsuite.motion.presets import PRESETS

# The extractors' input sizes, as their train_AE.py sets pose_dim (2020: 42; 2022: 174 / 162; 2023: the 56
# joints of extract_joint_positions.py x 3 = 168, also the pose_dim of the 2023 30-frame checkpoint).
INPUT_DIMS = {"genea2020": 42, "genea2022_fullbody": 174, "genea2022_upperbody": 162, "genea2023": 168}
# Values read off the source files (not off the shipped module): position, value.
SPOT_VALUES = {
    "genea2020": ("mean", 1, 21.7154182), "genea2022_fullbody": ("mean", 4, 182.54484156276828),
    "genea2022_upperbody": ("std", 161, 26.257726353590716), "genea2023": ("mean", 4, 183.03570635799917),
}


def write_checkpoint(path, pose_dim: int, conv_channels=(128, 64), seed: int = 0):
    torch.manual_seed(seed)
    net = EmbeddingNet(Architecture(pose_dim=pose_dim, window=30, conv_channels=conv_channels))
    state = {k: (v + 0.3 * torch.randn_like(v) if v.is_floating_point() else v) for k, v in net.state_dict().items()}
    for k in state:
        if k.endswith("running_var"):
            state[k] = state[k].abs() + 0.5
    torch.save({"pose_dim": pose_dim, "n_frames": 30, "gen_dict": state}, path)
    return path


def import_genea(*args):
    return CliRunner().invoke(main, ["fgd", "import-genea", *map(str, args)])


@pytest.mark.parametrize("name", sorted(INPUT_DIMS))
def test_each_preset_fits_its_extractor_input_and_holds_the_source_numbers(name):
    mean, std, source = stats_preset(name)
    assert mean.shape == std.shape == (INPUT_DIMS[name],)
    assert mean.dtype == std.dtype == np.float64
    assert np.isfinite(mean).all() and (std > 0).all()
    which, index, value = SPOT_VALUES[name]
    assert {"mean": mean, "std": std}[which][index] == value
    assert "@" in source and "train_AE.py" in source  # repository@commit and file
    assert name in source and f"{INPUT_DIMS[name]} values" in source


def test_genea2023_vectors_follow_the_genea2023_joint_preset():
    mean = np.asarray(STATS_PRESETS["genea2023"]["mean"]).reshape(-1, 3)
    assert len(mean) == len(PRESETS["genea2023"])
    height = dict(zip(PRESETS["genea2023"], mean[:, 1]))
    assert height["b_head"] == mean[:, 1].max()  # the head is the highest joint on average
    assert 90 < height["b_l_leg"] < 100 and 90 < height["b_r_leg"] < 100  # knees
    assert abs(height["body_world"]) < 1 and 180 < height["b_root"] < 186


def test_stats_preset_gives_the_same_model_as_a_file_of_its_numbers(tmp_path):
    ckpt = write_checkpoint(tmp_path / "model_checkpoint_30.bin", 168)
    mean, std, _ = stats_preset("genea2023")
    npz = tmp_path / "genea2023_stats.npz"
    np.savez(npz, mean=mean, std=std)
    r1 = import_genea(ckpt, "--stats", "genea2023", "--joints", "genea2023", "-o", tmp_path / "preset.pt")
    r2 = import_genea(ckpt, "--stats", npz, "--joints", "genea2023", "-o", tmp_path / "file.pt")
    assert r1.exit_code == 0, r1.output
    assert r2.exit_code == 0, r2.output
    a, b = load_model(tmp_path / "preset.pt"), load_model(tmp_path / "file.pt")
    assert np.array_equal(a.mean, b.mean) and np.array_equal(a.std, b.std)
    assert np.array_equal(a.mean, np.asarray(STATS_PRESETS["genea2023"]["mean"]))
    for name, tensor in a.net.state_dict().items():
        assert torch.equal(tensor, b.net.state_dict()[name]), name
    windows = mean + std * np.random.default_rng(0).normal(size=(12, 30, 168))
    np.testing.assert_array_equal(a.encode(windows), b.encode(windows))
    # Only the naming of the stats differs; the vectors' own hash is the same.
    assert a.meta["normalization"]["values_sha256"] == b.meta["normalization"]["values_sha256"]
    assert a.meta["normalization"]["source"].startswith("preset genea2023 (")
    assert b.meta["normalization"]["source"] == str(npz)
    strip = ("normalization", "training", "created_utc", "content_hash")
    assert {k: v for k, v in a.meta.items() if k not in strip} == {k: v for k, v in b.meta.items() if k not in strip}
    ta, tb = a.meta["training"], b.meta["training"]
    assert {k: v for k, v in ta.items() if not k.startswith("stats")} == \
        {k: v for k, v in tb.items() if not k.startswith("stats")}
    assert ta["stats_sha256"] is None and tb["stats_sha256"] is not None


@pytest.mark.parametrize("name, channels", [("genea2020", (32, 64)), ("genea2022_fullbody", (128, 64)),
                                            ("genea2022_upperbody", (128, 64))])
def test_2020_and_2022_presets_import_with_their_own_joint_lists(tmp_path, name, channels):
    dims = INPUT_DIMS[name]
    ckpt = write_checkpoint(tmp_path / "ckpt.bin", dims, channels)
    joints = ",".join(f"j{i}" for i in range(dims // 3))
    r = import_genea(ckpt, "--stats", name, "--joints", joints, "-o", tmp_path / "m.pt")
    assert r.exit_code == 0, r.output
    model = load_model(tmp_path / "m.pt")
    assert np.array_equal(model.std, np.asarray(STATS_PRESETS[name]["std"]))


def test_stats_errors_name_the_presets_and_the_sizes(tmp_path):
    ckpt = write_checkpoint(tmp_path / "ckpt.bin", 168)
    r = import_genea(ckpt, "--stats", "genea2020", "--joints", "genea2023", "-o", tmp_path / "x.pt")
    assert r.exit_code == 1 and "Traceback" not in r.output
    assert "--stats genea2020 must have 168 values each (the checkpoint's input), got mean 42 and std 42" in r.output
    r = import_genea(ckpt, "--stats", "genea2022", "--joints", "genea2023", "-o", tmp_path / "x.pt")
    assert "use genea2022_fullbody (174 values) or genea2022_upperbody (162 values)" in r.output
    r = import_genea(ckpt, "--joints", "genea2023", "-o", tmp_path / "x.pt")
    assert r.exit_code == 1
    assert "normalisation vectors are needed: --stats PRESET (genea2020, genea2022_fullbody, genea2022_upperbody, " \
           "genea2023) or a file" in r.output
    r = import_genea(ckpt, "--stats", tmp_path / "genea2023_stats.npz", "--joints", "genea2023", "-o", tmp_path / "x.pt")
    assert "genea2023_stats.npz: no such stats file, and not a preset (genea2020, " in r.output
    assert not (tmp_path / "x.pt").exists()
    with pytest.raises(InputError, match="unknown stats preset 'genea2019'"):
        stats_preset("genea2019")
    help_text = " ".join(CliRunner().invoke(main, ["fgd", "import-genea", "--help"]).output.split())
    assert "--stats PRESET|FILE" in help_text and "genea2022_upperbody" in help_text
    assert "Without it the import stops with an error" in help_text


def test_read_stats_takes_a_preset_name_like_a_file():
    mean, std = read_stats("genea2020")
    assert mean.shape == (42,) and std[1] == 0.1115134
