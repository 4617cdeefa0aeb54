"""Gesture Area Coverage: the coverage grid and its Dice/FP/FN against an independent, loop-by-loop
implementation of Tonoli et al.'s definition (their rasterizer and SetStats, written here from the paper and
the repository's README on self-made motion), and the family through ``evalsuite score``."""
from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from evalsuite.errors import InputError
from evalsuite.metrics.engine import ScoreOptions, score_folders
from evalsuite.metrics.figures import write_figures
from evalsuite.metrics.gac import GAC_CONVENTIONS, coverage, coverage_stats, dice, parse_gac
from evalsuite.motion.io import save_motion
from evalsuite.motion.motion import Motion

NAMES = ["world", "hips", "spine", "r_arm", "r_hand", "l_hand", "leg"]
PARENTS = np.array([-1, 0, 1, 2, 3, 2, 1])


def _motion(seed: int, amp: float, frames: int = 40, drift: float = 30.0) -> np.ndarray:
    """(T, 7, 3) positions in cm: a body walking along x (removed by the root lock) waving its hands."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames)[:, None]
    phase = rng.uniform(0, 2 * np.pi, 4)
    hips = np.stack([drift * t[:, 0] / frames, np.full(frames, 95.0), np.zeros(frames)], 1)
    pos = np.zeros((frames, 7, 3))
    pos[:, 0] = hips + [0, 0, 2]     # the world joint carries the travel (as GENEA 2023's body_world)
    pos[:, 1] = hips
    pos[:, 2] = hips + [0, 45, 0]
    pos[:, 3] = hips + np.stack([-20 - amp * np.sin(0.3 * t[:, 0] + phase[0]), 40 + 0 * t[:, 0], 3 + 0 * t[:, 0]], 1)
    pos[:, 4] = pos[:, 3] + np.stack([-5 + amp * np.cos(0.2 * t[:, 0] + phase[1]),
                                      -25 + 1.7 * amp * np.sin(0.25 * t[:, 0] + phase[2]), 10 + 0 * t[:, 0]], 1)
    pos[:, 5] = pos[:, 2] + np.stack([25 + amp * np.sin(0.17 * t[:, 0] + phase[3]), -30 + amp * np.cos(0.1 * t[:, 0]),
                                      8 + 0 * t[:, 0]], 1)
    pos[:, 6] = hips + [8, -90, 0]
    return pos + rng.normal(0, 0.3, pos.shape)


def _reference_grid(positions: np.ndarray, parents: np.ndarray, grid_range: float = 200, step: float = 0.5,
                    skip: int = 2, frame_skip: int = 1) -> np.ndarray:
    """The paper's coverage, one frame, one bone and one pixel at a time: joint 0's position subtracted
    (the authors' posLckHips), bone i -> parent drawn with the integer Bresenham line between
    rounded, clamped end pixels (x shifted by half the range), row = size - 1 - y; the grid clipped to 0/1."""
    size = int(grid_range / step)
    grid = [[0] * size for _ in range(size)]
    local = positions - positions[:, :1]
    for f in range(0, len(local), frame_skip):
        for i in range(skip, len(parents)):
            a, b = local[f, parents[i]], local[f, i]
            x0, y0 = int(np.rint((a[0] + grid_range / 2) / step)), int(np.rint(a[1] / step))
            x1, y1 = int(np.rint((b[0] + grid_range / 2) / step)), int(np.rint(b[1] / step))
            x0, y0, x1, y1 = (max(0, min(size - 1, v)) for v in (x0, y0, x1, y1))
            dx, dy = abs(x1 - x0), abs(y1 - y0)
            sx, sy = (1 if x0 < x1 else -1), (1 if y0 < y1 else -1)
            err = dx - dy
            while True:
                grid[size - 1 - y0][x0] += 1
                if x0 == x1 and y0 == y1:
                    break
                e2 = 2 * err
                if e2 > -dy:
                    err -= dy
                    x0 += sx
                if e2 < dx:
                    err += dx
                    y0 += sy
    return np.clip(np.asarray(grid), 0, 1)


def _set_stats(g1: np.ndarray, g2: np.ndarray) -> tuple[float, int, int, int]:
    s1, s2 = int((g1 == 1).sum()), int((g2 == 1).sum())
    tp = int(((g1 == 1) & (g2 == 1)).sum())
    fp = int(((g1 == 0) & (g2 == 1)).sum())
    fn = int(((g1 == 1) & (g2 == 0)).sum())
    return 2 * tp / (s1 + s2), tp, fp, fn


def test_coverage_equals_the_definition_loop_by_loop():
    conv = GAC_CONVENTIONS["tonoli2024"]
    nat, gen = _motion(0, 12.0), _motion(1, 5.0)
    g_nat, g_gen = coverage(nat, PARENTS, NAMES, conv), coverage(gen, PARENTS, NAMES, conv)
    r_nat, r_gen = _reference_grid(nat, PARENTS), _reference_grid(gen, PARENTS)
    assert g_nat.shape == (400, 400)
    np.testing.assert_array_equal(g_nat, r_nat.astype(bool))
    np.testing.assert_array_equal(g_gen, r_gen.astype(bool))
    ref_dice, tp, fp, fn = _set_stats(r_nat, r_gen)
    stats = coverage_stats(g_nat, g_gen)
    assert (stats["tp"], stats["fp"], stats["fn"]) == (tp, fp, fn)
    assert dice(stats["tp"], stats["fp"], stats["fn"]) == pytest.approx(ref_dice, abs=1e-12)
    assert 0.2 < ref_dice < 0.95 and fp > 0 and fn > 0
    # the leg below the hips is clamped to the bottom row, as in the authors' code
    assert g_nat[-1].any()


def test_frame_skip_grid_and_wrists_convention():
    nat = _motion(2, 10.0)
    conv = parse_gac("tonoli2024:step=1,range=300,frame_skip=3")
    assert conv.size == 300
    ref = _reference_grid(nat, PARENTS, grid_range=300, step=1, frame_skip=3)
    np.testing.assert_array_equal(coverage(nat, PARENTS, NAMES, conv), ref.astype(bool))
    wrists = parse_gac("wrists:joints=r_hand;l_hand")
    grid = coverage(nat, PARENTS, NAMES, wrists)
    # the hands' paths only: far fewer pixels than the skeleton's; their height kept, off the bottom row
    assert 0 < grid.sum() < coverage(nat, PARENTS, NAMES, GAC_CONVENTIONS["tonoli2024"]).sum()
    assert not grid[-1].any()


def test_min_count_binarises_by_repeats():
    still = np.repeat(_motion(3, 0.0, frames=1), 5, axis=0)
    once = coverage(still, PARENTS, NAMES, parse_gac("tonoli2024"))
    assert (coverage(still, PARENTS, NAMES, parse_gac("tonoli2024:min_count=5")) == once).all()
    # a pixel is marked once per bone drawn through it: joints shared by bones are marked more often
    twice = coverage(still, PARENTS, NAMES, parse_gac("tonoli2024:min_count=6"))
    assert 0 < twice.sum() < once.sum() and (once >= twice).all()
    assert not coverage(still, PARENTS, NAMES, parse_gac("tonoli2024:min_count=100")).any()


@pytest.mark.parametrize("spec", ["tonoli", "tonoli2024:size=3", "tonoli2024:step=abc", "tonoli2024:plane=xx",
                                  "wrists:normalisation=hips"])
def test_bad_specs_are_one_line_errors(spec):
    with pytest.raises(InputError) as err:
        parse_gac(spec)
    assert "\n" not in str(err.value) and "gac" in str(err.value)


def test_missing_joint_is_named():
    with pytest.raises(InputError, match="LeftWrist"):
        coverage(_motion(0, 5.0), PARENTS, NAMES, parse_gac("wrists:joints=LeftWrist"))


def _write(folder, name, pos):
    folder.mkdir(exist_ok=True)
    save_motion(Motion.from_positions(pos, NAMES, 30.0, PARENTS), folder / f"{name}.npz")


def test_family_through_the_engine(tmp_path):
    nat, sys_ = tmp_path / "natural", tmp_path / "sys"
    truth = {}
    for k in range(3):
        n, g = _motion(10 + k, 12.0), _motion(20 + k, 4.0, frames=44)   # longer: truncated to 40
        _write(nat, f"s{k}", n)
        _write(sys_, f"s{k}", g)
        truth[f"s{k}"] = _set_stats(_reference_grid(n, PARENTS), _reference_grid(g[:40], PARENTS))
    result = score_folders(nat, [sys_], ScoreOptions(metrics="gac", bootstrap=50, progress=False))
    rows = {(r["condition"], r["metric"]): r for r in result.summary}
    seq = {(r["sequence"], r["metric"]): r["value"] for r in result.per_sequence if r["condition"] == "sys"}
    for s, (d, tp, fp, fn) in truth.items():
        assert seq[(s, "gac_dice")] == pytest.approx(d)
        assert (seq[(s, "gac_fp")], seq[(s, "gac_fn")]) == (fp, fn)
    dices = [t[0] for t in truth.values()]
    assert rows[("sys", "gac_dice")]["value"] == pytest.approx(np.mean(dices))
    assert rows[("sys", "gac_dice")]["better"] == "higher" and rows[("sys", "gac_fn")]["better"] == "lower"
    tp, fp, fn = (sum(t[i] for t in truth.values()) for i in (1, 2, 3))
    assert rows[("sys", "gac_dice[pooled]")]["value"] == pytest.approx(2 * tp / (2 * tp + fp + fn))
    assert rows[("sys", "gac_fn[pooled]")]["value"] == pytest.approx(fn / (tp + fn))
    lo, hi = rows[("sys", "gac_dice")]["ci_low"], rows[("sys", "gac_dice")]["ci_high"]
    assert lo <= np.mean(dices) <= hi
    assert rows[("natural", "gac_dice")]["value"] == 1.0 and rows[("natural", "gac_fp")]["value"] == 0
    paths = write_figures(result, tmp_path / "fig")
    assert (tmp_path / "fig" / "gac_coverage.png") in paths


def test_not_in_the_default_set_and_the_score_option(tmp_path):
    from evalsuite.cli import main

    nat, sys_ = tmp_path / "natural", tmp_path / "sys"
    _write(nat, "a", _motion(1, 10.0))
    _write(sys_, "a", _motion(2, 10.0))
    plain = score_folders(nat, [sys_], ScoreOptions(progress=False, figures=False))
    assert not any(r["metric"].startswith("gac") for r in plain.summary)
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["score", "-r", str(nat), str(sys_), "-o", str(out), "-m", "kinematics",
                                    "--gac", "wrists:joints=r_hand;l_hand", "--quiet"])
    assert res.exit_code == 0, res.output
    text = (out / "summary.csv").read_text()
    assert "gac_dice" in text and "jerk" in text
    assert (out / "figures" / "gac_coverage.png").exists()
    bad = CliRunner().invoke(main, ["score", "-r", str(nat), str(sys_), "-o", str(out), "--gac", "nope"])
    assert bad.exit_code != 0 and "unknown GAC convention" in bad.output
