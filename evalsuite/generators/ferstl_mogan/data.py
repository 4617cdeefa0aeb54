"""The training sequences of the Ferstl et al. re-implementation: consecutive non-overlapping windows of each
segment, in memory (:func:`sequences`, the validation split's) or gathered batch by batch from a memory-mapped
store (:class:`Sequences`, the training split's)."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch

from evalsuite.generators.datastream import SegmentStore, Windows

__all__ = ["sequences", "Sequences"]


def sequences(arrays: Sequence[np.ndarray], length: int) -> tuple[np.ndarray, np.ndarray]:
    """Consecutive non-overlapping windows, and for each whether it directly follows the previous one."""
    out, follows = [], []
    for a in arrays:
        for k, s in enumerate(range(0, len(a) - length + 1, length)):
            out.append(a[s:s + length])
            follows.append(k > 0)
    return np.stack(out), np.asarray(follows)


class Sequences:
    """:func:`sequences`' windows of a store, gathered on demand: ``seqs[idx]`` (a tensor of indices) is the
    tensor ``(len(idx), length, D)``, or ``(len(idx), length)`` for a one-column store with ``squeeze``."""

    def __init__(self, store: SegmentStore, length: int, squeeze: bool = False):
        self.windows, self.squeeze = Windows(store, length, length), squeeze
        counts = [len(range(0, n - length + 1, length)) if n >= length else 0 for n in store.lengths.tolist()]
        self.follows = np.asarray([k > 0 for c in counts for k in range(c)], bool)

    def __len__(self) -> int:
        return len(self.windows)

    def __getitem__(self, idx: torch.Tensor) -> torch.Tensor:
        out = self.windows[idx.numpy()]
        return torch.from_numpy(out[..., 0] if self.squeeze else out)
