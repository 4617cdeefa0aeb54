"""Options of the re-implementations, each declared once: its type, default, help, range and the paper's value.

A system lists its options as one :class:`Options` (in ``evalsuite/generators/<system>/options.py``, without
torch); everything else derives from it:

- :meth:`Options.parse` gives what the plug-in's ``_settings()`` returns: every option's value from the user's
  options or its default, parsed and checked by the plug-in contract's accessors (``int_option``,
  ``float_option``, ...), so a bad ``--set`` value is the same one-line error naming the field;
- :meth:`Options.config_help` is the plug-in's ``spec.config`` (``evalsuite generators show NAME``);
- :meth:`Options.preset_rows` are the system's rows of the presets table (:mod:`evalsuite.generators.presets`):
  one per option that gives the paper's value (``source`` set).

An option's ``default`` is evalsuite's ``cpu-small`` value; ``paper`` the ``paper`` preset's value (the same as
``default`` unless given), ``source`` where the paper (or the original code) gives it, ``code`` the original
code's value where it differs from the paper's, ``allowed`` the range or the choices as the table states them.
"""
from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from evalsuite.generators.contract import GeneratorError

if TYPE_CHECKING:
    from evalsuite.generators.contract import Generator

__all__ = ["Option", "Options", "PresetOption", "KINDS", "UNSET"]

# int, float, fraction ([0, 1)), bool, choice (one of ``choices``), int_choice (one of ``choices``, as an int),
# optional_int (None when not set), str (free text; with ``choices``: one of them)
KINDS = ("int", "float", "fraction", "bool", "choice", "int_choice", "optional_int", "str")


class _Unset:
    def __repr__(self) -> str:
        return "UNSET"


UNSET: Any = _Unset()  # ``paper`` not given: the paper's value is the default


@dataclass(frozen=True)
class PresetOption:
    """One option of one system under both presets (a row of the presets table)."""

    name: str
    cpu_small: Any       # evalsuite's variant: the plug-in's default
    paper: Any           # the paper's value (or the original code's where the paper gives none; see ``source``)
    source: str          # where the paper (or code) gives it
    allowed: str = ""    # the range or the choices
    code: str = ""       # the original code's value, where it differs from the paper's

    def value(self, preset: str) -> Any:
        return self.cpu_small if preset == "cpu-small" else self.paper


@dataclass(frozen=True)
class Option:
    """One option of a re-implementation.

    ``minimum``: the smallest value accepted beyond the type's own check (an int: "must be a positive integer"
    when 1; a float: "must be >= minimum"). ``settings``: whether :meth:`Options.parse` returns it (False: read
    at generation only, e.g. Gesticulator's ``zero_audio``)."""

    name: str
    kind: str
    default: Any
    help: str
    choices: tuple[str, ...] = ()
    minimum: float | None = None
    allowed: str = ""
    paper: Any = UNSET
    source: str = ""
    code: str = ""
    settings: bool = True

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"option {self.name}: kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        if self.kind in ("choice", "int_choice") and not self.choices:
            raise ValueError(f"option {self.name}: a {self.kind} option needs its choices")

    @property
    def paper_value(self) -> Any:
        return self.default if self.paper is UNSET else self.paper

    def parse(self, gen: Generator, default: Any = UNSET) -> Any:
        """This option's value in ``gen``'s configuration (``default``: the declared one unless given)."""
        d = self.default if default is UNSET else default
        name, kind = self.name, self.kind
        if kind == "int":
            value: Any = gen.int_option(name, d)
        elif kind == "float":
            value = gen.float_option(name, d)
        elif kind == "fraction":
            value = gen.fraction_option(name, d)
        elif kind == "bool":
            value = gen.bool_option(name, d)
        elif kind == "choice":
            value = gen.choice_option(name, d, self.choices)
        elif kind == "int_choice":
            value = int(gen.choice_option(name, str(d), self.choices))
        elif kind == "optional_int":
            value = None if gen.option(name, d) is None else gen.int_option(name, d)
        else:
            value = str(gen.option(name, d))
            if self.choices and value not in self.choices:
                raise GeneratorError(f"{name} must be {' or '.join(self.choices)}, got {value!r}", field=name)
        if self.minimum is not None and value is not None and value < self.minimum:
            if kind == "int" and self.minimum == 1:
                raise GeneratorError(f"{name} must be a positive integer, got {value}", field=name)
            raise GeneratorError(f"{name} must be >= {self.minimum:g}, got {value}", field=name)
        return value

    def preset_row(self) -> PresetOption:
        allowed = self.allowed or ", ".join(self.choices)
        return PresetOption(self.name, self.default, self.paper_value, self.source, allowed, self.code)


@dataclass(frozen=True)
class Options:
    """A system's options, in the order ``evalsuite generators show`` and the presets table list them."""

    system: str
    options: tuple[Option, ...]
    _index: dict[str, Option] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        index = {o.name: o for o in self.options}
        if len(index) != len(self.options):
            raise ValueError(f"{self.system}: an option is declared twice")
        object.__setattr__(self, "_index", index)

    def __iter__(self) -> Iterator[Option]:
        return iter(self.options)

    def __getitem__(self, name: str) -> Option:
        return self._index[name]

    def __contains__(self, name: object) -> bool:
        return name in self._index

    def names(self) -> tuple[str, ...]:
        return tuple(self._index)

    def parse(self, gen: Generator, defaults: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """Every option that the settings hold (``settings=True``), in declaration order, parsed from ``gen``'s
        configuration; ``defaults`` replaces some declared defaults (one that depends on another option)."""
        defaults = defaults or {}
        return {o.name: o.parse(gen, defaults.get(o.name, UNSET)) for o in self.options if o.settings}

    def value(self, gen: Generator, name: str) -> Any:
        """One option's value (e.g. a generation-time option)."""
        return self[name].parse(gen)

    def defaults(self) -> dict[str, Any]:
        """The declared defaults: the ``cpu-small`` preset."""
        return {o.name: o.default for o in self.options}

    def config_help(self) -> dict[str, str]:
        """``spec.config``: option name -> help text."""
        return {o.name: o.help for o in self.options}

    def preset_rows(self) -> tuple[PresetOption, ...]:
        """The presets table's rows: the options whose paper value is given (``source`` set), in order."""
        return tuple(o.preset_row() for o in self.options if o.source)

    def paper_values(self) -> dict[str, Any]:
        """What the ``paper`` preset sets: each row's paper value."""
        return {o.name: o.paper_value for o in self.options if o.source}

    def revised(self, system: str, changes: Mapping[str, Mapping[str, Any]],
                drop: Sequence[str] = ()) -> Options:
        """A variant for a sibling system: ``changes`` maps an option's name to the fields it replaces
        (``{"width": {"paper": 256, "source": "..."}}``); ``drop``: options the sibling does not have."""
        unknown = sorted((set(changes) | set(drop)) - set(self._index))
        if unknown:
            raise ValueError(f"{system}: no option(s) {', '.join(unknown)} to revise")
        return Options(system, tuple(replace(o, **changes.get(o.name, {})) for o in self.options
                                     if o.name not in drop))
