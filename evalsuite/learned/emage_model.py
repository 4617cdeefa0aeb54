"""EMAGE AESKConv model files as FGD feature models, so ``evalsuite score --fgd aeskconv.pt`` uses them.

:func:`evalsuite.learned.modelfile.load_model` returns an :class:`EmageFeatureModel` for a file written by
``evalsuite fgd import-emage``. It has the parts of :class:`~evalsuite.learned.modelfile.FeatureModel` that the
FGD family uses. A "window" is the whole sequence cut to a multiple of 32 frames, ``(1, T', 330)``;
:meth:`EmageFeatureModel.encode` gives its latents, one 240-d row per 16 frames, as the Leaderboard pools them.
"""
from __future__ import annotations

import hashlib

import numpy as np
import torch

from evalsuite.errors import InputError
from evalsuite.learned.emage_aeskconv import (
    CHUNK,
    DOWNSAMPLE,
    INPUT_DIM,
    VAE_LENGTH,
    AESKConv,
    aeskconv_latents,
    axis_angle_to_rot6d,
)

__all__ = ["EmageFeatureModel", "state_hash"]

FPS = 30.0


def state_hash(meta: dict, state: dict[str, torch.Tensor]) -> str:
    """sha256 over the architecture name and every tensor (name, shape, float32 bytes) in name order."""
    h = hashlib.sha256(str(meta.get("architecture")).encode())
    for k in sorted(state):
        t = state[k].detach().cpu().to(torch.float32).contiguous()
        h.update(k.encode() + str(tuple(t.shape)).encode() + t.numpy().tobytes())
    return h.hexdigest()


class EmageFeatureModel:
    """The Leaderboard's FGD encoder behind the interface the FGD family uses (CPU, float32)."""

    window = CHUNK
    stride = CHUNK
    fps = FPS
    window_rule = "emage"

    def __init__(self, net: AESKConv, meta: dict, state: dict[str, torch.Tensor]):
        self.net = net.eval()
        self.meta = dict(meta)
        self.meta["content_hash"] = state_hash(meta, state)

    @property
    def representation(self) -> dict:
        """For folder readers: every joint of the file, no BVH convention (the model reads SMPL-X rotations)."""
        return {"kind": "smplx_rot6d", "joints": None, "convention": None}

    @property
    def joints(self) -> None:
        return None

    @property
    def content_hash(self) -> str:
        return self.meta["content_hash"]

    @property
    def short_hash(self) -> str:
        return self.content_hash[:12]

    def describe(self) -> str:
        return "\n".join([f"model {self.short_hash} (sha256 {self.content_hash})",
                          f"  {self.meta.get('architecture')} from {self.meta.get('source_file')} "
                          f"(sha256 {str(self.meta.get('source_sha256'))[:12]})",
                          f"  input: {self.meta.get('input')}",
                          f"  latents: {VAE_LENGTH}-d, one per {DOWNSAMPLE} frames"])

    def pose_vectors(self, motion) -> np.ndarray:
        """6D rotations (T, 330) of an SMPL-X motion's 55 joints (global orientation included, as EMAGE)."""
        data = getattr(motion, "smplx", None)
        where = getattr(motion, "source", None) or getattr(motion, "name", None)
        if data is None:
            raise InputError("the EMAGE AESKConv FGD model needs SMPL-X motion (.npz with poses (T,165))", path=where)
        if abs(float(data.fps) - FPS) > 1e-6:
            raise InputError(f"the EMAGE AESKConv FGD model expects {FPS:g} fps, the motion has {float(data.fps):g}",
                             path=where)
        return axis_angle_to_rot6d(data.poses)

    def windows(self, motion, stride: int | None = None) -> np.ndarray:
        """The whole sequence cut to a multiple of 32 frames, as one item ``(1, T', 330)``."""
        vec = self.pose_vectors(motion)
        n = len(vec) - len(vec) % CHUNK
        if n == 0:
            raise InputError(f"too short for the EMAGE AESKConv model: {len(vec)} frames, need at least {CHUNK}",
                             path=getattr(motion, "source", None) or getattr(motion, "name", None))
        return vec[None, :n]

    def normalize(self, windows: np.ndarray) -> np.ndarray:
        """No normalisation: the model reads 6D rotations as they are."""
        return np.asarray(windows, dtype=np.float64)

    def encode(self, windows: np.ndarray, normalized: bool = False) -> np.ndarray:
        """Latents of each item, stacked: ``(sum T'_i / 16, 240)`` float64 copies of the float32 output."""
        windows = np.asarray(windows)
        if windows.ndim != 3 or windows.shape[2] != INPUT_DIM:
            raise InputError(f"windows must have shape (N, T, {INPUT_DIM}), got {windows.shape}")
        return np.concatenate([aeskconv_latents(self.net, w) for w in windows]).astype(np.float64)

    def features(self, motion, stride: int | None = None) -> np.ndarray:
        return self.encode(self.windows(motion))
