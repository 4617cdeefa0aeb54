"""evalsuite.generators.epoch_loop: the one epoch loop of the re-implementations' training stages."""
from __future__ import annotations

import numpy as np
import pytest

from evalsuite.generators import checkpoints
from evalsuite.generators.early_stopping import BestWeights
from evalsuite.generators.epoch_loop import BUDGET_SPENT, EpochLoop


class _Killed(Exception):
    pass


def _run(loop: EpochLoop, rng: np.random.Generator, kill_after: int | None = None) -> None:
    for epoch in loop:
        record = {"stage": "s", "epoch": epoch + 1, "train_loss": float(rng.random())}
        if loop.end(record):
            break
        if kill_after is not None and epoch + 1 == kill_after:
            raise _Killed


def test_the_loop_runs_every_epoch_and_keeps_seconds_history_and_progress():
    history: list[dict] = []
    shown: list[dict] = []
    loop = EpochLoop("s", 4, {}, history=history, on_epoch=shown.append)
    _run(loop, np.random.default_rng(0))
    assert [r["epoch"] for r in history] == [1, 2, 3, 4]
    assert shown == history
    assert all(r["seconds"] >= 0 for r in history) and "stopped" not in history[-1]


def test_a_spent_budget_stops_after_the_epoch_and_says_so():
    history: list[dict] = []
    stopped: list[str] = []
    loop = EpochLoop("s", 10, {}, history=history, budget_seconds=0.0, stopped=stopped)
    _run(loop, np.random.default_rng(0))
    assert len(history) == 1 and history[0]["stopped"] == BUDGET_SPENT
    assert stopped == ["s"]


def test_budget_next_goes_on_at_that_epoch_instead_of_stopping():
    history: list[dict] = []
    loop = EpochLoop("s", 6, {}, history=history, budget_seconds=0.0, stopped=[])
    seen = []
    for epoch in loop:
        seen.append(epoch)
        if loop.end({"stage": "s", "epoch": epoch + 1}, budget_next=4 if epoch < 4 else None):
            break
    assert seen == [0, 4]
    assert [r["stopped"] for r in history] == [BUDGET_SPENT, BUDGET_SPENT]


def test_steps_between_logged_ones_are_not_kept_unless_the_stage_stops_there():
    history: list[dict] = []
    loop = EpochLoop("s", 5, {}, history=history)
    for step in loop:
        loop.end({"stage": "s", "step": step + 1}, log=step % 2 == 0)
    assert [r["step"] for r in history] == [1, 3, 5]
    history.clear()
    loop = EpochLoop("s", 5, {}, history=history, budget_seconds=0.0)
    for step in loop:
        if loop.end({"stage": "s", "step": step + 1}, log=False):
            break
    assert history == [{"stage": "s", "step": 1, "stopped": BUDGET_SPENT, "seconds": history[0]["seconds"]}]


def test_early_stopping_takes_precedence_over_the_budget():
    import torch

    history: list[dict] = []
    best = BestWeights(torch.nn.Linear(1, 1), patience=1)
    loop = EpochLoop("s", 10, {}, history=history, best=best, budget_seconds=1e9)
    for epoch in loop:
        if loop.end({"stage": "s", "epoch": epoch + 1, "val_loss": [1.0, 0.5, 0.7, 0.1][epoch]}):
            break
    assert len(history) == 3 and history[-1]["stopped"].startswith("no better validation loss")
    assert best.record is history[1]


def test_a_killed_stage_resumes_from_its_checkpoint_with_the_same_records(tmp_path):
    def train(kill_after: int | None, resume: bool) -> list[dict]:
        history: list[dict] = []
        rng = np.random.default_rng(3)
        with checkpoints.session(tmp_path, checkpoints.Every(epochs=1), resume):
            _run(EpochLoop("s", 5, {"rng": rng}, history=history), rng, kill_after)
        return history

    straight = train(None, False)
    with pytest.raises(_Killed):
        train(2, False)
    assert (tmp_path / "checkpoints" / "s.pt").exists()
    resumed = train(None, True)
    assert [(r["epoch"], r["train_loss"]) for r in resumed] == [(r["epoch"], r["train_loss"]) for r in straight]
    assert not (tmp_path / "checkpoints").exists()
