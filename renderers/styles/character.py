"""The skinned character style: a rigged glTF 2.0 body posed by the motion's joint positions.

``STYLES["character"].mesh(motion, settings, size)`` reads the character (``settings.character`` when set, else
evalsuite's own, ``renderers/data/characters/mpfb2_neutral.glb``: a CC0 MakeHuman/MPFB2 body of 10,000
triangles, see ``renderers/data/ATTRIBUTION.md``), picks a joint map (``settings.joint_map``, a YAML file beside
the character named ``<character>.joints.yaml``, or the shipped map that fits the motion best, see
:mod:`renderers.styles.character_maps`), scales the character to the motion's bone lengths and poses it per
block of frames (:mod:`renderers.styles.character_pose`). The vertex array is the same every frame in layout,
so the renderer updates it in place.
"""
from __future__ import annotations

import functools
import os
import pathlib
from typing import Any

import numpy as np

from renderers.figure import srgb_to_linear
from renderers.gltf_skin import SkinnedMesh, read_skinned_gltf
from renderers.styles import BodyStyle
from renderers.styles.character_maps import choose_map
from renderers.styles.character_pose import CharacterRig, skin

DEFAULT_CHARACTER = pathlib.Path(__file__).resolve().parent.parent / "data" / "characters" / "mpfb2_neutral.glb"
SKIN_COLOR = (0.80, 0.77, 0.73)     # sRGB: a neutral clay, the same for every condition (blinding)
MASK_COLOR = (0.96, 0.96, 0.96)     # sRGB: the blank face (a white mask, as the GENEA Leaderboard's stimuli)


def blank_face(character: SkinnedMesh, forward: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bind vertices, normals and mask weights ``(V,)`` of the character with its face smoothed into a mask.

    Head vertices (those skinned mostly to the joint :func:`renderers.figure.head_index` finds) in front of the
    head's centre are pulled onto the ellipsoid of the head's extent, ``c + r * u / |u|`` with
    ``u = (v - c) / r``, by ``t = smoothstep((v - c) . forward / r_f; 0.15, 0.45)``: nose, lips and eyes
    vanish, the back of the head and the neck stay. Returns the vertices, their normals (the ellipsoid's on the
    mask, blended by ``t``) and ``t``.
    """
    import trimesh

    from renderers.figure import head_index

    verts = character.vertices.copy()
    head = head_index(character.joint_names)
    if head is None:
        return verts, character.normals, np.zeros(len(verts))
    dominant = character.joints[np.arange(len(verts)), np.argmax(character.weights, axis=1)]
    idx = np.flatnonzero(dominant == head)
    if len(idx) < 10:
        return verts, character.normals, np.zeros(len(verts))
    pts = verts[idx]
    depth = pts @ forward
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    back, front = float(depth.min()), float(np.percentile(depth, 90))     # the nose tip does not count
    centre = (lo + hi) / 2.0
    centre = centre - (centre @ forward) * forward + (back + front) / 2.0 * forward
    radii = np.maximum((hi - lo) / 2.0, 1e-6)
    radii = radii - (radii @ np.abs(forward)) * np.abs(forward) + (front - back) / 2.0 * np.abs(forward)
    u = (pts - centre) / radii
    onto = centre + radii * u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), 1e-9)
    x = np.clip(((pts - centre) @ forward / ((front - back) / 2.0) - 0.15) / 0.3, 0.0, 1.0)
    t = np.zeros(len(verts))
    t[idx] = x * x * (3.0 - 2.0 * x)
    verts[idx] = pts + t[idx, None] * (onto - pts)
    # the ellipsoid's own normals on the mask (folded eyelid and lip triangles would shade as lines)
    normals = character.normals.copy()
    moved = t > 0
    computed = np.array(trimesh.Trimesh(verts, character.faces, process=False).vertex_normals)
    smooth = (verts[idx] - centre) / radii ** 2
    smooth /= np.maximum(np.linalg.norm(smooth, axis=1, keepdims=True), 1e-12)
    computed[idx] = (1.0 - t[idx, None]) * computed[idx] + t[idx, None] * smooth
    normals[moved] = computed[moved] / np.maximum(np.linalg.norm(computed[moved], axis=1, keepdims=True), 1e-12)
    return verts, normals, t


@functools.lru_cache(maxsize=4)
def _read(path: str, mtime: float) -> SkinnedMesh:
    return read_skinned_gltf(path)


def load_character(path=None) -> SkinnedMesh:
    """The character at ``path`` (default: the shipped one), read once per file version."""
    p = os.fspath(path) if path is not None else os.fspath(DEFAULT_CHARACTER)
    try:
        mtime = os.stat(p).st_mtime
    except OSError:
        mtime = -1.0
    return _read(p, mtime)


class CharacterMesh:
    """A character posed by a motion: constant :attr:`faces` and :attr:`colors`, per-frame :meth:`vertices`."""

    def __init__(self, character: SkinnedMesh, motion_joints, rest_positions, *, joint_map=None,
                 motion_source=None, color=SKIN_COLOR, face: str = "visible"):
        self.character = character
        self.map_name, mapping = choose_map(character.joint_names, list(motion_joints), joint_map=joint_map,
                                            motion_source=motion_source, character_source=character.source)
        self.rig = CharacterRig(character.joint_names, character.parents, character.bind_positions, mapping)
        self.rig.fit_scale(np.asarray(rest_positions, dtype=np.float64))
        n_v, n_j = len(character.vertices), len(character.joint_names)
        self.weights = np.zeros((n_v, n_j), dtype=np.float32)
        np.add.at(self.weights, (np.repeat(np.arange(n_v), 4), character.joints.ravel()), character.weights.ravel())
        verts, normals, mask = character.vertices, character.normals, np.zeros(n_v)
        if face == "blank":
            verts, normals, mask = blank_face(character, self.rig.forward)
        self._vertices = verts.astype(np.float32)
        self._normals = normals.astype(np.float32)
        self.faces = np.ascontiguousarray(character.faces, dtype=np.uint32)
        tint = np.clip(2.0 * mask - 1.0, 0.0, 1.0)[:, None]       # the mask's colour where it is fully flat
        self.colors = ((1.0 - tint) * srgb_to_linear(color) + tint * srgb_to_linear(MASK_COLOR)).astype(np.float32)

    def vertices(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vertex positions and normals ``(F, V, 3)`` float32 for the motion's joint positions ``(F, J, 3)``."""
        R, pos = self.rig.pose(positions)
        return skin(self.weights, self._vertices, self._normals, self.character.bind_positions, R, pos,
                    self.rig.scale)


class CharacterStyle(BodyStyle):
    name = "character"
    description = "a skinned glTF character (evalsuite's CC0 MakeHuman body, or --character FILE) driven by a joint map"
    frame_pad = 0.06   # the body's thickness beyond its joints, as a fraction of the figure size (framing)

    def __init__(self, character=None, joint_map=None):
        self.character = character
        self.joint_map = joint_map

    def mesh(self, motion: Any, settings: Any, size: float) -> CharacterMesh:
        path = self.character or getattr(settings, "character", None) or None
        joint_map = self.joint_map or getattr(settings, "joint_map", None) or None
        if joint_map is None and path:
            beside = pathlib.Path(path).with_suffix(".joints.yaml")
            joint_map = beside if beside.is_file() else None
        return CharacterMesh(load_character(path), motion.joint_names, motion.positions(), joint_map=joint_map,
                             motion_source=getattr(motion, "source", None),
                             face=getattr(settings, "face", "visible"))


STYLE = CharacterStyle()
