"""evalsuite.generators.joint_presets and `evalsuite train --joints`: every re-implementation trains on the synthetic
speaker written on the GENEA 2023 skeleton and writes its output on that skeleton (joint names and offsets)."""
from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.generators.joint_presets import JOINT_PRESETS, default_joints, resolve_joint_option
from evalsuite.motion.io import load_motion
from evalsuite.motion.presets import GENEA2020_UPPER

# a few steps each (CI scale)
TINY = {
    "gesticulator": ["epochs=5", "words=hash"],
    "aud2pose": ["epochs=2"],
    "aud2repr2pose": ["epochs=2", "dae_epochs=1"],
    "gesture2vec": ["words=hash", "codebook=8", "dae_epochs=1", "vq_epochs=1", "vq_decoder_epochs=1",
                    "translation_epochs=1"],
    "ferstl-mogan": ["classifier_epochs=1", "pretrain_epochs=2", "adversarial_steps=2", "batch_size=4",
                     "realism_pretrain_steps=2", "phase_pretrain_tries=2"],
}


def _synth(root: pathlib.Path, skeleton: str) -> pathlib.Path:
    res = CliRunner().invoke(main, ["corpus", "synth", "-o", str(root), "--minutes", "0.5", "--segment-seconds", "7",
                                    "--skeleton", skeleton, "--quiet"])
    assert res.exit_code == 0, res.output
    return root


@pytest.fixture(scope="module")
def genea2023(tmp_path_factory) -> pathlib.Path:
    return _synth(tmp_path_factory.mktemp("g23") / "corpus", "genea2023")


def _train_and_generate(name: str, corpus: pathlib.Path, joints: str | None, tmp: pathlib.Path) -> pathlib.Path:
    runner = CliRunner()
    sets = [a for s in TINY[name] for a in ("--set", s)]
    args = ["train", "-g", name, "--corpus", str(corpus), *sets, "--device", "cpu", "-o", str(tmp / "model")]
    res = runner.invoke(main, args + (["--joints", joints] if joints else []))
    assert res.exit_code == 0, res.output
    res = runner.invoke(main, ["generate", "-g", name, "--model", str(tmp / "model"), "--corpus", str(corpus),
                               "--split", "test", "--fps", "30", "--device", "cpu", "-o", str(tmp / "gen")])
    assert res.exit_code == 0, res.output
    return tmp


def test_presets_and_names():
    assert resolve_joint_option("genea2020-upper") == GENEA2020_UPPER
    assert len(JOINT_PRESETS["genea2023-upper"]) == 18 and len(JOINT_PRESETS["genea2023-upper-fingers"]) == 50
    assert "b_r_index3" not in JOINT_PRESETS["genea2023-upper"]
    assert len(JOINT_PRESETS["smplx-body-hands"]) == 13 + 30
    assert resolve_joint_option("b_r_arm, b_r_forearm,b_r_wrist") == ["b_r_arm", "b_r_forearm", "b_r_wrist"]
    assert resolve_joint_option(None) is None
    with pytest.raises(InputError, match="unknown joint preset 'genea2024'"):
        resolve_joint_option("genea2024")
    assert default_joints(GENEA2020_UPPER + ["Hips"]) == GENEA2020_UPPER
    assert default_joints(["b_root", "b_spine0", "b_spine1", "b_r_wrist"]) == JOINT_PRESETS["genea2023-upper"]


@pytest.mark.parametrize("name", list(TINY))
def test_each_reimplementation_on_the_genea2023_skeleton(name, genea2023, tmp_path):
    out = _train_and_generate(name, genea2023, "genea2023-upper", tmp_path)
    rep = json.loads((out / "model" / "representation.json").read_text())
    assert rep["joints"] == JOINT_PRESETS["genea2023-upper"]
    natural = load_motion(sorted((genea2023 / "tst" / "main-agent" / "bvh").glob("*.bvh"))[0])
    files = sorted(p for p in (out / "gen").iterdir() if p.suffix in (".bvh", ".npz"))
    assert files
    gen = load_motion(files[0])
    assert gen.joint_names == natural.joint_names               # the corpus's whole skeleton, fingers included
    if name == "ferstl-mogan":                                  # positions (the paper's representation)
        assert files[0].suffix == ".npz"
    else:                                                       # rotations on the corpus's offsets
        assert files[0].suffix == ".bvh"
        assert np.allclose(gen.skeleton.offsets, natural.skeleton.offsets)
    assert gen.n_frames == natural.n_frames


def test_beat_skeleton_and_the_default_joints(tmp_path):
    corpus = _synth(tmp_path / "beat", "beat")
    out = _train_and_generate("aud2pose", corpus, None, tmp_path)    # no --joints: the first preset it has
    assert json.loads((out / "model" / "representation.json").read_text())["joints"] == GENEA2020_UPPER
    gen = load_motion(sorted((out / "gen").glob("*.bvh"))[0])
    assert "RightHandIndex1" in gen.joint_names and "HeadEnd" in gen.joint_names


def test_explicit_joints_must_exist(genea2023, tmp_path):
    res = CliRunner().invoke(main, ["train", "-g", "aud2pose", "--corpus", str(genea2023), "--set", "epochs=1",
                                    "--joints", "b_r_arm,b_r_forearm,RightHand", "-o", str(tmp_path / "m")])
    assert res.exit_code != 0 and "no joint(s) RightHand" in res.output


def test_smplx_corpus_gives_smplx_output(tmp_path):
    from evalsuite.motion.smplx import read_smplx
    from evalsuite.motion.smplx_layout import SMPLX_JOINT_NAMES

    corpus = _synth(tmp_path / "smplx", "smplx")
    out = _train_and_generate("aud2pose", corpus, "smplx-body-hands", tmp_path)
    assert (out / "model" / "template.npz").is_file()                # rotations only: no body model needed
    natural = read_smplx(sorted((corpus / "tst" / "main-agent" / "bvh").glob("*.npz"))[0])
    gen = read_smplx(sorted((out / "gen").glob("*.npz"))[0])
    assert gen.poses.shape == natural.poses.shape and gen.fps == natural.fps
    knee = 3 * SMPLX_JOINT_NAMES.index("left_knee")                 # not modelled: held at the template's pose
    assert np.allclose(gen.poses[:, knee:knee + 3], gen.poses[:1, knee:knee + 3])
    elbow = 3 * SMPLX_JOINT_NAMES.index("right_elbow")              # modelled: it moves
    assert np.ptp(gen.poses[:, elbow:elbow + 3]) > 0


def test_learning_criteria_read_the_genea2023_joints(genea2023):
    from evalsuite.corpus import load_corpus
    from evalsuite.generators.criteria import diversity
    from evalsuite.generators.evaluation import segment_scores

    seg = load_corpus(genea2023).split("test")[0]
    natural = seg.load_motion()
    assert segment_scores(natural, seg)["pose_mse"] == 0.0
    div = diversity({"a": natural, "b": natural})
    assert div["l1div"] > 0
