"""What a metric family is, and the two contexts the scoring engine hands it.

A family (see :class:`MetricFamily`) declares its metrics (name, unit, better direction) and implements

* ``measure(ctx)``: per sequence file, in a worker; reads :class:`SequenceContext` (the file's positions,
  the natural positions of the same sequence, audio onsets, ...) and writes picklable summaries into
  ``ctx.record``, calling the public metric functions of :mod:`evalsuite.metrics`;
* ``fold(index, cond, record, natural_record, acc)`` (optional): in the parent, in task order, folds bulky
  summaries into running sums in ``acc`` (so memory does not grow with the number of files);
* ``reduce(ctx)``: in the parent, per condition; turns the records into summary, per-sequence and
  per-joint rows through :class:`ReduceContext` (which also does the bootstrap over sequences).
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, TypeVar, cast

import numpy as np

from evalsuite.metrics.conventions import Convention

__all__ = ["MetricInfo", "MetricFamily", "SequenceContext", "ReduceContext", "percentile_ci", "centred_ci",
           "bootstrap_bias", "weighted_mean_boot", "bootstrap_weights"]

NAN = float("nan")
T = TypeVar("T")
NAN_CI = (NAN, NAN)


@dataclass(frozen=True)
class MetricInfo:
    """A metric's name, unit and direction. ``unit_order`` (1, 2, 3) takes the unit from the convention
    (e.g. ``units/s^2``); otherwise ``unit`` is used as it is. ``samples``: how the metric uses several samples
    per sequence (:mod:`evalsuite.metrics.samples`): None follows the run's ``samples`` option (``first`` or
    ``each``); ``"all"`` for a metric that takes every sample at once (its family reads ``plan.samples``)."""

    name: str
    unit: str = ""
    better: str = "lower"            # "lower" | "higher" | "closer to natural"
    unit_order: int | None = None
    description: str = ""
    samples: str | None = None       # "all": takes every sample itself; None: as ``--samples`` (first | each)

    def unit_for(self, conv: Convention) -> str:
        return conv.unit(self.unit_order) if self.unit_order else self.unit


class MetricFamily:
    """Base class of a metric family; subclasses set ``name`` and ``metrics`` and override the hooks."""

    name: str = ""
    metrics: tuple[MetricInfo, ...] = ()
    default: bool = True            # part of the default metric set
    needs_audio: bool = False       # only with speech audio (``--audio``)
    needs_corpus: bool = False      # only with a corpus (``--corpus``): the segment's transcript and audio

    def measure(self, ctx: SequenceContext) -> None:
        """Write this family's per-sequence summaries into ``ctx.record``."""

    def fold(self, index: int, cond: str, record: dict[str, Any], natural: dict[str, Any], acc: dict[str, Any]) -> None:
        """Fold bulky parts of ``record`` into ``acc`` (in task order); default: nothing."""

    def drop(self, record: dict[str, Any]) -> None:
        """Remove what :meth:`fold` has used from ``record`` (not called when bootstrapping needs it)."""

    def reduce(self, ctx: ReduceContext) -> None:
        """Add this family's rows for one condition."""

    def bootstrap_work(self, setup: Any) -> int:
        """Costly resampled statistics per condition and resample (the bootstrap progress bar counts them;
        :meth:`reduce` reports them with :meth:`ReduceContext.advance`); default 0."""
        return 0


class SequenceContext:
    """One file of one sequence, as the families see it in a worker.

    ``pos``: the file's positions of the scored joints ``(T, J, 3)``, computed on first use (a family that reads
    only ``motion``, such as FGD on rotations, never needs them, so SMPL-X files score without a body model);
    ``natural_pos`` the natural file's
    (None while measuring the natural file itself is not the case: the natural file is measured first and
    sees itself); ``cache``: per-file values shared by families (e.g. derivative norms);
    ``natural_cache``: per-sequence values shared across the sequence's conditions; ``audio``: the
    sequence's speech ``(mono signal, sample rate)`` when read; ``segment``: its corpus segment
    (:class:`evalsuite.corpus.Segment`, with the transcript) when scoring with a corpus.
    """

    def __init__(self, motion: Any, pos: np.ndarray | Callable[[], np.ndarray], setup: Any, conv: Convention,
                 natural_pos: np.ndarray | Callable[[], np.ndarray] | None,
                 audio_onsets: np.ndarray | None, natural_cache: dict[Any, Any],
                 audio: tuple[np.ndarray, int] | None = None, segment: Any = None):
        self.motion = motion
        self._pos = pos
        self.fps = float(motion.fps)
        self.setup = setup
        self.conv = conv
        self._natural_pos = natural_pos
        self.audio_onsets = audio_onsets
        self.natural_cache = natural_cache
        self.audio = audio
        self.segment = segment
        self.cache: dict[str, Any] = {}
        self.record: dict[str, Any] = {"fps": self.fps, "n_frames": int(motion.n_frames)}

    @property
    def pos(self) -> np.ndarray:
        if callable(self._pos):
            self._pos = np.asarray(self._pos())
        return self._pos

    @property
    def natural_pos(self) -> np.ndarray | None:
        if callable(self._natural_pos):
            self._natural_pos = np.asarray(self._natural_pos())
        return self._natural_pos

    @property
    def families(self) -> set[str]:
        return set(self.setup.families)

    def memo(self, key: str, compute: Callable[[], T]) -> T:
        """``compute()``, computed once per file under ``key``."""
        if key not in self.cache:
            self.cache[key] = compute()
        return cast(T, self.cache[key])

    def norms(self, order: int) -> np.ndarray:
        """Per-step derivative norms ``(T - order, J)`` in the convention's unit (computed once per file)."""
        from evalsuite.metrics.kinematics import derivative_norms

        return self.memo(f"norms{order}", lambda: derivative_norms(self.pos, order, self.conv.rate(self.fps)))

    def aligned(self) -> tuple[np.ndarray, np.ndarray] | None:
        """This file and the natural one truncated to their common length (a warning is recorded once if
        they differ by more than the setup's tolerance); None without a natural file."""
        if self._natural_pos is None:
            return None

        def compute() -> tuple[np.ndarray, np.ndarray]:
            pos, nat = self.pos, self.natural_pos
            assert nat is not None
            n_common = min(len(pos), len(nat))
            diff_s = abs(len(pos) - len(nat)) / self.fps
            self.record["length_diff_s"] = diff_s
            if diff_s > self.setup.length_tolerance_s:
                self.record.setdefault("warnings", []).append(
                    f"{len(pos)} frames vs {len(nat)} natural ({diff_s:.2f} s apart, more than "
                    f"{self.setup.length_tolerance_s:g} s); truncated to {n_common} frames")
            return pos[:n_common], nat[:n_common]

        return self.memo("aligned", compute)


@dataclass
class ReduceContext:
    """One condition's records (``recs``, by sequence) with the natural ones (``ref``), in the parent.

    ``reference`` names the natural condition; ``names`` are the sequences scored in both, sorted;
    ``weights`` the bootstrap resampling weights over ``names`` (``(B, n)``) or None; ``seed`` the run's
    bootstrap seed; ``acc`` what the families folded for this condition; ``threads`` how many threads the
    bootstrap may use; ``progress`` counts resamples done (:meth:`advance`).
    """

    cond: str
    reference: str
    names: list[str]
    recs: dict[str, dict[str, Any]]
    ref: dict[str, dict[str, Any]]
    setup: Any
    conv: Convention
    weights: np.ndarray | None
    acc: dict[str, Any]
    summary: list[dict[str, Any]] = field(default_factory=list)
    per_sequence: list[dict[str, Any]] = field(default_factory=list)
    per_joint: list[dict[str, Any]] = field(default_factory=list)
    histograms: list[dict[str, Any]] = field(default_factory=list)
    issues: list[str] = field(default_factory=list)
    figure_data: dict[str, Any] = field(default_factory=dict)   # what a family's figure needs, by figure name
    info: dict[str, MetricInfo] = field(default_factory=dict)
    seed: int = 0
    threads: int = 1
    progress: Callable[[int], Any] | None = None

    def advance(self, n: int) -> None:
        """``n`` more resampled statistics are done (moves the bootstrap progress bar)."""
        if self.progress is not None:
            self.progress(n)

    @property
    def n_bootstrap(self) -> int:
        return 0 if self.weights is None else int(self.weights.shape[0])

    @property
    def n(self) -> int:
        return len(self.names)

    def wants(self, metric: str) -> bool:
        return metric in self.setup.metrics

    def unit(self, metric: str) -> str:
        base = metric.split("[")[0]
        return self.info[base].unit_for(self.conv) if base in self.info else ""

    def add(self, metric: str, value: float | np.floating | np.ndarray, std: float = NAN, n: int = 0,
            ci: tuple[float, float] = NAN_CI, unit: str | None = None, better: str | None = None) -> None:
        """One summary row (``metric`` may carry a group suffix, e.g. ``hellinger_speed[wrists]``)."""
        base = metric.split("[")[0]
        self.summary.append({
            "condition": self.cond, "metric": metric, "value": float(value),
            "unit": unit if unit is not None else self.unit(metric), "ci_low": ci[0], "ci_high": ci[1],
            "std": float(std), "n": int(n),
            "better": better or (self.info[base].better if base in self.info else ""),
            "convention": self.conv.name})

    def sequence_rows(self, metric: str, values: Sequence[float] | np.ndarray, unit: str | None = None) -> None:
        u = unit if unit is not None else self.unit(metric)
        for s, v in zip(self.names, values):
            self.per_sequence.append({"condition": self.cond, "sequence": s, "metric": metric,
                                      "value": float(v), "unit": u})

    def joint_rows(self, metric: str, values: Sequence[float] | np.ndarray, unit: str | None = None) -> None:
        u = unit if unit is not None else self.unit(metric)
        for j, v in zip(self.setup.joints, values):
            self.per_joint.append({"condition": self.cond, "joint": j, "metric": metric, "value": float(v),
                                   "unit": u})

    def mean_metric(self, metric: str, values: Sequence[float] | np.ndarray, unit: str | None = None) -> None:
        """Per-sequence rows and a summary row: mean (and std with the convention's ddof) across sequences,
        bootstrap CI of the mean when resampling."""
        v = np.asarray(values, dtype=np.float64)
        self.sequence_rows(metric, v, unit)
        finite = v[np.isfinite(v)]
        mean = float(finite.mean()) if finite.size else NAN
        ddof = self.conv.std_ddof
        std = float(np.std(finite, ddof=ddof)) if finite.size > ddof else NAN
        ci = percentile_ci(weighted_mean_boot(self.weights, v)) if self.weights is not None else NAN_CI
        self.add(metric, mean, std, finite.size, ci, unit)

    def boot(self, statistic: Callable[[np.ndarray], Any]) -> tuple[float, float]:
        """Percentile CI of ``statistic(weights)`` (one value per resample), or NaNs without a bootstrap."""
        return percentile_ci(statistic(self.weights)) if self.weights is not None else NAN_CI


def bootstrap_weights(n: int, n_boot: int, seed: int, cond_index: int) -> np.ndarray:
    """``(n_boot, n)`` multiplicities of a resample with replacement of ``n`` sequences, seeded per condition."""
    rng = np.random.default_rng([int(seed), int(cond_index)])
    idx = rng.integers(0, n, size=(n_boot, n))
    w = np.zeros((n_boot, n))
    np.add.at(w, (np.arange(n_boot)[:, None], idx), 1.0)
    return w


def percentile_ci(samples: Any) -> tuple[float, float]:
    """The 2.5th and 97.5th percentiles of the finite samples (NaNs if none)."""
    s = np.asarray(samples, dtype=np.float64)
    s = s[np.isfinite(s)]
    if s.size == 0:
        return NAN, NAN
    return float(np.percentile(s, 2.5)), float(np.percentile(s, 97.5))


def centred_ci(estimate: float, samples: Any, floor: float | None = 0.0, level: float = 0.95) -> tuple[float, float]:
    """The percentile interval (2.5-97.5 at ``level`` 0.95) moved so that the bootstrap median sits on
    ``estimate``:

        [estimate - (q50 - q2.5), estimate + (q97.5 - q50)]   (low end clipped at ``floor``)

    i.e. the percentile interval corrected for the bootstrap's median bias ``q50 - estimate``. It keeps the
    spread and skew of the resampled values and contains the estimate by construction, for statistics
    whose resamples are biased away from the estimate (Fréchet distances: a resample's duplicate
    sequences shrink its effective sample, and the distance's small-sample bias grows). NaNs if no
    finite sample.
    """
    s = np.asarray(samples, dtype=np.float64)
    s = s[np.isfinite(s)]
    if s.size == 0 or not np.isfinite(estimate):
        return NAN, NAN
    alpha = 100 * (1 - level) / 2
    lo, mid, hi = np.percentile(s, [alpha, 50.0, 100 - alpha])
    low = float(estimate - (mid - lo))
    return (low if floor is None else max(low, floor)), float(estimate + (hi - mid))


def bootstrap_bias(estimate: float, samples: Any) -> float:
    """Efron's bootstrap estimate of the bias: mean of the finite resampled values minus the estimate."""
    s = np.asarray(samples, dtype=np.float64)
    s = s[np.isfinite(s)]
    return float(s.mean() - estimate) if s.size else NAN


def weighted_mean_boot(w: np.ndarray | None, values: Any) -> np.ndarray:
    """Weighted means of ``values`` under each resample's weights, ignoring non-finite values."""
    assert w is not None
    v = np.asarray(values, dtype=np.float64)
    ok = np.isfinite(v)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray((w @ np.where(ok, v, 0.0)) / (w @ ok.astype(float)))
