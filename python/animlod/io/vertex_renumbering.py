"""Which vertex of the first frame each vertex of a later frame is, where an exporter numbers each
frame's vertices in another order.

Blender's PLY exporter writes a vertex per corner's (position, texture coordinate, ...) and
numbers them in the order the triangles use them. With "Triangulate Faces" it splits each quad
and n-gon along diagonals it picks from that frame's shape, so where a diagonal changes the
triangles use the vertices in another order and every later vertex takes another number. The
faces still come polygon by polygon in the same order, and a vertex's texture coordinates are the
same in every frame: a later frame's corner is the first frame's corner of the same face, or of
a face a few places away in the same polygon, with the same texture coordinates.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

# Faces before and after a corner's face where its polygon's other triangles may be: a hexagon's
# four triangles, split otherwise, are within two places of each other.
_WINDOW = 2


def first_frame_order(
    first_faces: np.ndarray, first_uvs: np.ndarray, faces: np.ndarray, uvs: np.ndarray
) -> np.ndarray | None:
    """``order (V,)``: the first frame's vertex that each vertex of a later frame is, given both
    frames' triangles ``(M, 3)`` and per-vertex texture coordinates ``(V, 2)``; None where the
    corners do not tell one first-frame vertex for every vertex, each taken once.

    A vertex is the first frame's vertex with its texture coordinates at the same corner of the
    same face; where that corner's vertex differs (a polygon split otherwise), the one with its
    texture coordinates among the corners of the faces within ``_WINDOW`` places."""
    if faces.shape != first_faces.shape or uvs.shape != first_uvs.shape:
        return None
    same_corner = _matching_pairs(first_faces, first_uvs, faces, uvs, shifts=[0], every_corner=False)
    nearby = _matching_pairs(first_faces, first_uvs, faces, uvs, range(-_WINDOW, _WINDOW + 1), every_corner=True)
    vertex_count = len(uvs)
    order = np.full(vertex_count, -1, dtype=np.int64)
    for pairs in (nearby, same_corner):  # a vertex the same corner names overrides its nearby guesses
        candidates = np.bincount(pairs[:, 0], minlength=vertex_count)
        single = pairs[candidates[pairs[:, 0]] == 1]
        order[single[:, 0]] = single[:, 1]
    if (order < 0).any() or np.unique(order).size != vertex_count:
        return None
    return order


def _matching_pairs(
    first_faces: np.ndarray,
    first_uvs: np.ndarray,
    faces: np.ndarray,
    uvs: np.ndarray,
    shifts: Iterable[int],
    every_corner: bool,
) -> np.ndarray:
    """The distinct (vertex, first-frame vertex) pairs with equal texture coordinates where a corner
    of face f meets a corner of the first frame's face f + shift: the same corner, or with
    ``every_corner`` any of its three."""
    found = []
    face_count = len(faces)
    for shift in shifts:
        own = np.arange(max(0, -shift), min(face_count, face_count - shift))
        if every_corner:
            vertices = np.repeat(faces[own], 3, axis=1).ravel()
            first = np.tile(first_faces[own + shift], (1, 3)).ravel()
        else:
            vertices, first = faces[own].ravel(), first_faces[own + shift].ravel()
        same = (uvs[vertices] == first_uvs[first]).all(axis=1)
        found.append(np.stack([vertices[same], first[same]], axis=1))
    return np.unique(np.concatenate(found), axis=0)
