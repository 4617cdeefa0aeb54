"""Body styles: how a motion is drawn (stick figure, mannequin, skinned character, a plug-in's).

A style is one module that registers a :class:`BodyStyle` in :data:`STYLES` (or a plug-in package's entry point in
the group ``evalsuite.renderer_styles``). The renderer asks the style for a :class:`BodyMesh` once per clip and
then only for vertices, block by block::

    mesh = STYLES[settings.body].mesh(motion, settings, size)      # once per clip
    verts, norms = mesh.vertices(positions[i:i + 64])              # (F, V, 3) float32 each
    # faces (K, 3) uint32 and colours (V, 3) float32 (linear RGB) never change within a clip

Everything is drawn through the same offscreen path (:class:`renderers.scene.FigureRenderer`): one vertex
array per frame, updated in place, so a style's only job is to turn joint positions into triangles fast.
"""
from __future__ import annotations

import abc
from typing import Any, Protocol

import numpy as np

from evalsuite.registry import Registry

__all__ = ["BodyMesh", "BodyStyle", "STYLES", "register_style"]


class BodyMesh(Protocol):
    """The triangles of one figure: constant ``faces`` and ``colors``, per-frame :meth:`vertices`."""

    faces: np.ndarray      # (K, 3) uint32
    colors: np.ndarray     # (V, 3) float32, linear RGB (pyrender gamma-corrects its output)

    def vertices(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vertex positions and normals ``(F, V, 3)`` float32 for joint positions ``(F, J, 3)``."""
        ...


class BodyStyle(abc.ABC):
    """A way to draw a motion. Subclasses set ``name`` and ``description`` and implement :meth:`mesh`."""

    name: str = ""
    description: str = ""

    @abc.abstractmethod
    def mesh(self, motion: Any, settings: Any, size: float) -> BodyMesh:
        """The mesh of ``motion`` (a :class:`evalsuite.motion.Motion` with non-body joints removed) drawn with
        ``settings`` (:class:`renderers.scene.RenderSettings`); ``size`` is the figure size shared by the
        conditions of a segment (radii scale with it, so no condition looks thicker than another)."""


STYLES: Registry[BodyStyle] = Registry("body style", "evalsuite.renderer_styles", base=BodyStyle,
                                       name_of=lambda s: s.name)


def register_style(style: BodyStyle) -> BodyStyle:
    """Add ``style`` to :data:`STYLES` under ``style.name`` (usable as a class decorator's result too)."""
    STYLES.register(style.name, style)
    return style


# The built-in styles, imported when first asked for (a style module may need trimesh, a glTF reader...).
STYLES.register_lazy("stick", "renderers.styles.stick:STYLE")
STYLES.register_lazy("mannequin", "renderers.styles.mannequin:STYLE")
STYLES.register_lazy("character", "renderers.styles.character:STYLE")
