"""Learning-rate schedules of the re-implementations: the papers' constant rate, or a cosine decay.

With the short CPU budgets and small corpora the re-implementations train on, trainings that end at the same
validation loss still scattered widely on held-out data while their weights moved with the full rate in the
last epochs (docs/generators.md); a cosine decay to 1 % of the rate by the last epoch made them agree.
"""
from __future__ import annotations

import math

__all__ = ["SCHEDULES", "learning_rate_at"]

SCHEDULES = ("constant", "cosine")


def learning_rate_at(schedule: str, base: float, epoch: int, epochs: int, floor: float = 0.01) -> float:
    """Rate of zero-based ``epoch`` of ``epochs``: ``base`` (constant) or
    ``base (floor + (1 - floor) (1 + cos(pi epoch / (epochs - 1))) / 2)`` (cosine: ``base`` at the first
    epoch, ``floor x base`` at the last)."""
    if schedule not in SCHEDULES:
        raise ValueError(f"lr_schedule must be 'constant' or 'cosine', got {schedule!r}")
    if schedule == "constant" or epochs <= 1:
        return base
    return base * (floor + (1 - floor) * 0.5 * (1 + math.cos(math.pi * min(epoch, epochs - 1) / (epochs - 1))))
