"""The one epoch loop of the re-implementations' training stages (resume, history, early stopping, budget, checkpoints).

Every stage of every re-implementation (Gesticulator; Aud2Pose/Aud2Motion/Aud2Repr2Pose's autoencoder and speech
network; Gesture2Vec's frame autoencoder, VQ-DVAE and translation; ferstl-mogan's classifier, MSE pre-training and
adversarial steps) trains as::

    loop = EpochLoop("speech", epochs, state, history=history, on_epoch=on_epoch, best=best,
                     budget_seconds=budget, started=t0)
    for epoch in loop:                 # from the checkpoint's epoch when resuming (none when the stage had ended)
        ...one epoch (step) of training, then the record {"stage": ..., "epoch": ..., "train_loss": ...}
        if loop.end(record):
            break

:meth:`EpochLoop.end` does, in this order: early stopping (:class:`~evalsuite.generators.early_stopping.BestWeights`),
the budget check (``record["stopped"] = "time budget spent"``, the record's stage added to ``stopped``),
``record["seconds"]`` (since ``started``), the history row, the progress callback, and the checkpoint step
(:mod:`evalsuite.generators.checkpoints`; always at the stage's end). Nothing in it draws random numbers, so the
weights are those of the loops it replaced. A stage with a cumulative budget share passes its deadline as
``budget_seconds`` (seconds after ``started``, the training's start).
"""
from __future__ import annotations

import time
from collections.abc import Callable, Iterator, Mapping
from typing import Any

from evalsuite.generators import checkpoints
from evalsuite.generators.early_stopping import BestWeights

__all__ = ["EpochLoop", "BUDGET_SPENT"]

BUDGET_SPENT = "time budget spent"   # ``record["stopped"]`` of the epoch after which the budget stopped a stage


class EpochLoop:
    """The epochs (steps) ``0 .. epochs - 1`` of one resumable training stage.

    ``state``: everything the next epoch depends on (:meth:`Checkpointer.start`'s objects; ``history`` and
    ``stopped`` are added); ``history``: the list the records are appended to (None: not kept); ``on_epoch``: the
    progress callback; ``best``: early stopping; ``budget_seconds``: the stage stops after the epoch that ends at or
    after this many seconds since ``started`` (default: now); ``stopped``: the list of stages the budget cut."""

    def __init__(self, stage: str, epochs: int, state: Mapping[str, Any], *, history: list[dict] | None = None,
                 on_epoch: Callable[[dict], None] | None = None, best: BestWeights | None = None,
                 budget_seconds: float | None = None, started: float | None = None,
                 stopped: list[str] | None = None):
        lists = {"history": history, "stopped": stopped}   # the loop's own lists are checkpointed with the stage
        self.stage, self.epochs = stage, epochs
        self.state = {**state, **{k: v for k, v in lists.items() if v is not None}}
        self.history, self.on_epoch, self.best, self.stopped = history, on_epoch, best, stopped
        self.budget_seconds = budget_seconds
        self._ck = checkpoints.current()
        self.first, self.done = self._ck.start(stage, self.state)   # (0, False) without a checkpoint
        self.started = time.perf_counter() if started is None else started
        self.epoch = self.first
        self._next = self.first

    def __iter__(self) -> Iterator[int]:
        self._next = self.first
        while not self.done and self._next < self.epochs:
            self.epoch = self._next
            self._next = self.epoch + 1
            yield self.epoch

    def elapsed(self) -> float:
        """Seconds since ``started``."""
        return time.perf_counter() - self.started

    def out_of_time(self) -> bool:
        """Whether the stage's budget is spent."""
        return self.budget_seconds is not None and self.elapsed() >= self.budget_seconds

    def end(self, record: dict, *, log: bool = True, late: bool | None = None,
            budget_next: int | None = None) -> bool:
        """Close the current epoch with its ``record``; True when the stage stops here (early stopping or the
        budget; the caller breaks). ``log``: keep the record in the history and show it (False: a step between
        logged ones, kept anyway when the stage stops there); ``late``: the budget check already made this epoch
        (None: check now); ``budget_next``: when the budget is spent, go on at this epoch instead of stopping
        (Gesture2Vec's cut VQ-DVAE still trains its decoder)."""
        stop = self.best.update(record) if self.best is not None else False
        if late is None:
            late = self.out_of_time()
        jump = False
        if not stop and late:
            record["stopped"] = BUDGET_SPENT
            if self.stopped is not None:
                self.stopped.append(str(record.get("stage", self.stage)))
            jump = budget_next is not None
            stop = not jump
        if log or stop:
            record["seconds"] = self.elapsed()
            if self.history is not None:
                self.history.append(record)
            if self.on_epoch is not None:
                self.on_epoch(record)
        self._next = budget_next if jump and budget_next is not None else self.epoch + 1
        self._ck.step(self.stage, self._next, self.state, done=stop or self._next >= self.epochs)
        return stop
