"""Rotation representations: Euler channels, matrices, quaternions, exponential maps, 6D.

BVH rotation channels are *intrinsic* rotations applied in the listed order:
``Zrotation Xrotation Yrotation`` means ``R = Rz(z) @ Rx(x) @ Ry(y)``, which is
``scipy.spatial.transform.Rotation.from_euler("ZXY", [z, x, y], degrees=True)``.

The conversions between representations use ``scipy.spatial.transform.Rotation``.
Only the Euler-to-matrix step on the forward-kinematics hot path is written out
elementwise (:func:`euler_to_matrix_elements`): composing millions of rotations as
separate numpy vectors of matrix *elements* is several times faster than building
scipy ``Rotation`` objects or batched ``3x3`` matmuls, and is checked against scipy in
the tests.

Quaternions are scalar-last ``(x, y, z, w)`` as in scipy.
"""
from __future__ import annotations

from typing import Any

import numpy as np

__all__ = [
    "euler_to_matrix",
    "euler_to_matrix_elements",
    "matrix_to_euler",
    "matrix_to_quaternion",
    "quaternion_to_matrix",
    "matrix_to_expmap",
    "expmap_to_matrix",
    "matrix_to_6d",
    "sixd_to_matrix",
    "quaternion_slerp",
]

# One entry of a matrix held as 9 entries: a constant 0.0/1.0 or an array over frames.
Element = float | np.ndarray


def _rotation() -> Any:
    # scipy.spatial takes ~0.4 s to import; forward kinematics never needs it.
    from scipy.spatial.transform import Rotation

    return Rotation


# A matrix is held as a list of 9 entries in row-major order. Each entry is either a
# Python float 0.0/1.0 (structurally constant) or an ndarray; keeping the constants
# symbolic lets the axis matrices' zeros and ones skip their multiplications.


def _axis_elements(axis: str, c: Element, s: Element, ns: Element) -> list[Element]:
    if axis == "X":
        return [1.0, 0.0, 0.0, 0.0, c, ns, 0.0, s, c]
    if axis == "Y":
        return [c, 0.0, s, 0.0, 1.0, 0.0, ns, 0.0, c]
    if axis == "Z":
        return [c, ns, 0.0, s, c, 0.0, 0.0, 0.0, 1.0]
    raise ValueError(f"unknown rotation axis {axis!r}; expected X, Y or Z")


def _product(x: Element, y: Element) -> Element | None:
    if isinstance(x, float):
        if x == 0.0:
            return None
        return y if x == 1.0 else x * y
    if isinstance(y, float):
        if y == 0.0:
            return None
        return x if y == 1.0 else x * y
    return x * y


def _sum(acc: Element | None, term: Element | None) -> Element | None:
    if term is None:
        return acc
    if acc is None:
        return term
    if isinstance(acc, float) and isinstance(term, float):
        return acc + term
    return acc + term


def multiply_elements(a: list[Element], b: list[Element]) -> list[Element]:
    """Product ``a @ b`` of two matrices held as 9 element entries (see module notes)."""
    out = []
    for i in range(3):
        for k in range(3):
            acc = None
            for m in range(3):
                acc = _sum(acc, _product(a[3 * i + m], b[3 * m + k]))
            out.append(0.0 if acc is None else acc)
    return out


def euler_to_matrix_elements(angles: np.ndarray, axes: str, degrees: bool = True) -> list[Element]:
    """Intrinsic rotation ``R = R_axes[0](a0) @ R_axes[1](a1) @ ...`` as 9 element arrays.

    ``angles`` has shape ``(len(axes), ...)``; each returned entry has the trailing shape
    (or is the float 0.0/1.0 where the element is constant). Any number of axes is
    allowed, including repeated ones (e.g. ``"ZXZ"``) and a single axis.
    """
    angles = np.asarray(angles, dtype=np.float64)
    if len(axes) != angles.shape[0]:
        raise ValueError(f"{len(axes)} axes but {angles.shape[0]} angle rows")
    if degrees:
        angles = np.deg2rad(angles)
    result = None
    for i, axis in enumerate(axes.upper()):
        c = np.cos(angles[i])
        s = np.sin(angles[i])
        m = _axis_elements(axis, c, s, -s)
        result = m if result is None else multiply_elements(result, m)
    if result is None:  # no rotation channels: identity
        return [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    return result


def elements_to_array(elements: list[Element], shape: tuple[int, ...]) -> np.ndarray:
    """Stack 9 element entries into an array of shape ``shape + (3, 3)``."""
    out = np.empty(shape + (9,), dtype=np.float64)
    for k, e in enumerate(elements):
        out[..., k] = e
    return out.reshape(shape + (3, 3))


def euler_to_matrix(angles: np.ndarray, axes: str, degrees: bool = True) -> np.ndarray:
    """Intrinsic Euler angles ``(..., len(axes))`` to rotation matrices ``(..., 3, 3)``."""
    angles = np.asarray(angles, dtype=np.float64)
    moved = np.moveaxis(angles, -1, 0)
    return elements_to_array(euler_to_matrix_elements(moved, axes, degrees), angles.shape[:-1])


def _flat(m: np.ndarray) -> tuple[np.ndarray, tuple[int, ...]]:
    m = np.asarray(m, dtype=np.float64)
    if m.shape[-2:] != (3, 3):
        raise ValueError(f"expected rotation matrices of shape (..., 3, 3), got {m.shape}")
    return m.reshape(-1, 3, 3), m.shape[:-2]


def matrix_to_euler(m: np.ndarray, axes: str, degrees: bool = True) -> np.ndarray:
    """Rotation matrices to intrinsic Euler angles in ``axes`` order (3 axes)."""
    flat, lead = _flat(m)
    eul = _rotation().from_matrix(flat).as_euler(axes.upper(), degrees=degrees)
    return np.asarray(eul.reshape(lead + (3,)))


def matrix_to_quaternion(m: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` to unit quaternions ``(..., 4)`` (x, y, z, w)."""
    flat, lead = _flat(m)
    return np.asarray(_rotation().from_matrix(flat).as_quat().reshape(lead + (4,)))


def quaternion_to_matrix(q: np.ndarray) -> np.ndarray:
    """Quaternions ``(..., 4)`` (x, y, z, w; normalised here) to matrices ``(..., 3, 3)``."""
    q = np.asarray(q, dtype=np.float64)
    return np.asarray(_rotation().from_quat(q.reshape(-1, 4)).as_matrix().reshape(q.shape[:-1] + (3, 3)))


def matrix_to_expmap(m: np.ndarray) -> np.ndarray:
    """Rotation matrices to exponential maps (axis * angle in radians), ``(..., 3)``."""
    flat, lead = _flat(m)
    return np.asarray(_rotation().from_matrix(flat).as_rotvec().reshape(lead + (3,)))


def expmap_to_matrix(v: np.ndarray) -> np.ndarray:
    """Exponential maps (axis * angle in radians) ``(..., 3)`` to matrices ``(..., 3, 3)``."""
    v = np.asarray(v, dtype=np.float64)
    return np.asarray(_rotation().from_rotvec(v.reshape(-1, 3)).as_matrix().reshape(v.shape[:-1] + (3, 3)))


def matrix_to_6d(m: np.ndarray) -> np.ndarray:
    """The continuous 6D representation (Zhou et al. 2019): the first two matrix columns.

    Returns ``(..., 6)`` as ``[m00, m10, m20, m01, m11, m21]``.
    """
    m = np.asarray(m, dtype=np.float64)
    return np.concatenate([m[..., :, 0], m[..., :, 1]], axis=-1)


def sixd_to_matrix(d6: np.ndarray) -> np.ndarray:
    """6D representation back to rotation matrices by Gram-Schmidt (columns a, b, a x b)."""
    d6 = np.asarray(d6, dtype=np.float64)
    a, b = d6[..., :3], d6[..., 3:]
    x = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b - np.sum(x * b, axis=-1, keepdims=True) * x
    y = b / np.linalg.norm(b, axis=-1, keepdims=True)
    z = np.cross(x, y)
    return np.stack([x, y, z], axis=-1)


def quaternion_slerp(q0: np.ndarray, q1: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation between quaternion arrays, vectorised.

    ``q0``, ``q1``: ``(..., 4)``; ``w``: weights broadcastable to ``q0.shape[:-1]``.
    Takes the shorter arc (flips ``q1`` where ``q0 . q1 < 0``).
    """
    q0 = np.asarray(q0, dtype=np.float64)
    q1 = np.asarray(q1, dtype=np.float64)
    w = np.asarray(w, dtype=np.float64)[..., None]
    dot = np.sum(q0 * q1, axis=-1, keepdims=True)
    q1 = np.where(dot < 0, -q1, q1)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin_theta = np.sin(theta)
    near = sin_theta < 1e-9  # nearly identical: linear interpolation is exact enough
    safe = np.where(near, 1.0, sin_theta)
    a = np.where(near, 1.0 - w, np.sin((1.0 - w) * theta) / safe)
    b = np.where(near, w, np.sin(w * theta) / safe)
    out = a * q0 + b * q1
    return np.asarray(out / np.linalg.norm(out, axis=-1, keepdims=True))
