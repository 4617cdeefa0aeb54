"""Reading a file for scoring: the motion at the run's frame rate, and the scored joints' positions on demand."""
from __future__ import annotations

import pathlib
import re
from typing import Any

import numpy as np

from evalsuite.errors import InputError
from evalsuite.metrics.options import ScoreSetup
from evalsuite.motion.io import load_motion

__all__ = ["Positions", "grouped_errors", "load_scored", "selected_positions"]


def load_scored(path: pathlib.Path, setup: ScoreSetup) -> tuple[Any, list[dict[str, Any]]]:
    """The motion (resampled to ``--resample``) and what was resampled, for the provenance."""
    from evalsuite.motion.ops import resample

    motion = load_motion(path, fallback_fps=setup.fps)
    done: list[dict[str, Any]] = []
    if setup.resample is not None and abs(motion.fps - setup.resample) > 1e-9 * setup.resample:
        done.append({"from_fps": float(motion.fps), "to_fps": float(setup.resample), "why": "--resample"})
        motion = resample(motion, setup.resample)
    return motion, done


def selected_positions(motion: Any, joints: list[str]) -> np.ndarray:
    index = {n: i for i, n in enumerate(motion.joint_names)}
    missing = [j for j in joints if j not in index]
    if missing:
        raise InputError(f"skeleton differs from the natural motion: missing joints {', '.join(missing[:8])}"
                         f"{' ...' if len(missing) > 8 else ''}; score a common subset with --joints",
                         path=motion.source)
    return np.asarray(motion.positions()[:, [index[j] for j in joints]])


class Positions:
    """The positions of ``joints`` of ``motion``, computed on first call and kept (shared by the conditions of a
    sequence for the natural file)."""

    def __init__(self, motion: Any, joints: list[str]):
        self.motion, self.joints = motion, joints
        self.value: np.ndarray | None = None

    def __call__(self) -> np.ndarray:
        if self.value is None:
            self.value = selected_positions(self.motion, self.joints)
        return self.value


_NAME = re.compile(r"'[^']*'|^[^ ]*[/\\][^ ]*: ")


def grouped_errors(errors: list[str], shown: int = 5) -> str:
    """The errors of several files, one message per kind: files that failed for the same reason (the same text
    once file names are left out, e.g. every SMPL-X file without a body model) are said once, with a count."""
    groups: dict[str, list[str]] = {}
    for e in errors:
        groups.setdefault(_NAME.sub("…", e), []).append(e)
    parts = [g[0] + (f" (and {len(g) - 1} more file(s) alike)" if len(g) > 1 else "") for g in groups.values()]
    return "; ".join(parts[:shown]) + (f"; and {len(parts) - shown} more kind(s) of error" if len(parts) > shown
                                        else "")
