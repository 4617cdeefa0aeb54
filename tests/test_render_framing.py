"""The shared view (renderers.framing): a static camera aimed at the mean root position, so the body is centred
in its frame whatever one arm does, and the framings full / above-knees / upper."""
from __future__ import annotations

import numpy as np
import pytest
from render_helpers import NAMES, PARENTS, TPOSE

from evalsuite.motion import Motion
from renderers.camera import frame_points, view_direction
from renderers.figure import FigureStyle
from renderers.framing import framed_mask
from renderers.render import prepare_motions, render_frames, view_for
from renderers.scene import RenderSettings

UP = np.array([0.0, 1.0, 0.0])


def _one_arm_out(frames=10) -> Motion:
    """The T-pose with the right arm hanging: the joints' bounding box is far from symmetric about the body."""
    pos = TPOSE.copy()
    for name, drop in (("RightElbow", 25.0), ("RightWrist", 50.0)):
        j = NAMES.index(name)
        pos[j] = [-15.0, 148.0 - drop, 0.0]
    pos = np.repeat(pos[None], frames, axis=0)
    pos[:, NAMES.index("LeftWrist"), 1] += np.linspace(0, 20, frames)
    return Motion.from_positions(pos, NAMES, 30.0, PARENTS)


def test_frame_points_with_an_aim_puts_it_on_the_centre_line_and_fits_everything():
    pts = np.random.default_rng(2).normal(size=(300, 3)) * [30, 60, 10] + [40, 100, 0]
    d = view_direction(np.array([0.0, 0.0, 1.0]), "y", "front", 8.0)
    aim = np.array([0.0, 100.0, 0.0])
    cam = frame_points(pts, d, "y", 400, 300, margin=0.1, aim=aim)
    assert cam.project(aim)[0] == pytest.approx(200.0, abs=0.5)
    uv = cam.project(pts)
    assert uv[:, 0].min() >= 0.05 * 400 - 1e-6 and uv[:, 0].max() <= 0.95 * 400 + 1e-6
    assert uv[:, 1].min() >= 0.05 * 300 - 1e-6 and uv[:, 1].max() <= 0.95 * 300 + 1e-6
    free = frame_points(pts, d, "y", 400, 300, margin=0.1)
    assert abs(free.project(aim)[0] - 200.0) > 20, "without an aim the extent, not the aim, is centred"


@pytest.mark.parametrize("body", ["stick", "mannequin"])
@pytest.mark.parametrize("framing", ["full", "above-knees", "upper"])
def test_the_root_is_centred_and_the_body_too_when_one_arm_reaches_out(body, framing):
    m = _one_arm_out()
    settings = RenderSettings(width=160, height=120, body=body, framing=framing, style=FigureStyle(floor=False))
    ms = prepare_motions([m], settings)
    view = view_for(ms, settings)
    root = ms[0].positions()[:, 0].mean(axis=0)
    assert view.camera.project(root)[0] == pytest.approx(80.0, abs=0.5)
    img = render_frames(ms, settings, view=view)[0]
    cols = np.nonzero(np.any(img < 235, axis=2))[1]
    # the trunk (the columns within 0.1 of the figure size of the root) is the densest part of the silhouette
    trunk = view.camera.project(root + [[-0.1 * view.size, 0, 0], [0.1 * view.size, 0, 0]])[:, 0]
    inside = ((cols >= trunk.min()) & (cols <= trunk.max())).mean()
    assert abs((trunk.min() + trunk.max()) / 2 - 80) < 1.0 and inside > 0.3
    assert cols.min() > 1 and cols.max() < 158, "nothing is cut at the sides"


def test_framed_joints_of_each_framing_by_name_and_without_names():
    pos = np.repeat(TPOSE[None], 2, axis=0)
    full = framed_mask(pos, NAMES, PARENTS, UP, "full")
    knees = framed_mask(pos, NAMES, PARENTS, UP, "above-knees")
    upper = framed_mask(pos, NAMES, PARENTS, UP, "upper")
    assert full.all()
    assert [n for n, k in zip(NAMES, knees) if not k] == ["LeftAnkle", "RightAnkle"]
    assert not upper[NAMES.index("LeftKnee")] and upper[NAMES.index("Head")]
    anonymous = [f"joint{j}" for j in range(len(NAMES))]
    knees = framed_mask(pos, anonymous, PARENTS, UP, "above-knees")
    assert not knees[NAMES.index("LeftAnkle")] and knees[NAMES.index("LeftKnee")] and knees[NAMES.index("Hips")]


@pytest.mark.parametrize("body", ["mannequin", "character"])
def test_an_upper_body_fills_its_frame_with_its_head_in_it_and_no_floor(body):
    """A skeleton without legs: no floor under it (unless asked), every framing frames all of it (there is no leg to
    leave out), and the head, as big as the body's stature makes it, stays inside the picture."""
    from render_helpers import upper_body

    motion = upper_body()
    for framing in ("full", "above-knees", "upper"):
        assert framed_mask(motion.positions(), motion.joint_names, motion.parents, np.array([0.0, 1.0, 0.0]),
                           framing).all()
    settings = RenderSettings(width=160, height=120, body=body)
    m = prepare_motions([motion], settings)[0]
    assert view_for([m], settings).floor_height is None
    assert view_for([m], RenderSettings(body=body, style=FigureStyle(floor=True))).floor_height is not None
    img = render_frames([m], settings)[0].astype(int)
    figure = np.abs(img - img[0, 0]).max(axis=-1) > 30
    rows = np.flatnonzero(figure.any(axis=1))
    assert rows[0] > 2, "the head is inside the picture, not cut at its top"
    assert not figure[0].any() and not figure[:, 0].any() and not figure[:, -1].any()
    cols = np.flatnonzero(figure.any(axis=0))
    assert abs((cols[0] + cols[-1]) / 2 - 80) < 12, "centred"
