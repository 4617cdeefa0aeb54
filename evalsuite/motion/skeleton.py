"""The skeleton of a motion: joint names, hierarchy, offsets, channels, End Sites."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")
KNOWN_CHANNELS = POSITION_CHANNELS + ROTATION_CHANNELS
_CANONICAL = {name.lower(): name for name in KNOWN_CHANNELS}


def canonical_channel(name: str) -> str | None:
    """``'xrotation'`` -> ``'Xrotation'``; ``None`` for names that are not BVH channels."""
    return _CANONICAL.get(name.lower())


@dataclass
class Skeleton:
    """Joint hierarchy in depth-first file order (every parent precedes its children).

    Attributes:
        names: joint names, unique.
        parents: parent index per joint, -1 for a root.
        offsets: ``(J, 3)`` OFFSET of each joint relative to its parent, in file units.
        channels: per joint, the tuple of its channel names in file order
            (canonical capitalisation, e.g. ``("Zrotation", "Xrotation", "Yrotation")``).
        end_site_parents: joint index each End Site hangs from.
        end_site_offsets: ``(E, 3)`` OFFSET of each End Site.
    """

    names: list[str]
    parents: np.ndarray
    offsets: np.ndarray
    channels: list[tuple[str, ...]]
    end_site_parents: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    end_site_offsets: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    def __post_init__(self) -> None:
        self.parents = np.asarray(self.parents, dtype=np.int64)
        self.offsets = np.asarray(self.offsets, dtype=np.float64).reshape(-1, 3)
        self.end_site_parents = np.asarray(self.end_site_parents, dtype=np.int64)
        self.end_site_offsets = np.asarray(self.end_site_offsets, dtype=np.float64).reshape(-1, 3)
        self.channels = [tuple(c) for c in self.channels]
        if not (len(self.names) == len(self.parents) == len(self.offsets) == len(self.channels)):
            raise ValueError("names, parents, offsets and channels must have one entry per joint")
        if len(set(self.names)) != len(self.names):
            raise ValueError("joint names must be unique")
        for j, p in enumerate(self.parents):
            if p >= j:
                raise ValueError("joints must be in an order where each parent precedes its children")

    # --- derived views -------------------------------------------------------------------
    @property
    def n_joints(self) -> int:
        return len(self.names)

    @property
    def n_channels(self) -> int:
        return sum(len(c) for c in self.channels)

    @property
    def channel_starts(self) -> np.ndarray:
        """Column of each joint's first channel in a frame vector."""
        counts = np.array([len(c) for c in self.channels], dtype=np.int64)
        return np.concatenate([[0], np.cumsum(counts)[:-1]]) if len(counts) else counts

    @property
    def end_site_names(self) -> list[str]:
        """End Sites are named ``<parent>_End`` (``_End2``, ... when a joint has several)."""
        names: list[str] = []
        seen: dict[int, int] = {}
        for p in self.end_site_parents:
            k = seen.get(int(p), 0) + 1
            seen[int(p)] = k
            names.append(f"{self.names[p]}_End" + ("" if k == 1 else str(k)))
        return names

    @property
    def roots(self) -> list[int]:
        return [j for j, p in enumerate(self.parents) if p < 0]

    def children(self, joint: int) -> list[int]:
        return [j for j, p in enumerate(self.parents) if p == joint]

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(name) from None

    def channel_names(self) -> list[str]:
        """``"<joint> <channel>"`` for every column of a frame vector."""
        return [f"{n} {c}" for n, chans in zip(self.names, self.channels) for c in chans]

    def depth(self) -> np.ndarray:
        d = np.zeros(self.n_joints, dtype=np.int64)
        for j, p in enumerate(self.parents):
            d[j] = 0 if p < 0 else d[p] + 1
        return d

    def copy(self) -> Skeleton:
        return Skeleton(list(self.names), self.parents.copy(), self.offsets.copy(), list(self.channels),
                        self.end_site_parents.copy(), self.end_site_offsets.copy())

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Skeleton):
            return NotImplemented
        return (self.names == other.names and np.array_equal(self.parents, other.parents)
                and self.channels == other.channels
                and np.allclose(self.offsets, other.offsets)
                and np.array_equal(self.end_site_parents, other.end_site_parents)
                and np.allclose(self.end_site_offsets, other.end_site_offsets))
