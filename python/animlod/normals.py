"""Normals of a triangle mesh built from its faces: smooth vertex normals for meshes that come
without them, and corner normals that keep a given mesh's shading (flat, hard edges or smooth)
on its simplified levels."""

from __future__ import annotations

import numpy as np


def vertex_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals ``(V, 3) float32`` of a counter-clockwise mesh (zero for
    a vertex no face uses)."""
    positions = np.asarray(positions, dtype=np.float64)
    corners = positions[faces]
    face_normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])  # length = 2 * area
    normals = np.zeros_like(positions)
    np.add.at(normals, faces.ravel(), np.repeat(face_normals, 3, axis=0))
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return (normals / np.where(length > 0.0, length, 1.0)).astype(np.float32)


# A mesh is flat shaded when this share of its faces has equal corner normals along the face's
# own normal (cosine above _FLAT_COSINE).
_FLAT_SHARE, _FLAT_COSINE = 0.99, 0.999
# Rebuilt normals smooth across edges whose faces turn by less than this (radians).
CREASE_ANGLE = np.radians(60.0)


def shading_crease(positions: np.ndarray, normals: np.ndarray, faces: np.ndarray) -> float | None:
    """How a mesh's own ``normals (V, 3)`` shade it, as the crease angle of :func:`corner_normals`
    that rebuilds them: None where no two vertices at one position differ in normal (smooth), 0
    for flat shading, :data:`CREASE_ANGLE` for hard edges among smooth faces."""
    _, point = np.unique(positions, axis=0, return_inverse=True)
    keyed = np.unique(np.concatenate([point.reshape(-1, 1), normals], axis=1), axis=0)
    if len(keyed) == point.max(initial=-1) + 1:
        return None
    return 0.0 if is_flat_shaded(normals, positions, faces) else float(CREASE_ANGLE)


def is_flat_shaded(normals: np.ndarray | None, positions: np.ndarray, faces: np.ndarray) -> bool:
    """Whether (nearly) every face's three corners carry the face's own normal."""
    if normals is None or len(faces) == 0:
        return False
    corners = positions[faces].astype(np.float64)
    face_normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(face_normal, axis=1)
    usable = length > 0.0
    face_normal = face_normal[usable] / length[usable, None]
    corner_normals = normals[faces[usable]].astype(np.float64)
    agree = np.all(np.einsum("fkc,fc->fk", corner_normals, face_normal) > _FLAT_COSINE, axis=1)
    return bool(agree.mean() >= _FLAT_SHARE) if agree.size else False


def corner_normals(positions: np.ndarray, faces: np.ndarray, crease: float) -> np.ndarray:
    """``(3M, 3) float32`` unit normal of each corner of ``faces (M, 3)`` (in ``faces.ravel()``
    order): the area-weighted normal of the faces around its vertex that turn from its own face
    by at most ``crease`` radians (0: flat shading; pi: smooth)."""
    positions = np.asarray(positions, dtype=np.float64)
    corners = positions[faces]
    area_normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(area_normal, axis=1, keepdims=True)
    unit = area_normal / np.where(length > 0.0, length, 1.0)
    corner_vertex, corner_face = faces.ravel(), np.repeat(np.arange(len(faces)), 3)
    a, b = pairs_within_groups(corner_vertex, corner_vertex)  # every pair of corners at one vertex
    # A corner always takes its own face (at crease 0, rounding can put a unit vector's dot with
    # itself below cos 0 = 1, which left flat-shaded levels with zero normals).
    close = (a == b) | (np.einsum("pc,pc->p", unit[corner_face[a]], unit[corner_face[b]]) >= np.cos(crease) - 1e-9)
    normal = np.zeros((corner_vertex.size, 3))
    np.add.at(normal, a[close], area_normal[corner_face[b[close]]])
    normal = unit_vectors(normal)
    # A degenerate face's corner gets nothing (its face has no normal): it takes its vertex's
    # smooth normal, or +Z where every face at the vertex is degenerate.
    lost = ~normal.any(axis=1)
    if lost.any():
        smooth = np.zeros((len(positions), 3))
        np.add.at(smooth, corner_vertex, area_normal[corner_face])
        normal[lost] = unit_vectors(smooth[corner_vertex[lost]])
        normal[~normal.any(axis=1)] = (0.0, 0.0, 1.0)
    return normal


def pairs_within_groups(group: np.ndarray, asked: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every pair (k, member) of an index k into ``asked`` (groups) and an item ``member`` of that
    group, ``group`` (N,) giving each item's; k ascending, members in item order within it."""
    order = np.argsort(group, kind="stable")
    starts = np.concatenate([[0], np.cumsum(np.bincount(group))])
    first, count = starts[asked], np.diff(starts)[asked]
    k = np.repeat(np.arange(len(asked)), count)
    block = np.cumsum(count) - count
    return k, order[first[k] + np.arange(k.size) - block[k]]


def unit_vectors(vectors: np.ndarray) -> np.ndarray:
    """``vectors (N, 3)`` scaled to unit length as float32; zero rows stay zero."""
    length = np.linalg.norm(vectors, axis=1, keepdims=True)
    return (vectors / np.where(length > 0.0, length, 1.0)).astype(np.float32)
