"""Shared data for the learned-metric tests: small homogeneous synthetic natural motion."""
from __future__ import annotations

import functools

from evalsuite.motion.ops import cut
from evalsuite.motion.synthetic import synthetic_motion

N_JOINTS = 20
FPS = 30.0
WINDOW = 20


@functools.cache
def natural(n_pieces: int = 8, seconds: float = 20.0, seed: int = 3) -> dict:
    """``n_pieces`` consecutive pieces of one long synthetic take (one motion 'style'), by name.

    One take cut into pieces keeps the pieces from the same distribution, so natural-vs-natural
    FGD is small (different seeds of synthetic_motion draw different motion characters).
    """
    take = synthetic_motion(n_joints=N_JOINTS, fps=FPS, seconds=n_pieces * seconds, seed=seed)
    return {f"take{i:02d}": cut(take, i * seconds, (i + 1) * seconds) for i in range(n_pieces)}


@functools.cache
def trained(seed: int = 0, epochs: int = 6):
    from evalsuite.learned.training import train_model

    return train_model(natural(), joints="all", window=WINDOW, fps=FPS, epochs=epochs, seed=seed,
                       learning_rate=1e-3, progress=False)
