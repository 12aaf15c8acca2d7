"""Quaternion and Euler-angle helpers, vectorised over leading axes.

Conventions (DESIGN.md): quaternions are stored (x, y, z, w) as glTF does; matrices are
(..., 3, 3) or (..., 4, 4) arrays acting on column vectors; angles are radians.
"""

from __future__ import annotations

import numpy as np

from . import _core

_AXIS_INDEX = {"X": 0, "Y": 1, "Z": 2}


def normalize(q: np.ndarray, name: str = "quaternion") -> np.ndarray:
    """Unit quaternions ``(..., 4)``; a zero quaternion is an error naming ``name`` and its index,
    never silently identity."""
    q = np.asarray(q, dtype=np.float64)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    bad = (norm[..., 0] == 0.0) | ~np.isfinite(norm[..., 0])
    if np.any(bad):
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{name}: index {index} has a zero or non-finite norm")
    return q / norm


def _last_axis(name: str, array: np.ndarray, size: int) -> None:
    """ValueError naming ``name`` unless ``array`` is ``(..., size)``: a longer last axis would
    be read in part, silently. A look at the shape only, cheap enough for the hot helpers."""
    if array.shape[-1:] != (size,):
        raise ValueError(f"{name}: expected shape (..., {size}), got {array.shape}")


def identity(shape: tuple[int, ...] = ()) -> np.ndarray:
    """Identity quaternions of the given leading ``shape``, ``shape + (4,)``."""
    q = np.zeros(shape + (4,))
    q[..., 3] = 1.0
    return q


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a * b`` (apply ``b`` first, then ``a``), broadcasting ``(..., 4)``;
    ValueError naming ``a`` or ``b`` when its last axis is not 4."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    _last_axis("a", a, 4)
    _last_axis("b", b, 4)
    ax, ay, az, aw = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bx, by, bz, bw = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def conjugate(q: np.ndarray) -> np.ndarray:
    """Inverse of unit quaternions ``(..., 4)``."""
    q = np.array(q, dtype=np.float64)
    q[..., :3] *= -1.0
    return q


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` over the last axis of ``(..., 3)`` arrays, broadcasting: numpy's cross, bit for bit,
    without its axis bookkeeping, which costs more than the products on the small per-joint
    arrays of motion LoD's loops (2-3x faster there)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v (..., 3)`` by unit quaternions ``q (..., 4)``, broadcasting; ValueError
    naming ``q`` or ``v`` when its last axis is not 4 or 3."""
    q = np.asarray(q, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    _last_axis("q", q, 4)
    _last_axis("v", v, 3)
    u = q[..., :3]
    w = q[..., 3:4]
    t = 2.0 * cross(u, v)
    return v + w * t + cross(u, t)


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` of unit quaternions ``q (..., 4)``; ValueError naming
    ``q`` when its last axis is not 4."""
    q = np.asarray(q, dtype=np.float64)
    _last_axis("q", q, 4)
    x, y, z, w = np.moveaxis(q, -1, 0)
    m = np.empty(x.shape + (3, 3))
    m[..., 0, 0] = 1 - 2 * (y * y + z * z)
    m[..., 0, 1] = 2 * (x * y - z * w)
    m[..., 0, 2] = 2 * (x * z + y * w)
    m[..., 1, 0] = 2 * (x * y + z * w)
    m[..., 1, 1] = 1 - 2 * (x * x + z * z)
    m[..., 1, 2] = 2 * (y * z - x * w)
    m[..., 2, 0] = 2 * (x * z - y * w)
    m[..., 2, 1] = 2 * (y * z + x * w)
    m[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return m


def from_matrix(m: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` with ``w >= 0`` from rotation matrices ``(..., 3, 3)``.

    Shepperd's method (the largest of the four diagonal combinations sets the divisor, for
    stability), in the core: pose.hpp's quaternions_from_matrices.
    """
    m = np.asarray(m, dtype=np.float64)
    flat = _core.quaternions_from_matrices(m.reshape(-1, 3, 3))
    return flat.reshape(m.shape[:-2] + (4,))


def from_axis_angle(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Quaternions ``(..., 4)`` rotating by ``angle (...)`` radians about unit ``axis (..., 3)``."""
    axis = np.asarray(axis, dtype=np.float64)
    half = 0.5 * np.asarray(angle, dtype=np.float64)[..., None]
    return np.concatenate([axis * np.sin(half), np.cos(half)], axis=-1)


def from_euler(angles: np.ndarray, order: str) -> np.ndarray:
    """Quaternions from intrinsic Euler angles ``(..., n)`` in radians, n = len(order).

    ``order`` names the axes as they appear in a BVH CHANNELS line, e.g. ``"ZXY"``: the
    rotation is ``R = R_Z(a0) @ R_X(a1) @ R_Y(a2)`` acting on column vectors. One or two
    axes (a hinge's ``"X"``) turn about those only.
    """
    angles = np.asarray(angles, dtype=np.float64)
    order = order.upper()
    if not 1 <= len(order) <= 3 or len(set(order)) != len(order) or set(order) - set(_AXIS_INDEX):
        raise ValueError(f"Euler order: must be one to three different axes of X, Y, Z, got {order!r}")
    if angles.shape[-1:] != (len(order),):
        raise ValueError(f"angles: expected (..., {len(order)}) for order {order!r}, got shape {angles.shape}")
    q = identity(angles.shape[:-1])
    for k, axis_name in enumerate(order):
        axis = np.zeros(3)
        axis[_AXIS_INDEX[axis_name]] = 1.0
        q = multiply(q, from_axis_angle(axis, angles[..., k]))
    return q


def to_euler(q: np.ndarray, order: str) -> np.ndarray:
    """Intrinsic Euler angles ``(..., 3)`` in radians for ``order`` (inverse of :func:`from_euler`).

    Works for the six Tait-Bryan orders; near gimbal lock the third angle is set to zero.
    """
    order = order.upper()
    if len(order) != 3 or len(set(order)) != 3 or set(order) - set(_AXIS_INDEX):
        raise ValueError(f"Euler order: only Tait-Bryan orders (three different axes) are supported, got {order!r}")
    i, j, k = (_AXIS_INDEX[a] for a in order)
    m = to_matrix(q)
    # For R = R_i(a) R_j(b) R_k(c): m[i, k] = sign * sin(b), with sign +1 for cyclic (i, j, k).
    sign = 1.0 if (j - i) % 3 == 1 else -1.0
    sin_b = np.clip(sign * m[..., i, k], -1.0, 1.0)
    b = np.arcsin(sin_b)
    locked = np.abs(sin_b) > 1.0 - 1e-12
    a = np.where(locked, np.arctan2(sign * m[..., k, j], m[..., j, j]), np.arctan2(-sign * m[..., j, k], m[..., k, k]))
    c = np.where(locked, 0.0, np.arctan2(-sign * m[..., i, j], m[..., i, i]))
    return np.stack([a, b, c], axis=-1)


def slerp(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spherical interpolation between unit quaternions ``a`` and ``b`` at ``t (...)``."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)[..., None]
    dot = np.sum(a * b, axis=-1, keepdims=True)
    b = np.where(dot < 0.0, -b, b)
    dot = np.abs(dot)
    theta = np.arccos(np.clip(dot, -1.0, 1.0))
    sin_theta = np.sin(theta)
    near = sin_theta < 1e-8
    safe = np.where(near, 1.0, sin_theta)
    wa = np.where(near, 1.0 - t, np.sin((1.0 - t) * theta) / safe)
    wb = np.where(near, t, np.sin(t * theta) / safe)
    return normalize(wa * a + wb * b)


def compose_transform(translation: np.ndarray, rotation: np.ndarray, scale: np.ndarray | None = None) -> np.ndarray:
    """4x4 matrices ``T @ R @ S`` from ``translation (..., 3)``, ``rotation (..., 4)``, ``scale (..., 3)``."""
    rotation = np.asarray(rotation, dtype=np.float64)
    m = np.zeros(rotation.shape[:-1] + (4, 4))
    r = to_matrix(rotation)
    if scale is not None:
        r = r * np.asarray(scale, dtype=np.float64)[..., None, :]
    m[..., :3, :3] = r
    m[..., :3, 3] = translation
    m[..., 3, 3] = 1.0
    return m
