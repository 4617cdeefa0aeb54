"""Never resample silently: every place that interpolates motion to another frame rate says so on the
command line and records which files, from what rate to what, in its output."""
from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner
from learned_helpers import natural, trained

from evalsuite.cli import main
from evalsuite.learned.fgd import score_fgd
from evalsuite.motion.io import save_motion
from evalsuite.motion.ops import resample


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("rates")
    model = trained()
    model_path = tmp / "model.pt"
    model.save(model_path)
    nat = natural()
    names = sorted(nat)
    for folder, pick, fps in (("natural", names[0::2], None), ("natural25", names[0::2], 25.0),
                              ("sys25", names[1::2], 25.0)):
        (tmp / folder).mkdir()
        for i, n in enumerate(pick):
            save_motion(nat[n] if fps is None else resample(nat[n], fps), tmp / folder / f"seq{i}.npz")
    return tmp, model_path


def test_score_fgd_rows_name_the_resampled_files():
    model = trained()
    nat = natural()
    names = sorted(nat)
    ref = {n: nat[n] for n in names[0::2]}
    cond = {n: resample(nat[n], 25.0) for n in names[1::2]}
    rows = score_fgd(model, ref, {"sys25": cond, "same": {n: nat[n] for n in names[1::2]}}, n_bootstrap=0)
    by = {(r["condition"], r["metric"]): r for r in rows}
    assert by[("same", "fgd")]["resampled"] == ""
    text = by[("sys25", "fgd")]["resampled"]
    assert text.count("25 -> 30 fps") == len(cond) and text == by[("sys25", "fgd_raw")]["resampled"]


def test_evalsuite_score_fgd_warns_and_records_provenance(folders):
    tmp, model_path = folders
    # Every file is at 25 fps, the model works at 30: the FGD family resamples all eight.
    r = CliRunner().invoke(main, ["score", "-r", str(tmp / "natural25"), str(tmp / "sys25"),
                                  "--fgd", str(model_path), "-m", "kinematics", "-o", str(tmp / "out"),
                                  "--no-figures", "--quiet"], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    warnings = [ln for ln in r.output.splitlines() if "resampled by interpolation" in ln]
    assert len(warnings) == 1 and "8 file(s)" in warnings[0] and "25 -> 30 fps, FGD model" in warnings[0]
    listed = list(_find(json.loads((tmp / "out" / "results.json").read_text()), "resampled_files"))
    assert len(listed) == 8 and all("(25 -> 30 fps, FGD model)" in e for e in listed)


def _find(obj, key):
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k == key:
                yield from v
            else:
                yield from _find(v, key)
    elif isinstance(obj, list):
        for v in obj:
            yield from _find(v, key)


def test_score_resample_option_is_recorded_too(folders):
    tmp, _ = folders
    r = CliRunner().invoke(main, ["score", "-r", str(tmp / "natural"), str(tmp / "sys25"), "-m", "kinematics",
                                  "-o", str(tmp / "out2"), "--no-figures", "--quiet", "--resample", "30"],
                           catch_exceptions=False)
    assert r.exit_code == 0, r.output
    assert "4 file(s) resampled by interpolation (25 -> 30 fps, --resample)" in r.output
    listed = list(_find(json.loads((tmp / "out2" / "results.json").read_text()), "resampled_files"))
    assert len(listed) == 4 and all("--resample" in e and "sys25" in e for e in listed)


def test_fgd_score_cli_warns_and_writes_the_field(folders):
    tmp, model_path = folders
    out = tmp / "fgd.json"
    r = CliRunner().invoke(main, ["fgd", "score", str(model_path), str(tmp / "natural"), str(tmp / "sys25"),
                                  "--no-latent", "--no-raw", "--bootstrap", "0", "--format", "json", "-o", str(out)],
                           catch_exceptions=False)
    assert r.exit_code == 0, r.output
    assert "warning: 4 file(s) resampled by interpolation from 25 to 30 fps" in r.output
    (row,) = json.loads(out.read_text())
    assert row["resampled"].count("(25 -> 30 fps)") == 4


def test_fgd_check_and_features_warn(folders):
    tmp, model_path = folders
    r = CliRunner().invoke(main, ["fgd", "features", str(model_path), str(tmp / "sys25" / "seq1.npz"), "-o",
                                  str(tmp / "f.npy")], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    assert "1 file(s) resampled by interpolation from 25 to 30 fps" in r.output
    assert np.load(tmp / "f.npy").ndim == 2
