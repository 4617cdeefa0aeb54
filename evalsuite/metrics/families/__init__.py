"""The registry of metric families that ``evalsuite score`` runs.

A family is a :class:`~evalsuite.metrics.families.base.MetricFamily`; :func:`register_family` adds one
(the built-in families register themselves when this package is imported). Adding a metric to
evalsuite is one family module that calls :func:`register_family` — see ``docs/architecture.md``.
"""
from __future__ import annotations

from evalsuite.errors import InputError
from evalsuite.metrics.families.base import (
    MetricFamily,
    MetricInfo,
    ReduceContext,
    SequenceContext,
    bootstrap_weights,
    percentile_ci,
    weighted_mean_boot,
)

__all__ = ["MetricFamily", "MetricInfo", "SequenceContext", "ReduceContext", "register_family",
           "unregister_family", "get_family", "registered_families", "metric_index", "bootstrap_weights",
           "percentile_ci", "weighted_mean_boot"]

_REGISTRY: dict[str, MetricFamily] = {}


def register_family(family: MetricFamily, *, replace: bool = False) -> MetricFamily:
    """Add ``family`` (an instance) to the registry; its metric names must be new."""
    if not family.name:
        raise ValueError("a metric family needs a name")
    if family.name in _REGISTRY and not replace:
        raise ValueError(f"a metric family named {family.name!r} is registered already")
    taken = {m: f for f, fam in _REGISTRY.items() if f != family.name for m in (i.name for i in fam.metrics)}
    clash = [m.name for m in family.metrics if m.name in taken]
    if clash or family.name in taken:
        raise ValueError(f"metric names of family {family.name!r} are taken: {', '.join(clash or [family.name])}")
    _REGISTRY[family.name] = family
    return family


def unregister_family(name: str) -> None:
    _REGISTRY.pop(name, None)


def registered_families() -> dict[str, MetricFamily]:
    """Name -> family, in registration order (the order of the summary rows)."""
    return dict(_REGISTRY)


def get_family(name: str) -> MetricFamily:
    try:
        return _REGISTRY[name]
    except KeyError:
        raise InputError(f"unknown metric family {name!r}; registered: {', '.join(_REGISTRY)}",
                         field="metrics") from None


def metric_index(families: dict[str, MetricFamily] | None = None) -> dict[str, tuple[str, MetricInfo]]:
    """Metric name -> (family name, info)."""
    fams = _REGISTRY if families is None else families
    return {m.name: (f, m) for f, fam in fams.items() for m in fam.metrics}


def _register_builtins() -> None:
    from evalsuite.metrics.families import beats, cca, coupling, distribution, errors, histograms, kinematics

    for module in (kinematics, histograms, errors, distribution, cca, beats, coupling):
        register_family(module.FAMILY, replace=True)


_register_builtins()
