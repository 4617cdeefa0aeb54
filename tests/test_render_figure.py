"""The stick figure's parts: side/leg/head detection from joint names, and the mesh geometry."""
from __future__ import annotations

import numpy as np
import pytest
from render_helpers import NAMES, PARENTS, TPOSE, waving_motion

from evalsuite.errors import InputError
from renderers.figure import (
    CENTRE,
    LEFT,
    RIGHT,
    FigureMesh,
    FigureStyle,
    forward_direction,
    head_index,
    joint_side,
    leg_mask,
)
from renderers.render import center_on_ground
from renderers.scene import RenderSettings


@pytest.mark.parametrize("name, side", [
    ("LeftArm", LEFT), ("RightForeArm", RIGHT), ("b_l_wrist", LEFT), ("b_r_wrist", RIGHT), ("L_Hand", LEFT),
    ("R_Hand", RIGHT), ("LHip", LEFT), ("RHip", RIGHT), ("mixamorig:LeftHand", LEFT), ("l-arm.001", LEFT),
    ("Spine", CENTRE), ("Head", CENTRE), ("Neck1", CENTRE), ("Hips", CENTRE), ("b_root", CENTRE),
    ("Leaf", CENTRE), ("Rhythm", CENTRE),
])
def test_joint_side_from_name(name, side):
    assert joint_side(name) == side


def test_leg_mask_and_head():
    names = ["Hips", "Spine", "LeftUpLeg", "RightLeg", "LeftFoot", "RightToeBase", "LeftHip", "RightKnee",
             "b_l_upleg", "LeftArm", "Head", "HeadTop_End"]
    assert leg_mask(names).tolist() == [False, False, True, True, True, True, True, True, True, False, False, False]
    assert head_index(names) == 10
    assert head_index(["b_neck0", "b_head"]) == 1
    assert head_index(["Hips", "Spine"]) is None


def test_forward_direction_of_a_figure_whose_left_is_plus_x_is_plus_z():
    np.testing.assert_allclose(forward_direction(TPOSE[None], NAMES, np.array([0.0, 1.0, 0.0])), [0, 0, 1],
                               atol=1e-12)
    mirrored = TPOSE * [-1, 1, 1]
    np.testing.assert_allclose(forward_direction(mirrored[None], NAMES, np.array([0.0, 1.0, 0.0])), [0, 0, -1],
                               atol=1e-12)


def test_mesh_vertices_lie_on_spheres_and_cylinders():
    style = FigureStyle(head_marker=False)
    pos = TPOSE[None]
    mesh = FigureMesh(NAMES, PARENTS, style, size=165.0, rest_positions=pos)
    verts, norms = mesh.vertices(pos)
    assert verts.shape == norms.shape == (1, mesh.n_vertices, 3)
    assert mesh.faces.max() == mesh.n_vertices - 1
    np.testing.assert_allclose(np.linalg.norm(norms[0], axis=1), 1.0, atol=1e-5)
    sv = len(mesh._sv)
    n = len(NAMES)
    spheres = verts[0, :n * sv].reshape(n, sv, 3)
    dist = np.linalg.norm(spheres - pos[0][:, None], axis=-1)
    np.testing.assert_allclose(dist, np.repeat(mesh.joint_radius[:, None], sv, axis=1), rtol=1e-5)
    cv = len(mesh._cv)
    bones = verts[0, n * sv:].reshape(len(mesh.child), cv, 3)
    for k, (c, p) in enumerate(zip(mesh.child, mesh.parent)):
        a, b = pos[0, p], pos[0, c]
        axis = (b - a) / np.linalg.norm(b - a)
        rel = bones[k] - a
        t = rel @ axis
        radial = np.linalg.norm(rel - t[:, None] * axis, axis=1)
        assert t.min() == pytest.approx(0.0, abs=1e-4)
        assert t.max() == pytest.approx(np.linalg.norm(b - a), rel=1e-5)
        side = radial > 1e-3   # cap centres sit on the axis
        np.testing.assert_allclose(radial[side], mesh.bone_radius[k], rtol=1e-4)
    # the right arm is drawn in the right side's colour, the spine in the centre colour
    colors = mesh.colors[: n * sv].reshape(n, sv, -1)[:, 0, :3]
    lin = np.power(np.asarray(style.right_color), 2.2)
    np.testing.assert_allclose(colors[NAMES.index("RightWrist")], lin, rtol=1e-5)
    np.testing.assert_allclose(colors[NAMES.index("Spine")], np.power(np.asarray(style.centre_color), 2.2), rtol=1e-5)


def test_head_marker_sits_above_the_head_joint():
    mesh = FigureMesh(NAMES, PARENTS, FigureStyle(), size=165.0, rest_positions=TPOSE[None])
    verts, _ = mesh.vertices(TPOSE[None])
    sv, n = len(mesh._sv), len(NAMES)
    head = verts[0, n * sv:n * sv + len(mesh._hv)]
    centre = (head.min(axis=0) + head.max(axis=0)) / 2
    np.testing.assert_allclose(centre, TPOSE[3] + [0, 0.6 * mesh.head_radius, 0], atol=1e-3 * mesh.head_radius)


def test_center_on_ground_moves_the_mean_root_only_horizontally():
    m = waving_motion(shift=(100.0, 7.0, -50.0))
    c = center_on_ground(m)
    root = c.positions()[:, 0]
    np.testing.assert_allclose(root.mean(axis=0)[[0, 2]], [0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(c.positions() - m.positions(), np.broadcast_to([-100.0, 0.0, 50.0], m.positions().shape))


@pytest.mark.parametrize("kwargs, field", [({"width": 101}, "resolution"), ({"view": "top"}, "view"),
                                           ({"framing": "face"}, "framing"), ({"msaa": 3}, "msaa"),
                                           ({"fps": -1.0}, "fps")])
def test_bad_settings_are_input_errors(kwargs, field):
    with pytest.raises(InputError) as exc:
        RenderSettings(**kwargs)
    assert exc.value.field == field


def test_grid_layout_places_panels_under_captions():
    from renderers.layout import Compositor

    comp = Compositor(5, 40, 30, layout="grid", captions=list("abcde"), caption_height=10, gap=4)
    assert (comp.rows, comp.cols) == (2, 3)
    assert (comp.width, comp.height) == (3 * 44 - 4, 2 * 44 - 4)
    panels = [np.full((30, 40, 3), 10 * (k + 1), np.uint8) for k in range(5)]
    frame = comp.compose(panels)
    for k in range(5):
        x, y = comp.panel_origin(k)
        assert (x, y) == ((k % 3) * 44, (k // 3) * 44 + 10)
        assert np.all(frame[y:y + 30, x:x + 40] == 10 * (k + 1))
        assert frame[y - 10:y, x:x + 40].min() < 128    # caption text drawn in the strip
    assert np.all(frame[44 + 10:, 88:] == 255), "the unused sixth cell is background"


def test_stored_stick_templates_are_trimeshs_parts():
    """The stick figure's default parts are read from renderers/data (no trimesh import); they must be exactly
    what trimesh makes, and other tessellations still come from trimesh."""
    from renderers.figure import DEFAULT_TESSELLATION, FigureStyle, stick_templates, templates_from_trimesh

    assert (FigureStyle().sphere_subdivisions, FigureStyle().cylinder_sections) == DEFAULT_TESSELLATION
    stored, made = stick_templates(*DEFAULT_TESSELLATION), templates_from_trimesh(*DEFAULT_TESSELLATION)
    assert sorted(stored) == sorted(made)
    for key in made:
        np.testing.assert_allclose(stored[key], made[key], rtol=0, atol=1e-12, err_msg=key)
    finer = stick_templates(2, 16)
    assert len(finer["sv"]) == 162 and len(finer["cf"]) == 32   # 16 sections, the side alone (2 triangles each)
