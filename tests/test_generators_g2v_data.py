"""evalsuite.generators.gesture2vec.data: word tracks kept in a memory-mapped store come back exactly, the
retrieval pool written one code at a time is the file np.savez writes and is read back memory-mapped, and the
pool's clips are grouped by code as the translation pairs meet them."""
from __future__ import annotations

import numpy as np

from evalsuite.generators.datastream import SegmentStore
from evalsuite.generators.gesture2vec.data import Clips, _pool, open_pool, save_pool, word_rows, word_tracks


def test_word_tracks_round_trip_through_a_store(tmp_path):
    rng = np.random.default_rng(0)
    tracks = [[(rng.normal(size=5).astype(np.float32), float(t)) for t in np.sort(rng.uniform(0, 9, size=n))]
              for n in (3, 0, 7)]
    back = word_tracks(SegmentStore(tmp_path / "w.npy", (word_rows(t, 5) for t in tracks), np.float64))
    assert len(back) == 3 and len(back[1]) == 0
    for got, want in zip(back, tracks):
        assert len(got) == len(want)
        for (e1, t1), (e2, t2) in zip(got, want):
            assert e1.dtype == np.float32 and np.array_equal(e1, e2) and t1 == t2


def test_the_pool_written_code_by_code_equals_savez(tmp_path):
    rng = np.random.default_rng(1)
    store = SegmentStore(tmp_path / "p.npy", [rng.normal(size=(90, 4)).astype(np.float32)])
    pool = {3: [store[0][0:30], store[0][60:90]], 0: [store[0][30:60]]}
    save_pool(tmp_path / "mine.npz", pool)
    np.savez(tmp_path / "ref.npz", **{f"code_{k}": np.stack(v) for k, v in pool.items()})
    mine, ref = np.load(tmp_path / "mine.npz"), np.load(tmp_path / "ref.npz")
    assert mine.files == ref.files == ["code_3", "code_0"]
    assert all(np.array_equal(mine[k], ref[k]) for k in ref.files)


def test_the_pool_is_read_back_memory_mapped(tmp_path):
    rng = np.random.default_rng(2)
    ref = {f"code_{k}": rng.normal(size=(n, 30, 4)).astype(np.float32) for k, n in ((7, 3), (1, 1), (250, 5))}
    np.savez(tmp_path / "ref.npz", **ref)
    store = SegmentStore(tmp_path / "p.npy", [np.concatenate([v.reshape(-1, 4) for v in ref.values()])])
    starts = np.cumsum([0, 30, 30, 30, 30, 30, 30, 30, 30])
    save_pool(tmp_path / "mine.npz", {7: Clips(store, starts[:3], 30), 1: Clips(store, starts[3:4], 30),
                                      250: Clips(store, starts[4:], 30)})
    for name in ("ref.npz", "mine.npz"):
        pool = open_pool(tmp_path / name)
        assert list(pool) == [7, 1, 250]
        for k, v in pool.items():
            assert isinstance(v, np.memmap) and np.array_equal(v, ref[f"code_{k}"])


def test_clips_are_grouped_by_code_in_first_seen_order(tmp_path):
    store = SegmentStore(tmp_path / "p.npy", [np.arange(200, dtype=np.float32).reshape(100, 2)])
    starts, codes = np.array([0, 10, 20, 30, 40, 50]), np.array([5, 2, 5, 9, 2, 5])
    pool = _pool(store, starts, codes, 10)
    assert list(pool) == [5, 2, 9]
    assert [c.starts.tolist() for c in pool.values()] == [[0, 20, 50], [10, 40], [30]]
    assert np.array_equal(pool[2][1], store.data[40:50]) and len(pool[9]) == 1
