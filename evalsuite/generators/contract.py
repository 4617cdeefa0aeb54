"""The generator plug-in contract: what a generator declares, what it is asked, what it returns.

A plug-in is a subclass of :class:`Generator` with a class attribute ``spec`` (:class:`GeneratorSpec`) and
the methods ``load``, ``generate`` and ``close``; optionally ``generate_batch`` (a whole split at once, e.g.
operators that need every segment) and ``fit`` (training on a corpus, when ``spec.trainable``).

Its module must be cheap to import: torch and other heavy modules are imported inside ``load``/``fit``,
so that ``evalsuite generators list|info`` never imports them. The runner
(:mod:`evalsuite.generators.runner`) enforces the rules of ``docs/generators.md`` on every output: length,
frame rate, finite values, joint names, units, determinism.
"""
from __future__ import annotations

import abc
import dataclasses
import math
import pathlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

from evalsuite.corpus.types import Corpus, Segment, Stream, Transcript
from evalsuite.errors import InputError

__all__ = ["GeneratorSpec", "GenerationRequest", "GenerationResult", "Generator", "TrainingResult",
           "GeneratorError", "INPUT_NEEDS", "OUTPUT_KINDS", "UNITS"]

INPUT_NEEDS = ("required", "optional", "none")
OUTPUT_KINDS = ("bvh", "positions", "any")
UNITS = ("cm", "m", "mm", "in", "dm")


def _finite_number(value: Any) -> float | None:
    """``value`` as a finite float (numbers and numeric strings, as ``--set`` and config files give them), else
    None; a bool is not a number here."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        return None
    try:
        number = float(value)
    except ValueError:
        return None
    return number if math.isfinite(number) else None


class GeneratorError(InputError):
    """A plug-in broke a rule of the contract (the message names the plug-in and the segment)."""


@dataclass(frozen=True)
class GeneratorSpec:
    """What a generator is and needs. Shown by ``evalsuite generators info`` without importing torch.

    ``audio``/``transcript``: ``"required" | "optional" | "none"``; ``word_timings``: ``"required"``,
    ``"estimated"`` (plain text is enough: timings are estimated) or ``"none"``. ``native_fps``: the rate
    the generator produces (``None``: whatever the request asks). ``output``: ``"bvh"`` (joint rotations on
    a skeleton), ``"positions"`` (joint positions) or ``"any"`` (operators: whatever their source is).
    ``joints``: the joint names it outputs (empty: not declared; the runner then only checks that names are
    unique and non-empty). ``units``: the units of
    positions and offsets. ``deviations``: how a re-implementation departs from its paper.
    """

    name: str
    version: str
    summary: str
    citation: str = ""
    license: str = "MIT"
    kind: str = "condition"          # "re-implementation" | "published model" | "adapter" | "condition" | "plug-in"
    audio: str = "none"
    transcript: str = "none"
    word_timings: str = "none"
    speaker: bool = False
    interlocutor: bool = False
    native_fps: float | None = None
    output: str = "bvh"
    joints: tuple[str, ...] = ()
    skeleton: str = ""
    units: str = "cm"
    stochastic: bool = False
    device: str = "cpu"              # "cpu" | "any" (uses a GPU when torch sees one)
    trainable: bool = False
    needs_model: bool = False        # generate needs --model (trained or published files)
    extra: str | None = None         # the optional extra it needs, e.g. "learned"
    config: Mapping[str, str] = field(default_factory=dict)   # option -> description (with default)
    deviations: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for name, value, allowed in (("audio", self.audio, INPUT_NEEDS), ("transcript", self.transcript, INPUT_NEEDS),
                                     ("word_timings", self.word_timings, ("required", "estimated", "none")),
                                     ("output", self.output, OUTPUT_KINDS), ("units", self.units, UNITS),
                                     ("device", self.device, ("cpu", "any"))):
            if value not in allowed:
                raise GeneratorError(f"spec of {self.name!r}: {name} must be one of {', '.join(allowed)}, "
                                     f"got {value!r}")
        if self.native_fps is not None and not self.native_fps > 0:
            raise GeneratorError(f"spec of {self.name!r}: native_fps must be positive, got {self.native_fps!r}")

    def as_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["joints"] = list(self.joints)
        d["deviations"] = list(self.deviations)
        d["config"] = dict(self.config)
        return d


@dataclass(frozen=True)
class GenerationRequest:
    """One segment to generate. ``duration`` (seconds) is authoritative: the output must cover it at ``fps``.

    ``seed`` is already specific to this segment and sample (the runner derives it from the run's seed), so
    a stochastic plug-in seeds its generator with it and nothing else. ``segment`` is the corpus segment when
    there is one (operators such as ``natural`` read its motion; learned generators must not).
    """

    segment_id: str
    duration: float
    fps: float
    seed: int
    audio: pathlib.Path | None = None
    transcript: Transcript | None = None
    speaker: str | None = None
    interlocutor: Stream | None = None
    sample: int = 0
    work_dir: pathlib.Path | None = None
    segment: Segment | None = field(default=None, compare=False)

    @property
    def n_frames(self) -> int:
        """Frames the output must have at ``fps``: ``round(duration * fps)``."""
        return int(round(self.duration * self.fps))

    @property
    def output_stem(self) -> str:
        return self.segment_id


@dataclass
class GenerationResult:
    """A generated motion (an :class:`evalsuite.motion.Motion`, hierarchical or positional) and notes; or, for
    an SMPL-X source, ``smplx`` (an :class:`evalsuite.motion.smplx.SmplxData` of exactly the requested frames and
    rate, written as SMPL-X ``.npz``) with ``motion`` None."""

    motion: Any
    meta: dict[str, Any] = field(default_factory=dict)
    smplx: Any = None


@dataclass
class TrainingResult:
    """What ``fit`` reports: the model folder it wrote and per-epoch history (``{"epoch", "train_loss",
    "val_loss", "seconds"}`` rows), plus anything else worth keeping in ``model.json``."""

    model_dir: pathlib.Path
    history: list[dict[str, Any]] = field(default_factory=list)
    meta: dict[str, Any] = field(default_factory=dict)


class Generator(abc.ABC):
    """Base class of a generator plug-in. Subclasses set ``spec`` and override the hooks.

    Lifecycle: ``load(config, model_dir)`` once (validates options and paths, loads weights), then
    ``generate(request)`` per segment (or ``generate_batch``), then ``close()``. ``fit(corpus, out_dir, seed,
    budget_minutes, progress)`` trains and writes a model folder that ``load`` can read.
    """

    spec: ClassVar[GeneratorSpec]

    def __init__(self) -> None:
        self.config: dict[str, Any] = {}
        self.model_dir: pathlib.Path | None = None

    # -- hooks ---------------------------------------------------------------------------------------
    def configure(self, config: Mapping[str, Any]) -> None:
        """Validate ``config`` against ``spec.config`` and keep it (before ``fit`` or as part of ``load``)."""
        unknown = sorted(set(config) - set(self.spec.config))
        if unknown:
            known = ", ".join(sorted(self.spec.config)) or "none"
            raise GeneratorError(f"{self.spec.name}: unknown option(s) {', '.join(unknown)} (options: {known})",
                                 field="config")
        self.config = dict(config)

    def load(self, config: Mapping[str, Any], model_dir: pathlib.Path | None = None) -> None:
        """Configure, and check that a model folder is given when the spec needs one; subclasses load weights
        here (after calling this)."""
        self.configure(config)
        if self.spec.needs_model and model_dir is None:
            raise GeneratorError(f"{self.spec.name} needs a model folder (--model): train one with "
                                 f"`evalsuite train -g {self.spec.name}` or name a published model's files")
        self.model_dir = model_dir

    @abc.abstractmethod
    def generate(self, request: GenerationRequest) -> GenerationResult:
        """One segment's motion at ``request.fps`` (or the spec's native rate), ``request.n_frames`` long."""

    def generate_batch(self, requests: Sequence[GenerationRequest]) -> list[GenerationResult]:
        """All requests of a run at once; the default calls :meth:`generate` for each."""
        return [self.generate(r) for r in requests]

    batch_only: ClassVar[bool] = False  # True: needs every request together (generate_batch), never split up

    def fit(self, corpus: Corpus, out_dir: pathlib.Path, *, seed: int, budget_minutes: float | None = None,
            progress: Callable[[dict[str, Any]], None] | None = None) -> TrainingResult:
        raise GeneratorError(f"{self.spec.name} is not trainable")

    def close(self) -> None:  # noqa: B027 - optional hook, empty by default
        """Release resources (subprocesses, files)."""

    @property
    def stochastic(self) -> bool:
        """Whether samples differ with the seed, as configured (the spec's value unless an option changes it,
        e.g. dropout left on at inference)."""
        return self.spec.stochastic

    # -- helpers for subclasses ----------------------------------------------------------------------
    def option(self, name: str, default: Any = None) -> Any:
        return self.config.get(name, default)

    def int_option(self, name: str, default: int | None = None) -> int:
        """An integer option; anything else (``--set epochs=ten``, 2.5) is a GeneratorError naming the field."""
        value = self.option(name, default)
        number = _finite_number(value)
        if number is None or not number.is_integer():
            raise GeneratorError(f"{self.spec.name}: option {name} must be an integer, got {value!r}", field=name)
        return int(number)

    def float_option(self, name: str, default: float | None = None) -> float:
        """A finite number option; anything else is a GeneratorError naming the field."""
        value = self.option(name, default)
        number = _finite_number(value)
        if number is None:
            raise GeneratorError(f"{self.spec.name}: option {name} must be a finite number, got {value!r}",
                                 field=name)
        return number

    def fraction_option(self, name: str, default: float | None = None) -> float:
        """A number in [0, 1) (a floor, a decay); anything else is a GeneratorError naming the field."""
        value = self.option(name, default)
        number = _finite_number(value)
        if number is None:
            raise GeneratorError(f"{self.spec.name}: option {name} must be a number in [0, 1), got {value!r}",
                                 field=name)
        if not 0.0 <= number < 1.0:
            raise GeneratorError(f"{self.spec.name}: option {name} must be in [0, 1), got {number:g}", field=name)
        return number

    def choice_option(self, name: str, default: str, choices: Sequence[str]) -> str:
        """One of ``choices`` (a plug-in's named variants: sizes, ablations, schedules); anything else is a
        GeneratorError naming the field and the choices."""
        value = str(self.option(name, default))
        if value not in choices:
            raise GeneratorError(f"{name} must be one of {', '.join(choices)}, got {value!r}", field=name)
        return value

    def bool_option(self, name: str, default: bool = False) -> bool:
        """true/false (also 1/0, yes/no, as --set gives them); anything else is a GeneratorError naming the field."""
        value = self.option(name, default)
        if isinstance(value, bool):
            return value
        text = str(value).strip().lower()
        if text in ("true", "1", "yes"):
            return True
        if text in ("false", "0", "no"):
            return False
        raise GeneratorError(f"{self.spec.name}: option {name} must be true or false, got {value!r}", field=name)
