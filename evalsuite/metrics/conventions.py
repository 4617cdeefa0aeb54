"""Named scoring conventions: how kinematics are scaled, how histograms are binned.

Reference scripts hard-code frame rates and bin ranges that changed between versions. A
:class:`Convention` bundles those choices so a run can reproduce a reference exactly
(``genea2020``, ``genea2022``, ``aud2repr2pose``) or use the corrected default:

========================  ==================  ===================  ==========  ========  ===========
convention                time scale          histogram bins       overflow    std ddof  CCA
========================  ==================  ===================  ==========  ========  ===========
``default``               fps of the data     auto from natural    extra bin   1         cross-fitted
``genea2020``             x 20^n              0..59, width 0.05    dropped     0         in-sample
``genea2022``             x 30^n              0..49, width 0.05    dropped     0         in-sample
``aud2repr2pose``         none (per frame)    0..1, width 0.05     dropped     0         in-sample
========================  ==================  ===================  ==========  ========  ===========

"dropped" means what the reference does (``np.histogram`` ignores values above the last edge);
evalsuite still reports the clipped fraction for those conventions.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from evalsuite.errors import InputError

__all__ = ["Convention", "CONVENTIONS", "get_convention", "reference_edges", "nice_ceil"]


@dataclass(frozen=True)
class Convention:
    """Choices that change metric values; see the module table.

    Attributes:
        name: the name used on the command line.
        time_scale: ``"data"`` (multiply the n-th difference by ``fps**n`` of the motion),
            a number (a fixed frame rate, as the reference scripts hard-code), or ``"frame"``
            (no scaling: units per frame^n).
        speed_bins, acceleration_bins: ``(max, width)`` giving edges
            ``np.arange(0, max + width, width)`` as the reference scripts build them, or
            ``None`` for automatic edges (100 bins up to a rounded 99.5th percentile of the
            natural motion).
        overflow: count values above the last edge in an extra bin that takes part in the
            normalisation (``True``), or drop them like ``np.histogram`` (``False``).
        std_ddof: delta degrees of freedom of the std across sequences (GENEA: ``np.std``, 0).
        cca_in_sample: fit and score CCA on the same frames (the references) instead of
            cross-fitting.
    """

    name: str
    description: str
    time_scale: str | float = "data"
    speed_bins: tuple[float, float] | None = None
    acceleration_bins: tuple[float, float] | None = None
    overflow: bool = True
    std_ddof: int = 1
    cca_in_sample: bool = False

    def rate(self, fps: float) -> float | None:
        """The rate that scales frame differences (``fps ** order``), or None for per-frame units."""
        if self.time_scale == "frame":
            return None
        return float(fps) if self.time_scale == "data" else float(self.time_scale)

    def scale(self, fps: float, order: int) -> float:
        """Factor turning an ``order``-th frame difference into the convention's unit."""
        if self.time_scale == "frame":
            return 1.0
        rate = float(fps) if self.time_scale == "data" else float(self.time_scale)
        return rate ** order

    def unit(self, order: int, length_unit: str = "units") -> str:
        """Unit of an ``order``-th derivative norm, e.g. ``units/s^2``."""
        per = "frame" if self.time_scale == "frame" else "s"
        return f"{length_unit}/{per}" + (f"^{order}" if order > 1 else "")

    def bins(self, quantity: str) -> tuple[float, float] | None:
        if quantity == "speed":
            return self.speed_bins
        if quantity == "acceleration":
            return self.acceleration_bins
        raise ValueError(f"no histogram bins for {quantity!r}")


CONVENTIONS: dict[str, Convention] = {
    "default": Convention(
        "default", "fps from the data, automatic bins with an overflow bin, joints by name, "
        "sample std across sequences, cross-fitted CCA"),
    "genea2020": Convention(
        "genea2020", "GENEA 2020 / Gesticulator scripts: x20^n, bins 0..59 width 0.05, values above "
        "the last edge dropped, np.std across sequences, in-sample CCA",
        time_scale=20.0, speed_bins=(59.0, 0.05), acceleration_bins=(59.0, 0.05), overflow=False,
        std_ddof=0, cca_in_sample=True),
    "genea2022": Convention(
        "genea2022", "GENEA 2022 scripts: x30^n, bins 0..49 width 0.05, values above the last edge "
        "dropped, np.std across sequences, in-sample CCA",
        time_scale=30.0, speed_bins=(49.0, 0.05), acceleration_bins=(49.0, 0.05), overflow=False,
        std_ddof=0, cca_in_sample=True),
    "aud2repr2pose": Convention(
        "aud2repr2pose", "Aud2Repr2Pose evaluation scripts: no fps scaling (per frame), bins 0..1 "
        "width 0.05 on per-frame displacement, values above the last edge dropped",
        time_scale="frame", speed_bins=(1.0, 0.05), acceleration_bins=(1.0, 0.05), overflow=False,
        std_ddof=0, cca_in_sample=True),
}


def get_convention(name: str | Convention) -> Convention:
    """A convention by name (or the Convention itself)."""
    if isinstance(name, Convention):
        return name
    if name not in CONVENTIONS:
        raise InputError(f"unknown convention {name!r}; expected one of {', '.join(CONVENTIONS)}",
                         field="convention")
    return CONVENTIONS[name]


def reference_edges(max_value: float, width: float) -> np.ndarray:
    """Bin edges built as the reference scripts do: ``np.arange(0, max + width, width)``."""
    if not (width > 0 and max_value > 0 and math.isfinite(width) and math.isfinite(max_value)):
        raise InputError(f"histogram range needs max > 0 and width > 0, got max={max_value}, width={width}",
                         field="bins")
    return np.arange(0, max_value + width, width)


def nice_ceil(value: float) -> float:
    """Smallest of 1, 2, 2.5, 5 x 10^k that is >= ``value`` (for readable automatic ranges)."""
    if not (value > 0 and math.isfinite(value)):
        return 1.0
    exp = math.floor(math.log10(value))
    for m in (1.0, 2.0, 2.5, 5.0, 10.0):
        candidate = m * 10.0 ** exp
        if candidate >= value * (1 - 1e-12):
            return candidate
    return 10.0 ** (exp + 1)
