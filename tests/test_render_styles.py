"""Body styles (renderers.styles): the settings name one, every render path asks it for the mesh, a plug-in
style registered at run time is drawn like a built-in."""
from __future__ import annotations

import numpy as np
import pytest
from render_helpers import waving_motion

from evalsuite.errors import InputError
from renderers.figure import FigureMesh
from renderers.render import _meshes, render_frames, view_for
from renderers.scene import RenderSettings
from renderers.styles import STYLES, BodyStyle


def test_body_setting_is_checked_against_the_registry_with_a_hint():
    assert RenderSettings().body == "stick" and RenderSettings().character is None
    with pytest.raises(InputError) as exc:
        RenderSettings(body="stik")
    assert exc.value.field == "body" and "'stick'" in str(exc.value) and "Did you mean" in str(exc.value)
    with pytest.raises(InputError, match="character"):
        RenderSettings(character=3)   # type: ignore[arg-type]


def test_body_and_character_round_trip_through_the_settings_dict():
    s = RenderSettings(body="stick", character="hero.glb")
    d = s.to_dict()
    assert d["body"] == "stick" and d["character"] == "hero.glb"
    assert RenderSettings.from_dict(d) == s


class _Box:
    """A test style's mesh: one cube around the root joint."""

    def __init__(self, size):
        self.h = 0.2 * size
        c = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
        self._c = c
        self.faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                               [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], np.uint32)
        self.colors = np.full((8, 3), 0.8, np.float32)

    def vertices(self, positions):
        v = positions[:, :1] + self.h * self._c[None]
        n = np.broadcast_to(self._c / np.sqrt(3), v.shape)
        return v.astype(np.float32), n.astype(np.float32)


class _BoxStyle(BodyStyle):
    name = "test-box"
    description = "a cube at the root"

    def mesh(self, motion, settings, size):
        return _Box(size)


def test_every_render_path_goes_through_the_named_style():
    STYLES.register("test-box", _BoxStyle())
    try:
        m = waving_motion(0.2)
        stick = RenderSettings(width=96, height=72)
        box = RenderSettings(width=96, height=72, body="test-box")
        assert isinstance(_meshes([m], stick, view_for([m], stick))[0], FigureMesh)
        assert isinstance(_meshes([m], box, view_for([m], box))[0], _Box)
        a, b = render_frames([m], stick)[0], render_frames([m], box, view=view_for([m], stick))[0]
        assert (a < 200).any() and (b < 200).any() and not np.array_equal(a, b)
    finally:
        STYLES.unregister("test-box")
