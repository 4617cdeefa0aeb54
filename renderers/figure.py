"""The stick figure: which joint is left/right/head/leg, its style, and its triangle mesh.

The mesh of one frame is every joint as a sphere, every bone as a cylinder (the joint
spheres round off its ends, so bones read as capsules) and an optional head marker, all
pre-transformed in numpy into ONE vertex array with per-vertex colours: a single draw call
per frame, which is what matters for speed on a CPU rasteriser. Vertices are computed for a
block of frames at once (vectorised over frames, joints and template vertices).
"""
from __future__ import annotations

import functools
import pathlib
import re
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

LEFT, RIGHT, CENTRE = 0, 1, 2

_LEFT_RE = re.compile(r"(^|[^a-z])(l|left)([^a-z]|$)")
_RIGHT_RE = re.compile(r"(^|[^a-z])(r|right)([^a-z]|$)")
# Leg joints (not the root 'Hips'): framed out by the upper-body framing.
_LEG_RE = re.compile(r"(upleg|up_leg|leg|knee|ankle|foot|feet|toe|thigh|shin|calf|"
                     r"(^|[^a-z])(left|right|l|r)_?hip($|[^a-z]))")


def joint_side(name: str) -> int:
    """LEFT, RIGHT or CENTRE from a joint name (``LeftArm``, ``b_l_wrist``, ``L_Hand``, ``LHip``)."""
    low = name.lower()
    tail = low.rsplit(":", 1)[-1]   # drop namespaces such as 'mixamorig:'
    if tail.startswith("left") or "left" in tail or _LEFT_RE.search(tail) or re.match(r"^L[A-Z]", name.rsplit(":", 1)[-1]):
        return LEFT
    if tail.startswith("right") or "right" in tail or _RIGHT_RE.search(tail) or re.match(r"^R[A-Z]", name.rsplit(":", 1)[-1]):
        return RIGHT
    return CENTRE


def joint_sides(names) -> np.ndarray:
    return np.array([joint_side(n) for n in names], dtype=np.int64)


def leg_mask(names) -> np.ndarray:
    """True for leg joints (hips of the legs, knees, ankles, feet, toes)."""
    return np.array([bool(_LEG_RE.search(n.lower().rsplit(":", 1)[-1])) for n in names], dtype=bool)


def head_index(names) -> int | None:
    """The joint called ``Head`` (or the first whose name contains 'head'), else None."""
    low = [n.lower().rsplit(":", 1)[-1] for n in names]
    for exact in ("head", "b_head"):
        if exact in low:
            return low.index(exact)
    hits = [i for i, n in enumerate(low) if "head" in n and "end" not in n and "top" not in n]
    return hits[0] if hits else None


def srgb_to_linear(c) -> np.ndarray:
    """sRGB colour components in [0, 1] to linear light (the approximation pyrender inverts)."""
    return np.power(np.clip(np.asarray(c, dtype=np.float64), 0.0, 1.0), 2.2)


def body_size(positions: np.ndarray) -> float:
    """Typical size of the figure: median over frames of its largest bounding-box side."""
    pos = np.asarray(positions, float)
    ext = np.ptp(pos, axis=1).max(axis=1)
    ext = ext[np.isfinite(ext)]
    size = float(np.median(ext)) if len(ext) else 0.0
    return size if size > 0 else 1.0


def forward_direction(positions: np.ndarray, names, up: np.ndarray) -> np.ndarray | None:
    """Direction the figure faces, from the mean left-minus-right joint vector, or None.

    With ``up`` = +Y and the figure's left at +X the figure faces +Z: forward = (L - R) x up.
    """
    sides = joint_sides(names)
    left, right = sides == LEFT, sides == RIGHT
    if not left.any() or not right.any():
        return None
    pos = np.asarray(positions, float)
    lr = np.nanmean(pos[:, left], axis=(0, 1)) - np.nanmean(pos[:, right], axis=(0, 1))
    fwd = np.cross(lr, up)
    n = np.linalg.norm(fwd)
    return fwd / n if n > 1e-9 else None


def head_marker_centres(positions: np.ndarray, head: int, head_parent: int, radius: float) -> np.ndarray:
    """Centre ``(T, 3)`` of the head marker: 0.6 radius beyond the head joint, along neck -> head
    (the head joint of most skeletons sits at the base of the skull)."""
    pos = np.asarray(positions, float)
    h = pos[:, head]
    if head_parent < 0:
        return h
    d = h - pos[:, head_parent]
    norm = np.linalg.norm(d, axis=-1, keepdims=True)
    d = np.where(norm > 1e-9, d / np.maximum(norm, 1e-12), 0.0)
    return h + 0.6 * radius * d


TEMPLATES_FILE = pathlib.Path(__file__).resolve().parent / "data" / "stick_templates.npz"
DEFAULT_TESSELLATION = (1, 10)   # FigureStyle's sphere_subdivisions, cylinder_sections: the stored templates


def templates_from_trimesh(sphere_subdivisions: int, cylinder_sections: int) -> dict[str, np.ndarray]:
    """The stick figure's unit parts from trimesh: joint sphere ``s*`` (``icosphere(subdivisions)``), head
    sphere ``h*`` (``icosphere(subdivisions + 1)``) and bone cylinder ``c*`` (radius 1, z from 0 at the parent to
    1 at the child; its side, without end caps); ``*v`` vertices (V, 3), ``*n`` vertex normals (V, 3), ``*f`` faces
    (K, 3)."""
    import trimesh

    cyl = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=cylinder_sections)
    cyl.apply_translation([0.0, 0.0, 0.5])
    out = {}
    for key, mesh in (("s", trimesh.creation.icosphere(subdivisions=sphere_subdivisions, radius=1.0)),
                      ("h", trimesh.creation.icosphere(subdivisions=sphere_subdivisions + 1, radius=1.0))):
        out[key + "v"], out[key + "n"] = np.asarray(mesh.vertices), np.asarray(mesh.vertex_normals)
        out[key + "f"] = np.asarray(mesh.faces)
    # The bone is the cylinder's side alone: its end caps lie inside the joint spheres (a joint is wider than its
    # bones, FigureMesh), where they cost a CPU rasteriser triangles that never show; side normals are radial.
    side = np.abs(np.asarray(cyl.face_normals)[:, 2]) < 0.5
    used, faces = np.unique(np.asarray(cyl.faces)[side], return_inverse=True)
    v = np.asarray(cyl.vertices)[used]
    out["cv"], out["cf"] = v, faces.reshape(-1, 3)
    out["cn"] = np.concatenate([v[:, :2] / np.linalg.norm(v[:, :2], axis=1, keepdims=True), np.zeros((len(v), 1))], 1)
    return out


@functools.lru_cache(maxsize=8)
def stick_templates(sphere_subdivisions: int, cylinder_sections: int) -> dict[str, np.ndarray]:
    """:func:`templates_from_trimesh`, read from ``renderers/data/stick_templates.npz`` for the default
    tessellation (written with ``np.savez`` from that function; a test checks they agree): a rendering command
    then needs neither trimesh nor scipy, about a second of its start."""
    if (sphere_subdivisions, cylinder_sections) == DEFAULT_TESSELLATION and TEMPLATES_FILE.is_file():
        with np.load(TEMPLATES_FILE) as data:
            return {k: data[k] for k in data.files}
    return templates_from_trimesh(sphere_subdivisions, cylinder_sections)


@dataclass(frozen=True)
class FigureStyle:
    """How the figure looks. Radii are fractions of the figure's size (see :func:`body_size`)."""

    joint_radius: float = 0.024
    bone_radius: float = 0.015
    head_radius: float = 0.065
    head_marker: bool = True
    left_color: tuple = (0.10, 0.38, 0.85)     # blue
    right_color: tuple = (0.92, 0.35, 0.08)    # orange
    centre_color: tuple = (0.32, 0.32, 0.35)   # dark grey
    head_color: tuple = (0.45, 0.45, 0.50)
    background: tuple = (1.0, 1.0, 1.0)
    floor: bool | None = None                   # None: the body style's default (the mannequin stands on one)
    shadow: bool = False                        # cast the key light's shadow (on the floor); slower
    floor_color: tuple = (0.80, 0.80, 0.78)
    sphere_subdivisions: int = 1                # joint sphere tessellation (icosphere subdivisions)
    cylinder_sections: int = 10
    body_color: tuple = (0.62, 0.63, 0.66)      # the mannequin's one body colour (neutral grey)
    visor_color: tuple = (0.16, 0.17, 0.20)     # the mannequin's visor (face visible)

    def to_dict(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}

    @classmethod
    def from_dict(cls, d: dict) -> FigureStyle:
        fields = cls.__dataclass_fields__
        values: dict[str, Any] = {k: (tuple(v) if isinstance(v, list) else v) for k, v in d.items() if k in fields}
        return cls(**values)

    def side_colors(self) -> np.ndarray:
        c = np.zeros((3, 3))
        c[LEFT], c[RIGHT], c[CENTRE] = self.left_color, self.right_color, self.centre_color
        return c


class FigureMesh:
    """Turns joint positions ``(F, J, 3)`` into the triangles of the stick figure.

    Faces and colours are the same in every frame; :meth:`vertices` returns per-frame
    positions and normals. ``size`` is the figure size the style's radii scale with (share
    it across the conditions of a segment so no figure looks thicker than another).
    """

    def __init__(self, joint_names, parents, style: FigureStyle, size: float, rest_positions=None):
        self.style = style
        names = list(joint_names)
        parents = np.asarray(parents, dtype=np.int64)
        n = len(names)
        self.n_joints = n
        sides = joint_sides(names)
        colors = style.side_colors()
        r_joint = np.full(n, style.joint_radius * size)
        bones = [(j, int(p)) for j, p in enumerate(parents) if 0 <= p < n and p != j]
        child = np.array([b[0] for b in bones], dtype=np.int64)
        parent = np.array([b[1] for b in bones], dtype=np.int64)
        r_bone = np.full(len(bones), style.bone_radius * size)
        if rest_positions is not None and len(bones):
            # Short bones (fingers) get thinner bones and smaller joints so hands stay legible.
            lengths = np.nanmedian(np.linalg.norm(rest_positions[:, child] - rest_positions[:, parent], axis=-1),
                                   axis=0)
            keep = lengths > 1e-6 * size
            child, parent, lengths, r_bone = child[keep], parent[keep], lengths[keep], r_bone[keep]
            r_bone = np.minimum(r_bone, 0.25 * lengths)
            shortest = np.full(n, np.inf)
            np.minimum.at(shortest, child, lengths)
            np.minimum.at(shortest, parent, lengths)
            r_joint = np.where(np.isfinite(shortest), np.minimum(r_joint, 0.4 * shortest), r_joint)
            # A joint sphere stays a little wider than its bones so it caps their ends.
            widest_bone = np.zeros(n)
            np.maximum.at(widest_bone, child, r_bone)
            np.maximum.at(widest_bone, parent, r_bone)
            r_joint = np.maximum(r_joint, 1.15 * widest_bone)
        self.child, self.parent = child, parent
        self.joint_radius = r_joint
        self.bone_radius = r_bone

        # Joints are small on screen: a once-subdivided icosahedron (80 faces) looks round
        # there; the head marker is larger and gets a finer sphere.
        t = stick_templates(style.sphere_subdivisions, style.cylinder_sections)
        self._sv, self._sn, self._hv, self._hn, self._cv, self._cn = t["sv"], t["sn"], t["hv"], t["hn"], t["cv"], t["cn"]
        nb = len(child)
        self.head = head_index(names) if style.head_marker else None
        self.head_parent = int(parents[self.head]) if self.head is not None else -1
        sv, hv, cv = len(self._sv), len(self._hv) if self.head is not None else 0, len(self._cv)
        # vertex layout: n joint spheres, then the head marker, then nb bones
        faces = [(t["sf"][None] + (np.arange(n) * sv)[:, None, None]).reshape(-1, 3)]
        if self.head is not None:
            faces.append(t["hf"] + n * sv)
        faces.append((t["cf"][None] + (n * sv + hv + np.arange(nb) * cv)[:, None, None]).reshape(-1, 3))
        self.faces = np.concatenate(faces).astype(np.uint32)
        parts = [np.repeat(colors[sides], sv, axis=0)]
        if self.head is not None:
            parts.append(np.repeat(np.asarray(style.head_color, float)[None], hv, axis=0))
        parts.append(np.repeat(colors[sides[child]] if nb else np.zeros((0, 3)), cv, axis=0))
        # pyrender's shader gamma-corrects its output: pass linear colours so the picture
        # shows the sRGB colours of the style.
        self.colors = srgb_to_linear(np.concatenate(parts)).astype(np.float32)
        self.head_radius = style.head_radius * size
        self.n_vertices = n * sv + hv + nb * cv

    def vertices(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vertex positions and normals ``(F, V, 3)`` (float32) for joint positions ``(F, J, 3)``."""
        pos = np.nan_to_num(np.asarray(positions, dtype=np.float64))
        f = len(pos)
        sphere_v = pos[:, :, None, :] + self.joint_radius[None, :, None, None] * self._sv[None, None]
        sphere_n = np.broadcast_to(self._sn, sphere_v.shape)
        parts_v, parts_n = [sphere_v.reshape(f, -1, 3)], [sphere_n.reshape(f, -1, 3)]
        if self.head is not None:
            head = head_marker_centres(pos, self.head, self.head_parent, self.head_radius)
            parts_v.append(head[:, None, :] + self.head_radius * self._hv[None])
            parts_n.append(np.broadcast_to(self._hn, (f,) + self._hn.shape))
        a, b = pos[:, self.parent], pos[:, self.child]       # (F, B, 3)
        axis = b - a
        length = np.linalg.norm(axis, axis=-1, keepdims=True)
        z = np.where(length > 1e-12, axis / np.maximum(length, 1e-12), np.array([0.0, 0.0, 1.0]))
        helper = np.where(np.abs(z[..., 1:2]) < 0.9, np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]))
        x = np.cross(helper, z)
        x /= np.linalg.norm(x, axis=-1, keepdims=True)
        y = np.cross(z, x)
        cv = self._cv
        r = self.bone_radius[None, :, None, None]
        bone_v = (a[:, :, None, :] + r * (cv[None, None, :, 0:1] * x[:, :, None] + cv[None, None, :, 1:2] * y[:, :, None])
                  + cv[None, None, :, 2:3] * axis[:, :, None])
        cn = self._cn
        bone_n = (cn[None, None, :, 0:1] * x[:, :, None] + cn[None, None, :, 1:2] * y[:, :, None]
                  + cn[None, None, :, 2:3] * z[:, :, None])
        verts = np.concatenate(parts_v + [bone_v.reshape(f, -1, 3)], axis=1)
        norms = np.concatenate(parts_n + [bone_n.reshape(f, -1, 3)], axis=1)
        return verts.astype(np.float32), norms.astype(np.float32)
