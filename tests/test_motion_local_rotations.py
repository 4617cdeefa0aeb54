"""Motion.local_rotations against scipy's Euler convention, Skeleton's own validation, and the in-sample
CCA convention of `evalsuite score` against a direct computation."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

import evalsuite
from evalsuite.metrics.cca import canonical_correlation
from evalsuite.metrics.engine import score_folders
from evalsuite.motion.skeleton import Skeleton
from evalsuite.motion.synthetic import synthetic_motion


@pytest.mark.parametrize("order", ["ZXY", "XYZ", "YZX"])
def test_local_rotations_are_the_channels_intrinsic_euler_rotations(order):
    motion = synthetic_motion(n_joints=20, fps=30, seconds=1.0, seed=4, rotation_order=order)
    local = motion.local_rotations()
    assert local.shape == (motion.n_frames, motion.n_joints, 3, 3)
    sk = motion.skeleton
    for j in range(motion.n_joints):
        chans = sk.channels[j]
        rot = [k for k, c in enumerate(chans) if c.lower().endswith("rotation")]
        start = sk.channel_starts[j]
        axes = "".join(chans[k][0].upper() for k in rot)
        angles = motion.values[:, start + np.array(rot)]
        # BVH channels are intrinsic rotations in channel order (upper-case axes in scipy)
        expected = Rotation.from_euler(axes, angles, degrees=True).as_matrix()
        np.testing.assert_allclose(local[:, j], expected, atol=1e-12)
        np.testing.assert_allclose(local[:, j] @ local[:, j].transpose(0, 2, 1),
                                   np.broadcast_to(np.eye(3), local[:, j].shape), atol=1e-12)


def test_local_rotations_of_positional_motion_are_refused():
    m = evalsuite.Motion.from_positions(np.zeros((3, 2, 3)), ["a", "b"], 30)
    with pytest.raises(evalsuite.MotionError, match="positions only"):
        m.local_rotations()


def test_skeleton_validates_its_structure():
    ok = dict(names=["root", "child"], parents=[-1, 0], offsets=np.zeros((2, 3)),
              channels=[("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"),
                        ("Zrotation", "Xrotation", "Yrotation")])
    sk = Skeleton(**ok)
    assert sk.n_joints == 2
    assert sk.n_channels == 9
    with pytest.raises(ValueError, match="one entry per joint"):
        Skeleton(**{**ok, "parents": [-1]})
    with pytest.raises(ValueError, match="unique"):
        Skeleton(**{**ok, "names": ["root", "root"]})
    with pytest.raises(ValueError, match="parent precedes its children"):
        Skeleton(**{**ok, "parents": [1, -1]})


def test_in_sample_cca_equals_a_direct_computation(tmp_path):
    """GENEA conventions fit and score CCA on the same frames: the score equals canonical_correlation of
    all paired frames stacked."""
    from evalsuite.motion.io import save_motion

    rng = np.random.default_rng(0)
    nat_dir, gen_dir = tmp_path / "natural", tmp_path / "gen"
    nat_dir.mkdir()
    gen_dir.mkdir()
    nats, gens = [], []
    for i in range(3):
        m = synthetic_motion(n_joints=20, fps=20, seconds=30, seed=i)
        g = m.with_values(m.values + rng.normal(0, 5, m.values.shape))
        save_motion(m, nat_dir / f"s{i}.bvh")
        save_motion(g, gen_dir / f"s{i}.bvh")
        nats.append(evalsuite.load_motion(nat_dir / f"s{i}.bvh").positions())
        gens.append(evalsuite.load_motion(gen_dir / f"s{i}.bvh").positions())
    result = score_folders(nat_dir, [f"gen={gen_dir}"], metrics=["cca"], convention="genea2020", progress=False,
                           figures=False)
    row = pd.DataFrame(result.summary).set_index(["condition", "metric"]).loc[("gen", "cca")]
    x = np.concatenate([g.reshape(len(g), -1) for g in gens])
    y = np.concatenate([n.reshape(len(n), -1) for n in nats])
    assert row["value"] == pytest.approx(canonical_correlation(x, y), rel=1e-9)
