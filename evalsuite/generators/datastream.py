"""Training data on disk: segments' arrays in one memory-mapped ``.npy`` file, statistics and training windows
read from it in chunks, so that a training's memory does not grow with hours of corpus.

:class:`SegmentStore` appends each segment's ``(T_i, D)`` array to ``FILE.npy`` as it is computed (one segment in
memory at a time) and opens the file with ``numpy.load(mmap_mode="r")``; ``store[i]`` is segment ``i`` as a view
of the map. :func:`mean_std` gives exactly (bit for bit) what ``np.concatenate(arrays).mean(0)`` and ``.std(0)``
give, one segment at a time: both sums run over the frames in order, as numpy's reduction over axis 0 does
for two or more columns (a single column is concatenated: it is small). :class:`Windows` stands for the
``(N, length, D)`` array of overlapping training windows without making it: ``windows[idx]`` gathers a batch
from the map, and :class:`Rows` the ``(N, D)`` concatenation of a store's rows. :class:`Mapped` applies a
function to each segment when it is read (normalised or differenced segments, one at a time).

A map's pages that a process has read count in its resident memory (``ru_maxrss``) until it unmaps them, so a
store drops them (``madvise(MADV_DONTNEED)``; they stay in the page cache) after every :data:`RELEASE_BYTES` of
segments it hands out: a pass over a 10-hour corpus holds at most about that much of it. Random reads (gathered
rows and windows, copies of segments) do not go through the map at all: they are read with ``preadv`` into the
output array. Through the map, each small random read would cost a whole page-cache folio of resident memory
(Linux maps the cached pages around a fault: 64-256 KiB on ext4 here), so 16,384 random 540-byte rows of a
216 MB map left 206 MB resident, while counting their bytes said 9 MB.

:func:`training_folder` gives a training's temporary folder for its maps, under one root per user with the
owning process's id in its name; folders whose process is gone (a training killed with SIGKILL, which runs no
clean-up) are removed when the next training starts.
"""
from __future__ import annotations

import mmap
import os
import pathlib
import re
import shutil
import tempfile
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

import numpy as np

from evalsuite.corpus.types import Segment
from evalsuite.generators.pose_repr import PoseRepresentation
from evalsuite.generators.reimpl import SegmentArrays, corpus_arrays

__all__ = ["SegmentStore", "mean_std", "max_abs_deviation", "Windows", "Rows", "Mapped", "stream_arrays",
           "RELEASE_BYTES", "release", "training_folder", "remove_stale_folders"]

RELEASE_BYTES = 64 << 20  # bytes of segments handed out as views of a map before its pages are dropped
_HEADER = 128  # bytes of the .npy header (version 1.0), written once with room for any shape


def _npy_header(shape: tuple[int, ...], dtype: np.dtype) -> bytes:
    text = f"{{'descr': '{dtype.str}', 'fortran_order': False, 'shape': {shape}, }}"
    text = text.ljust(_HEADER - 10 - 1) + "\n"
    return b"\x93NUMPY\x01\x00" + len(text).to_bytes(2, "little") + text.encode("latin1")


class SegmentStore(Sequence[np.ndarray]):
    """Arrays ``(T_i, D)`` of one dtype, one after another in ``path`` (a ``.npy`` file), memory-mapped.

    ``SegmentStore(path, arrays)`` writes them all; or ``SegmentStore(path)``, then :meth:`append` each array
    and :meth:`finish`."""

    def __init__(self, path: str | pathlib.Path, arrays: Iterable[np.ndarray] | None = None,
                 dtype: Any = None):
        self.path = pathlib.Path(path)
        self.dtype = np.dtype(dtype) if dtype is not None else None  # None: the first array's
        self._lengths: list[int] = []
        self._width: int | None = None
        self._read = 0
        self._fh = open(self.path, "wb")  # noqa: SIM115 (closed by finish())
        self._fh.write(_npy_header((0, 0), np.dtype(np.float32)))  # rewritten by finish()
        if arrays is not None:
            for a in arrays:
                self.append(a)
            self.finish()

    def append(self, a: np.ndarray) -> None:
        self.dtype = self.dtype or np.asarray(a).dtype
        a = np.ascontiguousarray(a, dtype=self.dtype)
        if a.ndim != 2 or (self._width is not None and a.shape[1] != self._width):
            raise ValueError(f"segment arrays must be (T, {self._width or 'D'}), got {a.shape}")
        self._width = a.shape[1]
        self._fh.write(a.tobytes())
        self._lengths.append(len(a))

    def finish(self) -> SegmentStore:
        """Write the header's shape, close the file and map it (read-only)."""
        self._fh.seek(0)
        self._fh.write(_npy_header((sum(self._lengths), self._width or 0), self.dtype or np.dtype(np.float32)))
        self._fh.close()
        self.lengths = np.asarray(self._lengths, np.int64)
        self.offsets = np.concatenate([[0], np.cumsum(self.lengths)]).astype(np.int64)
        self.data: np.ndarray = np.load(self.path, mmap_mode="r")
        return self

    @property
    def width(self) -> int:
        return int(self.data.shape[1])

    def __len__(self) -> int:
        return len(self.lengths)

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        if not -len(self) <= i < len(self):
            raise IndexError(f"segment {i} of {len(self)}")
        i = i + len(self) if i < 0 else i
        self._count(int(self.lengths[i]) * self._row_bytes)
        return self.data[self.offsets[i]:self.offsets[i + 1]]

    @property
    def _row_bytes(self) -> int:
        return int(self.data.shape[1] * self.data.itemsize)

    def _count(self, nbytes: int) -> None:
        """Count bytes handed out; past :data:`RELEASE_BYTES`, drop the pages read so far (views stay valid: a
        later read takes their pages from the page cache again), so that a pass holds at most that much."""
        self._read += nbytes
        if self._read >= RELEASE_BYTES:
            self.release()

    def __iter__(self) -> Iterator[np.ndarray]:
        """The segments in order; at the end of a whole pass the pages it read are dropped (a store left after a
        pass, e.g. the corpus's poses once normalised, keeps none resident)."""
        for i in range(len(self)):
            yield self[i]
        self.release()

    def gather(self, rows: np.ndarray) -> np.ndarray:
        """``data[rows]`` (an integer array of row numbers, any shape) as an array in memory, read from the file
        (``preadv``, one call per run of consecutive rows), not through the map: no page of the map is touched."""
        rows = np.asarray(rows, np.int64)
        n, width = int(self.data.shape[0]), int(self.data.shape[1])
        flat = np.where(rows < 0, rows + n, rows).reshape(-1)
        if flat.size and (flat.min() < 0 or flat.max() >= n):
            raise IndexError(f"row {int(rows.reshape(-1)[np.argmax((flat < 0) | (flat >= n))])} of {n}")
        out = np.empty((flat.size, width), self.data.dtype)
        if not hasattr(os, "preadv"):     # no preadv (Windows): through the map
            out[:] = self.data[flat]
            return out.reshape(*rows.shape, width)
        cuts = (np.flatnonzero(np.diff(flat) != 1) + 1).tolist()
        size = self._row_bytes
        with open(self.path, "rb", buffering=0) as fh:
            for a, b in zip([0, *cuts], [*cuts, flat.size]):
                want = (b - a) * size
                if want and os.preadv(fh.fileno(), [out[a:b].data.cast("B")], _HEADER + int(flat[a]) * size) != want:
                    raise OSError(f"{self.path}: short read at row {int(flat[a])}")
        return out.reshape(*rows.shape, width)

    def take(self, indices: Iterable[int]) -> list[np.ndarray]:
        """Copies of segments ``indices``, read from the file (not through the map)."""
        return [self.gather(np.arange(self.offsets[int(i)], self.offsets[int(i) + 1])) for i in indices]

    def release(self) -> None:
        """Drop the pages of the map that this process has read (a later read takes them from the page cache)."""
        self._read = 0
        release(self.data)


def release(view: np.ndarray) -> None:
    """Drop the pages of the map under ``view`` (any view of a store's ``data``) from this process's memory."""
    handle = getattr(view, "_mmap", None)
    if handle is not None and hasattr(handle, "madvise"):
        handle.madvise(mmap.MADV_DONTNEED)


def mean_std(arrays: Iterable[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Per-column mean and standard deviation of the arrays' rows, in the first array's dtype, equal bit for bit
    to ``x.mean(0), x.std(0)`` of ``x = np.concatenate(arrays)`` (arrays of one dtype), one array at a time:
    ``mean = (sum_t x_t) / N`` and ``std = sqrt((sum_t (x_t - mean)^2) / N)``, each sum in frame order."""
    items = arrays if isinstance(arrays, Sequence) else list(arrays)
    dtype = np.asarray(items[0]).dtype if len(items) else np.dtype(np.float32)
    if len(items) and np.asarray(items[0]).shape[1] == 1:  # one column: numpy sums it pairwise, not in order
        x = np.concatenate(list(items))
        return x.mean(0), x.std(0)
    total, n = None, 0
    for a in items:
        a = np.asarray(a, dtype)
        total = a.sum(0) if total is None else np.add.reduce(np.concatenate([total[None], a]), axis=0)
        n += len(a)
    if total is None or n == 0:
        raise ValueError("no frames to compute a mean from")
    mean = np.true_divide(total, n, dtype=dtype)
    sq = None
    for a in items:
        d = np.asarray(a, dtype) - mean
        d = np.multiply(d, d, out=d)
        sq = d.sum(0) if sq is None else np.add.reduce(np.concatenate([sq[None], d]), axis=0)
    assert sq is not None
    return mean, np.sqrt(np.true_divide(sq, n, dtype=dtype))


def max_abs_deviation(arrays: Iterable[np.ndarray], mean: np.ndarray) -> np.ndarray:
    """Per-column ``max_t |x_t - mean|`` over the rows of all arrays, one array at a time (exact: a maximum)."""
    out = None
    for a in arrays:
        if len(a):
            m = np.abs(a - mean).max(0)
            out = m if out is None else np.maximum(out, m)
    if out is None:
        raise ValueError("no frames to take a maximum over")
    return out


class Windows:
    """The ``(N, length, D)`` windows every ``stride`` frames of each segment of a store (padded segments), as
    ``np.stack`` of the slices would hold them, gathered on demand: ``windows[idx]`` is ``(len(idx), length, D)``."""

    def __init__(self, store: SegmentStore, length: int, stride: int):
        starts = []
        for i, n in enumerate(store.lengths.tolist()):
            first = int(store.offsets[i])
            starts += [first + s for s in range(0, max(n - length, 0) + 1, stride) if s + length <= n]
        self.store, self.length = store, length
        self.starts = np.asarray(starts, np.int64)

    def __len__(self) -> int:
        return len(self.starts)

    def __getitem__(self, idx: np.ndarray) -> np.ndarray:
        rows = self.starts[np.asarray(idx)][:, None] + np.arange(self.length)
        return self.store.gather(rows)


class Rows:
    """The ``(N, D)`` concatenation of a store's segments, gathered on demand: ``rows[idx]`` is ``(len(idx), D)``."""

    def __init__(self, store: SegmentStore):
        self.store = store

    def __len__(self) -> int:
        return int(self.store.data.shape[0])

    def __getitem__(self, idx: np.ndarray) -> np.ndarray:
        return self.store.gather(np.asarray(idx))


class Mapped(Sequence[np.ndarray]):
    """``func(items[i])`` computed when item ``i`` is read, so that a pass holds one result at a time."""

    def __init__(self, func: Callable[[np.ndarray], np.ndarray], items: Sequence[np.ndarray]):
        self.func, self.items = func, items

    def __len__(self) -> int:
        return len(self.items)

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        return self.func(self.items[i])

    def __iter__(self) -> Iterator[np.ndarray]:
        return (self.func(a) for a in self.items)


def stream_arrays(segments: Sequence[Segment], rep: PoseRepresentation, folder: pathlib.Path, *,
                  audio_recipe: str | None, words: str | None, timing: bool = True,
                  speech: Callable[[SegmentArrays, Segment], np.ndarray] | None = None,
                  ) -> tuple[SegmentStore, SegmentStore, SegmentArrays]:
    """:func:`~evalsuite.generators.reimpl.corpus_arrays` one segment at a time, written to ``folder``: the
    speech features ``(T, A + X)`` (or ``speech(arrays, segment)``) and poses ``(T, D)`` as two stores
    (``speech.npy``, ``poses.npy``), and the first segment's arrays (for the feature sizes)."""
    speech_store, poses = SegmentStore(folder / "speech.npy"), SegmentStore(folder / "poses.npy")
    first: SegmentArrays | None = None
    for seg in segments:
        arrays = corpus_arrays([seg], rep, audio_recipe=audio_recipe, words=words, timing=timing)[0]
        first = first or arrays
        speech_store.append(arrays.speech if speech is None else speech(arrays, seg))
        poses.append(arrays.poses)
    if first is None:
        raise ValueError("no segment to train on")
    return speech_store.finish(), poses.finish(), first


_FOLDER = re.compile(r"^(?P<system>.+)-data-(?P<pid>\d+)-[A-Za-z0-9_]+$")


def _training_root() -> pathlib.Path:
    """``<temp dir>/evalsuite-training-<uid>`` (mode 0700): one root per user, so that only the owner's
    trainings are looked at and removed."""
    uid = os.getuid() if hasattr(os, "getuid") else 0
    root = pathlib.Path(tempfile.gettempdir()) / f"evalsuite-training-{uid}"
    root.mkdir(mode=0o700, exist_ok=True)
    return root


def _running(pid: int) -> bool:
    """Whether process ``pid`` exists (``kill(pid, 0)``: no signal is sent; another user's process counts)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_folders(root: pathlib.Path | None = None) -> list[pathlib.Path]:
    """Remove the training folders ``<system>-data-<pid>-<random>`` in ``root`` (default: the training root) whose
    process ``pid`` no longer runs; returns them. (A pid reused by a new process keeps its folder until that
    process ends.) Not on Windows, where ``os.kill(pid, 0)`` would stop the process."""
    root = _training_root() if root is None else root
    removed: list[pathlib.Path] = []
    if os.name == "nt" or not root.is_dir():
        return removed
    for path in sorted(root.iterdir()):
        match = _FOLDER.match(path.name)
        if match and path.is_dir() and not _running(int(match["pid"])):
            shutil.rmtree(path, ignore_errors=True)
            removed.append(path)
    return removed


def training_folder(system: str) -> tempfile.TemporaryDirectory:
    """A new temporary folder for ``system``'s training maps: ``<temp dir>/evalsuite-training-<uid>/
    <system>-data-<pid>-<random>``, removed by its ``cleanup()`` (or when it is garbage collected). Stale folders
    of trainings whose process is gone are removed first (:func:`remove_stale_folders`)."""
    remove_stale_folders()
    return tempfile.TemporaryDirectory(prefix=f"{system}-data-{os.getpid()}-", dir=_training_root())
