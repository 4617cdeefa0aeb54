"""evalsuite.generators.ferstl_mogan.data: the training sequences gathered from a memory-mapped store equal the
in-memory ones, with the same "follows the previous window" flags."""
from __future__ import annotations

import numpy as np
import torch

from evalsuite.generators.datastream import SegmentStore
from evalsuite.generators.ferstl_mogan.data import Sequences, sequences


def test_streamed_sequences_equal_the_in_memory_ones(tmp_path):
    rng = np.random.default_rng(3)
    arrays = [rng.normal(size=(int(n), 4)).astype(np.float32) for n in rng.integers(5, 200, size=8)]
    labels = [rng.integers(0, 5, size=len(a)) for a in arrays]
    x, follows = sequences(arrays, 30)
    lab, _ = sequences([np.asarray(c, np.int64) for c in labels], 30)
    xs = Sequences(SegmentStore(tmp_path / "x.npy", arrays), 30)
    ls = Sequences(SegmentStore(tmp_path / "l.npy", [np.asarray(c, np.int64)[:, None] for c in labels]), 30,
                   squeeze=True)
    assert len(xs) == len(x) == len(ls) and np.array_equal(xs.follows, follows)
    idx = torch.from_numpy(rng.permutation(len(x))[:9])
    assert torch.equal(xs[idx], torch.from_numpy(x[idx.numpy()]))
    assert torch.equal(ls[idx], torch.from_numpy(lab[idx.numpy()]))
