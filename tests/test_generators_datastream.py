"""evalsuite.generators.datastream: segments memory-mapped on disk, their statistics and training windows exactly as
the in-memory arrays would give them."""
from __future__ import annotations

import numpy as np
import pytest

from evalsuite.generators.datastream import SegmentStore, Windows, mean_std
from evalsuite.generators.gesticulator.net import GesticulatorConfig
from evalsuite.generators.gesticulator.training import Normaliser, make_sequences, sequence_windows


def _segments(width, dtype=np.float32, n=12, seed=0):
    rng = np.random.default_rng(seed)
    return [rng.normal(3.0, 2.0, size=(int(rng.integers(1, 400)), width)).astype(dtype) for _ in range(n)]


@pytest.mark.parametrize("width,dtype", [(1, np.float32), (2, np.float32), (45, np.float64), (197, np.float32)])
def test_mean_and_std_one_segment_at_a_time_equal_the_concatenations_bit_for_bit(width, dtype):
    arrays = _segments(width, dtype)
    x = np.concatenate(arrays)
    mean, std = mean_std(arrays)
    assert mean.dtype == dtype and np.array_equal(mean, x.mean(0)) and np.array_equal(std, x.std(0))


def test_a_store_is_a_memory_mapped_npy_of_the_segments(tmp_path):
    arrays = _segments(7, np.float64)
    store = SegmentStore(tmp_path / "a.npy", arrays)
    assert isinstance(store.data, np.memmap) and store.data.dtype == np.float64
    assert np.array_equal(np.load(tmp_path / "a.npy"), np.concatenate(arrays))
    assert len(store) == len(arrays) and all(np.array_equal(store[i], a) for i, a in enumerate(arrays))
    with pytest.raises(ValueError, match="segment arrays"):
        SegmentStore(tmp_path / "b.npy", [np.zeros((3, 2)), np.zeros((3, 4))])


def test_windows_gather_what_make_sequences_stacks(tmp_path):
    config = GesticulatorConfig(audio_dim=3, text_dim=2, pose_dim=4, past=2, future=3)
    speech, poses = _segments(5, seed=1), _segments(4, seed=2)
    for s, p in zip(speech, poses):   # one length per segment on both sides
        n = min(len(s), len(p))
        s.resize((n, 5), refcheck=False)
        p.resize((n, 4), refcheck=False)
    sn, pn = Normaliser.fit(speech), Normaliser.fit(poses)
    x, y = make_sequences([sn(s) for s in speech], [pn(p) for p in poses], config, 20, 6)
    xs, ys = sequence_windows(speech, poses, sn, pn, config, 20, 6, tmp_path)
    assert len(xs) == len(x) == len(ys)
    idx = np.random.default_rng(0).permutation(len(x))[:17]
    assert np.array_equal(xs[idx], x[idx]) and np.array_equal(ys[idx], y[idx])
    assert isinstance(xs, Windows) and (tmp_path / "speech_windows.npy").exists()


def test_rows_mapped_and_release(tmp_path):
    from evalsuite.generators import datastream
    from evalsuite.generators.datastream import Mapped, Rows

    arrays = _segments(3, seed=4)
    store = SegmentStore(tmp_path / "r.npy", arrays)
    x = np.concatenate(arrays)
    rows = Rows(store)
    idx = np.random.default_rng(1).permutation(len(x))[:40]
    assert len(rows) == len(x) and np.array_equal(rows[idx], x[idx])
    doubled = Mapped(lambda a: 2 * a, store)
    assert len(doubled) == len(arrays) and all(np.array_equal(d, 2 * a) for d, a in zip(doubled, arrays))
    assert np.array_equal(doubled[-1], 2 * arrays[-1])
    with pytest.raises(IndexError):
        store[len(arrays)]
    datastream.RELEASE_BYTES, saved = 1, datastream.RELEASE_BYTES   # release after every segment read
    try:
        assert np.array_equal(store[0], arrays[0]) and store._read == 0
        assert np.array_equal(store[0], arrays[0])   # read again after the pages were dropped
        assert np.array_equal(rows[idx[::-1]], x[idx[::-1]])
    finally:
        datastream.RELEASE_BYTES = saved


def test_a_pass_over_the_segments_drops_the_pages_it_read(tmp_path):
    from evalsuite.generators import datastream

    arrays = _segments(4, seed=5)
    store = SegmentStore(tmp_path / "s.npy", arrays)
    datastream.RELEASE_BYTES, saved = 64, datastream.RELEASE_BYTES
    try:
        released = []
        store.release = lambda: (released.append(store._read), setattr(store, "_read", 0))  # type: ignore
        assert np.array_equal(np.concatenate(list(store)), np.concatenate(arrays))
        assert len(released) > 1 and all(r >= 64 for r in released[:-1])   # the last: the end of the pass
        assert np.array_equal(mean_std(store)[0], np.concatenate(arrays).mean(0))
    finally:
        datastream.RELEASE_BYTES = saved


def test_a_whole_pass_leaves_no_page_of_the_map_resident(tmp_path):
    x = np.random.default_rng(2).normal(size=(40000, 64)).astype(np.float32)   # 10 MiB, under a release
    store = SegmentStore(tmp_path / "s.npy", [x[:15000], x[15000:30000], x[30000:]])
    assert float(sum(a.sum() for a in store)) == pytest.approx(float(x.sum()), rel=1e-4)
    assert _resident_mb(tmp_path / "s.npy") == 0
    assert float(store[1].sum()) == pytest.approx(float(x[15000:30000].sum()), rel=1e-4)   # still readable


def _resident_mb(path) -> float:
    """Resident MB of this process's maps of ``path`` (Linux's /proc/self/smaps)."""
    total, inside = 0, False
    with open("/proc/self/smaps") as fh:
        lines = fh.readlines()
    for line in lines:
        head = line.split()
        if head and "-" in head[0] and not head[0].endswith(":"):
            inside = len(head) > 5 and head[5] == str(path)
        elif inside and head[0] == "Rss:":
            total += int(head[1])
    return total / 1024


def test_gathered_rows_windows_and_copies_are_read_without_touching_the_map(tmp_path):
    """Through the map, each random row would leave a page-cache folio (64-256 KiB) resident: 3,200 random rows of
    a 32 MiB map left all of it resident before the next release."""
    path = tmp_path / "rows.npy"
    x = np.random.default_rng(1).normal(size=(131072, 64)).astype(np.float32)   # 32 MiB, cached once written
    store = SegmentStore(path, [x[:100000], x[100000:]])
    rng = np.random.default_rng(0)
    for _ in range(200):
        idx = rng.integers(0, 131072, 16)
        assert np.array_equal(store.gather(idx), x[idx])
    wins = Windows(store, 30, 10)
    idx = rng.integers(0, len(wins), 8)
    assert np.array_equal(wins[idx], np.stack([x[s:s + 30] for s in wins.starts[idx]]))
    assert np.array_equal(store.take([1])[0], x[100000:]) and np.array_equal(store.gather(np.array([-1])), x[-1:])
    assert _resident_mb(path) == 0
    with pytest.raises(IndexError):
        store.gather(np.array([5, 131072]))
