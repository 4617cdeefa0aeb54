"""evalsuite.generators.gesture2vec.data and the plug-in's pool writer: word tracks kept in a memory-mapped store
come back exactly, and the retrieval pool written one code at a time is the file np.savez writes."""
from __future__ import annotations

import numpy as np

from evalsuite.generators.datastream import SegmentStore
from evalsuite.generators.gesture2vec.data import word_rows, word_tracks
from evalsuite.generators.gesture2vec.plugin import _save_pool


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
    _save_pool(tmp_path / "mine.npz", pool)
    np.savez(tmp_path / "ref.npz", **{f"code_{k}": np.stack(v) for k, v in pool.items()})
    mine, ref = np.load(tmp_path / "mine.npz"), np.load(tmp_path / "ref.npz")
    assert mine.files == ref.files == ["code_3", "code_0"]
    assert all(np.array_equal(mine[k], ref[k]) for k in ref.files)
