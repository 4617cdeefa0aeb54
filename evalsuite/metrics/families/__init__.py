"""The registry of metric families that ``evalsuite score`` runs.

A family is a :class:`~evalsuite.metrics.families.base.MetricFamily`; :func:`register_family` adds one
(the built-in families register themselves when this package is imported); an installed package adds one
with an entry point in the group ``evalsuite.metric_families``. :data:`FAMILIES` is the
:class:`~evalsuite.registry.Registry`. Adding a metric to evalsuite is one family module — see
``docs/architecture.md``.
"""
from __future__ import annotations

from evalsuite.metrics.families.base import (
    MetricFamily,
    MetricInfo,
    ReduceContext,
    SequenceContext,
    bootstrap_weights,
    percentile_ci,
    weighted_mean_boot,
)
from evalsuite.registry import Registry

__all__ = ["FAMILIES", "MetricFamily", "MetricInfo", "SequenceContext", "ReduceContext", "register_family",
           "unregister_family", "get_family", "registered_families", "metric_index", "bootstrap_weights",
           "percentile_ci", "weighted_mean_boot"]


def _no_metric_clash(name: str, family: MetricFamily) -> None:
    taken = {m: f for f, fam in FAMILIES.current().items() if f != name for m in (i.name for i in fam.metrics)}
    clash = [m.name for m in family.metrics if m.name in taken]
    if clash or name in taken:
        raise ValueError(f"metric names of family {name!r} are taken: {', '.join(clash or [name])}")


FAMILIES: Registry[MetricFamily] = Registry(
    "metric family", "evalsuite.metric_families", base=MetricFamily, name_of=lambda f: f.name,
    check=_no_metric_clash, field="metrics")


def register_family(family: MetricFamily, *, replace: bool = False) -> MetricFamily:
    """Add ``family`` (an instance) to the registry; its metric names must be new."""
    return FAMILIES.register(family.name, family, replace=replace)


def unregister_family(name: str) -> None:
    FAMILIES.unregister(name)


def registered_families() -> dict[str, MetricFamily]:
    """Name -> family, in registration order (the order of the summary rows): the built-in families, then
    those registered in this process, then installed plug-ins (entry-point group ``evalsuite.metric_families``)."""
    return FAMILIES.loaded()


def get_family(name: str) -> MetricFamily:
    return FAMILIES.get(name)


def metric_index(families: dict[str, MetricFamily] | None = None) -> dict[str, tuple[str, MetricInfo]]:
    """Metric name -> (family name, info)."""
    fams = FAMILIES.loaded() if families is None else families
    return {m.name: (f, m) for f, fam in fams.items() for m in fam.metrics}


def _register_builtins() -> None:
    from evalsuite.metrics.families import beats, cca, coupling, distribution, errors, gac, histograms, kinematics

    for module in (kinematics, histograms, errors, distribution, cca, beats, coupling, gac):
        register_family(module.FAMILY, replace=True)


_register_builtins()
