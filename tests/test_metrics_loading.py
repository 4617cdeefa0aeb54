"""evalsuite.metrics.loading: positions read only when a chosen family needs them, errors said once per kind."""
from __future__ import annotations

import pytest
from click.testing import CliRunner

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.metrics.loading import grouped_errors
from evalsuite.motion.smplx_body import MODEL_ENV
from tests.smplx_helpers import fake_smplx_model, write_fake_beat2_recording


def test_grouped_errors_says_a_shared_reason_once_with_a_count():
    errors = [f"'s{i}' needs SMPL-X joint positions: pass --smplx-model PATH" for i in range(4)]
    errors.append("/data/x/s9.bvh: line 3: expected HIERARCHY")
    text = grouped_errors(errors)
    assert text.count("needs SMPL-X joint positions") == 1 and "(and 3 more file(s) alike)" in text
    assert "/data/x/s9.bvh: line 3: expected HIERARCHY" in text
    many = [f"/d/f{i}.bvh: problem number {i}" + "x" * i for i in range(8)]
    assert grouped_errors(many, shown=5).endswith("; and 3 more kind(s) of error")


@pytest.fixture
def beat2_folders(tmp_path, monkeypatch):
    monkeypatch.delenv(MODEL_ENV, raising=False)
    for side, seed in (("nat", 0), ("sys", 10)):
        (tmp_path / side).mkdir()
        for i in range(3):
            write_fake_beat2_recording(tmp_path / side / f"s{i}.npz", n_frames=96, seed=seed + i)
    return tmp_path


def test_fgd_on_rotations_scores_smplx_without_a_body_model(beat2_folders):
    from evalsuite.learned import emage_aeskconv as ea
    from tests.test_learned_emage import random_checkpoint

    d = beat2_folders
    random_checkpoint(d / "ck.bin")
    ea.import_emage(d / "ck.bin", d / "m.pt")
    res = CliRunner().invoke(main, ["score", "-r", str(d / "nat"), str(d / "sys"), "--fgd", str(d / "m.pt"),
                                    "-m", "fgd", "-o", str(d / "out"), "--quiet"])
    assert res.exit_code == 0, res.output
    assert res.output.count("needs SMPL-X joint positions") == 1       # only the wrist-track figure's warning
    assert "wrist-track figure leaves files out" in res.output
    assert "sys,fgd," in (d / "out" / "summary.csv").read_text()


def test_position_metrics_without_a_model_fail_with_one_message(beat2_folders):
    d = beat2_folders
    res = CliRunner().invoke(main, ["score", "-r", str(d / "nat"), str(d / "sys"), "-m", "jerk",
                                    "-o", str(d / "out"), "--quiet"])
    assert res.exit_code != 0
    assert res.output.count("needs SMPL-X joint positions") == 1 and "--smplx-model" in res.output
    assert "more file(s) alike" in res.output
    fake_smplx_model(d / "model.npz", n_betas=300, n_verts=80)
    res = CliRunner().invoke(main, ["score", "-r", str(d / "nat"), str(d / "sys"), "-m", "jerk",
                                    "-o", str(d / "out"), "--quiet", "--smplx-model", str(d / "model.npz")])
    assert res.exit_code == 0, res.output


def test_a_family_that_reads_positions_gets_them_lazily():
    from evalsuite.metrics.loading import Positions

    class Fake:
        joint_names = ["a", "b"]
        source = "x"
        calls = 0

        def positions(self):
            Fake.calls += 1
            raise InputError("no positions here")

    lazy = Positions(Fake(), ["a"])
    assert Fake.calls == 0
    with pytest.raises(InputError, match="no positions here"):
        lazy()
