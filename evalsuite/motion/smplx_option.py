"""The ``--smplx-model`` option, declared once for every command that may need SMPL-X joint positions.

The option names the user's SMPL-X model file and sets ``EVALSUITE_SMPLX_MODEL`` for the command (and the
worker processes it starts), so every SMPL-X file the command loads has positions; without it (and without
the variable), rotation-space work runs and anything needing positions stops with one line naming the option.
"""
from __future__ import annotations

import os
import pathlib
from collections.abc import Callable
from typing import Any, TypeVar

import click

from evalsuite.motion.smplx_body import MODEL_ENV, MODES, REGISTER_URL

__all__ = ["smplx_model_option", "positions_mode_option"]

F = TypeVar("F", bound=Callable[..., Any])


def _export(ctx: click.Context, param: click.Parameter, value: pathlib.Path | None) -> pathlib.Path | None:
    if value is not None:
        if not value.expanduser().is_file():
            raise click.BadParameter(f"no such file: {value}", ctx=ctx, param=param)
        previous = os.environ.get(MODEL_ENV)
        os.environ[MODEL_ENV] = os.fspath(value.expanduser().resolve())
        # Restored when the command ends, so an in-process call (tests, notebooks) leaves no model behind.
        ctx.call_on_close(lambda: _restore(previous))
    return value


def _restore(previous: str | None) -> None:
    if previous is None:
        os.environ.pop(MODEL_ENV, None)
    else:
        os.environ[MODEL_ENV] = previous


def smplx_model_option(fn: F) -> F:
    """``--smplx-model PATH`` (not passed to the command: it sets ``EVALSUITE_SMPLX_MODEL``)."""
    return click.option(
        "--smplx-model", type=click.Path(dir_okay=False, path_type=pathlib.Path), default=None, metavar="PATH",
        expose_value=False, is_eager=True, callback=_export,
        help=f"Your SMPL-X model file (.npz, e.g. SMPLX_NEUTRAL_2020.npz; register at {REGISTER_URL} to download "
             f"it) for the joint positions of SMPL-X motion [default: ${MODEL_ENV}]. Rotations need none.")(fn)


def positions_mode_option(fn: F) -> F:
    """``--positions full|leaderboard`` (passed to the command as ``positions``)."""
    return click.option(
        "--positions", "positions", type=click.Choice(MODES), default="full", show_default=True,
        help="SMPL-X joint positions: full (orientation, translation, jaw, eyes and expressions applied) or "
             "leaderboard (those zeroed, as the GENEA Leaderboard computes positions).")(fn)
