"""Pose a skinned character from joint positions alone, and skin it (linear blend skinning in numpy).

For every mapped character joint ``m`` the *segment* runs along its main child chain to the next mapped joint
``e``; the joints in between move with ``m``. Its world rotation ``R_m`` (relative to the bind pose) takes the
character's bind direction ``d0 = b_e - b_m`` to the motion's ``d = P_e - P_m``:

* **frame** where the segment has two side branches (hips: the thighs; chest: the shoulders; hand: index and
  little finger; thumbs are not used): ``R = F(d, s) F(d0, s0)^T`` with ``F(a, b)`` the orthonormal frame of
  ``a`` and the part of ``b`` orthogonal to it, ``s = P_left - P_right`` of the branches;
* **swing** otherwise: ``R = S(R_parent d0 -> d) R_parent``, the smallest rotation after the parent's, so the
  bone keeps its parent's twist;
* **hinge** (upper arm, thigh): the swing is turned about ``d`` by ``w * phi`` where ``phi`` is the angle that
  puts the character's rest bend direction on the motion's bend (the next segment's direction orthogonal to
  ``d``) and ``w = clip((theta - 15 deg) / 20 deg, 0, 1)`` with ``theta`` the elbow/knee angle (no twist
  from an almost straight limb);
* **twist split**: a swing segment followed by a frame segment (forearm before hand, spine before chest) takes
  half of the twist between the two about its own axis, as the forearm's bones do, so the wrist ring of
  vertices is not pinched (candy-wrapping).

Unmapped joints off any segment keep their parent's rotation. The character is scaled by ``scale`` (motion
bone length / character bone length, summed over segments), and each segment is stretched along its motion
direction by ``k = |d| / (scale |d0|)`` (clipped to 0.5-2), so ``A_j = (I + (k - 1) u u^T) R_j`` with
``u = d / |d|``, for the limbs only (upper arm, forearm, thigh, shin: their lengths place the hands and feet;
stretching the trunk creases the mesh where differently stretched bones meet). Joint positions follow the
bones, ``p_j = p_parent + scale * A_parent (b_j - b_parent)``, the topmost mapped joint placed at the motion's.
Skinning: ``M_j = [scale A_j | p_j - scale A_j b_j]``, ``v' = sum_j W_vj M_j [v; 1]``, normals by the blended
linear part, renormalised.
"""
from __future__ import annotations

import re

import numpy as np

from renderers.figure import forward_direction

_HINGE_RE = re.compile(r"(upperarm|upper_arm|(?<!fore)arm$|upleg|up_leg|thigh)")
_LEG_RE = re.compile(r"(upleg|up_leg|thigh)")
UP = np.array([0.0, 1.0, 0.0])


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def swing(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(F, 3, 3)`` taking unit ``a`` to unit ``b`` (each ``(F, 3)``) by the smallest angle.

    Rodrigues: ``R = I + [v]x + [v]x^2 / (1 + c)``, ``v = a x b``, ``c = a . b``; opposite vectors turn by pi
    about an axis orthogonal to ``a``."""
    a, b = np.broadcast_arrays(_unit(a), _unit(b))
    v = np.cross(a, b)
    c = np.einsum("fi,fi->f", a, b)
    k = np.zeros(a.shape[:-1] + (3, 3))
    k[:, 0, 1], k[:, 0, 2], k[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    k[:, 1, 0], k[:, 2, 0], k[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    out = np.eye(3) + k + (k @ k) / np.maximum(1.0 + c, 1e-9)[:, None, None]
    flip = c < -1.0 + 1e-6
    if flip.any():
        helper = np.where(np.abs(a[flip, 0:1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        axis = _unit(np.cross(a[flip], helper))
        out[flip] = 2.0 * axis[:, :, None] * axis[:, None, :] - np.eye(3)
    return out


def axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """``(F, 3, 3)`` rotations by ``angle (F,)`` about unit ``axis (F, 3)``."""
    x, y, z = axis[:, 0], axis[:, 1], axis[:, 2]
    c, s = np.cos(angle), np.sin(angle)
    t = 1.0 - c
    return np.stack([np.stack([t * x * x + c, t * x * y - s * z, t * x * z + s * y], -1),
                     np.stack([t * x * y + s * z, t * y * y + c, t * y * z - s * x], -1),
                     np.stack([t * x * z - s * y, t * y * z + s * x, t * z * z + c], -1)], axis=-2)


def twist_angle(axis: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Signed angle ``(F,)`` about unit ``axis`` from ``u`` to ``v`` once both are projected orthogonal to it."""
    u = u - np.einsum("fi,fi->f", u, axis)[:, None] * axis
    v = v - np.einsum("fi,fi->f", v, axis)[:, None] * axis
    return np.arctan2(np.einsum("fi,fi->f", axis, np.cross(u, v)), np.einsum("fi,fi->f", u, v))


def frame(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal frames ``(F, 3, 3)`` (columns: ``a``, ``b`` orthogonalised, their cross product) and the
    length of ``b``'s orthogonal part relative to ``|b|`` (near 0: the frame is ill-defined)."""
    e1 = _unit(a)
    b_perp = b - np.einsum("fi,fi->f", b, e1)[:, None] * e1
    quality = np.linalg.norm(b_perp, axis=-1) / np.maximum(np.linalg.norm(b, axis=-1), 1e-12)
    e2 = _unit(b_perp)
    return np.stack([e1, e2, np.cross(e1, e2)], axis=-1), quality


class CharacterRig:
    """The segments, side branches and hinges of a character for one joint map (see the module doc).

    Args:
        names, parents, bind: the character's joints, parent indices ``(J,)`` and bind positions ``(J, 3)``.
        mapping: ``{character joint: motion joint}`` indices.
    """

    def __init__(self, names, parents, bind, mapping: dict[int, int]):
        self.names = list(names)
        self.parents = np.asarray(parents, dtype=np.int64)
        self.bind = np.asarray(bind, dtype=np.float64)
        self.mapping = dict(mapping)
        n = len(self.names)
        self.order = self._topological()
        children: list[list[int]] = [[] for _ in range(n)]
        for j in self.order:
            if self.parents[j] >= 0:
                children[self.parents[j]].append(j)
        has_mapped = np.zeros(n, dtype=bool)
        for j in reversed(self.order):
            has_mapped[j] = j in self.mapping or any(has_mapped[c] for c in children[j])
        main = np.full(n, -1)
        for j in range(n):
            cands = [c for c in children[j] if has_mapped[c]]
            if cands:
                p = self.parents[j]
                incoming = _unit(self.bind[j] - self.bind[p]) if p >= 0 else UP
                main[j] = max(cands, key=lambda c: float(np.dot(_unit(self.bind[c] - self.bind[j]), incoming)))
        self.segment: dict[int, tuple[int, list[int]]] = {}       # m -> (end e, joints moving with m)
        self.sides: dict[int, tuple[int, int]] = {}                # m -> (branch a, branch b) mapped joints
        for m in self.mapping:
            path, j = [m], int(main[m])
            while j >= 0 and j not in self.mapping:
                path.append(j)
                j = int(main[j])
            if j < 0:
                continue
            self.segment[m] = (j, path)
            branch_ends = []
            for q in path:
                for c in children[q]:
                    if c in path or c == j or "thumb" in self.names[c].lower():
                        continue
                    end = self._first_mapped(c, main)
                    if end is not None:
                        branch_ends.append(end)
            if len(branch_ends) >= 2:
                pairs = [(a, b) for a in branch_ends for b in branch_ends if a < b]
                self.sides[m] = max(pairs, key=lambda ab: float(np.linalg.norm(self.bind[ab[0]] - self.bind[ab[1]])))
        fwd = forward_direction(self.bind[None], self.names, UP)
        self.forward = fwd if fwd is not None else np.array([0.0, 0.0, 1.0])
        self.hinges = {m for m in self.segment if _HINGE_RE.search(self.names[m].lower().rsplit(":", 1)[-1])
                       and self.segment[m][0] in self.segment and m not in self.sides}
        self.splits = {m for m, (e, path) in self.segment.items() if e in self.sides and m not in self.sides
                       and m not in self.hinges and all(len(children[q]) == 1 for q in path)}
        # the limbs take the motion's lengths (upper arm, forearm, thigh, shin); the trunk, hands and feet keep
        # the character's proportions (stretching them creases the mesh where differently stretched bones meet)
        self.limbs = self.hinges | {self.segment[h][0] for h in self.hinges if self.segment[h][0] in self.segment}
        mapped = sorted(self.mapping, key=self._depth)
        self.anchor = mapped[0]
        self.scale = 1.0

    def _topological(self) -> list[int]:
        order: list[int] = []
        done = np.zeros(len(self.names), dtype=bool)
        while len(order) < len(self.names):
            for j in range(len(self.names)):
                p = self.parents[j]
                if not done[j] and (p < 0 or done[p]):
                    order.append(j)
                    done[j] = True
        return order

    def _depth(self, j: int) -> int:
        d = 0
        while self.parents[j] >= 0:
            j, d = int(self.parents[j]), d + 1
        return d

    def _first_mapped(self, j: int, main: np.ndarray) -> int | None:
        while j >= 0 and j not in self.mapping:
            j = int(main[j])
        return j if j >= 0 else None

    def fit_scale(self, positions: np.ndarray) -> float:
        """Set :attr:`scale` from the median bone lengths of a clip ``(T, Jm, 3)``; returns it."""
        motion = char = 0.0
        for m, (e, _) in self.segment.items():
            a, b = self.mapping[m], self.mapping[e]
            motion += float(np.nanmedian(np.linalg.norm(positions[:, b] - positions[:, a], axis=-1)))
            char += float(np.linalg.norm(self.bind[e] - self.bind[m]))
        self.scale = motion / char if char > 0 and motion > 0 else 1.0
        return self.scale

    def pose(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Linear parts ``(F, J, 3, 3)`` (rotation, times the segment's stretch) and positions ``(F, J, 3)`` of the
        joints for motion positions ``(F, Jm, 3)``."""
        P = np.nan_to_num(np.asarray(positions, dtype=np.float64))
        f, n = len(P), len(self.names)
        R = np.repeat(np.repeat(np.eye(3)[None, None], f, axis=0), n, axis=1)
        done = np.zeros(n, dtype=bool)
        for j in self.order:
            if done[j]:
                continue
            p = self.parents[j]
            Rp = R[:, p] if p >= 0 else np.repeat(np.eye(3)[None], f, axis=0)
            if j not in self.segment:
                R[:, j] = Rp
                continue
            e, path = self.segment[j]
            d0 = self.bind[e] - self.bind[j]
            d = P[:, self.mapping[e]] - P[:, self.mapping[j]]
            Rj = swing(Rp @ d0, d) @ Rp
            if j in self.sides:
                a, b = self.sides[j]
                F0, _ = frame(d0[None], (self.bind[a] - self.bind[b])[None])
                F1, quality = frame(d, P[:, self.mapping[a]] - P[:, self.mapping[b]])
                good = quality > 0.2
                Rj = np.where(good[:, None, None], F1 @ F0[0].T, Rj)
            elif j in self.hinges:
                Rj = self._hinge(j, e, d0, d, P, Rj)
            R[:, path] = Rj[:, None]
            done[path] = True
        for m in self.splits:
            e, path = self.segment[m]
            axis = _unit(R[:, m] @ (self.bind[e] - self.bind[m]))
            probe = np.cross(self.bind[e] - self.bind[m], UP if abs(_unit(self.bind[e] - self.bind[m])[1]) < 0.9
                             else np.array([1.0, 0.0, 0.0]))
            phi = twist_angle(axis, R[:, m] @ probe, R[:, e] @ probe)
            R[:, path] = (axis_angle(axis, 0.5 * phi) @ R[:, m])[:, None]
        # stretch each limb segment along its motion direction to the motion's length
        A = R.copy()
        for m in self.limbs:
            e, path = self.segment[m]
            d = P[:, self.mapping[e]] - P[:, self.mapping[m]]
            length = np.linalg.norm(d, axis=-1)
            k = np.clip(length / max(self.scale * float(np.linalg.norm(self.bind[e] - self.bind[m])), 1e-12),
                        0.5, 2.0)
            u = _unit(d)
            stretch = np.eye(3) + (k - 1.0)[:, None, None] * u[:, :, None] * u[:, None, :]
            A[:, path] = (stretch @ R[:, m])[:, None]
        pos = np.zeros((f, n, 3))
        s = self.scale
        for j in self.order:
            p = self.parents[j]
            if p >= 0:
                pos[:, j] = pos[:, p] + s * (A[:, p] @ (self.bind[j] - self.bind[p]))
        # place the whole figure so the anchor joint lands where the motion has it
        pos += (P[:, self.mapping[self.anchor]] - pos[:, self.anchor])[:, None]
        return A, pos

    def _hinge(self, m, e, d0, d, P, Rj):
        f_end = self.segment[e][0]
        rest_next = self.bind[f_end] - self.bind[e]
        rest_bend = rest_next - np.dot(rest_next, _unit(d0)) * _unit(d0)
        if np.linalg.norm(rest_bend) < 0.17 * np.linalg.norm(rest_next):     # straight at rest: anatomy decides
            sign = -1.0 if _LEG_RE.search(self.names[m].lower()) else 1.0
            rest_bend = sign * self.forward
        nxt = P[:, self.mapping[f_end]] - P[:, self.mapping[e]]
        axis = _unit(d)
        theta = np.arccos(np.clip(np.einsum("fi,fi->f", axis, _unit(nxt)), -1.0, 1.0))
        w = np.clip((np.degrees(theta) - 15.0) / 20.0, 0.0, 1.0)
        phi = twist_angle(axis, Rj @ rest_bend, nxt)
        return axis_angle(axis, w * phi) @ Rj


def skin(weights: np.ndarray, vertices: np.ndarray, normals: np.ndarray, bind: np.ndarray, R: np.ndarray,
         pos: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Linear blend skinning: vertices and normals ``(F, V, 3)`` float32.

    ``weights (V, J)`` dense, ``vertices``/``normals (V, 3)`` in the bind pose, ``bind (J, 3)``, ``R (F, J, 3, 3)``
    the joints' linear parts (rotation, possibly stretched), ``pos (F, J, 3)``: ``M_j = [s R_j | p_j - s R_j b_j]``,
    ``v' = sum_j W_vj M_j [v; 1]``."""
    f, n = R.shape[:2]
    M = np.empty((f, n, 3, 4), dtype=np.float32)
    M[..., :3] = scale * R
    M[..., 3] = pos - scale * np.einsum("fjab,jb->fja", R, bind)
    A = (np.asarray(weights, dtype=np.float32) @ M.reshape(f, n, 12)).reshape(f, -1, 3, 4)     # (F, V, 3, 4)
    v = np.asarray(vertices, dtype=np.float32)[None, :, None, :]
    nv = np.asarray(normals, dtype=np.float32)[None, :, None, :]
    # the 3x3 products written out as multiply-adds over (F, V, 3) arrays: far faster than einsum here
    verts = A[..., 0] * v[..., 0] + A[..., 1] * v[..., 1] + A[..., 2] * v[..., 2] + A[..., 3]
    norms = A[..., 0] * nv[..., 0] + A[..., 1] * nv[..., 1] + A[..., 2] * nv[..., 2]
    norms /= np.maximum(np.sqrt(np.einsum("fvi,fvi->fv", norms, norms))[..., None], 1e-12)
    return verts, norms
