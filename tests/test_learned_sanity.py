"""The FGD sanity suite (`evalsuite fgd check`) holds its halves to the small-sample rule of `evalsuite score`."""
from __future__ import annotations

from learned_helpers import natural, trained

from evalsuite.learned.network import LATENT_DIM
from evalsuite.learned.sanity import check_model
from evalsuite.metrics.frechet import min_samples


def test_check_warns_when_the_halves_are_too_small_for_fgd():
    result = check_model(trained(), natural(), seed=0)
    n_ref = result["rows"][0]["n_windows_reference"]
    assert result["n_sequences"] == (4, 4)
    assert n_ref < min_samples(LATENT_DIM)
    text = " | ".join(result["warnings"])
    assert f"use at least {min_samples(LATENT_DIM)} windows per side" in text
    assert "4 sequence(s) on a side (fewer than 10)" in text


def test_check_of_halves_large_enough_has_no_warning():
    many = natural(n_pieces=20, seconds=20.0)
    result = check_model(trained(), many, seed=0)
    assert result["n_sequences"] == (10, 10)
    assert result["rows"][0]["n_windows_reference"] >= min_samples(LATENT_DIM)
    assert result["warnings"] == []


def test_a_failing_check_on_small_halves_says_the_sample_is_too_small(tmp_path, monkeypatch):
    from click.testing import CliRunner

    from evalsuite.cli import main
    from evalsuite.learned import sanity
    from evalsuite.motion import save_motion

    monkeypatch.setattr(sanity, "NEAR_ZERO_FRACTION", 0.0)   # make "natural halves near 0" fail on this data
    model = tmp_path / "m.pt"
    trained().save(model)
    nat_dir = tmp_path / "natural"
    nat_dir.mkdir()
    for name, motion in natural().items():
        save_motion(motion, nat_dir / f"{name}.npz")
    result = CliRunner().invoke(main, ["fgd", "check", str(model), str(nat_dir)])
    assert result.exit_code == 1
    assert "warning: 4 sequence(s) on a side" in result.output
    assert "the halves are too small for FGD (see the warnings)" in result.output   # in the table
    assert "the natural halves are too small for FGD (see the warnings)" in result.output
