"""Closed-surface building blocks for the procedural assets: tubes, capsules, icospheres.

Every builder returns vertices and counter-clockwise faces (normals outward), built with numpy
broadcasting over rings and segments; the only Python loops run over subdivision levels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Tube:
    """A closed generalised cylinder: R rings of S vertices plus two pole vertices.

    Attributes
    ----------
    positions : (R * S + 2, 3) float64; ring r, segment s at index ``r * S + s``, then the
        start pole and the end pole.
    faces : (2 * S * R, 3) int32, counter-clockwise seen from outside.
    around : (R * S + 2,) float64 in [0, 1): angle of each vertex about the axis / 2 pi
        (0.5 for the poles); a cylindrical texture coordinate.
    along : (R * S + 2,) float64 in [0, 1]: ring position along the axis, from the start pole (0)
        to the end pole (1).
    """

    positions: np.ndarray
    faces: np.ndarray
    around: np.ndarray
    along: np.ndarray


def orthonormal_frame(axis: np.ndarray, width_hint: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Right-handed frame ``(u, v, w)`` with ``w`` along ``axis`` and ``u`` nearest ``width_hint``.

    ``u x v = w``, so a ring traversed from ``u`` towards ``v`` winds counter-clockwise about ``w``.
    """
    w = np.asarray(axis, dtype=np.float64)
    w = w / np.linalg.norm(w)
    u = np.asarray(width_hint, dtype=np.float64)
    u = u - np.dot(u, w) * w
    u = u / np.linalg.norm(u)
    return u, np.cross(w, u), w


def cross_section(segments: int, shape: str = "ellipse") -> np.ndarray:
    """Unit cross-section outline ``(S, 2)``, counter-clockwise from the +u direction.

    ``"ellipse"`` gives a circle (scaled per ring into an ellipse); ``"square"`` projects the
    same angles onto the square of half-side 1 (corners included when S is a multiple of 8).
    """
    if segments < 3:
        raise ValueError(f"segments: need at least 3, got {segments}")
    angle = 2.0 * np.pi * np.arange(segments) / segments
    outline = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    if shape == "square":
        outline /= np.abs(outline).max(axis=1, keepdims=True)
    elif shape != "ellipse":
        raise ValueError(f"shape: expected 'ellipse' or 'square', got {shape!r}")
    return outline


def tube(
    centres: np.ndarray,
    half_widths: np.ndarray,
    half_depths: np.ndarray,
    frame: tuple[np.ndarray, np.ndarray, np.ndarray],
    poles: np.ndarray,
    outline: np.ndarray,
) -> Tube:
    """Sweep ``outline`` along ring ``centres`` and close both ends with a triangle fan to a pole.

    Parameters
    ----------
    centres : (R, 3) ring centres, R >= 2, ordered along ``frame``'s axis ``w``.
    half_widths, half_depths : (R,) ring radii along ``u`` and ``v``.
    frame : ``(u, v, w)`` from :func:`orthonormal_frame`.
    poles : (2, 3) the vertex closing the first ring and the one closing the last ring.
    outline : (S, 2) unit cross-section from :func:`cross_section`.
    """
    u, v, w = frame
    centres = np.asarray(centres, dtype=np.float64)
    poles = np.asarray(poles, dtype=np.float64)
    ring_count, segment_count = centres.shape[0], outline.shape[0]
    if ring_count < 2:
        raise ValueError(f"centres: a tube needs at least 2 rings, got {ring_count}")
    radii_u = np.asarray(half_widths, dtype=np.float64)[:, None, None] * outline[None, :, 0:1]
    radii_v = np.asarray(half_depths, dtype=np.float64)[:, None, None] * outline[None, :, 1:2]
    rings = centres[:, None, :] + radii_u * u + radii_v * v  # (R, S, 3)
    positions = np.concatenate([rings.reshape(-1, 3), poles])

    ring = np.arange(ring_count)[:, None]
    segment = np.arange(segment_count)[None, :]
    here = ring * segment_count + segment  # (R, S)
    ahead = ring * segment_count + (segment + 1) % segment_count
    # Quads between ring r and r + 1; (here, ahead) runs from u towards v, so with the next ring
    # further along w the triangle normals point away from the axis.
    a, b = here[:-1].ravel(), ahead[:-1].ravel()
    c, d = ahead[1:].ravel(), here[1:].ravel()
    sides = np.concatenate([np.stack([a, b, c], -1), np.stack([a, c, d], -1)])
    start_pole, end_pole = ring_count * segment_count, ring_count * segment_count + 1
    first, first_ahead = here[0], ahead[0]
    last, last_ahead = here[-1], ahead[-1]
    start_cap = np.stack([np.full(segment_count, start_pole), first_ahead, first], -1)  # faces -w
    end_cap = np.stack([np.full(segment_count, end_pole), last, last_ahead], -1)  # faces +w
    faces = np.concatenate([sides, start_cap, end_cap]).astype(np.int32)

    around = np.concatenate([np.tile(np.arange(segment_count) / segment_count, ring_count), [0.5, 0.5]])
    ring_along = (centres - poles[0]) @ w / ((poles[1] - poles[0]) @ w)
    along = np.concatenate([np.repeat(ring_along, segment_count), [0.0, 1.0]])
    return Tube(positions, faces, around, along)


def capsule(
    start: np.ndarray,
    axis: np.ndarray,
    width_hint: np.ndarray,
    stations: np.ndarray,
    segments: int,
    spacing: float,
    cap_rings: int = 3,
    shift_direction: np.ndarray | None = None,
) -> Tube:
    """A tube with rounded (elliptic quarter-circle) ends and a radius profile from ``stations``.

    Parameters
    ----------
    start : (3,) point where the tube begins (its start pole).
    axis : (3,) direction of the tube; the tube ends at ``start + axis_unit * stations[-1, 0]``.
    width_hint : (3,) direction of the half-width ``stations[:, 1]``.
    stations : (N, 4) rows ``(distance along axis, half-width, half-depth, shift)``, distances
        increasing from 0; profiles are linear in between.
    segments : vertices per ring.
    spacing : target distance between body rings.
    cap_rings : rings in each rounded end.
    shift_direction : (3,) direction in which ``shift`` moves the ring centre (default none).
    """
    stations = np.asarray(stations, dtype=np.float64)
    frame = orthonormal_frame(axis, width_hint)
    length = stations[-1, 0]
    # A rounded end is as long as the mean radius there, at most a third of the tube.
    cap_lengths = np.minimum(0.5 * (stations[[0, -1], 1] + stations[[0, -1], 2]), length / 3.0)
    body_count = max(2, round((length - cap_lengths.sum()) / spacing) + 1)
    body = np.linspace(cap_lengths[0], length - cap_lengths[1], body_count)
    theta = 0.5 * np.pi * np.arange(1, cap_rings + 1) / (cap_rings + 1)  # pole -> body
    start_cap = cap_lengths[0] * (1.0 - np.sin(theta))
    end_cap = length - cap_lengths[1] * (1.0 - np.sin(theta[::-1]))
    distance = np.concatenate([start_cap, body, end_cap])
    roundness = np.concatenate([np.cos(theta), np.ones(body_count), np.cos(theta[::-1])])

    profile = [np.interp(distance, stations[:, 0], stations[:, k]) for k in (1, 2, 3)]
    half_widths, half_depths, shift = profile
    shift_vector = np.zeros(3) if shift_direction is None else np.asarray(shift_direction, dtype=np.float64)
    centres = np.asarray(start, dtype=np.float64) + distance[:, None] * frame[2] + shift[:, None] * shift_vector
    end_shift = stations[[0, -1], 3][:, None] * shift_vector
    poles = np.asarray(start, dtype=np.float64) + np.array([0.0, length])[:, None] * frame[2] + end_shift
    return tube(centres, half_widths * roundness, half_depths * roundness, frame, poles, cross_section(segments))


def icosphere(subdivisions: int = 2, radius: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A geodesic sphere: the icosahedron with each triangle split into four ``subdivisions`` times.

    Returns ``positions (10 * 4**n + 2, 3) float32`` on the sphere of ``radius`` about the origin
    and ``faces (20 * 4**n, 3) int32``, counter-clockwise seen from outside.
    """
    if subdivisions < 0:
        raise ValueError(f"subdivisions: must be >= 0, got {subdivisions}")
    t = (1.0 + np.sqrt(5.0)) / 2.0
    positions = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
        dtype=np.float64,
    )  # fmt: skip
    faces = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]],
        dtype=np.int64,
    )  # fmt: skip
    positions /= np.linalg.norm(positions, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        unique_edges, edge_of = np.unique(edges, axis=0, return_inverse=True)
        midpoints = positions[unique_edges].sum(axis=1)
        midpoints /= np.linalg.norm(midpoints, axis=1, keepdims=True)
        ab, bc, ca = (len(positions) + np.asarray(edge_of).reshape(-1, 3)).T
        a, b, c = faces.T
        faces = np.concatenate([np.stack(tri, -1) for tri in ((a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca))])
        positions = np.concatenate([positions, midpoints])
    return (radius * positions).astype(np.float32), faces.astype(np.int32)


def merge(parts: list[tuple[np.ndarray, np.ndarray]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Concatenate ``(positions, faces)`` parts into one mesh.

    Returns ``positions (V, 3)``, ``faces (M, 3) int32`` with indices offset per part, and
    ``part_of_vertex (V,) int32``.
    """
    counts = np.array([len(p) for p, _ in parts])
    offsets = np.concatenate([[0], np.cumsum(counts)[:-1]])
    positions = np.concatenate([p for p, _ in parts])
    faces = np.concatenate([f + o for (_, f), o in zip(parts, offsets)]).astype(np.int32)
    part_of_vertex = np.repeat(np.arange(len(parts), dtype=np.int32), counts)
    return positions, faces, part_of_vertex
