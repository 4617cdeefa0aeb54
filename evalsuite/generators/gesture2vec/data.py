"""Gesture2Vec's training data: the VQ-DVAE's latent chunks, the translation model's word windows and their
codes, and the retrieval pool. Word tracks and word windows of the training split can live in memory-mapped stores
(:mod:`evalsuite.generators.datastream`), the pool's clips are read from the poses' map (:class:`Clips`) and
written, then read back, as an uncompressed ``.npz`` memory-mapped member by member (:func:`save_pool`,
:func:`open_pool`), so that memory does not grow with hours of corpus."""
from __future__ import annotations

import pathlib
import struct
import zipfile
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import torch

from evalsuite.generators.datastream import RELEASE_BYTES, Mapped, SegmentStore, Windows, release
from evalsuite.generators.gesture2vec.net import VQDVAE, G2VConfig

__all__ = ["WordTrack", "word_rows", "word_tracks", "Clips", "save_pool", "open_pool"]

WordTrack = Sequence[tuple[np.ndarray, float]]   # (embedding, start time in seconds) per word


def word_rows(track: WordTrack, text_dim: int) -> np.ndarray:
    """A word track as ``(n_words, E + 1)`` float64 rows: the embedding, then the start time (both exact)."""
    rows = [np.concatenate([np.asarray(e, np.float64), [t]]) for e, t in track]
    return np.asarray(rows, np.float64).reshape(-1, text_dim + 1)


def word_tracks(store: SegmentStore) -> Sequence[WordTrack]:
    """The word tracks of a store of :func:`word_rows`, each read when it is used (float32 embeddings)."""
    tracks: Any = Mapped(lambda rows: [(r[:-1].astype(np.float32), float(r[-1])) for r in rows],  # type: ignore
                         store)
    return tracks


def _latent_chunks(latent: np.ndarray, chunk: int, stride: int) -> np.ndarray:
    feat = np.concatenate([latent, np.diff(latent, axis=0, prepend=latent[:1])], axis=1)
    starts = range(0, len(feat) - chunk + 1, stride)
    return np.stack([feat[s:s + chunk] for s in starts]) if len(starts) else np.zeros((0, chunk, feat.shape[1]))


def _window_words(words: WordTrack, start: float, length: float, text_dim: int) -> np.ndarray:
    rows = [np.concatenate([emb, [(t - start) / length]]) for emb, t in words if start <= t < start + length]
    return np.asarray(rows, np.float32).reshape(-1, text_dim + 1)


def _aligned(words: WordTrack, start: float, chunk_s: float, n: int, text_dim: int) -> np.ndarray:
    """(n, 2 (text_dim + 1)): per chunk k of a window, the mean (embedding, position in the chunk) of the words
    starting in chunk k, then of those starting in chunk k - 1 (zeros without words)."""
    out = np.zeros((n + 1, text_dim + 1), np.float32)     # row j: chunk j - 1 (row 0: the chunk before the window)
    count = np.zeros(n + 1)
    for emb, t in words:
        j = int(np.floor((t - start) / chunk_s)) + 1
        if 0 <= j <= n:
            out[j] += np.concatenate([emb, [(t - start) / chunk_s - (j - 1)]])
            count[j] += 1
    out /= np.maximum(count, 1)[:, None]
    return np.concatenate([out[1:], out[:-1]], axis=1)


def _pad_words(items: list[np.ndarray], text_dim: int) -> tuple[torch.Tensor, torch.Tensor]:
    width = max(1, max(len(w) for w in items))
    x = np.zeros((len(items), width, text_dim + 1), np.float32)
    mask = np.zeros((len(items), width), bool)
    for i, w in enumerate(items):
        x[i, :len(w)] = w
        mask[i, :len(w)] = True
        if not len(w):
            mask[i, 0] = True  # an empty window attends to one zero row (silence)
    return torch.from_numpy(x), torch.from_numpy(mask)


class Clips(Sequence[np.ndarray]):
    """The clips ``(length, D)`` of a store's rows starting at rows ``starts`` (N,), each read from its file when
    it is used (:meth:`SegmentStore.gather`): one code's retrieval pool without a Python object per clip."""

    def __init__(self, store: SegmentStore, starts: np.ndarray, length: int):
        self.store, self.starts, self.length = store, np.asarray(starts, np.int64), length

    def __len__(self) -> int:
        return len(self.starts)

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        s = int(self.starts[i])
        return self.store.gather(np.arange(s, s + self.length))


def _pool(store: SegmentStore, starts: np.ndarray, codes: np.ndarray, length: int) -> dict[int, Clips]:
    """Clips grouped by code: codes in the order of their first clip, each code's clips in their order."""
    order = np.argsort(codes, kind="stable")
    keys, first = np.unique(codes, return_index=True)
    bounds = np.searchsorted(codes[order], keys, side="left").tolist() + [len(codes)]
    groups = {int(k): Clips(store, starts[order[bounds[j]:bounds[j + 1]]], length) for j, k in enumerate(keys)}
    return {int(keys[j]): groups[int(keys[j])] for j in np.argsort(first, kind="stable")}


def _translation_pairs(vq: VQDVAE, latents: Sequence[np.ndarray], words: Sequence[WordTrack], c: G2VConfig,
                       fps: float, norm: SegmentStore | None = None,
                       pool: dict[int, Sequence[np.ndarray]] | None = None, folder: pathlib.Path | None = None
                       ) -> tuple[Any, np.ndarray, Any]:
    """Word windows and the codes ``(n_windows, chunks_per_window)`` of their non-overlapping chunks (and, with
    ``pool`` and the normalised poses' store ``norm``, each code's clips as :class:`Clips` of ``norm``). The
    windows' word rows ``(n_words, E + 1)`` and aligned words ``(chunks_per_window, 2 (E + 1))``: lists, or with
    ``folder`` a store (one segment per window) and :class:`Windows` of a store (memory-mapped).

    A window starts every ``c.stride`` frames (10), the step of the VQ-DVAE's training chunks, not every
    ``c.chunk`` frames: three times the pairs from one corpus, with each keyword at more offsets within a chunk.
    On the 30-minute synthetic corpus this raised the generated motion's lexical contrast from 0.26 to 0.62 x
    natural's (the translator over-fits the paper's K = 300 classes from non-overlapping windows alone)."""
    win = c.chunk * c.chunks_per_window
    srcs: Any = [] if folder is None else SegmentStore(folder / "word_windows.npy", dtype=np.float32)
    tgts: list[np.ndarray] = []      # per segment: (its windows, chunks_per_window)
    aligned: Any = [] if folder is None else SegmentStore(folder / "aligned_words.npy", dtype=np.float32)
    starts: list[np.ndarray] = []    # per segment: the pooled chunks' first rows in norm, and their codes
    codes_of: list[np.ndarray] = []
    with torch.no_grad():
        for i, (lat, track) in enumerate(zip(latents, words)):
            seg_codes, pooled = [], np.zeros(len(lat), bool)  # overlapping windows share chunks: pool each once
            for s in range(0, len(lat) - win + 1, c.stride):
                feats = _latent_chunks(lat[s:s + win], c.chunk, c.chunk)
                codes = vq.quantise(vq.encode(torch.from_numpy(feats.astype(np.float32)))).numpy()
                srcs.append(_window_words(track, s / fps, win / fps, c.text_dim))
                aligned.append(_aligned(track, s / fps, c.chunk / fps, c.chunks_per_window, c.text_dim))
                seg_codes.append(codes)
                if pool is not None and norm is not None:
                    firsts = s + c.chunk * np.arange(len(codes))
                    new = ~pooled[firsts]
                    pooled[firsts] = True
                    starts.append(int(norm.offsets[i]) + firsts[new])
                    codes_of.append(codes[new])
            if seg_codes:
                tgts.append(np.stack(seg_codes))
    if pool is not None and norm is not None and starts:
        pool.update(_pool(norm, np.concatenate(starts), np.concatenate(codes_of), c.chunk))
    if folder is not None:
        srcs = srcs.finish() if len(tgts) else []
        aligned = Windows(aligned.finish(), c.chunks_per_window, c.chunks_per_window) if len(tgts) else []
    targets = np.concatenate(tgts) if tgts else np.zeros((0, c.chunks_per_window), np.int64)
    return srcs, targets, aligned


def save_pool(path: pathlib.Path, pool: Mapping[int, Sequence[np.ndarray]]) -> None:
    """What ``np.savez(path, code_K=np.stack(clips of code K), ...)`` saves, one clip in memory at a time: each
    entry's ``.npy`` header, then its clips' bytes (clips that are views of a memory-mapped file have its pages
    dropped after every :data:`~evalsuite.generators.datastream.RELEASE_BYTES` written)."""
    written = 0
    with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
        for k, clips in pool.items():
            first = clips[0]
            header = {"descr": np.lib.format.dtype_to_descr(first.dtype), "fortran_order": False,
                      "shape": (len(clips), *first.shape)}
            with zf.open(f"code_{k}.npy", "w", force_zip64=True) as fh:
                np.lib.format.write_array_header_1_0(fh, header)
                for clip in clips:
                    fh.write(np.ascontiguousarray(clip, first.dtype).tobytes())
                    written += clip.nbytes
                    if written >= RELEASE_BYTES:
                        release(clip)
                        written = 0
    if written and len(pool):
        release(next(iter(pool.values()))[0])


def open_pool(path: pathlib.Path) -> dict[int, np.ndarray]:
    """A pool written by :func:`save_pool` (or ``np.savez``) as ``{K: (n_K, chunk, D)}`` arrays memory-mapped
    from the ``.npz`` (its members are stored uncompressed: each is a ``.npy`` at an offset of the file); a
    compressed member is read into memory."""
    pool: dict[int, np.ndarray] = {}
    with open(path, "rb") as fh, zipfile.ZipFile(fh) as zf:
        for info in zf.infolist():
            key = int(info.filename.split("_")[1].split(".")[0])
            if info.compress_type != zipfile.ZIP_STORED:
                with zf.open(info) as member:
                    pool[key] = np.lib.format.read_array(member)
                continue
            fh.seek(info.header_offset)
            local = fh.read(30)      # the local file header: its name and extra field lengths at bytes 26-29
            fh.seek(info.header_offset + 30 + sum(struct.unpack("<HH", local[26:30])))
            version = np.lib.format.read_magic(fh)
            read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            shape, fortran, dtype = read(fh)
            if not np.prod(shape):
                pool[key] = np.zeros(shape, dtype)
                continue
            pool[key] = np.memmap(path, dtype, "r", fh.tell(), shape, "F" if fortran else "C")
    return pool
