"""Early stopping for the re-implementations: keep the weights of the epoch with the lowest validation loss.

The papers select models by validation loss; with the small corpora a CPU trains on, the speech networks
overfit after a few dozen epochs, so the weights of the best validation epoch are restored at the end and
training may stop after ``patience`` epochs without improvement. The history marks the chosen epoch
(``"best": true``) and the stopping reason.
"""
from __future__ import annotations

import math
from typing import Any

__all__ = ["BestWeights"]


class BestWeights:
    def __init__(self, module: Any, patience: int | None = None):
        self.module = module
        self.patience = patience
        self.best = math.inf
        self.state: dict[str, Any] | None = None
        self.record: dict[str, Any] | None = None
        self.since = 0

    def update(self, record: dict[str, Any]) -> bool:
        """Note an epoch's record; True when training should stop (no improvement for ``patience`` epochs)."""
        loss = record.get("val_loss")
        if loss is None or not math.isfinite(loss):
            return False
        if loss < self.best:
            self.best, self.record, self.since = float(loss), record, 0
            self.state = {k: v.detach().clone() for k, v in self.module.state_dict().items()}
            return False
        self.since += 1
        if self.patience is not None and self.since >= self.patience:
            record["stopped"] = f"no better validation loss for {self.patience} epochs"
            return True
        return False

    def state_dict(self) -> dict[str, Any]:
        """What a checkpoint keeps (:mod:`evalsuite.generators.checkpoints`): the best loss and weights, the
        best epoch's record and the epochs since."""
        return {"best": self.best, "state": self.state, "record": self.record, "since": self.since}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.best, self.state, self.record, self.since = state["best"], state["state"], state["record"], state["since"]

    def restore(self) -> None:
        """Load the best epoch's weights (when there was a validation loss) and mark that epoch."""
        if self.state is not None and self.record is not None:
            self.module.load_state_dict(self.state)
            self.record["best"] = True
