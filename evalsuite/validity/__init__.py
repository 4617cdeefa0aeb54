"""The known-truth validity benchmark of the objective metrics (``evalsuite validate-metrics``).

On a synthetic-speaker corpus the quality order of some conditions is known by construction: the oracle
(another performance of the same speech by the speaker's own model) is the best a generator can do, and
graded degradations of it (speech-gesture time offsets, semantic gestures or beats removed, attenuated
amplitude, jitter, over-smoothing) are worse the stronger they are. Every condition is generated through
the generator plug-ins and scored against natural motion with every metric of ``evalsuite score`` (FGD
included); for each metric and graded family, Kendall's tau between the metric's verdict and the true
order, with a paired bootstrap over segments, tells which metrics can be trusted for which property.

* :mod:`~evalsuite.validity.plan`: the conditions, their families and their generation;
* :mod:`~evalsuite.validity.scoring`: scoring with the per-segment records kept, and bootstrap replicates;
* :mod:`~evalsuite.validity.analysis`: tau, its interval, the worsening and the verdicts;
* :mod:`~evalsuite.validity.report`: ``validity.csv``, ``.md``, ``.tex`` and the heat map;
* :mod:`~evalsuite.validity.cli`: the command and :func:`~evalsuite.validity.cli.run_validation`.

This package sits in the commands layer: it imports generators, metrics and (for FGD) learned.
"""
from __future__ import annotations
