"""A scorer learned from pairwise votes: ``evalsuite critic train|score`` (issue 40).

A frozen motion encoder (:data:`ENCODERS`: ``kinematic``, numpy only; ``fgd``, evalsuite's FGD encoder, needs the
``learned`` extra and a model file) gives each stimulus (a condition's motion on a segment) an embedding
``e`` (the mean of its window features, z-scored over the stimuli of the votes). A Bradley-Terry head scores it
``s = w . e`` and models a vote as ``P(a beats b) = sigmoid(s_a - s_b)``; ``w`` is the L2-penalised maximum
likelihood fit on the votes (ties left out). The head is only reported with held-out pairwise agreement (the
share of non-tied test votes whose winner the head scores higher) under two splits, by rater (k folds of
raters) and by system (leave one system out: test votes involve it, training votes do not), beside the
agreement of a Fréchet distance to natural motion in the same encoder's window features on the same
votes (FGD itself with the ``fgd`` encoder), each with a percentile bootstrap CI over the test raters.

Modules: :mod:`~evalsuite.critic.core` (encoders, head, evaluation), :mod:`~evalsuite.critic.cli`.
"""
from __future__ import annotations

from evalsuite.critic.core import ENCODERS, Encoder, evaluate, fit_head, load_votes

__all__ = ["ENCODERS", "Encoder", "evaluate", "fit_head", "load_votes"]
