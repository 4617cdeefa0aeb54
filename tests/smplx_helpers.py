"""Fake SMPL-X data for tests: a model file with the real key names, shapes and parent table but random numbers
(nothing licensed), and BEAT2-style recordings."""
from __future__ import annotations

import pathlib

import numpy as np

from evalsuite.motion.smplx_layout import SMPLX_PARENTS


def fake_smplx_model(path, n_betas: int = 10, n_verts: int = 200, seed: int = 0) -> pathlib.Path:
    """Write a fake SMPL-X model ``.npz``: ``v_template`` (V, 3), ``shapedirs`` (V, 3, S) with S = 20 for
    10 betas (the old 10 shape + 10 expression layout) or 300 + 100 for 300 betas, ``J_regressor`` (55, V)
    (rows of non-negative weights summing to 1), ``kintree_table`` (2, 55) (root parent 2**32 - 1 as in
    the real files), ``posedirs``, ``weights`` and ``f``."""
    rng = np.random.default_rng(seed)
    path = pathlib.Path(path)
    n_cols = 400 if n_betas > 10 else 20
    v_template = rng.normal(0.0, 0.3, (n_verts, 3))
    shapedirs = rng.normal(0.0, 0.002, (n_verts, 3, n_cols))
    jr = rng.random((55, n_verts)) * (rng.random((55, n_verts)) < 0.1)
    jr[:, 0] += 1e-3
    jr /= jr.sum(axis=1, keepdims=True)
    parents = np.array(SMPLX_PARENTS, dtype=np.int64)
    parents[0] = 2**32 - 1
    kintree = np.stack([parents, np.arange(55)]).astype(np.int64)
    np.savez(path, v_template=v_template, shapedirs=shapedirs, J_regressor=jr, kintree_table=kintree,
             posedirs=rng.normal(0.0, 0.001, (n_verts, 3, 486)), weights=rng.random((n_verts, 55)),
             f=rng.integers(0, n_verts, (2 * n_verts, 3)).astype(np.uint32))
    return path


def fake_poses(n_frames: int = 40, seed: int = 0, scale: float = 0.4) -> np.ndarray:
    """(T, 165) smooth random axis-angle poses (radians)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 2.0 * np.pi, n_frames)[:, None]
    phase = rng.uniform(0.0, 2.0 * np.pi, (1, 165))
    amp = rng.uniform(0.0, scale, (1, 165))
    return amp * np.sin(t + phase) + rng.normal(0.0, 0.05, (1, 165))


def write_fake_beat2_recording(path, n_frames: int = 40, seed: int = 0, n_betas: int = 300, n_expr: int = 100,
                               fps: int = 30, dtype=np.float64, betas: np.ndarray | None = None,
                               poses: np.ndarray | None = None) -> pathlib.Path:
    """Write a BEAT2-style ``.npz``: ``poses`` (T, 165), ``trans`` (T, 3), ``betas`` (n_betas,),
    ``expressions`` (T, n_expr), ``model`` 'smplx2020', ``gender`` 'neutral', ``mocap_frame_rate`` fps."""
    rng = np.random.default_rng(seed + 1000)
    path = pathlib.Path(path)
    if poses is None:
        poses = fake_poses(n_frames, seed)
    n_frames = len(poses)
    trans = np.cumsum(rng.normal(0.0, 0.005, (n_frames, 3)), axis=0) + np.array([0.0, 0.9, 0.0])
    if betas is None:
        betas = rng.normal(0.0, 1.0, n_betas)
    expressions = rng.normal(0.0, 0.5, (n_frames, n_expr))
    np.savez(path, poses=poses.astype(dtype), trans=trans.astype(dtype), betas=np.asarray(betas).astype(dtype),
             expressions=expressions.astype(dtype), model=np.array("smplx2020"), gender=np.array("neutral"),
             mocap_frame_rate=np.array(fps))
    return path
