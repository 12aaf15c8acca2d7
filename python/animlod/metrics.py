"""Surface error between an animated mesh and its simplification, frame by frame.

Distances are measured both ways between the two surfaces (points sampled on one surface,
closest points on the other), with the core's ``point_mesh_squared_distance`` (a bounding-volume
hierarchy over the triangles, on every core, the GIL released; libigl's function of the same name
is its reference in the tests). Each
frame gives a symmetric Hausdorff distance and an RMS distance; both are reported in asset
units and relative to the original frame's bounding-box diagonal. Where only the largest
Hausdorff distance over the frames counts (the pipelines' level errors),
:func:`hausdorff_distance` gives it, the same value for a fraction of the cost
(:func:`hausdorff_distances` for several levels of one original), and where each frame's
Hausdorff distance counts without the RMS (the face levels' worst frame), :func:`frame_hausdorff`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from . import _core
from .model import AnimatedMesh, whole_number


@dataclass
class SurfaceError:
    """Per-frame surface error of a simplification.

    Attributes
    ----------
    hausdorff : (F,) float64 symmetric Hausdorff distance per frame, asset units.
    rms : (F,) float64 root mean square distance per frame (both directions pooled), asset units.
    diagonal : (F,) float64 bounding-box diagonal of the original in each frame.
    """

    hausdorff: np.ndarray
    rms: np.ndarray
    diagonal: np.ndarray

    @property
    def relative_hausdorff(self) -> np.ndarray:
        return _relative(self.hausdorff, self.diagonal)

    @property
    def relative_rms(self) -> np.ndarray:
        return _relative(self.rms, self.diagonal)

    def summary(self) -> dict[str, float]:
        """Mean and max over frames of both errors, relative to the bounding-box diagonal."""
        return {
            "hausdorff_mean": float(self.relative_hausdorff.mean()),
            "hausdorff_max": float(self.relative_hausdorff.max()),
            "rms_mean": float(self.relative_rms.mean()),
            "rms_max": float(self.relative_rms.max()),
        }


@dataclass
class FrameHausdorff:
    """Per-frame symmetric Hausdorff distance of a simplification (:func:`frame_hausdorff`).

    Attributes
    ----------
    hausdorff : (F,) float64 symmetric Hausdorff distance per frame, asset units.
    diagonal : (F,) float64 bounding-box diagonal of the original in each frame.
    """

    hausdorff: np.ndarray
    diagonal: np.ndarray

    @property
    def relative_hausdorff(self) -> np.ndarray:
        return _relative(self.hausdorff, self.diagonal)


@dataclass
class SurfaceSamples:
    """Fixed points on a mesh's surface, followed through its frames.

    Attributes
    ----------
    faces : (S,) int64 face of each sample.
    barycentric : (S, 3) float64 barycentric coordinates in that face.
    """

    faces: np.ndarray
    barycentric: np.ndarray

    def positions(self, mesh: AnimatedMesh, frame: int | slice) -> np.ndarray:
        """(S, 3) float64 positions of the samples in ``frame``, or (T, S, 3) in a slice of frames."""
        corners = mesh.frames[frame][..., mesh.faces[self.faces], :].astype(np.float64)  # ([T,] S, 3, 3)
        return np.einsum("sk,...skd->...sd", self.barycentric, corners)


def sample_surface(mesh: AnimatedMesh, count: int, seed: int = 0) -> SurfaceSamples:
    """Draw ``count`` points uniformly by area on frame 0 of ``mesh`` (deterministic from ``seed``).

    The same face/barycentric pairs are used in every frame, so the samples move with the surface.
    """
    count, seed = whole_number("samples", count, 0), whole_number("seed", seed, 0)
    corners = mesh.frames[0][mesh.faces].astype(np.float64)
    areas = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    rng = np.random.default_rng(seed)
    total = areas.sum()
    probabilities = areas / total if total > 0 else None
    faces = rng.choice(mesh.face_count, size=count, p=probabilities)
    # Uniform on a triangle: reflect points of the unit square that fall outside it.
    u, v = rng.random(count), rng.random(count)
    outside = u + v > 1
    u[outside], v[outside] = 1 - u[outside], 1 - v[outside]
    return SurfaceSamples(faces, np.stack([1 - u - v, u, v], axis=1))


def surface_error(
    original: AnimatedMesh, simplified: AnimatedMesh, samples: int = 20000, seed: int = 0
) -> SurfaceError:
    """Symmetric Hausdorff and RMS distance between two animations with the same frame count.

    Parameters
    ----------
    original : (F, V, 3) reference sequence.
    simplified : (F, V', 3) approximation of it (any connectivity).
    samples : points drawn on each surface, in addition to its vertices.
    seed : seed of the sampling, so that repeated measurements agree.

    Returns
    -------
    SurfaceError with (F,) arrays; ``summary()`` gives the mean/max over frames relative to the
    bounding-box diagonal.
    """
    there, back, measured = _both_ways(original, simplified, samples, seed, _core.point_mesh_squared_distance)
    squared = np.concatenate([there, back], axis=1)
    return SurfaceError(np.sqrt(squared.max(axis=1)), np.sqrt(squared.mean(axis=1)), _diagonals(measured, samples))


def frame_hausdorff(
    original: AnimatedMesh, simplified: AnimatedMesh, samples: int = 20000, seed: int = 0
) -> FrameHausdorff:
    """The symmetric Hausdorff distance of each frame, equal to :func:`surface_error`'s to the
    bit (the same points, measured both ways), without the distances that cannot raise a frame's
    largest: the core's ``point_mesh_frame_max_squared_distances`` ends a point's search at the
    first triangle no farther than its frame's largest so far (a 100k-vertex head's levels
    measured in a fraction of the time)."""
    there, back, measured = _both_ways(
        original, simplified, samples, seed, _core.point_mesh_frame_max_squared_distances
    )
    return FrameHausdorff(np.sqrt(np.maximum(there, back)), _diagonals(measured, samples))


def _both_ways(
    original: AnimatedMesh, simplified: AnimatedMesh, samples: int, seed: int, kernel: Callable
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``kernel(points, vertices, faces)`` of the original's measured points against the
    simplified surface and of the simplified's against the original, and the original's points
    (:func:`_measured_points`)."""
    _check_frames(original, simplified)
    a, from_original = _measured_points(original, samples, seed)
    b, from_simplified = _measured_points(simplified, samples, seed + 1)
    return kernel(from_original, b, simplified.faces), kernel(from_simplified, a, original.faces), from_original


def _diagonals(measured: np.ndarray, samples: int) -> np.ndarray:
    """(F,) bounding-box diagonal of each frame of a mesh's used vertices, the front of its
    measured points (``_measured_points``; the drawn points follow them)."""
    return np.linalg.norm(np.ptp(measured[:, : measured.shape[1] - samples], axis=1), axis=-1)


def hausdorff_distance(
    original: AnimatedMesh, simplified: AnimatedMesh, samples: int = 20000, seed: int = 0, at_least: float = 0.0
) -> float:
    """The largest symmetric Hausdorff distance over the frames, or ``at_least`` if larger.

    Equal to ``max(at_least, surface_error(original, simplified, samples, seed).hausdorff.max())``
    to the bit (the same points, measured both ways), without the distances that cannot raise
    it: the core's ``point_mesh_max_squared_distance`` ends a point's search at the first
    triangle no farther than the largest distance so far, which starts at ``at_least`` (a
    running maximum the caller holds over clips or levels prunes from the start). ValueError for
    an ``at_least`` that is not a number >= 0 or frame counts that differ.
    """
    return hausdorff_distances(original, [simplified], samples, seed, [at_least])[0]


def hausdorff_distances(
    original: AnimatedMesh,
    simplified: Sequence[AnimatedMesh],
    samples: int = 20000,
    seed: int = 0,
    at_least: Sequence[float] | None = None,
) -> list[float]:
    """:func:`hausdorff_distance` of each of several simplifications of one original (levels),
    each from its own ``at_least`` (default 0); the original's points are drawn once."""
    at_least = [0.0] * len(simplified) if at_least is None else list(at_least)
    if len(at_least) != len(simplified):
        raise ValueError(f"at_least: {len(at_least)} values for {len(simplified)} simplified meshes")
    for value in at_least:
        if not value >= 0.0:
            raise ValueError(f"at_least: {value!r}, expected a distance >= 0")
    for each in simplified:
        _check_frames(original, each)
    if not simplified:
        return []
    a, from_original = _measured_points(original, samples, seed)
    squared, from_simplified = [], []
    for each, floor in zip(simplified, at_least):
        b, points = _measured_points(each, samples, seed + 1)
        squared.append(_core.point_mesh_max_squared_distance(from_original, b, each.faces, floor=floor * floor))
        from_simplified.append(points)
    # Every level's points against the original at once: its tree is built once for them all.
    ends = np.cumsum([points.shape[1] for points in from_simplified])
    squared = _core.point_mesh_max_squared_distances(
        np.concatenate(from_simplified, axis=1), a, original.faces, ends, np.array(squared)
    )
    return [max(floor, float(np.sqrt(value))) for floor, value in zip(at_least, squared)]


def _check_frames(original: AnimatedMesh, simplified: AnimatedMesh) -> None:
    if original.frame_count != simplified.frame_count:
        raise ValueError(f"simplified: {simplified.frame_count} frames, the original has {original.frame_count}")


def _measured_points(mesh: AnimatedMesh, samples: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The mesh's (F, V, 3) float64 frames and the points measured against the other surface:
    the vertices its faces use (one no face uses is no part of the surface) and ``samples``
    points drawn on its surface, (F, U + samples, 3), every frame in one array (the core builds
    each mesh's tree once and refits it from frame to frame)."""
    frames = mesh.frames.astype(np.float64)
    used = np.zeros(mesh.vertex_count, bool)
    used[mesh.faces] = True  # a mask, not np.unique: no sort of every corner (seconds at 1M faces)
    vertices = frames if used.all() else frames[:, used]
    drawn = sample_surface(mesh, samples, seed).positions(mesh, slice(None))
    return frames, np.concatenate([vertices, drawn], axis=1)


def _relative(distance: np.ndarray, diagonal: np.ndarray) -> np.ndarray:
    """``distance / diagonal`` per frame; where a frame has collapsed to one point (diagonal 0),
    0 for no distance and inf otherwise, never NaN (with no numpy RuntimeWarning)."""
    safe = np.where(diagonal > 0.0, diagonal, 1.0)
    return np.where(diagonal > 0.0, distance / safe, np.where(distance == 0.0, 0.0, np.inf))
