"""Options shared by ``evalsuite train`` and ``evalsuite generate``: ``--device``/``--amp``
(:mod:`evalsuite.generators.device`) and, for ``train``, ``--joints`` (:mod:`evalsuite.generators.joint_presets`).
Each decorator adds its options and runs the command inside the matching context, so the command function takes
no parameter for them (as ``--on-mismatch``)."""
from __future__ import annotations

import functools
from typing import Any

import click

from evalsuite.generators.device import DEVICES
from evalsuite.generators.joint_presets import JOINT_PRESETS

__all__ = ["device_options", "joints_option"]


def device_options(f: Any) -> Any:
    """``--device auto|cpu|cuda|mps`` and ``--amp``."""
    @functools.wraps(f)
    def run(*args: Any, device: str, amp: bool, **kwargs: Any) -> Any:
        from evalsuite.generators.device import use_device

        with use_device(device, amp):
            return f(*args, **kwargs)

    run = click.option("--amp", is_flag=True,
                       help="Mixed precision (bfloat16 autocast) on CUDA; an error on another device.")(run)
    return click.option("--device", type=click.Choice(DEVICES), default="cpu", show_default=True,
                        help="Where the re-implementations compute: auto (cuda, else mps, else cpu), cpu, cuda or "
                             "mps; an unavailable device is an error. docs/generators.md.")(run)


def joints_option(f: Any) -> Any:
    """``--joints PRESET|names``: the joints the re-implementations model."""
    @functools.wraps(f)
    def run(*args: Any, joints: str | None, **kwargs: Any) -> Any:
        from evalsuite.generators.pose_repr import modelled_joints

        with modelled_joints(joints):
            return f(*args, **kwargs)

    return click.option("--joints", metavar="PRESET|NAMES",
                        help=f"Joints to model: a preset ({', '.join(JOINT_PRESETS)}) or comma-separated joint names; "
                             "default: the first preset the corpus's skeleton has. Output is written on the "
                             "corpus's whole skeleton.")(run)
