"""evalsuite.generators.aud2repr2pose.training: the streamed training data (normalisers fitted one segment at a time,
pairs gathered from memory-mapped files) equals what the in-memory arrays give."""
from __future__ import annotations

import numpy as np
import pytest

from evalsuite.generators.aud2repr2pose.training import MaxAbsScaler, Standardiser, StreamedPairs, _chunks, _windows
from evalsuite.generators.datastream import SegmentStore


def _segments(width, n=9, seed=0, low=1, high=300):
    rng = np.random.default_rng(seed)
    lengths = rng.integers(low, high, size=n)
    return [rng.normal(1.0, 3.0, size=(int(t), width)).astype(np.float32) for t in lengths]


@pytest.mark.parametrize("width", [1, 26, 45])
def test_normalisers_fitted_per_segment_equal_the_concatenations_bit_for_bit(width):
    arrays = _segments(width)
    x = np.concatenate(arrays)
    scaler, std = MaxAbsScaler.fit(arrays, 0.1), Standardiser.fit(arrays)
    mean = x.mean(0)
    assert np.array_equal(scaler.mean, mean)
    assert np.array_equal(scaler.scale, MaxAbsScaler.fit([x], 0.1).scale)
    assert np.array_equal(std.mean, mean) and np.array_equal(std.std, np.maximum(x.std(0), 1e-6))


@pytest.mark.parametrize("form,vel", [("sequence", True), ("sequence", False), ("windowed", True),
                                      ("windowed", False)])
def test_streamed_pairs_equal_the_in_memory_pairs(form, vel, tmp_path):
    speech, poses = _segments(4, seed=1, low=20), _segments(3, seed=1, low=20)
    poses = [p[:len(s)] for s, p in zip(speech, _segments(3, seed=1, low=300, high=301))]
    chunk, context = 20, 3
    if form == "windowed":   # each frame's window of speech, each frame's target
        x = np.concatenate([_windows(s, context) for s in speech])
        y = np.concatenate([np.concatenate([p, np.diff(p, axis=0, prepend=p[:1])], 1) if vel else p for p in poses])
    else:                    # chunks every chunk // 2 frames, the target's frame difference within each chunk
        x = np.stack([c for s in speech for c in _chunks(s, chunk) if len(c) == chunk])
        y = np.stack([c for p in poses for c in _chunks(p, chunk) if len(c) == chunk])
        y = np.concatenate([y, np.diff(y, axis=1, prepend=y[:, :1])], -1) if vel else y
    pairs = StreamedPairs(SegmentStore(tmp_path / "x.npy", speech), SegmentStore(tmp_path / "y.npy", poses), form,
                          context, chunk, vel, tmp_path)
    assert len(pairs) == len(x) == len(y)
    idx = np.random.default_rng(0).permutation(len(x))[:50]
    xb, yb = pairs[idx]
    assert np.array_equal(xb.numpy(), x[idx]) and np.array_equal(yb.numpy(), y[idx])


def test_no_chunk_long_enough_is_a_clear_error(tmp_path):
    short = [np.zeros((5, 2), np.float32)]
    with pytest.raises(ValueError, match="20 frames"):
        StreamedPairs(SegmentStore(tmp_path / "x.npy", short), SegmentStore(tmp_path / "y.npy", short), "sequence",
                      3, 20, False, tmp_path)
