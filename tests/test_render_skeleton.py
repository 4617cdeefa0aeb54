"""Joints that are not part of the body (a world root at the floor, zero-length helpers) are neither
drawn nor framed: checked on a GENEA 2023 stand-in, CMU-, BEAT- and generator-style skeletons."""
from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner
from render_helpers import NAMES, PARENTS, TPOSE, genea2023_standin, waving_motion

from evalsuite.cli import main
from evalsuite.errors import InputError
from evalsuite.motion import Motion
from evalsuite.motion.io import save_motion
from renderers.figure import FigureMesh
from renderers.render import prepare_motions, render_frames, view_for
from renderers.scene import RenderSettings
from renderers.skeleton import body_motion, non_body_joints
from renderers.stimuli import load_config


def _dropped(motion: Motion) -> list[str]:
    mask = non_body_joints(motion.joint_names, motion.parents, motion.positions())
    return [n for n, d in zip(motion.joint_names, mask) if d]


def _renamed_root(motion: Motion, name: str) -> Motion:
    pos = motion.positions()
    return Motion.from_positions(pos, [name] + motion.joint_names[1:], motion.fps, motion.parents)


def test_genea2023_world_root_is_dropped_by_name_and_by_geometry():
    m = genea2023_standin()
    assert _dropped(m) == ["body_world"]
    # the same skeleton with a neutral root name: it stays put at the floor, far below its child
    assert _dropped(_renamed_root(m, "Root")) == ["Root"]
    body = body_motion(m)
    assert body.joint_names == m.joint_names[1:]
    assert body.parents[0] == -1                                   # b_root is the root now
    np.testing.assert_allclose(body.positions(), m.positions()[:, 1:])


def test_a_world_root_that_follows_the_pelvis_on_the_floor_is_dropped():
    """Game-style root motion: the root slides along the floor under the pelvis (GENEA 2022-like)."""
    m = genea2023_standin(2.0)
    pos = m.positions().copy()
    pos[:, 0] = pos[:, 1] * [1, 0, 1] + [0, 0, 40] * np.linspace(0, 1, len(pos))[:, None]
    moving = Motion.from_positions(pos, ["Reference"] + m.joint_names[1:], m.fps, m.parents)
    assert _dropped(moving) == ["Reference"]
    assert _dropped(_renamed_root(moving, "Root")) == ["Root"]   # at the floor, whatever its name


def test_a_world_named_root_that_carries_the_pelvis_is_kept():
    """body_world holding the pelvis motion with a zero-offset b_root: the helper goes, the root stays."""
    m = genea2023_standin()
    pos = m.positions().copy()
    pos[:, 0] = pos[:, 1]
    carried = Motion.from_positions(pos, m.joint_names, m.fps, m.parents)
    assert _dropped(carried) == ["b_root"]
    body = body_motion(carried)
    assert body.joint_names[0] == "body_world"
    assert body.parents[body.joint_names.index("b_spine0")] == 0


def test_cmu_zero_length_helpers_are_dropped_and_bones_unchanged():
    names = ["Hips", "LHipJoint", "LeftUpLeg", "LeftLeg", "RHipJoint", "RightUpLeg", "RightLeg", "LowerBack",
             "Spine", "Neck", "Head", "LeftArm", "LeftForeArm", "RightArm", "RightForeArm"]
    parents = [-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 9, 8, 11, 8, 13]
    pose = np.array([[0, 95, 0], [0, 95, 0], [9, 90, 0], [9, 50, 0], [0, 95, 0], [-9, 90, 0], [-9, 50, 0],
                     [0, 95, 0], [0, 130, 0], [0, 150, 0], [0, 165, 0], [18, 145, 0], [45, 145, 0],
                     [-18, 145, 0], [-45, 145, 0]], dtype=float)
    t = np.arange(30) / 30.0
    pos = np.repeat(pose[None], 30, axis=0) + (5 * np.sin(2 * np.pi * t))[:, None, None] * [1, 0, 0]
    cmu = Motion.from_positions(pos, names, 30.0, parents)
    assert _dropped(cmu) == ["LHipJoint", "RHipJoint", "LowerBack"]
    body = body_motion(cmu)
    bones = {(body.joint_names[j], body.joint_names[p]) for j, p in enumerate(body.parents) if p >= 0}
    assert ("LeftUpLeg", "Hips") in bones and ("Spine", "Hips") in bones and ("RightUpLeg", "Hips") in bones
    np.testing.assert_allclose(body.positions(), pos[:, [n not in ("LHipJoint", "RHipJoint", "LowerBack")
                                                         for n in names]])


def test_beat_and_generator_skeletons_keep_every_joint():
    """A BEAT-style Hips root (moving) and a generator's output with the root held still keep all joints."""
    assert _dropped(waving_motion(1.0, amplitude=40.0)) == []        # Hips fixed in place
    swaying = waving_motion(1.0, shift=(0, 0, 0))
    pos = swaying.positions() + (4 * np.sin(np.arange(30) / 5.0))[:, None, None] * [1, 0, 1]
    assert _dropped(Motion.from_positions(pos, NAMES, 30.0, PARENTS)) == []
    assert body_motion(swaying) is swaying


def test_genea2023_render_has_no_pole_and_the_world_root_is_out_of_the_framing():
    settings = RenderSettings(width=160, height=120)
    ms = prepare_motions([genea2023_standin()], settings)
    assert "body_world" not in ms[0].joint_names
    view = view_for(ms, settings)
    floor_uv = view.camera.project([0.0, 0.0, 0.0])
    assert floor_uv[1] > 120, "the world root at the floor is below the picture"
    mesh = FigureMesh(ms[0].joint_names, ms[0].parents, settings.style, view.size, rest_positions=ms[0].positions())
    verts, _ = mesh.vertices(ms[0].positions()[:1])
    assert verts[0][:, 1].min() > 40.0, "no geometry reaches down to the floor (the knees are at 48 cm)"
    # pixels straight under the pelvis, from below its sphere down to the knees, are background
    img = render_frames(ms, settings)[0]
    pelvis = ms[0].positions()[0, ms[0].joint_names.index("b_root")]
    top = view.camera.project(pelvis - [0, 12, 0])
    bottom = view.camera.project(pelvis - [0, 45, 0])
    u = int(top[0])
    column = img[int(top[1]):int(bottom[1]), u - 1:u + 2]
    assert column.size and column.min() > 240, "a pole under the pelvis"


def test_upper_framing_of_genea2023_covers_shoulders_to_head_and_hands():
    settings = RenderSettings(width=160, height=120, framing="upper")
    ms = prepare_motions([genea2023_standin()], settings)
    view = view_for(ms, settings)
    names = ms[0].joint_names
    uv = view.camera.project(ms[0].positions())                       # (T, J, 2)
    upper = [names.index(n) for n in ("b_head", "b_l_shoulder", "b_r_shoulder", "b_l_wrist", "b_r_wrist",
                                      "b_l_middle3", "b_r_middle3", "b_root")]
    assert (uv[:, upper] >= 0).all() and (uv[:, upper, 0] <= 160).all() and (uv[:, upper, 1] <= 120).all()
    span = (uv[:, upper, 1].max() - uv[:, upper, 1].min()) / 120
    assert span > 0.6, f"the upper body fills the picture's height (spans {span:.2f} of it)"
    assert (uv[:, names.index("b_l_leg"), 1] > 120).all(), "the knees are below the picture"
    assert view.camera.project([0.0, 0.0, 0.0])[1] > 1.5 * 120, "the floor is far below"


def test_drop_joints_setting_cli_option_and_stimuli_key(tmp_path):
    settings = RenderSettings(width=96, height=72, drop_joints="b_l_leg, b_r_leg")
    assert settings.drop_joints == ("b_l_leg", "b_r_leg")
    assert RenderSettings.from_dict(settings.to_dict()) == settings
    ms = prepare_motions([genea2023_standin()], settings)
    assert not {"b_l_leg", "b_r_leg", "body_world"} & set(ms[0].joint_names)
    with pytest.raises(InputError, match="b_nose"):
        prepare_motions([genea2023_standin()], RenderSettings(drop_joints=["b_nose"]))
    bvh = tmp_path / "standin.bvh"
    save_motion(genea2023_standin(), bvh)
    png = tmp_path / "s.png"
    res = CliRunner().invoke(main, ["render", "still", str(bvh), "-o", str(png), "--width", "96", "--height", "72",
                                    "--drop-joints", "b_l_leg,b_r_leg"])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(main, ["render", "still", str(bvh), "-o", str(png), "--drop-joints", "b_nose"])
    assert res.exit_code == 1 and "b_nose" in res.output and "Traceback" not in res.output
    cfg = tmp_path / "stimuli.yaml"
    cfg.write_text("segments: [s1]\nconditions: {natural: '{segment}.bvh'}\ndrop_joints: [b_l_leg]\n")
    assert load_config(cfg)["settings"].drop_joints == ("b_l_leg",)
    cfg.write_text("segments: [s1]\nconditions: {natural: '{segment}.bvh'}\ndrop_joints: [b_l_leg]\n"
                   "render: {drop_joints: [b_r_leg]}\n")
    with pytest.raises(InputError, match="not both"):
        load_config(cfg)


def test_upper_framing_of_the_plain_skeleton_is_unchanged():
    """The helpers' T-pose skeleton has no non-body joint: its framing is what it was."""
    settings = RenderSettings(width=160, height=120, framing="upper")
    prepared = prepare_motions([Motion.from_positions(TPOSE[None], NAMES, 30.0, PARENTS)], settings)
    assert prepared[0].joint_names == NAMES
