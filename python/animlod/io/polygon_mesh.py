"""What the OBJ and PLY readers and writers share: faces of fewer than three corners left out,
face corners checked and fan-triangulated, tokens parsed with the element named, and a mesh
checked before it is written. Whole arrays at a time, no loop over vertices or faces."""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..model import AnimatedMesh
from .errors import FormatError, UnreadAttributesWarning
from .tokens import parses


def polygon_mask(path: Path, sizes: np.ndarray, element: str, refusal: str) -> np.ndarray:
    """(M,) bool: the faces of three vertices or more. Points and lines written among the faces
    have no surface: they are left out with a warning naming ``element``, and a file of nothing
    else is refused there with ``refusal``."""
    polygons = sizes >= 3
    if sizes.size and not polygons.any():
        raise FormatError(path, element, refusal)
    if not polygons.all():
        short = sizes.size - int(polygons.sum())
        warnings.warn(f"{path}: {element}: {short} of {sizes.size} faces have fewer than 3 vertices (points or "
                      "lines); left out", stacklevel=4)  # fmt: skip
    return polygons


def all_finite(
    path: Path, values: np.ndarray | None, what: str, name_vertex: Callable[[int], str]
) -> np.ndarray | None:
    """``values`` (a vertex attribute, a row per vertex) if every one is finite; else None, with a
    warning naming the first vertex that is not: levels carry an attribute for every vertex or
    for none."""
    if values is None or np.isfinite(values).all():
        return values
    bad = int(np.argmin(np.isfinite(values).all(axis=1)))
    warnings.warn(f"{path}: {name_vertex(bad)}: its {what} {values[bad].tolist()} are not finite; the levels are "
                  f"written without {what}", UnreadAttributesWarning, stacklevel=4)  # fmt: skip
    return None


def checked_for_writing(
    path: str | os.PathLike, vertices: np.ndarray, faces: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``vertices (V, 3) float32`` and ``faces (M, 3) int32`` checked as AnimatedMesh checks a
    frame (shapes, finite values, indices in range); otherwise a ValueError that names the file
    and the argument (``out.obj: vertices: vertex 2 [nan, 0.0, 0.0] is not finite``)."""
    given = np.asarray(vertices)
    if not (given.ndim == 2 and given.shape[1] == 3):
        raise ValueError(f"{os.fspath(path)}: vertices: expected shape (V, 3), got {given.shape}")
    try:
        with np.errstate(over="ignore"):  # 1e39 becomes inf, refused below
            positions = np.ascontiguousarray(given, dtype=np.float32)
    except (TypeError, ValueError):
        raise ValueError(f"{os.fspath(path)}: vertices: expected numbers, got dtype {given.dtype}") from None
    finite = np.isfinite(positions).all(axis=1)
    if not finite.all():
        vertex = int(np.argmin(finite))
        reason = f"vertex {vertex} {given[vertex].tolist()} is not finite as float32"
        raise ValueError(f"{os.fspath(path)}: vertices: {reason}")
    try:
        mesh = AnimatedMesh(faces, positions[None])  # checks the faces against the vertex count
    except ValueError as error:
        raise ValueError(f"{os.fspath(path)}: {error}") from None
    return mesh.frames[0], mesh.faces


def parse_numbers(path: Path, tokens: np.ndarray, dtype: type, element: Callable[[int], str]) -> np.ndarray:
    """Convert byte-string tokens to ``dtype``; on failure name the element holding the first bad token."""
    try:
        return tokens.astype(dtype)
    except (ValueError, OverflowError):
        flat = tokens.ravel()
        bad = next(index for index, token in enumerate(flat) if not parses(token, dtype))
        text = flat[bad].decode(errors="replace")
        raise FormatError(path, element(bad), f"{text!r} is not a number or out of range") from None


def check_finite_vertices(path: Path, vertices: np.ndarray, element: Callable[[int], str]) -> None:
    finite = np.isfinite(vertices).all(axis=1)
    if not finite.all():
        vertex = int(np.argmin(finite))
        raise FormatError(path, element(vertex), f"coordinates {vertices[vertex].tolist()} are not finite")


def check_face_indices(
    path: Path,
    indices: np.ndarray,
    written: np.ndarray,
    owner: np.ndarray,
    vertex_count: int,
    element: Callable[[int], str],
    indexed: tuple[str, str] = ("vertex", "vertices"),
) -> None:
    """``indices`` are 0-based corners, ``written`` as in the file, ``owner`` the face of each
    corner; ``indexed``: what they index, for the message (an OBJ corner's texture coordinates)."""
    outside = np.flatnonzero((indices < 0) | (indices >= vertex_count))
    if outside.size:
        corner = outside[0]
        reason = f"{indexed[0]} index {written[corner]} is outside the {vertex_count} {indexed[1]}"
        raise FormatError(path, element(int(owner[corner])), reason)


def within_runs(sizes: np.ndarray) -> np.ndarray:
    """For runs of the given lengths back to back, each item's place in its run: 0, 1, .., n - 1."""
    return np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)


def fan_triangulate(corners: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """Triangles ``(sum(sizes - 2), 3) int32`` fanning each polygon from its first corner.

    ``corners`` holds the vertex indices of all polygons back to back, ``sizes`` their lengths.
    """
    first = np.cumsum(sizes) - sizes
    triangle_counts = sizes - 2
    polygon = np.repeat(np.arange(sizes.size), triangle_counts)
    step = within_runs(triangle_counts)
    base = first[polygon]
    return np.stack([corners[base], corners[base + step + 1], corners[base + step + 2]], axis=1).astype(np.int32)


def polygon_of_triangle(sizes: np.ndarray, triangle: int) -> int:
    """The polygon (an index into ``sizes``, the corner counts of every face as the file lists them)
    whose fan holds triangle ``triangle`` of :func:`fan_triangulate` over the faces of three corners
    or more, as the readers triangulate them."""
    kept = np.flatnonzero(sizes >= 3)
    return int(kept[np.searchsorted(np.cumsum(sizes[kept] - 2), triangle, side="right")])
