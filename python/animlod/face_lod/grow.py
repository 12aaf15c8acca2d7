"""Region labels for faces that have none, grown from their motion (beyond seeds/004, whose
region choice "is not fully automatic", Section 6).

A vertex's motion feature is its trajectory over the frames (displacements from the first
frame, one 3-vector per frame) or, for a blendshape face, its delta in every target scaled by
the largest weight the animation gives that target. Vertices that hardly move form the region
"static"; the others are clustered by direction and size of their motion (k-means with
farthest-point seeds, so the result is deterministic), each cluster is split into pieces
connected through mesh edges, and pieces smaller than ``min_vertices`` are merged into the
neighbouring region they share most edges with. The result is a :class:`FaceRegions` with two
groups, "moving" (importance 1) and "static".

Shapes: ``V`` vertices, ``M`` faces, ``D`` motion-feature dimensions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..components import component_labels
from ..model import check_finite, checked_faces
from .regions import FaceRegions, RegionGroup


@dataclass
class GrowOptions:
    """How :func:`grow_regions` labels a face.

    Attributes
    ----------
    region_count : clusters of moving vertices (before splitting into connected pieces).
    static_fraction : a vertex whose largest motion is below this fraction of the largest motion
        of any vertex is static.
    min_vertices : pieces with fewer vertices are merged into a neighbour.
    static_importance : importance of the "static" group (the "moving" group has 1).
    iterations : k-means iterations.
    """

    region_count: int = 8
    static_fraction: float = 0.05
    min_vertices: int = 8
    static_importance: float = 0.5
    iterations: int = 30


def motion_of_frames(frames: np.ndarray) -> np.ndarray:
    """(V, 3 F) motion features of ``frames (F, V, 3)``: each frame minus the first."""
    frames = np.asarray(frames, dtype=np.float64)
    return (frames - frames[:1]).transpose(1, 0, 2).reshape(frames.shape[1], -1)


def motion_of_targets(targets: np.ndarray, largest_weights: np.ndarray) -> np.ndarray:
    """(V, 3 N) motion features of blendshape ``targets (N, V, 3)`` used up to ``largest_weights (N,)``."""
    scaled = np.asarray(targets, dtype=np.float64) * np.asarray(largest_weights, dtype=np.float64)[:, None, None]
    return scaled.transpose(1, 0, 2).reshape(scaled.shape[1], -1)


def grow_regions(features: np.ndarray, faces: np.ndarray, options: GrowOptions | None = None) -> FaceRegions:
    """Region labels from per-vertex motion ``features (V, D)`` on a mesh with ``faces (M, 3)``.

    Returns regions named "static" (when any vertex is static) and "motion_<k>", numbered by
    decreasing size. ValueError when no vertex moves (every vertex would be static: there is
    nothing to animate by region), and ValueError naming the argument and the element when
    ``features`` is not ``(V, D)`` with D a multiple of 3 or holds a non-finite value, or when
    ``faces`` is not ``(M, 3)`` whole indices in [0, V).
    """
    options = options or GrowOptions()
    features = np.asarray(features, dtype=np.float64)
    if features.ndim != 2 or features.shape[1] % 3:
        raise ValueError(f"features: expected shape (V, D) with D a multiple of 3, got {features.shape}")
    check_finite("features", features)
    vertex_count, dimensions = features.shape
    faces = checked_faces(faces, vertex_count).astype(np.int64)
    magnitude = np.linalg.norm(features.reshape(vertex_count, dimensions // 3, 3), axis=2).max(axis=1, initial=0.0)
    largest = float(magnitude.max(initial=0.0))
    if not largest > 0.0:
        raise ValueError("grow regions: no vertex moves in any frame or target, so there are no motion regions")
    moving = magnitude > options.static_fraction * largest
    labels = np.full(vertex_count, -1, np.int64)
    labels[moving] = _kmeans(features[moving] / largest, options.region_count, options.iterations)
    labels = _connected_pieces(labels, faces)
    labels = _merge_small(labels, faces, options.min_vertices)
    # Number moving regions by decreasing size; static last.
    pieces, counts = np.unique(labels[labels >= 0], return_counts=True)
    order = pieces[np.argsort(-counts, kind="stable")]
    renumber = np.full(labels.max(initial=-1) + 2, -1, np.int64)
    renumber[order] = np.arange(order.size)
    names = [f"motion_{k}" for k in range(order.size)]
    result = renumber[labels]
    groups = [RegionGroup("moving", list(names), 1.0)]
    if np.any(labels < 0):
        result[labels < 0] = len(names)
        names.append("static")
        groups.append(RegionGroup("static", ["static"], options.static_importance))
    return FaceRegions(names, result.astype(np.int32), groups)


def _edges(faces: np.ndarray) -> np.ndarray:
    """(E, 2) unique undirected edges, lower vertex first."""
    pairs = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    return np.unique(pairs, axis=0)


def _kmeans(points: np.ndarray, count: int, iterations: int) -> np.ndarray:
    """(P,) cluster of each point: Lloyd's algorithm from farthest-point seeds (deterministic)."""
    count = max(1, min(count, len(points)))
    seeds = [int(np.argmax(np.linalg.norm(points, axis=1)))]
    distance = np.linalg.norm(points - points[seeds[0]], axis=1)
    for _ in range(count - 1):  # O(count) steps, vectorised over points
        seeds.append(int(np.argmax(distance)))
        distance = np.minimum(distance, np.linalg.norm(points - points[seeds[-1]], axis=1))
    centres = points[seeds]
    assignment = np.zeros(len(points), np.int64)
    for _ in range(iterations):
        squared = (points**2).sum(1)[:, None] - 2.0 * points @ centres.T + (centres**2).sum(1)[None]
        updated = np.argmin(squared, axis=1)
        if _ > 0 and np.array_equal(updated, assignment):
            break
        assignment = updated
        sums = np.zeros_like(centres)
        np.add.at(sums, assignment, points)
        sizes = np.bincount(assignment, minlength=len(centres))
        centres = np.where(sizes[:, None] > 0, sums / np.maximum(sizes, 1)[:, None], centres)
    return assignment


def _connected_pieces(labels: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each label split into pieces joined by mesh edges between equally labelled vertices
    (label propagation with pointer jumping); -1 stays -1."""
    edges = _edges(faces)
    same = edges[(labels[edges[:, 0]] == labels[edges[:, 1]]) & (labels[edges[:, 0]] >= 0)]
    return np.where(labels >= 0, component_labels(len(labels), same), -1)


def _merge_small(labels: np.ndarray, faces: np.ndarray, min_vertices: int) -> np.ndarray:
    """Pieces smaller than ``min_vertices`` join the neighbouring label (static included) they
    share most edges with; repeated until no small piece has a neighbour to join."""
    edges = _edges(faces)
    labels = labels.copy()
    while True:
        ids, counts = np.unique(labels[labels >= 0], return_counts=True)
        small = ids[counts < min_vertices]
        if small.size == 0:
            return labels
        a, b = labels[edges[:, 0]], labels[edges[:, 1]]
        crossing = np.concatenate([np.stack([a, b], 1), np.stack([b, a], 1)])
        crossing = crossing[(crossing[:, 0] != crossing[:, 1]) & np.isin(crossing[:, 0], small)]
        if crossing.size == 0:
            return labels
        pairs, shared = np.unique(crossing, axis=0, return_counts=True)
        # For each small piece, the neighbour with most shared edges (ties: smallest label).
        order = np.lexsort((pairs[:, 1], -shared, pairs[:, 0]))
        pairs = pairs[order]
        first = np.concatenate([[True], pairs[1:, 0] != pairs[:-1, 0]])
        source, target = pairs[first, 0], pairs[first, 1]
        # Pieces whose chosen neighbour is large (or static) merge together; otherwise only the
        # smallest piece merges, so two small neighbours cannot swap labels forever.
        settled = ~np.isin(target, small)
        if not np.any(settled):
            sizes = counts[np.searchsorted(ids, source)]
            settled = np.arange(source.size) == np.lexsort((source, sizes))[0]
        lookup = np.arange(labels.max() + 2) - 1  # lookup[label + 1] = label
        lookup[source[settled] + 1] = target[settled]
        labels = lookup[labels + 1]
