"""Motion file formats: one registry that :func:`evalsuite.load_motion` dispatches through.

Each format is a :class:`MotionFormat` in the :class:`~evalsuite.registry.Registry` :data:`MOTION_FORMATS`:
the built-in ``bvh`` (:mod:`~evalsuite.motion.format_bvh`), ``smplx`` (:mod:`~evalsuite.motion.format_smplx`:
SMPL-X/BEAT2 ``.npz`` with ``poses``) and ``positions`` (:mod:`~evalsuite.motion.format_positions`: joint
positions as ``.npy``, ``.npz`` or ``.csv``). :func:`register_motion_format` adds one in code, and an installed
package adds one with an entry point in the group ``evalsuite.motion_formats``
(``name = "package.module:FORMAT"``, a ``MotionFormat``).

A file goes to the first format, in registration order, that lists its suffix and whose ``detect`` (if any)
accepts it: an ``.npz`` holding ``poses`` is SMPL-X, any other ``.npz`` evalsuite's positions archive.
"""
from __future__ import annotations

import os
import pathlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

from evalsuite.errors import InputError
from evalsuite.registry import Registry

if TYPE_CHECKING:
    from evalsuite.motion.motion import Motion

__all__ = ["MotionFormat", "MOTION_FORMATS", "register_motion_format", "motion_format_for", "motion_suffixes"]


@dataclass(frozen=True)
class MotionFormat:
    """A motion file format.

    ``load(path, **options) -> Motion`` gets every keyword option of :func:`evalsuite.load_motion` (``fps``,
    ``joint_names``, ``parents``, ``convention``, ``root_offset``, ``joint_translation``, ``fallback_fps``,
    ``smplx_model``, ``positions``, ``betas``, ``nan``) and ignores those it has no use for (``**options``).
    ``suffixes`` are lower case; ``detect(path) -> bool`` (None: every file with a listed suffix) lets two
    formats share a suffix."""

    name: str
    suffixes: tuple[str, ...]
    load: Callable[..., Motion]
    detect: Callable[[pathlib.Path], bool] | None = None
    description: str = ""


MOTION_FORMATS: Registry[MotionFormat] = Registry("motion format", "evalsuite.motion_formats", base=MotionFormat,
                                                  name_of=lambda f: f.name, field="format")
MOTION_FORMATS.register_lazy("bvh", "evalsuite.motion.format_bvh:FORMAT")
MOTION_FORMATS.register_lazy("smplx", "evalsuite.motion.format_smplx:FORMAT")
MOTION_FORMATS.register_lazy("positions", "evalsuite.motion.format_positions:FORMAT")


def register_motion_format(fmt: MotionFormat, *, replace: bool = False) -> MotionFormat:
    """Add a format; its name must be new (``replace=True`` swaps an existing one)."""
    return MOTION_FORMATS.register(fmt.name, fmt, replace=replace)


def motion_suffixes() -> tuple[str, ...]:
    """The suffixes of every format (installed plug-ins included), each once, in registration order."""
    return tuple(dict.fromkeys(s for f in MOTION_FORMATS.values() for s in f.suffixes))


def motion_format_for(path: str | os.PathLike[str], format: str | None = None) -> MotionFormat:
    """The format of ``path``: the one named ``format``, else the first that lists the suffix and detects it."""
    if format is not None:
        return MOTION_FORMATS.get(format)
    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    for fmt in MOTION_FORMATS.values():
        if suffix in fmt.suffixes and (fmt.detect is None or fmt.detect(path)):
            return fmt
    raise InputError(f"unknown motion file type {path.suffix!r}; expected one of {', '.join(motion_suffixes())}",
                     path=path)
