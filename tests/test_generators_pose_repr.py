"""evalsuite.generators.pose_repr: positions decoded on the corpus's whole skeleton (root included), so that a
positions generator (ferstl-mogan) scores against its corpus's natural motion with no joint filter."""
from __future__ import annotations

import csv
import pathlib

import numpy as np
import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.generators.pose_repr import PoseRepresentation
from evalsuite.motion.io import load_motion
from evalsuite.synth.body import upper_body_skeleton
from tests.synth_helpers import build_corpus


@pytest.fixture(scope="module")
def corpus_dir(tmp_path_factory) -> pathlib.Path:
    return build_corpus(tmp_path_factory.mktemp("rep") / "corpus", minutes=0.6, segment_s=8.0)


def test_positions_decode_writes_every_joint_of_the_skeleton(corpus_dir):
    motion = load_motion(next((corpus_dir / "trn" / "main-agent" / "bvh").glob("*.bvh")))
    rep = PoseRepresentation.from_motion(motion, "positions")
    assert "Hips" not in rep.joints
    data = rep.encode(motion)
    out = rep.decode(data)
    assert out.joint_names == motion.joint_names          # the root and every other joint, in the corpus's order
    pos, rest = out.positions(), rep.template.positions()[0]
    root = motion.joint_index("Hips")
    assert np.allclose(pos[:, root], rest[root])             # hip-centric: the root at the template's position
    for k, j in enumerate(rep.joints):                      # the modelled joints where the model put them
        assert np.allclose(pos[:, motion.joint_index(j)] - rest[root], data[:, 3 * k:3 * k + 3], atol=1e-4)
    assert list(upper_body_skeleton().names) == motion.joint_names


def test_ferstl_output_scores_against_the_corpus_without_a_joint_filter(corpus_dir, tmp_path):
    runner = CliRunner()
    cfg = ["--set", "classifier_epochs=1", "--set", "pretrain_epochs=2", "--set", "adversarial_steps=2",
           "--set", "batch_size=4", "--set", "realism_pretrain_steps=2", "--set", "phase_pretrain_tries=2"]
    res = runner.invoke(main, ["train", "-g", "ferstl-mogan", "--corpus", str(corpus_dir), *cfg,
                               "-o", str(tmp_path / "model")])
    assert res.exit_code == 0, res.output
    res = runner.invoke(main, ["generate", "-g", "ferstl-mogan", "--model", str(tmp_path / "model"), "--corpus",
                               str(corpus_dir), "--split", "test", "--fps", "30", "-o", str(tmp_path / "gen")])
    assert res.exit_code == 0, res.output
    res = runner.invoke(main, ["score", "-r", f"natural={corpus_dir / 'tst' / 'main-agent' / 'bvh'}",
                               f"ferstl={tmp_path / 'gen'}", "-m", "kinematics", "-o", str(tmp_path / "scores")])
    assert res.exit_code == 0, res.output
    assert "missing joints" not in res.output and "skip" not in res.output.lower()
    text = (tmp_path / "scores" / "summary.csv").read_text().splitlines()
    rows = [r for r in csv.DictReader(text) if r["condition"] == "ferstl"]
    n_test = len(list((corpus_dir / "tst" / "main-agent" / "bvh").glob("*.bvh")))
    assert rows and all(int(r["n"]) == n_test for r in rows)
