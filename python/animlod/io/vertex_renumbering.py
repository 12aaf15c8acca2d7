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

from ..sorted_keys import among, distinct
from .polygon_splits import undirected_edge_keys

# How far, in faces before and after a corner's, its polygon's other triangles are looked for,
# each step for the vertices the one before left: a quad's two triangles are next to each other,
# a 32-gon cap's 30 within 29 places.
_WINDOWS = (2, 8, 32, 128)


def first_frame_order(
    first_faces: np.ndarray, first_uvs: np.ndarray, faces: np.ndarray, uvs: np.ndarray
) -> np.ndarray | None:
    """``order (V,)``: the first frame's vertex that each vertex of a later frame is, given both
    frames' triangles ``(M, 3)`` and per-vertex texture coordinates ``(V, 2)``; None where the
    corners do not tell one first-frame vertex for every vertex, each taken once.

    A vertex is the first frame's vertex with its texture coordinates at the same corner of the
    same face; where that corner's vertex differs (a polygon split otherwise), the one vertex not
    yet matched with its texture coordinates among the corners of the faces within a few places
    (``_WINDOWS``, widening for the vertices a narrower window leaves), or where several are (UVs
    repeated: mirrored, loose parts alike), the one of them beside the first-frame match of one of
    its neighbours."""
    if faces.shape != first_faces.shape or uvs.shape != first_uvs.shape:
        return None
    vertex_count = len(uvs)
    order = np.full(vertex_count, -1, dtype=np.int64)
    taken = np.zeros(vertex_count, dtype=bool)
    every_face = np.arange(len(faces))
    _assign(order, taken, _matching_pairs(first_faces, first_uvs, faces, uvs, every_face, [0], every_corner=False))
    first_edges = distinct(undirected_edge_keys(first_faces, vertex_count))
    neighbours = _Neighbours(faces, vertex_count)
    for window in _WINDOWS:
        open_faces = np.flatnonzero((order[faces] < 0).any(axis=1))  # those with a vertex to match
        shifts = range(-window, window + 1)
        pairs = _matching_pairs(first_faces, first_uvs, faces, uvs, open_faces, shifts, every_corner=True)
        matched = -1
        while matched < (order >= 0).sum() < vertex_count:  # each match may place a neighbour's
            matched = (order >= 0).sum()
            pairs = pairs[(order[pairs[:, 0]] < 0) & ~taken[pairs[:, 1]]]
            _assign(order, taken, pairs)
            pairs = pairs[(order[pairs[:, 0]] < 0) & ~taken[pairs[:, 1]]]
            _assign(order, taken, pairs[neighbours.beside_matches(pairs, order, first_edges)])
    if (order < 0).any() or np.bincount(order, minlength=vertex_count).max(initial=0) > 1:
        return None
    return order


class _Neighbours:
    """The vertices that share an edge with each vertex of a frame's triangles."""

    def __init__(self, faces: np.ndarray, vertex_count: int) -> None:
        starts = faces.ravel()
        ends = np.roll(faces, -1, axis=1).ravel()
        source, target = np.concatenate([starts, ends]), np.concatenate([ends, starts])
        by_source = np.argsort(source, kind="stable")
        self.targets = target[by_source]
        self.offsets = np.searchsorted(source[by_source], np.arange(vertex_count + 1))
        self.vertex_count = vertex_count

    def beside_matches(self, pairs: np.ndarray, order: np.ndarray, first_edges: np.ndarray) -> np.ndarray:
        """(P,) bool: which (vertex, first-frame vertex) ``pairs`` put the vertex beside the first-frame
        match (``order``) of one of its neighbours, along an edge of ``first_edges`` (keys)."""
        starts = self.offsets[pairs[:, 0]]
        counts = self.offsets[pairs[:, 0] + 1] - starts
        pair = np.repeat(np.arange(len(pairs)), counts)
        neighbour = self.targets[np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts) + starts[pair]]
        placed = order[neighbour]
        keys = np.minimum(placed, pairs[pair, 1]) * self.vertex_count + np.maximum(placed, pairs[pair, 1])
        beside = np.zeros(len(pairs), dtype=bool)
        beside[pair[(placed >= 0) & among(keys, first_edges)]] = True
        return beside


def _assign(order: np.ndarray, taken: np.ndarray, pairs: np.ndarray) -> None:
    """Match each vertex of ``pairs (P, 2)`` (vertex, first-frame vertex) that has one candidate
    there, not yet matched, to it: ``order`` and ``taken`` (the first frame's matched vertices)."""
    pairs = pairs[order[pairs[:, 0]] < 0]
    candidates = np.bincount(pairs[:, 0], minlength=len(order))
    single = pairs[candidates[pairs[:, 0]] == 1]
    order[single[:, 0]] = single[:, 1]
    taken[single[:, 1]] = True


def _matching_pairs(
    first_faces: np.ndarray,
    first_uvs: np.ndarray,
    faces: np.ndarray,
    uvs: np.ndarray,
    looked_at: np.ndarray,
    shifts: Iterable[int],
    every_corner: bool,
) -> np.ndarray:
    """The distinct (vertex, first-frame vertex) pairs with equal texture coordinates where a corner
    of face f (of the faces ``looked_at``) meets a corner of the first frame's face f + shift: the
    same corner, or with ``every_corner`` any of its three."""
    found = [np.zeros(0, dtype=np.int64)]  # pairs as keys vertex * V + first-frame vertex
    face_count, vertex_count = len(faces), len(uvs)
    for shift in shifts:
        own = looked_at[(looked_at + shift >= 0) & (looked_at + shift < face_count)]
        if every_corner:
            vertices = np.repeat(faces[own], 3, axis=1).ravel().astype(np.int64)
            first = np.tile(first_faces[own + shift], (1, 3)).ravel()
        else:
            vertices, first = faces[own].ravel().astype(np.int64), first_faces[own + shift].ravel()
        same = (uvs[vertices] == first_uvs[first]).all(axis=1)
        found.append(vertices[same] * vertex_count + first[same])
    return np.stack(np.divmod(distinct(np.concatenate(found)), vertex_count), axis=1)
