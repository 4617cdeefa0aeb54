"""What a scoring run is told, and what the engine hands its workers.

* :class:`ScoreOptions`: every choice of a run (the options of ``evalsuite score``), one frozen dataclass,
  each option declared once with its default;
* :class:`ScoreSetup`: what the engine resolves from the options and the plan (joints, metrics, groups,
  histogram bins) for the per-file work;
* :class:`ScoreTask`: the per-file work of one sequence name (its file in every condition), picklable for
  the process pool and for dask.
"""
from __future__ import annotations

import dataclasses
import pathlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from evalsuite.errors import InputError, did_you_mean
from evalsuite.metrics.families import MetricFamily
from evalsuite.metrics.planning import DEFAULT_GROUPS

__all__ = ["ScoreOptions", "ScoreSetup", "ScoreTask", "parse_bins"]


@dataclass(frozen=True)
class ScoreOptions:
    """The choices of one scoring run; ``ScoreOptions()`` is ``evalsuite score`` without options.

    Sequences given as lists are kept as tuples, and a ``MAX:WIDTH`` bins string as ``(max, width)``, so two
    runs with the same choices have equal options. :meth:`replace` names the closest option of a misspelt one.
    """

    joints: str | Sequence[str] | None = None
    """Joint preset (e.g. ``genea2020_upper``) or joint names; None: every joint of the natural motion."""
    metrics: str | Sequence[str] | None = None
    """Metric families or metric names; None: the default set (beats with audio, coupling with a corpus)."""
    convention: str = "default"
    """Scaling and binning conventions (``default``, ``genea2020``, ``genea2022``, ``aud2repr2pose``)."""
    audio_dir: str | pathlib.Path | None = None
    """Folder of ``<sequence>.wav`` speech audio for beat alignment."""
    corpus: str | pathlib.Path | None = None
    """Corpus whose segments the files are (stem = segment id): its speech and transcripts."""
    fps: float | None = None
    """Frame rate of files that store none (.npy, .csv)."""
    resample: float | None = None
    """Resample every file to this frame rate first."""
    speed_bins: str | tuple[float, float] | None = None
    """Speed histogram range and bin width, ``(max, width)`` or ``"MAX:WIDTH"``; None: the convention's."""
    acceleration_bins: str | tuple[float, float] | None = None
    """Acceleration histogram range and bin width, as ``speed_bins``."""
    groups: Sequence[str] = DEFAULT_GROUPS
    """Joint groups for the histograms (presets or ``NAME:J1,J2``); all joints pooled is always included."""
    sigma: float = 0.1
    """Beat alignment sigma in seconds."""
    bootstrap: int = 0
    """Bootstrap resamples over sequences for 95% confidence intervals (0: none)."""
    seed: int = 0
    """Seed of the bootstrap."""
    jobs: int = 1
    """Local worker processes for the per-file work (and threads for the bootstrap)."""
    dask_address: str | None = None
    """Run the per-file work on this dask.distributed scheduler instead."""
    strict: bool = False
    """Fail on any unreadable file or missing pair instead of reporting it and scoring the rest."""
    progress: bool = True
    """Show progress bars."""
    figures: bool = True
    """Keep what the figures need (wrist tracks)."""
    extra_families: Sequence[MetricFamily] = ()
    """Metric families for this run only (e.g. FGD with a trained model), added to the registered ones."""
    samples: str = "first"
    """Several samples per sequence (``<name>_<k>`` files): score the ``first`` of each, or ``each`` sample index and
    report the mean over them (evalsuite.metrics.samples); metrics that take all samples at once say ``all``."""

    def __post_init__(self) -> None:
        for name in ("joints", "metrics", "groups", "extra_families"):
            value = getattr(self, name)
            if value is not None and not isinstance(value, str):
                object.__setattr__(self, name, tuple(value))
        for name in ("speed_bins", "acceleration_bins"):
            object.__setattr__(self, name, parse_bins(getattr(self, name)))
        if self.samples not in ("first", "each"):
            raise InputError(f"samples must be 'first' or 'each', got {self.samples!r}", field="samples")

    def replace(self, **changes: Any) -> ScoreOptions:
        """A copy with ``changes``; a name that is no option is a ``TypeError`` naming the closest ones."""
        known = [f.name for f in dataclasses.fields(self)]
        for name in changes:
            if name not in known:
                raise TypeError(f"unknown scoring option {name!r} (the options are the fields of "
                                f"evalsuite.metrics.options.ScoreOptions){did_you_mean(name, known)}")
        return dataclasses.replace(self, **changes) if changes else self

    def bins(self, quantity: str) -> tuple[float, float] | None:
        """The ``(max, width)`` histogram bins given for ``quantity`` (``speed`` or ``acceleration``)."""
        return parse_bins(self.speed_bins if quantity == "speed" else self.acceleration_bins)


def parse_bins(spec: str | tuple[float, float] | None) -> tuple[float, float] | None:
    """``"MAX:WIDTH"`` (e.g. ``"250:2.5"``) -> ``(250.0, 2.5)``; a tuple or None is returned as it is."""
    if spec is None or isinstance(spec, tuple):
        return spec
    try:
        top, width = (float(v) for v in str(spec).split(":"))
    except ValueError:
        raise InputError(f"expected bins as MAX:WIDTH (e.g. 250:2.5), got {spec!r}", field="bins") from None
    return top, width


@dataclass
class ScoreSetup:
    """Everything a worker needs besides the file paths (picklable, sent with every task)."""

    joints: list[str]
    metrics: list[str]
    family_objects: tuple[MetricFamily, ...] = ()
    convention: str = "default"
    fps: float | None = None          # for positions files without a frame rate
    resample: float | None = None     # resample every file to this rate first
    edges: dict[str, np.ndarray] = field(default_factory=dict)   # quantity -> bin edges
    groups: dict[str, list[str]] = field(default_factory=dict)   # group name -> joint names
    sigma: float = 0.1
    length_tolerance_s: float = 1.0
    figures: bool = True

    @property
    def families(self) -> list[str]:
        """Names of the families that have a metric in ``metrics``, in registration order."""
        wanted = set(self.metrics)
        return [f.name for f in self.family_objects if any(m.name in wanted for m in f.metrics)]

    def active(self) -> list[MetricFamily]:
        names = set(self.families)
        return [f for f in self.family_objects if f.name in names]


@dataclass(frozen=True)
class ScoreTask:
    """One sequence name in every condition: ``entries`` are ``(condition, path)``, the natural file first;
    ``audio`` its speech (or None) and ``segment`` its corpus segment (with a corpus)."""

    name: str
    entries: tuple[tuple[str, pathlib.Path], ...]
    audio: pathlib.Path | None
    setup: ScoreSetup
    segment: Any = None

    def describe(self) -> str:
        """How error messages name this task."""
        return f"sequence {self.name!r}"
