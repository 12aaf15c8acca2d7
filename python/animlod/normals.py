"""Normals of a triangle mesh built from its faces: smooth vertex normals for meshes that come
without them, and corner normals that keep a given mesh's shading (flat, hard edges or smooth)
on its simplified levels."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


def vertex_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals ``(V, 3) float32`` of a counter-clockwise mesh (zero for
    a vertex no face uses)."""
    normals = np.zeros((len(positions), 3))
    np.add.at(normals, faces.ravel(), np.repeat(area_normals(positions, faces), 3, axis=0))
    return unit_vectors(normals)


def area_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``(M, 3) float64`` each face's normal by its winding, twice its area long."""
    corners = np.asarray(positions, dtype=np.float64)[faces]
    return np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])


# Normals within this angle (about 1.8 degrees) of their position's mean are one normal: exporters
# write a corner's normal with rounding noise, and 1e-4 apart split a smooth sphere into hard edges.
_SAME_NORMAL_COSINE = 0.9995
# A mesh is flat shaded when this share of its faces have one normal at their three corners (a
# quad's own, 3 degrees off its triangles when bent) and this share of its positions carry more
# than one normal: a dense smooth mesh also has nearly one normal per face, but splits only
# along its hard edges.
_FLAT_SHARE = 0.9
# Rebuilt normals smooth across edges whose faces turn by less than this (radians).
CREASE_ANGLE = np.radians(60.0)


class Shading(NamedTuple):
    """How a mesh's own normals shade it: ``crease`` the angle of :func:`corner_normals` that
    rebuilds them (0 flat, :data:`CREASE_ANGLE` hard edges, pi smooth), and ``inward`` where they
    point against the faces' winding (clockwise faces with outward normals)."""

    crease: float
    inward: bool


def shading_of(positions: np.ndarray, normals: np.ndarray, faces: np.ndarray) -> Shading:
    """The :class:`Shading` of a mesh with ``normals (V, 3)`` (any length) at its vertices."""
    crease = shading_crease(positions, normals, faces)
    agreement = np.einsum("fkc,fc->f", unit_vectors(normals)[faces].astype(np.float64), area_normals(positions, faces))
    return Shading(np.pi if crease is None else crease, bool(np.count_nonzero(agreement < 0.0) > agreement.size / 2))


def shading_crease(positions: np.ndarray, normals: np.ndarray, faces: np.ndarray) -> float | None:
    """How a mesh's own ``normals (V, 3)`` shade it, as the crease angle of :func:`corner_normals`
    that rebuilds them: None where the vertices at each position agree in normal (smooth), 0 for
    flat shading, :data:`CREASE_ANGLE` for hard edges among smooth faces."""
    _, point = np.unique(positions, axis=0, return_inverse=True)
    point = point.ravel()
    # A zero normal (an exporter's for a vertex it could not shade) tells nothing of the shading.
    given = np.any(normals != 0.0, axis=1)
    unit = np.where(given[:, None], unit_vectors(normals), 0.0).astype(np.float64)
    mean = np.zeros((point.max(initial=-1) + 1, 3))
    np.add.at(mean, point, unit)
    differs = given & (np.einsum("vc,vc->v", unit, unit_vectors(mean)[point]) < _SAME_NORMAL_COSINE)
    split = np.zeros(mean.shape[0], dtype=bool)
    split[point[differs]] = True
    if not split.any():
        return None
    used = np.zeros(mean.shape[0], dtype=bool)  # positions some face uses
    used[point[faces.ravel()]] = True
    corner = unit[faces]
    one_normal = np.all(np.einsum("fkc,fc->fk", corner[:, 1:], corner[:, 0]) >= _SAME_NORMAL_COSINE, axis=1)
    flat = split[used].mean() >= _FLAT_SHARE and one_normal.mean() >= _FLAT_SHARE
    return 0.0 if flat else float(CREASE_ANGLE)


def corner_normals(positions: np.ndarray, faces: np.ndarray, crease: float) -> np.ndarray:
    """``(3M, 3) float32`` unit normal of each corner of ``faces (M, 3)`` (in ``faces.ravel()``
    order): the area-weighted normal of the faces around its vertex that turn from its own face
    by at most ``crease`` radians (0: flat shading; pi: smooth)."""
    area_normal = area_normals(positions, faces)
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
