"""``evalsuite corpus mean-velocity``: the --bc-mean-vel file from a BEAT2 split, equal to the Python API."""
from __future__ import annotations

import numpy as np
from click.testing import CliRunner
from smplx_helpers import fake_smplx_model, write_fake_beat2_recording

from evalsuite.cli import main
from evalsuite.leaderboard.meanvel import mean_velocity_of_split
from evalsuite.motion.smplx_body import MODEL_ENV


def test_mean_velocity_command_writes_the_split_mean(tmp_path, monkeypatch):
    monkeypatch.setenv(MODEL_ENV, "")
    lang = tmp_path / "beat_english_v2.0.0"
    (lang / "smplxflame_30").mkdir(parents=True)
    rows = ["id,type"]
    for i, kind in enumerate(("train", "train", "test")):
        vid = f"2_scott_0_{i + 1}_{i + 1}"
        write_fake_beat2_recording(lang / "smplxflame_30" / f"{vid}.npz", n_frames=40 + 10 * i, seed=i)
        rows.append(f"{vid},{kind}")
    (lang / "train_test_split.csv").write_text("\n".join(rows) + "\n")
    model = fake_smplx_model(tmp_path / "model.npz", n_betas=300, n_verts=80)
    run = CliRunner().invoke
    res = run(main, ["corpus", "mean-velocity", str(lang), "-o", str(tmp_path / "mv.npy"), "--quiet"])
    assert res.exit_code == 1 and "--smplx-model" in res.output and len(res.output.strip().splitlines()) == 1
    for split, api in (("train", "train"), ("all", None)):
        out = tmp_path / f"mv_{split}.npy"
        res = run(main, ["corpus", "mean-velocity", str(lang), "-o", str(out), "--split", split, "--quiet",
                         "--smplx-model", str(model)])
        assert res.exit_code == 0, res.output
        got = np.load(out)
        assert got.shape == (55,) and got.dtype == np.float32
        assert np.allclose(got, mean_velocity_of_split(lang, model, api), rtol=1e-6)
    res = run(main, ["corpus", "mean-velocity", str(lang), "-o", str(tmp_path / "x.npy"), "--split", "val",
                     "--quiet", "--smplx-model", str(model)])
    assert res.exit_code == 1 and "no recordings of the 'val' split" in res.output
    assert "mean-velocity" in run(main, ["corpus", "--help"]).output
