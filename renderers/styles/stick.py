"""The stick figure (:class:`renderers.figure.FigureMesh`) as a body style: joints as spheres, bones as
capsules, a head marker; left blue, right orange. Fastest; shows no volume, hands or facing."""
from __future__ import annotations

from typing import Any

from renderers.figure import FigureMesh
from renderers.styles import BodyStyle


class StickStyle(BodyStyle):
    name = "stick"
    description = "joints as spheres and bones as capsules, left blue and right orange (fastest)"

    def mesh(self, motion: Any, settings: Any, size: float) -> FigureMesh:
        return FigureMesh(motion.joint_names, motion.parents, settings.style, size,
                          rest_positions=motion.positions())


STYLE = StickStyle()
