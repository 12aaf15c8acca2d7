"""Whether two triangulations of one vertex set tile the same polygons.

Exporters that triangulate each frame of a deforming mesh (Blender's OBJ and PLY exporters with
"Triangulate Faces") pick each quad's and n-gon's diagonals from that frame's shape, and may start
a triangle at another corner: the frames are one surface with triangles that differ. The test is
on the triangles of each set not in the other (as multisets): where both use the same vertices
and have the same directed boundary edges, and each set's polygons (its triangles joined across
the diagonals the other set lacks) have every corner on their boundary, as a polygon's triangles
do, they tile the same polygons. Without that last test a closed mesh whose vertices are numbered
otherwise passed: both sets are then the whole surface, without a boundary.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..components import component_labels
from ..sorted_keys import among, distinct


class TriangleChange(NamedTuple):
    """How a frame's triangles stand to the first frame's (:func:`triangle_change`)."""

    listed_otherwise: bool  # every one is the first frame's: in another order, or started at another corner
    stray: int | None  # the first that tiles none of the first frame's polygons; None where they all do


def triangle_change(faces: np.ndarray, first_faces: np.ndarray, vertex_count: int) -> TriangleChange:
    """How ``faces`` stand to ``first_faces`` (both (M, 3) triangles, as many): the same triangles,
    each perhaps started at another corner (winding kept), listed otherwise; else whether they tile
    the same polygons, split along other diagonals, as exporters that triangulate each frame's
    deformed shape split them (``stray`` None), or the first of ``faces`` (in their order) that
    breaks this.

    The triangles of each not among the other's (as multisets) must use the same vertices and have
    the same directed boundary edges (those whose reverse is not in the same set), and none may have
    a corner inside its polygon (:func:`_inside_their_polygons`): then both tile the same polygons."""
    frame_triangles, first_triangles = _canonical_triangles(faces), _canonical_triangles(first_faces)
    frame_only = ~_among(frame_triangles, first_triangles)
    if not frame_only.any():
        return TriangleChange(listed_otherwise=True, stray=None)
    first_only = ~_among(first_triangles, frame_triangles)
    added, removed = faces[frame_only], first_faces[first_only]
    added_boundary = _boundary_edges(added, vertex_count)
    removed_boundary = _boundary_edges(removed, vertex_count)
    added_inside = _inside_their_polygons(added, removed, vertex_count)
    whole_polygons = not added_inside.any() and not _inside_their_polygons(removed, added, vertex_count).any()
    same_vertices = np.array_equal(distinct(added.ravel()), distinct(removed.ravel()))
    if np.array_equal(added_boundary, removed_boundary) and same_vertices and whole_polygons:
        return TriangleChange(listed_otherwise=False, stray=None)
    # The first added triangle with an outer edge that no replaced triangle has (a polygon split
    # otherwise has only edges of the triangles it replaces), else one off their boundary.
    added_edges, added_faces = _directed_edges(added, vertex_count), np.flatnonzero(frame_only)
    for known in (_directed_edges(removed, vertex_count), removed_boundary):
        stray = among(added_edges, added_boundary[~among(added_boundary, known)]).reshape(3, -1).any(axis=0)
        if stray.any():
            return TriangleChange(listed_otherwise=False, stray=int(added_faces[np.argmax(stray)]))
    first_stray = np.argmax(added_inside) if added_inside.any() else 0
    return TriangleChange(listed_otherwise=False, stray=int(added_faces[first_stray]))


def _inside_their_polygons(triangles: np.ndarray, others: np.ndarray, vertex_count: int) -> np.ndarray:
    """(T,) bool: which of ``triangles (T, 3)`` have a corner inside the polygon they tile, none on
    its boundary. Their polygons are the triangles joined across their diagonals, the edges that no
    triangle of ``others`` has; a polygon's triangles have every corner on its boundary."""
    count = len(triangles)
    directed = _directed_edges(triangles, vertex_count)  # triangle t's edge e at e * count + t
    owner = np.tile(np.arange(count), 3)
    starts = directed // vertex_count
    undirected = _undirected(directed, vertex_count)
    diagonal = ~among(undirected, undirected_edge_keys(others, vertex_count))
    order = np.argsort(undirected[diagonal], kind="stable")
    keys, holders = undirected[diagonal][order], owner[diagonal][order]
    shared = keys[1:] == keys[:-1]
    polygon = component_labels(count, np.stack([holders[:-1][shared], holders[1:][shared]], axis=1))
    # An edge is on its polygon's boundary where no triangle of the same polygon has its reverse.
    by_edge = np.argsort(directed, kind="stable")
    reverse = _reversed(directed, vertex_count)
    found = np.clip(np.searchsorted(directed[by_edge], reverse), 0, max(directed.size - 1, 0))
    inner = (directed[by_edge][found] == reverse) & (polygon[owner[by_edge][found]] == polygon[owner])
    on_boundary = polygon[owner[~inner]] * vertex_count + starts[~inner]
    return (~among(polygon[owner] * vertex_count + starts, on_boundary)).reshape(3, -1).any(axis=0)


def _canonical_triangles(faces: np.ndarray) -> np.ndarray:
    """``faces (M, 3)`` each rotated to start at its smallest vertex, winding kept: a triangle
    started at another corner is then the same row."""
    start = np.argmin(faces, axis=1)
    return faces[np.arange(len(faces))[:, None], (start[:, None] + np.arange(3)) % 3]


def _among(rows: np.ndarray, others: np.ndarray) -> np.ndarray:
    """(len(rows),) bool: whether each of ``rows (R, 3)`` is among ``others``, counting repeats:
    the k-th copy of a row is among them where ``others`` hold it k times or more."""
    ids = _row_ids(np.concatenate([rows, others]))
    scale = max(len(ids), 1)  # more than any copy number
    own, theirs = (part * scale + _copy_numbers(part) for part in (ids[: len(rows)], ids[len(rows) :]))
    return among(own, theirs)


def _row_ids(rows: np.ndarray) -> np.ndarray:
    """(R,) int64: an id per distinct row of ``rows (R, 3)``, equal rows alike (a lexicographic sort
    of the columns: numpy's unique over rows took seconds at 180k triangles)."""
    order = np.lexsort(rows.T[::-1])
    ordered = rows[order]
    starts = np.ones(len(rows), dtype=bool)
    starts[1:] = (ordered[1:] != ordered[:-1]).any(axis=1)
    ids = np.empty(len(rows), dtype=np.int64)
    ids[order] = np.cumsum(starts) - 1
    return ids


def _copy_numbers(ids: np.ndarray) -> np.ndarray:
    """(N,) int64: which copy of its id each of ``ids`` is (0 for the first, in their order)."""
    order = np.argsort(ids, kind="stable")
    ordered = ids[order]
    copies = np.empty(len(ids), np.int64)
    copies[order] = np.arange(len(ids)) - np.searchsorted(ordered, ordered)
    return copies


def _directed_edges(triangles: np.ndarray, vertex_count: int) -> np.ndarray:
    """(3 * T,) int64 keys ``a * vertex_count + b`` of the edges a -> b of ``triangles (T, 3)``:
    all first edges, then all second, then all third."""
    starts = triangles.T.astype(np.int64)
    return (starts * vertex_count + np.roll(starts, -1, axis=0)).ravel()


def _boundary_edges(triangles: np.ndarray, vertex_count: int) -> np.ndarray:
    """The sorted keys (:func:`_directed_edges`) of the edges of ``triangles`` whose reverse no
    triangle of them has."""
    edges = _directed_edges(triangles, vertex_count)
    return np.sort(edges[~among(_reversed(edges, vertex_count), edges)])


def undirected_edge_keys(triangles: np.ndarray, vertex_count: int) -> np.ndarray:
    """(3 * T,) int64 keys ``min * vertex_count + max`` of the edges of ``triangles (T, 3)``, in the
    order of :func:`_directed_edges`."""
    return _undirected(_directed_edges(triangles, vertex_count), vertex_count)


def _undirected(edges: np.ndarray, vertex_count: int) -> np.ndarray:
    """The keys of directed ``edges`` (:func:`_directed_edges`) with each edge's ends in order."""
    starts, ends = np.divmod(edges, vertex_count)
    return np.minimum(starts, ends) * vertex_count + np.maximum(starts, ends)


def _reversed(edges: np.ndarray, vertex_count: int) -> np.ndarray:
    """The keys of directed ``edges`` (:func:`_directed_edges`) each the other way."""
    return (edges % vertex_count) * vertex_count + edges // vertex_count
