"""One executor for evalsuite's per-file work: scoring, FGD, rendering and generation.

:func:`run` maps a picklable function over tasks and delivers the results **in task order**, whatever
order they finish in, so every reduction over them is identical however the work was run:

* ``jobs=1``: in this process;
* ``jobs>1``: in that many spawned local processes, each pinned to one BLAS thread (N processes x N
  BLAS threads would oversubscribe the cores);
* ``dask_address``: on an existing dask.distributed scheduler (connection timeout 10 s).

A tqdm progress bar counts ``weights`` (e.g. files per task). An exception raised by a task reaches the
caller: :class:`~evalsuite.errors.InputError` as it is (its message names the file), anything else mapped
to an InputError naming the task, so the command line shows one line, not a worker's traceback.
"""
from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from typing import Any, TypeVar

from evalsuite.errors import InputError

__all__ = ["run", "BLAS_THREAD_VARS", "TaskError"]

T = TypeVar("T")
R = TypeVar("R")

BLAS_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
DASK_TIMEOUT = "10s"


class TaskError(InputError):
    """A task failed with an unexpected exception (the message names the task and the exception)."""


def _checked(func: Callable[[T], R], index: int, task: T, describe: Callable[[T], str] | None) -> R:
    try:
        return func(task)
    except InputError:
        raise
    except Exception as exc:  # a worker's bug must reach the caller as one readable line
        name = describe(task) if describe else f"task {index}"
        raise TaskError(f"{name}: {type(exc).__name__}: {exc}") from exc


class _Call:
    """Picklable wrapper: ``_Call(func, describe)((index, task))``."""

    def __init__(self, func: Callable[[Any], Any], describe: Callable[[Any], str] | None):
        self.func, self.describe = func, describe

    def __call__(self, item: tuple[int, Any]) -> Any:
        return _checked(self.func, item[0], item[1], self.describe)


def run(func: Callable[[T], R], tasks: Iterable[T], *, jobs: int = 1, dask_address: str | None = None,
        progress: bool = True, weights: Sequence[float] | None = None, desc: str = "tasks", unit: str = "file",
        consume: Callable[[int, R], Any] | None = None,
        describe: Callable[[T], str] | None = None) -> list[Any]:
    """``[func(t) for t in tasks]`` in task order, locally, in ``jobs`` processes or on a dask cluster.

    ``consume(i, result)``, if given, is called for every result in task order (early results wait in a
    buffer); what it returns replaces the result (e.g. with bulky parts folded into running sums and
    dropped). ``describe(task)`` names a task in error messages.
    """
    from tqdm import tqdm

    task_list = list(tasks)
    w = list(weights) if weights is not None else [1] * len(task_list)
    results: list[Any] = [None] * len(task_list)
    waiting: dict[int, Any] = {}
    next_index = 0
    bar = tqdm(total=sum(w), unit=unit, desc=desc, disable=not progress, leave=False)
    call = _Call(func, describe)

    def deliver(i: int, res: Any) -> None:
        nonlocal next_index
        waiting[i] = res
        while next_index in waiting:
            r = waiting.pop(next_index)
            results[next_index] = consume(next_index, r) if consume is not None else r
            next_index += 1
        bar.update(w[i])

    try:
        if dask_address:
            _run_dask(call, task_list, dask_address, deliver)
        elif jobs > 1 and len(task_list) > 1:
            _run_processes(call, task_list, jobs, deliver)
        else:
            for i, t in enumerate(task_list):
                deliver(i, call((i, t)))
    finally:
        bar.close()
    return results


def _run_dask(call: _Call, tasks: list[Any], address: str, deliver: Callable[[int, Any], None]) -> None:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise InputError("--dask needs dask.distributed: pip install 'evalsuite[dask]'") from None
    try:
        client = Client(address, timeout=DASK_TIMEOUT)
    except (OSError, TimeoutError) as exc:
        raise InputError(f"cannot connect to the dask scheduler at {address} ({exc})", field="dask") from None
    try:
        futures = client.map(call, list(enumerate(tasks)), pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in as_completed(futures):
            deliver(index[fut.key], fut.result())
    finally:
        client.close()


def _run_processes(call: _Call, tasks: list[Any], jobs: int, deliver: Callable[[int, Any], None]) -> None:
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor, as_completed

    ctx = multiprocessing.get_context("spawn")
    # The variables are read when a spawned worker imports numpy.
    saved = {k: os.environ.get(k) for k in BLAS_THREAD_VARS}
    os.environ.update({k: "1" for k in BLAS_THREAD_VARS})
    try:
        with ProcessPoolExecutor(max_workers=min(jobs, len(tasks)), mp_context=ctx) as pool:
            futs = {pool.submit(call, (i, t)): i for i, t in enumerate(tasks)}
            for fut in as_completed(futs):
                deliver(futs[fut], fut.result())
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
