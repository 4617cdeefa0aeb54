"""The mannequin body style (renderers.styles.mannequin) and the bone classes it is built from
(renderers.styles.bones), on the four kinds of input: a GENEA 2023 BVH, a BEAT-style BVH, an SMPL-X recording and
a positions file (all self-made stand-ins, see body_helpers)."""
from __future__ import annotations

import pathlib

import imageio.v3 as iio
import numpy as np
import pytest
from body_helpers import beat_standin, four_inputs
from render_helpers import NAMES, PARENTS, TPOSE, genea2023_standin, waving_motion

from evalsuite.motion import Motion
from evalsuite.motion.smplx_layout import SMPLX_JOINT_NAMES, SMPLX_PARENTS
from renderers.figure import FigureStyle
from renderers.render import _meshes, prepare_motions, render_frames, view_for
from renderers.scene import RenderSettings
from renderers.styles.bones import bone_classes, joint_kinds
from renderers.styles.mannequin import MannequinMesh

DATA = pathlib.Path(__file__).parent / "data"
NO_FLOOR = FigureStyle(floor=False)


def _classes(names, parents, positions):
    lengths = np.array([np.linalg.norm(positions[j] - positions[p]) if p >= 0 else 0.0
                        for j, p in enumerate(parents)])
    return dict(zip(names, bone_classes(names, parents, lengths, 170.0)))


def test_bone_classes_of_four_skeletons():
    g = genea2023_standin()
    c = _classes(g.joint_names, g.parents, g.positions()[0])
    assert [c[n] for n in ("b_l_shoulder", "b_l_arm", "b_l_arm_twist", "b_l_forearm", "b_l_wrist_twist",
                           "b_l_wrist", "b_l_index1", "b_l_index2", "b_l_upleg", "b_l_leg", "b_spine1",
                           "b_neck0", "b_head")] == [
        "clavicle", "clavicle", "upperarm", "upperarm", "forearm", "forearm", "palm", "finger", "pelvis",
        "thigh", "spine", "spine", "neck"]
    b = beat_standin()
    c = _classes(b.joint_names, b.parents, b.positions()[0])
    assert [c[n] for n in ("LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand", "LeftHandIndex1",
                           "LeftHandIndex2", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToeBase", "Neck1",
                           "Head")] == [
        "clavicle", "clavicle", "upperarm", "forearm", "palm", "finger", "pelvis", "thigh", "shin", "foot",
        "neck", "neck"]
    assert joint_kinds(["mixamorig:LeftArm", "mixamorig:LeftShoulder"], [1, -1]) == ["shoulder", "clavicle"]
    names = list(SMPLX_JOINT_NAMES)
    kinds = dict(zip(names, joint_kinds(names, SMPLX_PARENTS)))
    assert (kinds["left_collar"], kinds["left_shoulder"], kinds["left_ankle"], kinds["left_foot"]) == (
        "clavicle", "shoulder", "ankle", "toe")
    c = dict(zip(names, bone_classes(names, SMPLX_PARENTS, np.full(55, 10.0), 170.0)))
    assert (c["left_elbow"], c["left_wrist"], c["left_foot"], c["left_knee"], c["left_thumb1"]) == (
        "upperarm", "forearm", "foot", "thigh", "palm")
    # no known name: by length relative to the figure size
    assert bone_classes(["a", "b", "c", "d"], [-1, 0, 1, 2], [0, 50.0, 20.0, 5.0], 170.0) == [
        "", "upperarm", "forearm", "finger"]


def test_one_vertex_array_with_unit_normals_and_constant_faces():
    m = waving_motion(0.3)
    mesh = MannequinMesh(m.joint_names, m.parents, m.positions(), 165.0)
    v, n = mesh.vertices(m.positions())
    assert v.shape == n.shape == (m.n_frames, mesh.n_vertices, 3) and v.dtype == np.float32
    assert mesh.faces.dtype == np.uint32 and mesh.faces.max() == mesh.n_vertices - 1
    assert mesh.colors.shape == (mesh.n_vertices, 3)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, atol=1e-4)
    # one body colour (no left/right colours): every vertex but the visor's and the contact shadow's
    body = np.all(np.isclose(mesh.colors, mesh.colors[0]), axis=1)
    assert body.mean() > 0.85
    # the torso is wider than deep and the figure is solid around its spine
    hips = m.positions()[0, 0]
    around = v[0][np.linalg.norm(v[0] - (hips + [0, 20, 0]), axis=1) < 40]
    assert np.ptp(around[:, 0]) > 1.3 * np.ptp(around[:, 2])


def test_head_faces_forward_with_a_nose_unless_the_face_is_blank():
    m = Motion.from_positions(TPOSE[None], NAMES, 30.0, PARENTS)
    visible = MannequinMesh(NAMES, PARENTS, TPOSE[None], 165.0)
    blank = MannequinMesh(NAMES, PARENTS, TPOSE[None], 165.0, face="blank")
    assert blank.n_vertices < visible.n_vertices
    v, _ = visible.vertices(m.positions())
    head = TPOSE[NAMES.index("Head")]
    near = v[0][np.linalg.norm(v[0] - head - [0, 10, 0], axis=1) < 25]
    assert near[:, 2].max() > -near[:, 2].min() + 1.0, "the nose sticks out at the front (+Z), not the back"
    turned = TPOSE * [-1, 1, -1]   # the same figure turned to face -Z
    v2, _ = visible.vertices(turned[None])
    near = v2[0][np.linalg.norm(v2[0] - turned[NAMES.index("Head")] - [0, 10, 0], axis=1) < 25]
    assert -near[:, 2].min() > near[:, 2].max() + 1.0


def _silhouette(img, bg=(255, 255, 255)):
    return np.any(np.abs(img.astype(int) - bg) > 12, axis=2)


@pytest.mark.parametrize("body", ["stick", "mannequin"])
def test_four_inputs_are_drawn_centred_with_visible_hands(tmp_path, monkeypatch, body):
    for name, path in four_inputs(tmp_path, monkeypatch).items():
        for framing in ("full", "above-knees", "upper"):
            settings = RenderSettings(width=160, height=120, body=body, framing=framing, style=NO_FLOOR)
            ms = prepare_motions([path], settings)
            view = view_for(ms, settings)
            img = render_frames(ms, settings, view=view)[0]
            sil = _silhouette(img)
            area = sil.mean()
            low, high = (0.02, 0.25) if body == "stick" else (0.05, 0.45)
            assert low < area < high, f"{name} {framing}: silhouette covers {area:.3f} of the picture"
            cx = np.nonzero(sil)[1].mean() / 160
            assert abs(cx - 0.5) < 0.04, f"{name} {framing}: silhouette centroid at {cx:.3f} of the width"
            assert not sil[:, :2].any() and not sil[:, -2:].any(), f"{name} {framing}: clipped at a side"
            m = ms[0]
            hands = [j for j, k in enumerate(joint_kinds(m.joint_names, m.parents)) if k in ("wrist", "finger")]
            uv = view.camera.project(m.positions()[0, hands])
            inside = (uv[:, 0] >= 0) & (uv[:, 0] < 160) & (uv[:, 1] >= 0) & (uv[:, 1] < 120)
            assert inside.all(), f"{name} {framing}: a hand is outside the picture"
            hit = [sil[max(int(v) - 1, 0):int(v) + 2, max(int(u) - 1, 0):int(u) + 2].any() for u, v in uv]
            assert np.mean(hit) > 0.9, f"{name} {framing}: the hands are not drawn where their joints are"


def test_above_knees_cuts_at_the_knees(tmp_path, monkeypatch):
    path = four_inputs(tmp_path, monkeypatch)["beat"]
    settings = RenderSettings(width=160, height=120, body="mannequin", framing="above-knees")
    ms = prepare_motions([path], settings)
    view = view_for(ms, settings)
    names = ms[0].joint_names
    uv = view.camera.project(ms[0].positions()[0])
    assert 0.8 * 120 < uv[names.index("LeftLeg"), 1] < 120, "the knees are near the bottom edge"
    assert uv[names.index("LeftFoot"), 1] > 120, "the ankles are below the picture"
    assert uv[names.index("Head"), 1] > 0


def test_contact_shadow_fades_into_the_floor():
    m = waving_motion(0.2)
    settings = RenderSettings(width=160, height=120, body="mannequin")
    assert settings.style.floor is None
    view = view_for([m], settings)
    assert view.floor_height is not None, "the mannequin stands on a floor by default"
    mesh = _meshes([m], settings, view)[0]
    assert mesh.floor_height == view.floor_height
    img = render_frames([m], settings, view=view)[0].astype(int)
    feet = m.positions()[0, [NAMES.index("LeftAnkle"), NAMES.index("RightAnkle")]].mean(0)
    ground = feet * [1, 0, 1] + [0, view.floor_height, 0]
    u, v = view.camera.project(ground)
    under = img[int(v), int(u) - 12:int(u) - 8].sum(axis=-1).mean()    # beside the legs, on the shadow
    far = img[int(v), 4:10].sum(axis=-1).mean()                           # the floor far from the figure
    rim_u, _ = view.camera.project(ground + [0.3 * view.size, 0, 0])
    assert under < far - 60, "the floor under the feet is darker"
    assert abs(img[int(v), int(rim_u) + 2].sum() - far) < 6, "the shadow's rim is the floor's colour"
    off = render_frames([m], RenderSettings(width=160, height=120, body="mannequin", style=NO_FLOOR))[0]
    assert tuple(off[-1, 0]) == (255, 255, 255) and tuple(img[-1, 0]) != (255, 255, 255)


def test_mannequin_matches_its_reference_image(tmp_path, monkeypatch):
    """Frame 10 of the BEAT stand-in at 96x72 against a committed PNG: a small tolerance for rasteriser
    differences, none for a changed body."""
    path = four_inputs(tmp_path, monkeypatch)["beat"]
    settings = RenderSettings(width=96, height=72, body="mannequin", framing="above-knees")
    img = render_frames(prepare_motions([path], settings), settings, frames=[10])[0].astype(int)
    ref = iio.imread(DATA / "mannequin_beat_96x72.png").astype(int)
    diff = np.abs(img - ref).max(axis=2)
    assert diff.mean() < 3.0 and (diff > 48).mean() < 0.02, f"mean {diff.mean():.2f}, {(diff > 48).mean():.3f}"


def test_legs_ending_at_the_ankle_get_feet_pointing_forward():
    mesh = MannequinMesh(NAMES, PARENTS, TPOSE[None], 165.0)
    v, _ = mesh.vertices(TPOSE[None])
    ankle = TPOSE[NAMES.index("LeftAnkle")]
    near = v[0][np.linalg.norm(v[0] - ankle, axis=1) < 25]
    assert near[:, 2].max() > ankle[2] + 0.09 * 165, "a foot reaches forward (+Z) of the ankle"
    assert near[:, 2].min() > ankle[2] - 0.05 * 165, "and not backward"
    beat = beat_standin(0.1)
    with_toes = MannequinMesh(beat.joint_names, beat.parents, beat.positions(), 165.0)
    assert with_toes._stubs == [], "a skeleton with toe joints draws its own feet"


def test_partial_redraw_over_the_floor_leaves_no_trace_of_earlier_frames():
    """Frames drawn one after another (only the figure's box is redrawn, the floor is static) equal frames drawn
    afresh, while the figure walks sideways across the floor."""
    m = waving_motion(0.34)
    pos = m.positions() + (np.linspace(0.0, 60.0, m.n_frames)[:, None, None] * [1, 0, 0])
    moving = Motion.from_positions(pos, NAMES, 30.0, PARENTS)
    settings = RenderSettings(width=96, height=72, body="mannequin", center=False)
    view = view_for([moving], settings)
    assert view.floor_height is not None
    sequence = render_frames([moving], settings, view=view, frames=range(moving.n_frames))
    for k in (3, moving.n_frames - 1):
        fresh = render_frames([moving], settings, view=view, frames=[k])[0]
        np.testing.assert_array_equal(sequence[k], fresh)


def test_an_upper_body_is_as_thick_as_the_whole_body_it_comes_from():
    """Part sizes are fractions of the body's stature: for a skeleton without legs (its extent is its torso and
    arms) the stature its torso and shoulder span suggest (styles.bones.body_scale), not its extent, so the torso,
    head and limbs keep a body's proportions instead of becoming a slim pole."""
    from render_helpers import upper_body

    from renderers.figure import body_size
    from renderers.styles.bones import body_scale

    upper = upper_body()
    whole = np.concatenate([upper.positions()[0], TPOSE[10:]])[None]   # the same body with its legs
    assert body_size(upper.positions()) < 75 and body_size(whole) > 155
    assert body_scale(NAMES, PARENTS, whole, 160.0) == 160.0, "a body with legs: its extent is its stature"
    scale = body_scale(upper.joint_names, upper.parents, upper.positions(), body_size(upper.positions()))
    assert 150 < scale < 175      # median of 50 / 0.288 and 30 / 0.20
    mesh_upper = MannequinMesh(upper.joint_names, upper.parents, upper.positions(), body_size(upper.positions()))
    mesh_whole = MannequinMesh(NAMES, PARENTS, whole, body_size(whole))
    assert abs(mesh_upper.size / mesh_whole.size - 1) < 0.1

    def torso_half_width(mesh):   # the widest lateral semi-axis of the torso's parts
        return max(np.abs(parts.offsets[..., 0]).max() for kind, _, parts in mesh._groups if kind == "trunk")

    assert torso_half_width(mesh_upper) > 0.8 * torso_half_width(mesh_whole) > 10   # (0.4 x before body_scale)
