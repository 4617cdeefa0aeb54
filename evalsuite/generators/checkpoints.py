"""Checkpoints of the re-implementations' training loops, and resuming after a kill.

``evalsuite train --checkpoint-every 10m|N`` saves, every 10 minutes or every N epochs (steps for the
adversarial stage of ``ferstl-mogan``), and at the end of every stage, everything a loop's next epoch depends on:
the networks, the optimisers, the weight average, the early-stopping state (best weights, epochs without
improvement), the history so far, the loop's own ``numpy.random.Generator`` (the data order) and the global random
states of torch, numpy and Python. ``--resume`` loads the latest checkpoint of each stage and carries on, so that a
training killed with SIGKILL and resumed ends with the same weights as one that ran through (on one machine, CPU).

A checkpoint is written to ``OUT/checkpoints/<stage>.pt.tmp`` and renamed over ``<stage>.pt`` (atomic on POSIX),
so a kill while writing leaves the previous checkpoint. ``OUT/checkpoints/run.json`` holds the generator, options,
seed and preset of the run; resuming with other ones is refused. The folder is removed when training ends.

A loop uses it as::

    ck = current()
    state = {"net": net, "opt": opt, "rng": rng, "history": history, "best": best}
    start, done = ck.start("speech", state)          # (0, False) without a checkpoint
    for epoch in range(start, epochs if not done else start):
        ...
        ck.step("speech", epoch + 1, state, done=stop or epoch + 1 == epochs)
        if stop: break

Objects are anything with ``state_dict``/``load_state_dict`` (modules, optimisers, :class:`BestWeights`,
:class:`WeightAverage`), a ``numpy.random.Generator``, or a list (replaced in place).
"""
from __future__ import annotations

import contextlib
import json
import os
import pathlib
import random
import re
import shutil
import time
from collections.abc import Iterator, Mapping
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any

import numpy as np

from evalsuite.errors import InputError

__all__ = ["Every", "parse_every", "Checkpointer", "current", "session", "check_run", "CHECKPOINT_FOLDER"]

CHECKPOINT_FOLDER = "checkpoints"


@dataclass(frozen=True)
class Every:
    """How often to save: every ``epochs`` epochs (steps) or every ``minutes`` minutes (or both)."""

    epochs: int | None = None
    minutes: float | None = None


def parse_every(text: str | None) -> Every | None:
    """``"5"`` (every 5 epochs/steps), ``"10m"`` / ``"10min"`` (every 10 minutes), ``"off"`` or None (no periodic
    checkpoint; stage ends are still saved when checkpointing is on)."""
    if text is None or str(text).strip().lower() in ("", "off", "none"):
        return None
    s = str(text).strip().lower()
    m = re.fullmatch(r"(\d+(?:\.\d+)?)\s*(m|min|minutes?)", s)
    if m and float(m.group(1)) > 0:
        return Every(minutes=float(m.group(1)))
    if s.isdigit() and int(s) > 0:
        return Every(epochs=int(s))
    raise InputError(f"--checkpoint-every takes a number of epochs (5) or of minutes (10m), got {text!r}",
                     field="--checkpoint-every")


def _get(obj: Any) -> Any:
    if isinstance(obj, np.random.Generator):
        return obj.bit_generator.state
    if isinstance(obj, list):
        return list(obj)
    return obj.state_dict()


def _set(obj: Any, state: Any) -> None:
    if isinstance(obj, np.random.Generator):
        obj.bit_generator.state = state
    elif isinstance(obj, list):
        obj[:] = state
    else:
        obj.load_state_dict(state)


class Checkpointer:
    """Saves and restores one training's loop states in ``folder`` (None: checkpointing off, every call a no-op)."""

    def __init__(self, folder: pathlib.Path | None, every: Every | None = None, resume: bool = False):
        self.folder = folder
        self.every = every
        self.resume = resume
        self.resumed: list[str] = []          # stages restored from a checkpoint
        self._last = time.monotonic()

    def _path(self, stage: str) -> pathlib.Path:
        assert self.folder is not None
        return self.folder / (re.sub(r"[^A-Za-z0-9_.-]+", "_", stage) + ".pt")

    def start(self, stage: str, objects: Mapping[str, Any]) -> tuple[int, bool]:
        """(epoch to start from, whether the stage had ended): the stage's checkpoint loaded into ``objects`` and
        the global random states, when resuming and there is one; (0, False) otherwise."""
        if self.folder is None or not self.resume or not self._path(stage).exists():
            return 0, False
        import torch

        payload = torch.load(self._path(stage), map_location="cpu", weights_only=False)
        missing = sorted(set(objects) - set(payload["objects"]))
        if missing:
            raise InputError(f"the checkpoint of stage {stage!r} lacks {', '.join(missing)}: it was written by another "
                             "version; train again without --resume", path=self._path(stage))
        for name, obj in objects.items():
            _set(obj, payload["objects"][name])
        torch.set_rng_state(payload["rng"]["torch"])
        np.random.set_state(payload["rng"]["numpy"])
        random.setstate(payload["rng"]["python"])
        self.resumed.append(stage)
        return int(payload["epoch"]), bool(payload["done"])

    def due(self, epoch: int) -> bool:
        if self.every is None:
            return False
        by_epochs = self.every.epochs is not None and epoch % self.every.epochs == 0
        by_time = self.every.minutes is not None and time.monotonic() - self._last >= 60.0 * self.every.minutes
        return by_epochs or by_time

    def step(self, stage: str, epoch: int, objects: Mapping[str, Any], *, done: bool = False) -> None:
        """After ``epoch`` epochs (steps) of ``stage``: save when due, and always when the stage has ended."""
        if self.folder is None or not (done or self.due(epoch)):
            return
        import torch

        payload = {"stage": stage, "epoch": epoch, "done": done,
                   "objects": {name: _get(obj) for name, obj in objects.items()},
                   "rng": {"torch": torch.get_rng_state(), "numpy": np.random.get_state(),
                           "python": random.getstate()}}
        self.folder.mkdir(parents=True, exist_ok=True)
        path = self._path(stage)
        tmp = path.with_name(path.name + ".tmp")
        with open(tmp, "wb") as fh:
            torch.save(payload, fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
        self._last = time.monotonic()


_ACTIVE: ContextVar[Checkpointer | None] = ContextVar("evalsuite_checkpointer", default=None)


def current() -> Checkpointer:
    """The checkpointer of the training running in this context (a no-op one outside :func:`session`)."""
    return _ACTIVE.get() or Checkpointer(None)


def check_run(out_dir: pathlib.Path, run: Mapping[str, Any], resume: bool) -> None:
    """Write ``checkpoints/run.json`` for a new run; for ``resume``, refuse a run whose generator, options, seed
    or preset differ from the checkpointed one's."""
    folder = out_dir / CHECKPOINT_FOLDER
    path = folder / "run.json"
    if resume and path.exists():
        saved = json.loads(path.read_text(encoding="utf-8"))
        differ = sorted(k for k in set(saved) | set(run) if saved.get(k) != json.loads(json.dumps(run.get(k))))
        if differ:
            raise InputError(f"--resume needs the same {', '.join(differ)} as the interrupted run "
                             f"({', '.join(f'{k}={saved.get(k)!r}' for k in differ)})", path=path, field="--resume")
        return
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    path.write_text(json.dumps(run, indent=1, sort_keys=True), encoding="utf-8")


@contextlib.contextmanager
def session(out_dir: pathlib.Path, every: Every | None, resume: bool) -> Iterator[Checkpointer]:
    """Checkpoint the loops run inside the ``with`` block in ``out_dir/checkpoints``; the folder is removed when
    the block ends without an error."""
    ck = Checkpointer(out_dir / CHECKPOINT_FOLDER, every, resume)
    token = _ACTIVE.set(ck)
    try:
        yield ck
    finally:
        _ACTIVE.reset(token)
    shutil.rmtree(out_dir / CHECKPOINT_FOLDER, ignore_errors=True)
