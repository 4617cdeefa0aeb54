"""The mannequin: a neutral body for any skeleton, from joint positions alone.

Every part is one *tapered elliptic capsule*: two half-ellipsoids with semi-axes ``r0`` (at end ``a``) and ``r1``
(at end ``b``) joined by a tapered tube; with ``a == b`` it is an ellipsoid. For a template vertex with unit
offset ``u`` (on a UV sphere split at its equator, ``e`` = 0 on ``a``'s half and 1 on ``b``'s) and the part's axes
``X, Y, Z`` (rows of ``A``, ``Z`` along the bone)::

    r      = r0 + e (r1 - r0)                    semi-axes (3,)
    vertex = a + e (b - a) + (r * u) @ A         (F, N, V, 3)
    normal = normalise(u / r) @ A                (the ellipsoid's normal; smooth shading)

so a frame block costs two broadcast matrix products per part group (``r * u`` and ``u / r`` are constant per
clip). Parts (radii as fractions of the figure size ``s`` shared by the conditions of a segment):

- a capsule per bone, radii by the kinds of its joints (:mod:`renderers.styles.bones`): shoulder 0.030 s, elbow
  0.023 s, wrist 0.018 s, hip 0.050 s, knee 0.033 s, ankle 0.022 s...; fingers 0.0075 s; bones of no known kind by
  their length;
- a torso: the spine bones as capsules flattened front to back (half-widths from the hip and shoulder joints'
  spacing, waist narrower), plus a pelvis capsule between the hip joints; arms read in front of or behind it;
- a head ellipsoid beyond the head joint (along neck -> head) facing ``forward = (left - right) x up`` (the
  shoulder line); ``face="visible"`` adds a nose and a dark visor at eye level, ``"blank"`` leaves a plain head
  (a face mask, as the GENEA Leaderboard's stimuli); joints below the head (jaw, eyes, head top) are not drawn;
- a mitten (a flat capsule along forearm -> wrist) on each wrist without finger joints, a foot (pointing forward)
  on each ankle without a toe joint;
- a soft contact shadow: a disc under the feet (or root) on the floor, darkest at its centre and fading to the
  floor colour at its rim, when the view has a floor (``floor_height``, set by the renderer).

All parts are written into ONE vertex array per frame, one body colour (no left/right colours).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from renderers.figure import LEFT, RIGHT, head_index, joint_sides, srgb_to_linear
from renderers.styles import BodyStyle
from renderers.styles.bones import body_scale, bone_classes, descendants, joint_kinds

# radius of a limb at a joint of this kind, and default radii of bone classes (fractions of the figure size)
JOINT_RADIUS = {"shoulder": 0.030, "arm_mid": 0.027, "elbow": 0.023, "forearm_mid": 0.021, "wrist": 0.018,
                "hip": 0.050, "knee": 0.033, "ankle": 0.022, "toe": 0.016, "clavicle": 0.028, "neck": 0.027,
                "head": 0.026}
CLASS_RADIUS = {"neck": 0.027, "clavicle": 0.028, "upperarm": 0.028, "forearm": 0.020, "palm": 0.011,
                "finger": 0.0075, "pelvis": 0.050, "thigh": 0.045, "shin": 0.030, "foot": 0.020}
HEAD = np.array([0.047, 0.062, 0.055])       # head semi-axes: lateral, up, forward
SHADOW_RINGS = np.array([0.0, 0.07, 0.14, 0.21])
SHADOW_DARKNESS = np.array([0.55, 0.62, 0.82, 1.0])


def _template(sections: int, rings: int):
    """Unit offsets ``u`` (V, 3), end flags ``e`` (V,) and faces of a UV sphere split at its equator."""
    lat = np.concatenate([np.linspace(-np.pi / 2, 0.0, rings + 1), np.linspace(0.0, np.pi / 2, rings + 1)])
    ends = np.repeat([0.0, 1.0], rings + 1)
    lon = np.linspace(0.0, 2 * np.pi, sections, endpoint=False)
    u = np.stack([np.cos(lat)[:, None] * np.cos(lon)[None], np.cos(lat)[:, None] * np.sin(lon)[None],
                  np.repeat(np.sin(lat)[:, None], sections, axis=1)], axis=-1).reshape(-1, 3)
    e = np.repeat(ends, sections)
    rows, k = len(lat), np.arange(sections)
    faces = []
    for i in range(rows - 1):
        a, b = i * sections + k, i * sections + (k + 1) % sections
        c, d = a + sections, b + sections
        faces += [np.stack([a, b, d], 1), np.stack([a, d, c], 1)]
    return u, e, np.concatenate(faces)


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > 1e-9, v / np.maximum(n, 1e-12), fallback)


def _axes(z: np.ndarray, ref: np.ndarray, alt: np.ndarray) -> np.ndarray:
    """Rows X, Y, Z ``(..., 3, 3)``: Z given, X = ``ref`` made orthogonal to Z (``alt`` where ref is nearly
    parallel to Z), Y = Z x X."""
    ref = np.where(np.abs(np.sum(ref * z, -1, keepdims=True)) > 0.95, alt, ref)
    x = _unit(ref - np.sum(ref * z, -1, keepdims=True) * z, np.array([1.0, 0.0, 0.0]))
    return np.stack([x, np.cross(z, x), z], axis=-2)


def _mittens(kinds, parents) -> list[tuple[int, int]]:
    """(wrist, its parent) of each topmost wrist joint without finger joints below it."""
    return [(j, int(p)) for j, p in enumerate(parents) if kinds[j] == "wrist" and p >= 0 and kinds[p] != "wrist"
            and not any(kinds[c] == "finger" for c in np.flatnonzero(descendants(parents, j)))]


class _Parts:
    """Parts of one template: semi-axes ``r0``/``r1`` (N, 3) at their two ends, colour (3,)."""

    def __init__(self, template, r0, r1, color):
        u, e, faces = template
        self.n = len(r0)
        r = np.asarray(r0, float)[:, None] + e[None, :, None] * (np.asarray(r1, float) - np.asarray(r0, float))[:, None]
        self.offsets = r * u[None]                                        # (N, V, 3)
        self.normals = _unit(u[None] / np.maximum(r, 1e-12), np.array([0.0, 0.0, 1.0]))
        self.e = e[None, None, :, None]
        self.faces, self.nv, self.color = faces, len(u), np.asarray(color, float)

    def place(self, a, b, axes):
        """Vertices and normals ``(F, N * V, 3)`` for ends ``a``, ``b`` ``(F, N, 3)`` and axes ``(F, N, 3, 3)``."""
        f = len(a)
        v = a[:, :, None] + self.e * (b - a)[:, :, None] + np.matmul(self.offsets[None], axes)
        n = np.matmul(self.normals[None], axes)
        return v.reshape(f, -1, 3), n.reshape(f, -1, 3)


class MannequinMesh:
    """Joint positions ``(F, J, 3)`` -> the mannequin's triangles (see the module doc).

    ``rest_positions`` ``(T, J, 3)`` (the clip) give bone lengths, widths and the torso's proportions;
    ``face`` is ``"visible"`` or ``"blank"``; ``floor_height`` (None: no contact shadow) may be set before the
    first :meth:`vertices` call.
    """

    def __init__(self, joint_names, parents, rest_positions, size: float, *, up=(0.0, 1.0, 0.0),
                 face: str = "visible", body_color=(0.62, 0.63, 0.66), visor_color=(0.16, 0.17, 0.20),
                 floor_color=(0.80, 0.80, 0.78)):
        names = list(joint_names)
        par = np.asarray(parents, dtype=np.int64)
        rest = np.asarray(rest_positions, float)
        med = np.nanmedian(rest, axis=0) if len(rest) else np.zeros((len(names), 3))
        med = np.nan_to_num(med)
        self.size, self.up = body_scale(names, par, rest, float(size)), np.asarray(up, float)
        self.floor_height: float | None = None
        kinds = joint_kinds(names, par)
        sides = joint_sides(names)
        lengths = np.array([np.linalg.norm(med[j] - med[p]) if p >= 0 else 0.0 for j, p in enumerate(par)])
        classes = bone_classes(names, par, lengths, self.size)
        head = head_index(names)
        skip = descendants(par, head) if head is not None else np.zeros(len(names), bool)
        self.head, self.head_parent = head, (int(par[head]) if head is not None else -1)
        # left/right reference joints (the shoulder line; else hips; else any sided joint)
        for group in (("clavicle", "shoulder"), ("hip",), None):
            pick = np.array([group is None or k in group for k in kinds])
            left, right = np.flatnonzero(pick & (sides == LEFT)), np.flatnonzero(pick & (sides == RIGHT))
            if len(left) and len(right):
                break
        self._left, self._right = left, right
        s = self.size
        # torso: spine bones (and the pelvis) flattened front to back, proportions from the skeleton
        hips = [np.flatnonzero((np.array(kinds) == "hip") & (sides == side)) for side in (LEFT, RIGHT)]
        shoulders = [np.flatnonzero((np.array(kinds) == "shoulder") & (sides == side)) for side in (LEFT, RIGHT)]
        hip_half = (np.linalg.norm(med[hips[0][0]] - med[hips[1][0]]) / 2 / s
                    if len(hips[0]) and len(hips[1]) else 0.05)
        sh_half = (np.linalg.norm(med[shoulders[0][0]] - med[shoulders[1][0]]) / 2 / s
                   if len(shoulders[0]) and len(shoulders[1]) else 0.11)
        hip_w, chest_w = np.clip(hip_half + 0.05, 0.08, 0.115), np.clip(0.78 * sh_half, 0.07, 0.10)
        roots = np.flatnonzero(par < 0)
        root = int(roots[0]) if len(roots) else 0
        neck = next((j for j, k in enumerate(kinds) if k == "neck"), self.head_parent if head is not None else -1)
        span = med[neck] - med[root] if neck >= 0 else np.zeros(3)
        height = float(np.linalg.norm(span))

        def torso(j):
            t = float(np.clip(np.dot(med[j] - med[root], span) / height ** 2, 0.0, 1.0)) if height > 0 else 0.5
            rx = np.interp(t, [0.0, 0.35, 0.75, 1.0], [hip_w, 0.85 * hip_w, chest_w, 0.9 * chest_w])
            ry = np.interp(t, [0.0, 0.35, 0.75, 1.0], [0.062, 0.055, 0.066, 0.052])
            return np.array([rx, ry, 0.7 * min(rx, ry)]) * s

        limbs, trunk = [], []
        for j, p in enumerate(par):
            cl = classes[j]
            if p < 0 or skip[j] or cl in ("hand", "head_end") or lengths[j] < 1e-6 * s:
                continue
            if cl == "spine":
                trunk.append((p, j, torso(p), torso(j)))
                continue
            if cl in ("finger", "palm"):
                r0 = r1 = CLASS_RADIUS[cl] * s
                r0, r1 = min(r0, 0.45 * lengths[j]), min(0.85 * r1, 0.45 * lengths[j])
            else:
                r0 = JOINT_RADIUS.get(kinds[p], CLASS_RADIUS.get(cl, 0.02)) * s
                r1 = JOINT_RADIUS.get(kinds[j], CLASS_RADIUS.get(cl, 0.02)) * s
                if cl == "clavicle" and kinds[p] not in JOINT_RADIUS:
                    r0 = CLASS_RADIUS["clavicle"] * s
            limbs.append((p, j, np.full(3, r0), np.full(3, r1)))
        # the pelvis between the hip joints, the shoulder line between the shoulder joints
        for pair, r in ((hips, np.array([0.05, 0.05, 0.045])), (shoulders, np.array([0.034, 0.04, 0.034]))):
            if len(pair[0]) and len(pair[1]):
                trunk.append((int(pair[1][0]), int(pair[0][0]), r * s, r * s))
        # mittens on wrists without fingers (the topmost wrist joint of a chain)
        self._mittens = _mittens(kinds, par)
        # a foot on each ankle without a toe joint below it (legs that end at the ankle)
        self._stubs = [j for j, k in enumerate(kinds) if k == "ankle" and par[j] >= 0
                       and not any(kinds[c] == "toe" for c in np.flatnonzero(par == j))]
        body = srgb_to_linear(body_color)
        # tessellation: triangles cost on a CPU rasteriser, so limbs (whose ends hide in their neighbours) get
        # fewer rings than the torso, fingers fewer sections
        fine, limb, coarse = _template(12, 3), _template(10, 2), _template(6, 2)
        fingers = [b for b in limbs if b[2][0] < 0.012 * s]
        limbs = [b for b in limbs if b[2][0] >= 0.012 * s]
        self._groups: list[tuple[str, Any, _Parts]] = []

        def add(kind, idx, template, r0, r1, color):
            if len(r0):
                self._groups.append((kind, idx, _Parts(template, np.asarray(r0), np.asarray(r1), color)))

        for kind, bones, tpl in (("trunk", trunk, fine), ("limb", limbs, limb), ("limb", fingers, coarse)):
            idx = (np.array([b[0] for b in bones], int), np.array([b[1] for b in bones], int))
            add(kind, idx, tpl, [b[2] for b in bones], [b[3] for b in bones], body)
        m = len(self._mittens)
        add("mitten", None, limb, np.tile([0.013, 0.024, 0.02], (m, 1)) * s,
            np.tile([0.012, 0.028, 0.03], (m, 1)) * s, body)
        f = len(self._stubs)
        add("foot", None, limb, np.tile([0.024, 0.02, 0.02], (f, 1)) * s, np.tile([0.022, 0.014, 0.016], (f, 1)) * s,
            body)
        self.face = face
        if head is not None:
            add("head", None, _template(16, 5), [HEAD * s], [HEAD * s], body)
            if face == "visible":
                add("nose", None, _template(6, 2), [np.array([0.009, 0.014, 0.016]) * s],
                    [np.array([0.009, 0.014, 0.016]) * s], body)
                visor = HEAD * s * [0.9, 0.2, 0.62]
                add("visor", None, _template(12, 3), [visor], [visor], srgb_to_linear(visor_color))
        # contact shadow: a fan of rings around the centre
        seg = 24
        k = np.arange(seg)
        faces = [np.stack([np.zeros(seg, int), 1 + (k + 1) % seg, 1 + k], 1)]     # counter-clockwise seen from above
        for ring in range(len(SHADOW_RINGS) - 2):
            a, b = 1 + ring * seg + k, 1 + ring * seg + (k + 1) % seg
            faces += [np.stack([a, b + seg, a + seg], 1), np.stack([a, b, b + seg], 1)]
        self._disc_faces = np.concatenate(faces)
        ang = 2 * np.pi * k / seg
        self._disc_unit = np.stack([np.cos(ang), np.sin(ang)], 1)
        floor = srgb_to_linear(floor_color)
        self._disc_colors = np.concatenate([[floor * SHADOW_DARKNESS[0]]] + [
            np.repeat((floor * d)[None], seg, 0) for d in SHADOW_DARKNESS[1:]])
        self._feet = np.flatnonzero(np.isin(kinds, ["ankle", "toe"]))
        self._root = root
        faces, colors, offset = [], [], 0
        for _, _, parts in self._groups:
            faces.append((parts.faces[None] + offset + parts.nv * np.arange(parts.n)[:, None, None]).reshape(-1, 3))
            colors.append(np.repeat(parts.color[None], parts.n * parts.nv, 0))
            offset += parts.n * parts.nv
        faces.append(self._disc_faces + offset)
        colors.append(self._disc_colors)
        self.faces = np.concatenate(faces).astype(np.uint32)
        self.colors = np.concatenate(colors).astype(np.float32)
        self.n_vertices = offset + len(self._disc_colors)

    def frame_axes(self, pos: np.ndarray):
        """Per-frame lateral (figure's left), forward and up unit vectors ``(F, 3)`` each."""
        up = np.broadcast_to(self.up, (len(pos), 3))
        if len(self._left):
            lr = pos[:, self._left].mean(1) - pos[:, self._right].mean(1)
            lateral = _unit(lr - np.sum(lr * up, -1, keepdims=True) * up, np.array([1.0, 0.0, 0.0]))
        else:
            lateral = np.broadcast_to(np.cross(self.up, [0.0, 0.0, 1.0]) if abs(self.up[2]) < 0.9
                                      else np.array([1.0, 0.0, 0.0]), (len(pos), 3))
        forward = np.cross(lateral, up)
        return lateral, forward, up

    def vertices(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vertex positions and normals ``(F, V, 3)`` float32 for joint positions ``(F, J, 3)``."""
        pos = np.nan_to_num(np.asarray(positions, dtype=np.float64))
        s = self.size
        lateral, forward, up = self.frame_axes(pos)
        vs, ns = [], []
        head = None
        for kind, idx, parts in self._groups:
            if kind in ("trunk", "limb"):
                a, b = pos[:, idx[0]], pos[:, idx[1]]
                z = _unit(b - a, up[:, None])
                axes = _axes(z, lateral[:, None], forward[:, None])
            elif kind == "mitten":
                w = pos[:, [m[0] for m in self._mittens]]
                d = _unit(w - pos[:, [m[1] for m in self._mittens]], -up[:, None])
                a, b = w + 0.012 * s * d, w + 0.07 * s * d
                axes = _axes(d, np.broadcast_to(up[:, None], d.shape), lateral[:, None])
            elif kind == "foot":
                ankle = pos[:, self._stubs] - 0.012 * s * up[:, None]
                a, b = ankle, ankle + (0.085 * forward[:, None] - 0.01 * up[:, None]) * s
                axes = _axes(_unit(b - a, forward[:, None]), lateral[:, None], up[:, None])
            else:
                if head is None:
                    h = pos[:, self.head]
                    u = _unit(h - pos[:, self.head_parent], up) if self.head_parent >= 0 else up
                    fwd = _unit(forward - np.sum(forward * u, -1, keepdims=True) * u, forward)
                    head = (h + 0.55 * HEAD[1] * s * u, np.stack([np.cross(u, fwd), u, fwd], -2), u, fwd)
                c, axes, u, fwd = head
                if kind == "nose":
                    c = c + (0.97 * HEAD[2] * fwd - 0.12 * HEAD[1] * u) * s
                elif kind == "visor":
                    c = c + (0.5 * HEAD[2] * fwd + 0.16 * HEAD[1] * u) * s
                a = b = c[:, None]
                axes = axes[:, None]
            v, n = parts.place(a, b, axes)
            vs.append(v)
            ns.append(n)
        vs.append(self._disc(pos, lateral, forward, up))
        ns.append(np.broadcast_to(up[:, None], vs[-1].shape))
        return (np.concatenate(vs, 1).astype(np.float32), np.concatenate(ns, 1).astype(np.float32))

    def _disc(self, pos, lateral, forward, up):
        """The contact shadow's vertices: centred under the feet (or root) on the floor; collapsed into the
        root when there is no floor."""
        if self.floor_height is None:
            return np.repeat(pos[:, self._root][:, None], len(self._disc_colors), 1)
        centre = pos[:, self._feet].mean(1) if len(self._feet) else pos[:, self._root]
        centre = centre - np.sum(centre * up, -1, keepdims=True) * up + (self.floor_height + 0.002 * self.size) * up
        cos, sin = self._disc_unit[None, :, 0:1], self._disc_unit[None, :, 1:2]
        ring = cos * lateral[:, None] + sin * forward[:, None]                      # (F, seg, 3)
        return np.concatenate([centre[:, None]] + [centre[:, None] + r * self.size * ring
                                                   for r in SHADOW_RINGS[1:]], 1)


class MannequinStyle(BodyStyle):
    name = "mannequin"
    description = "a neutral body of tapered capsules with a torso, a head facing forward and hands (any skeleton)"
    floor = True       # drawn on a floor with a soft contact shadow unless the settings say otherwise
    frame_pad = 0.05   # the body's thickness beyond its joints, as a fraction of the figure size (framing)

    def frame_points(self, positions: np.ndarray, names, parents, size: float) -> np.ndarray:
        """Points ``(N, 3)`` the camera must also frame: the mitten tips (0.1 scale beyond wrists without fingers)
        and the head's extremes (its centre lies beyond the head joint), the scale being :func:`body_scale`'s."""
        if parents is None:
            return np.zeros((0, 3))
        pos, par = np.asarray(positions, float), np.asarray(parents, dtype=np.int64)
        s, pts = body_scale(names, par, pos, size), [np.zeros((0, 3))]
        mittens = _mittens(joint_kinds(names, par), par)
        if mittens:
            w, p = pos[:, [m[0] for m in mittens]], pos[:, [m[1] for m in mittens]]
            pts.append((w + 0.1 * s * _unit(w - p, np.zeros(3))).reshape(-1, 3))
        head = head_index(names)
        if head is not None and par[head] >= 0:
            h = pos[:, head]
            c = h + 0.55 * HEAD[1] * s * _unit(h - pos[:, par[head]], np.zeros(3))
            pts.append((c[:, None] + np.concatenate([np.eye(3), -np.eye(3)]) * HEAD.max() * s).reshape(-1, 3))
        return np.concatenate(pts)

    def mesh(self, motion: Any, settings: Any, size: float) -> MannequinMesh:
        from renderers.camera import UP_AXES

        style = settings.style
        return MannequinMesh(motion.joint_names, motion.parents, motion.positions(), size,
                             up=UP_AXES[settings.up_axis], face=getattr(settings, "face", "visible"),
                             body_color=style.body_color, visor_color=style.visor_color,
                             floor_color=style.floor_color)


STYLE = MannequinStyle()
