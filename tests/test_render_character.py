"""The skinned character style (renderers.styles.character, renderers.gltf_skin, character_maps/_pose): a
synthetic skinned glTF made here follows a motion exactly, the shipped character is posed from a GENEA-2023-like
BVH and from a real BVH without candy-wrapping at the wrists, shoulders and elbows, and bad input gives one-line
errors naming the file."""
from __future__ import annotations

import base64
import json
import struct

import numpy as np
import pytest
from render_helpers import NAMES, PARENTS, TPOSE, genea2023_standin
from scipy.spatial import ConvexHull

from evalsuite.errors import InputError
from evalsuite.motion import Motion, load_motion
from evalsuite.motion.bvh_writer import write_bvh
from evalsuite.motion.samples import sample_path
from renderers.gltf_skin import read_skinned_gltf, write_skinned_glb
from renderers.render import prepare_motions, render_frames
from renderers.scene import RenderSettings
from renderers.styles import STYLES
from renderers.styles.character import DEFAULT_CHARACTER, CharacterMesh, CharacterStyle, load_character
from renderers.styles.character_maps import choose_map, shipped_maps

RADIUS, FRACTIONS, SECTIONS = 0.02, (0.25, 0.5, 0.75), 8


def synthetic_character(path):
    """A tube of rings along every bone of the render_helpers T-pose (metres), each ring skinned 100 % to the
    bone's parent joint, plus one vertex on the bone's axis at its middle. Returns the on-axis vertex of each bone."""
    bind = TPOSE / 100.0
    verts, faces, joints, axis_vertex = [], [], [], {}
    for child, parent in enumerate(PARENTS):
        if parent < 0:
            continue
        a, b = bind[parent], bind[child]
        d = (b - a) / np.linalg.norm(b - a)
        u = np.cross(d, [0.0, 0.0, 1.0] if abs(d[2]) < 0.9 else [1.0, 0.0, 0.0])
        u /= np.linalg.norm(u)
        w = np.cross(d, u)
        first = len(verts)
        for t in FRACTIONS:
            for k in range(SECTIONS):
                ang = 2 * np.pi * k / SECTIONS
                verts.append(a + t * (b - a) + RADIUS * (np.cos(ang) * u + np.sin(ang) * w))
                joints.append(parent)
        for r in range(len(FRACTIONS) - 1):
            for k in range(SECTIONS):
                p0, p1 = first + r * SECTIONS + k, first + r * SECTIONS + (k + 1) % SECTIONS
                faces += [[p0, p1, p1 + SECTIONS], [p0, p1 + SECTIONS, p0 + SECTIONS]]
        axis_vertex[(parent, child)] = len(verts)
        verts.append(a + 0.5 * (b - a))
        joints.append(parent)
        faces.append([first, first + 1, len(verts) - 1])
    j4 = np.zeros((len(verts), 4), dtype=np.int64)
    j4[:, 0] = joints
    w4 = np.zeros((len(verts), 4))
    w4[:, 0] = 1.0
    write_skinned_glb(path, np.array(verts), np.array(faces), NAMES, PARENTS, bind, j4, w4)
    (path.parent / "identity.yaml").write_text("joints:\n" + "".join(f"  {n}: {n}\n" for n in NAMES))
    return axis_vertex


def _rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def arm_motion(frames=12):
    """The T-pose (cm) with the left arm raised/lowered about the shoulder and the elbow bending, rigidly
    (bone lengths kept), the whole body walking along X."""
    pos = np.repeat(TPOSE[None], frames, axis=0).astype(float)
    sh, el, wr = NAMES.index("LeftShoulder"), NAMES.index("LeftElbow"), NAMES.index("LeftWrist")
    for f in range(frames):
        up, bend = np.radians(-60 + 10 * f), np.radians(7 * f)
        elbow = TPOSE[sh] + _rot_z(up) @ (TPOSE[el] - TPOSE[sh])
        pos[f, el] = elbow
        pos[f, wr] = elbow + _rot_z(up + bend) @ (TPOSE[wr] - TPOSE[el])
    pos += np.arange(frames)[:, None, None] * np.array([2.0, 0.0, 0.0])
    return Motion.from_positions(pos, NAMES, 30.0, PARENTS, name="arm", source="arm.csv")


def test_a_vertex_skinned_to_a_bone_moves_with_that_bone_exactly(tmp_path):
    axis_vertex = synthetic_character(tmp_path / "tube.glb")
    motion = arm_motion()
    style = CharacterStyle(character=str(tmp_path / "tube.glb"), joint_map=tmp_path / "identity.yaml")
    mesh = style.mesh(motion, RenderSettings(), 1.0)
    assert mesh.rig.scale == pytest.approx(100.0)
    P = motion.positions()
    verts, norms = mesh.vertices(P)
    assert verts.shape == (len(P), len(mesh.character.vertices), 3) and verts.dtype == np.float32
    assert np.allclose(np.linalg.norm(norms, axis=-1), 1.0, atol=1e-4)
    for (parent, child), v in axis_vertex.items():
        expected = P[:, parent] + 0.5 * (P[:, child] - P[:, parent])
        assert np.allclose(verts[:, v], expected, atol=1e-3), NAMES[child]
    # the rings of the forearm stay round about the moving forearm, at the bind radius times the scale
    el, wr = NAMES.index("LeftElbow"), NAMES.index("LeftWrist")
    ring = np.flatnonzero(mesh.character.joints[:, 0] == el)[:-1]
    d = P[:, wr] - P[:, el]
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    rel = verts[:, ring] - P[:, el][:, None]
    radial = np.linalg.norm(rel - np.einsum("fvi,fi->fv", rel, d)[..., None] * d[:, None], axis=-1)
    assert np.allclose(radial, RADIUS * 100.0, rtol=1e-4)


def test_gltf_round_trip_glb_and_gltf_with_separate_and_embedded_buffers(tmp_path):
    synthetic_character(tmp_path / "tube.glb")
    a = read_skinned_gltf(tmp_path / "tube.glb")
    assert a.joint_names == NAMES and list(a.parents) == PARENTS
    assert np.allclose(a.bind_positions, TPOSE / 100.0, atol=1e-6)
    raw = (tmp_path / "tube.glb").read_bytes()
    n_json = struct.unpack_from("<I", raw, 12)[0]
    doc = json.loads(raw[20:20 + n_json])
    binary = raw[20 + n_json + 8:]
    (tmp_path / "tube.bin").write_bytes(binary)
    doc["buffers"][0]["uri"] = "tube.bin"
    (tmp_path / "tube.gltf").write_text(json.dumps(doc))
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(binary).decode()
    (tmp_path / "embedded.gltf").write_text(json.dumps(doc))
    del doc["skins"][0]["inverseBindMatrices"]       # bind pose from the joint nodes' transforms instead
    doc["nodes"][0]["rotation"] = [0.0, 0.0, 0.0, 1.0]
    (tmp_path / "no_ibm.gltf").write_text(json.dumps(doc))
    assert np.allclose(read_skinned_gltf(tmp_path / "no_ibm.gltf").bind_positions, a.bind_positions, atol=1e-6)
    for name in ("tube.gltf", "embedded.gltf"):
        b = read_skinned_gltf(tmp_path / name)
        for field in ("vertices", "normals", "faces", "joints", "weights", "bind_positions"):
            assert np.array_equal(getattr(a, field), getattr(b, field)), (name, field)


def _one_line_error(exc, *needles):
    text = str(exc.value)
    assert "\n" not in text
    for n in needles:
        assert n in text, (n, text)


def test_bad_input_gives_one_line_errors_naming_the_file(tmp_path):
    synthetic_character(tmp_path / "tube.glb")
    raw = (tmp_path / "tube.glb").read_bytes()
    n_json = struct.unpack_from("<I", raw, 12)[0]
    doc = json.loads(raw[20:20 + n_json])
    del doc["skins"]
    doc["nodes"][-1].pop("skin")
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(raw[20 + n_json + 8:]).decode()
    (tmp_path / "noskin.gltf").write_text(json.dumps(doc))
    with pytest.raises(InputError) as exc:
        read_skinned_gltf(tmp_path / "noskin.gltf")
    _one_line_error(exc, "noskin.gltf", "no skinned mesh")
    (tmp_path / "junk.glb").write_bytes(b"glTF\x01\x00")
    with pytest.raises(InputError) as exc:
        read_skinned_gltf(tmp_path / "junk.glb")
    _one_line_error(exc, "junk.glb")
    # a motion none of whose joints the shipped maps know
    odd = Motion.from_positions(TPOSE[None], [f"j{k}" for k in range(len(NAMES))], 30.0, PARENTS,
                                source="odd_names.bvh")
    with pytest.raises(InputError) as exc:
        STYLES["character"].mesh(odd, RenderSettings(), 1.0)
    _one_line_error(exc, "odd_names.bvh", "map onto the character")
    # a user map naming a joint the character or the motion does not have
    character = load_character()
    for text, needle in (("LeftArm: LeftShoulder\nNose: Head\n", "'Nose'"),
                         ("LeftArm: LeftBicep\n", "'LeftBicep'"),
                         ("LeftArm: [LeftShoulder\n", "YAML")):
        (tmp_path / "user.yaml").write_text(text)
        with pytest.raises(InputError) as exc:
            CharacterMesh(character, NAMES, TPOSE[None], joint_map=tmp_path / "user.yaml")
        _one_line_error(exc, "user.yaml", needle)


def test_the_shipped_maps_fit_the_shipped_character_and_are_chosen_by_the_motion_names():
    character = load_character()
    assert len(character.faces) <= 12_000 and DEFAULT_CHARACTER.stat().st_size < 2_000_000
    for name, entries in shipped_maps().items():
        assert set(entries) <= set(character.joint_names), name
    smplx = ["pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2", "spine3", "neck",
             "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder", "left_elbow", "right_elbow",
             "left_wrist", "right_wrist"]
    cases = {"smplx": smplx, "genea2023": genea2023_standin().joint_names,
             "classic": load_motion(sample_path("mocapbank")).joint_names,
             "mixamo": load_motion(sample_path("walk01")).joint_names}
    for expected, names in cases.items():
        assert choose_map(character.joint_names, names)[0] == expected


def _ring(character, joint, child, frac, width=0.02, radius=0.07):
    """Bind-pose vertices within ``width`` of the plane across bone joint->child at ``frac`` of its length."""
    j, e = character.joint_names.index(joint), character.joint_names.index(child)
    a = character.bind_positions[e] - character.bind_positions[j]
    length = np.linalg.norm(a)
    a /= length
    rel = character.vertices - (character.bind_positions[j] + frac * length * a)
    along = rel @ a
    radial = np.linalg.norm(rel - along[:, None] * a, axis=1)
    return np.flatnonzero((np.abs(along) < width) & (radial < radius))


def _area(points):
    """Area of the convex hull of a ring of points in its best-fitting plane."""
    pts = points - points.mean(axis=0)
    basis = np.linalg.svd(pts, full_matrices=False)[2][:2]
    return ConvexHull(pts @ basis.T).volume


def ring_ratios(mesh, positions) -> dict:
    """Cross-section area of the wrist, shoulder and elbow rings posed / at rest, per frame."""
    c = mesh.character
    rings = {}
    for s in ("Left", "Right"):
        rings[f"{s} wrist"] = _ring(c, s + "ForeArm", s + "Hand", 1.0)
        rings[f"{s} shoulder"] = _ring(c, s + "Arm", s + "ForeArm", 0.1)
        rings[f"{s} elbow"] = _ring(c, s + "Arm", s + "ForeArm", 1.0)
    verts, _ = mesh.vertices(positions)
    out = {}
    for name, idx in rings.items():
        assert len(idx) >= 8, name
        rest = _area(c.vertices[idx]) * mesh.rig.scale ** 2
        out[name] = np.array([_area(v[idx]) / rest for v in verts])
    return out


def _twisted_genea(degrees):
    """The GENEA 2023 stand-in with both hands turned about the forearm (pronation) and the arms swinging."""
    m = genea2023_standin()
    values = m.values.copy()
    start = {n: int(s) for n, s in zip(m.skeleton.names, m.skeleton.channel_starts)}
    for s in ("l", "r"):
        values[:, start[f"b_{s}_wrist"] + 1] = degrees                                    # Xrotation
        values[:, start[f"b_{s}_arm"] + 2] = 40 * np.sin(np.linspace(0, 6, len(values)))   # Yrotation
    return Motion(m.skeleton, values, m.fps, name=f"twist{degrees}")


@pytest.mark.parametrize("degrees", [-80, 80, 120])
def test_no_candy_wrapping_when_the_hands_turn_about_the_forearm(degrees):
    settings = RenderSettings()
    motion = prepare_motions([_twisted_genea(degrees)], settings)[0]
    mesh = CharacterMesh(load_character(), motion.joint_names, motion.positions())
    assert mesh.map_name == "genea2023"
    for name, ratio in ring_ratios(mesh, motion.positions()).items():
        assert ratio.min() >= 0.75 and ratio.max() <= 1.25, (name, ratio.min(), ratio.max())


def _silhouette_checks(img, background=255):
    mask = np.any(img < background - 8, axis=-1)
    h, w = mask.shape
    frac = mask.mean()
    assert 0.03 < frac < 0.6, frac
    ys, xs = np.nonzero(mask)
    assert abs(xs.mean() - w / 2) < 0.15 * w and abs(ys.mean() - h / 2) < 0.25 * h
    return mask


def test_the_shipped_character_renders_a_genea2023_like_bvh(tmp_path):
    m = genea2023_standin()
    path = tmp_path / "genea.bvh"
    write_bvh(path, m.skeleton, m.values, 1.0 / m.fps)
    settings = RenderSettings(body="character", width=320, height=240, msaa=0)
    motions = prepare_motions([path], settings)
    mesh = STYLES["character"].mesh(motions[0], settings, 1.0)
    assert mesh.map_name == "genea2023" and len(mesh.rig.mapping) >= 45     # fingers included
    img = render_frames(motions, settings, frames=[10])[0]
    _silhouette_checks(img)


def test_the_shipped_character_follows_extreme_poses_of_a_real_bvh():
    settings = RenderSettings(body="character", width=320, height=240, msaa=0)
    motions = prepare_motions([sample_path("mocapbank")], settings)
    m = motions[0]
    P, names = m.positions(), m.joint_names
    picks = set()
    for s in ("Left", "Right"):
        sh, el, wr = (names.index(s + j) for j in ("Shoulder", "Elbow", "Wrist"))
        upper, fore = P[:, el] - P[:, sh], P[:, wr] - P[:, el]
        elevation = upper[:, 1] / np.linalg.norm(upper, axis=-1)
        flexion = np.einsum("fi,fi->f", upper, fore) / np.linalg.norm(upper, axis=-1) / np.linalg.norm(fore, axis=-1)
        picks |= {int(np.argmax(elevation)), int(np.argmin(elevation)), int(np.argmin(flexion))}
    frames = sorted(picks)
    mesh = CharacterMesh(load_character(), names, P)
    assert mesh.map_name == "classic"
    for name, ratio in ring_ratios(mesh, P[frames]).items():
        assert ratio.min() >= 0.75 and ratio.max() <= 1.25, (name, ratio.min(), ratio.max())
    # every posed bone points where the motion's does; the limbs also have the motion's lengths
    _, pos = mesh.rig.pose(P[frames])
    for cj, (e, _) in mesh.rig.segment.items():
        d_motion = P[frames][:, mesh.rig.mapping[e]] - P[frames][:, mesh.rig.mapping[cj]]
        d_char = pos[:, e] - pos[:, cj]
        cos = np.einsum("fi,fi->f", d_motion, d_char) / np.linalg.norm(d_motion, axis=-1) / np.linalg.norm(
            d_char, axis=-1)
        assert np.all(cos > 0.9999), mesh.rig.names[cj]
        if cj in mesh.rig.limbs:
            assert np.allclose(np.linalg.norm(d_char, axis=-1), np.linalg.norm(d_motion, axis=-1), rtol=1e-6)
    assert {mesh.rig.names[j] for j in mesh.rig.limbs} == {f"{s}{b}" for s in ("Left", "Right")
                                                          for b in ("Arm", "ForeArm", "UpLeg", "Leg")}
    for img in render_frames(motions, settings, frames=frames[:2]):
        _silhouette_checks(img)


def test_a_character_file_with_a_joint_map_beside_it_renders_through_the_settings(tmp_path):
    synthetic_character(tmp_path / "tube.glb")
    (tmp_path / "identity.yaml").rename(tmp_path / "tube.joints.yaml")
    settings = RenderSettings(body="character", character=str(tmp_path / "tube.glb"), width=160, height=120,
                              msaa=0)
    img = render_frames([arm_motion()], settings, frames=[3])[0]
    assert np.any(img < 200)


def test_a_motion_in_the_characters_rest_pose_leaves_the_mesh_as_modelled():
    """SMPL-X joint names on the character's own bind positions (in centimetres): every bone keeps its rest
    rotation, so the skinned mesh is the modelled one, scaled by 100 and shifted with the root."""
    character = load_character()
    entries = shipped_maps()["smplx"]
    names, rows = [], []
    for cj, motion_names in entries.items():
        names.append(motion_names[0])
        rows.append(character.bind_positions[character.joint_names.index(cj)] * 100.0 + [5.0, 0.0, -3.0])
    rest = np.array(rows)[None].repeat(3, axis=0)
    mesh = CharacterMesh(character, names, rest)
    assert mesh.map_name == "smplx" and mesh.rig.scale == pytest.approx(100.0)
    verts, norms = mesh.vertices(rest)
    assert np.allclose(verts, character.vertices * 100.0 + [5.0, 0.0, -3.0], atol=1e-3)
    assert np.allclose(norms, character.normals, atol=1e-4)


@pytest.mark.parametrize("framing", ["full", "above-knees", "upper"])
def test_four_inputs_are_drawn_centred_with_visible_hands(tmp_path, monkeypatch, framing):
    """GENEA 2023 and BEAT-style BVH, an SMPL-X recording and a positions file (body_helpers' stand-ins)."""
    from body_helpers import four_inputs

    from renderers.render import view_for
    from renderers.styles.bones import joint_kinds

    for name, path in four_inputs(tmp_path, monkeypatch).items():
        settings = RenderSettings(width=160, height=120, body="character", framing=framing, msaa=0)
        ms = prepare_motions([path], settings)
        view = view_for(ms, settings)
        img = render_frames(ms, settings, view=view)[0]
        sil = np.any(np.abs(img.astype(int) - 255) > 12, axis=2)
        assert 0.05 < sil.mean() < 0.5, f"{name} {framing}: silhouette covers {sil.mean():.3f} of the picture"
        cx = np.nonzero(sil)[1].mean() / 160
        assert abs(cx - 0.5) < 0.05, f"{name} {framing}: silhouette centroid at {cx:.3f} of the width"
        assert not sil[:, :2].any() and not sil[:, -2:].any(), f"{name} {framing}: clipped at a side"
        # the character's own wrists (its proportions, the motion's limb lengths) are in the picture and drawn,
        # and near the motion's wrists (within a tenth of the picture's height)
        m = ms[0]
        mesh = STYLES["character"].mesh(m, settings, view.size)
        _, pos = mesh.rig.pose(m.positions()[:1])
        wrists = [mesh.rig.names.index(n) for n in ("LeftHand", "RightHand")]
        uv = view.camera.project(pos[0, wrists])
        hit = [sil[max(int(v) - 2, 0):int(v) + 3, max(int(u) - 2, 0):int(u) + 3].any() for u, v in uv]
        assert all(hit), f"{name} {framing}: a hand is not drawn"
        motion_wrists = [j for j, k in enumerate(joint_kinds(m.joint_names, m.parents)) if k == "wrist"]
        target = view.camera.project(m.positions()[0, motion_wrists])
        gap = min(np.linalg.norm(uv - target, axis=-1).max(), np.linalg.norm(uv - target[::-1], axis=-1).max())
        assert len(motion_wrists) == 2 and gap < 12, f"{name} {framing}: a hand is {gap:.1f} px from its wrist"


def test_a_blank_face_is_a_smooth_white_mask():
    """face="blank" (the GENEA Leaderboard's face mask): the nose and lips are pulled back onto the head's
    ellipsoid and coloured as the mask; nothing else of the body changes."""
    from renderers.figure import srgb_to_linear
    from renderers.styles.character import MASK_COLOR, SKIN_COLOR

    character = load_character()
    names = ["Hips", "Spine", "Spine1", "Spine2", "Neck", "Head", "LeftShoulder", "LeftArm", "RightShoulder",
             "RightArm"]
    rest = np.array([character.bind_positions[character.joint_names.index(n)] for n in names])[None] * 100.0
    visible = CharacterMesh(character, names, rest)
    blank = CharacterMesh(character, names, rest, face="blank")
    v_vis, _ = visible.vertices(rest)
    v_blank, n_blank = blank.vertices(rest)
    forward = blank.rig.forward
    head = character.joint_names.index("Head")
    dominant = character.joints[np.arange(len(character.vertices)), np.argmax(character.weights, axis=1)]
    on_head = np.flatnonzero(dominant == head)
    nose = on_head[np.argmax(character.vertices[on_head] @ forward)]      # the head's frontmost vertex
    assert (v_vis[0, nose] - v_blank[0, nose]) @ forward > 0.5    # cm: pulled back
    moved = np.linalg.norm(v_vis[0] - v_blank[0], axis=-1) > 1e-4
    assert moved.any() and np.all(dominant[moved] == head)
    assert np.allclose(blank.colors[nose], srgb_to_linear(MASK_COLOR), atol=1e-5)
    off_head = np.ones(len(moved), dtype=bool)
    off_head[on_head] = False
    assert np.allclose(blank.colors[off_head], srgb_to_linear(SKIN_COLOR), atol=1e-5)
    assert np.allclose(visible.colors, srgb_to_linear(SKIN_COLOR), atol=1e-5)
    assert np.allclose(np.linalg.norm(n_blank, axis=-1), 1.0, atol=1e-4)
