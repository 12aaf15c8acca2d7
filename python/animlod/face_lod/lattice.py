"""Control lattices of face regions: boxes, rational FFD and the 2x2x2 least-squares lattice.

Each region has a lattice of 3x3x3 control points along its bounding box (seeds/004, Section
3.2.2), with one weight per control point (rational FFD). An MPA moves control points; the
region's vertices follow through the rational Bernstein volume, evaluated in the C++ core
(``animlod._core.ffd_*``, cpp/include/animlod/ffd_lattice.hpp). At coarse levels a region's
3x3x3 lattice is replaced by a 2x2x2 one (Section 4.2.2, Figure 8) whose control displacements
are fitted by least squares to what the 3x3x3 lattice does to the region's vertices.

Shapes: ``V`` vertices, ``(l, m, n)`` control points per axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _core

DEFAULT_SIZE = (3, 3, 3)
REDUCED_SIZE = (2, 2, 2)


@dataclass
class RegionLattice:
    """The lattice of one region.

    Attributes
    ----------
    region : region name.
    box : (4, 3) float64 origin and S, T, U edge vectors, asset units.
    weights : (l, m, n) float64 > 0 rational weights (all ones: plain Bezier FFD).
    """

    region: str
    box: np.ndarray
    weights: np.ndarray

    @property
    def size(self) -> tuple[int, int, int]:
        return tuple(int(n) for n in self.weights.shape)  # type: ignore[return-value]

    def local(self, points: np.ndarray) -> np.ndarray:
        """(V, 3) float32 local coordinates of ``points (V, 3)`` in the box (ValueError naming the
        region for a degenerate box)."""
        try:
            return _core.ffd_local_coordinates(points, self.box)
        except ValueError as error:
            raise ValueError(f"region {self.region!r}: {error}") from None

    def control_points(self) -> np.ndarray:
        """(l, m, n, 3) float64 rest control points: the regular grid over the box."""
        axes = [np.linspace(0.0, 1.0, n) for n in self.size]
        s, t, u = np.meshgrid(*axes, indexing="ij")
        return self.box[0] + s[..., None] * self.box[1] + t[..., None] * self.box[2] + u[..., None] * self.box[3]


def bounding_box(points: np.ndarray, margin: float = 0.05) -> np.ndarray:
    """Axis-aligned box (4, 3) around ``points (V, 3)``, grown on every side by ``margin`` times
    its largest extent (so that a flat region still gets a box with depth)."""
    points = np.asarray(points, dtype=np.float64)
    low, high = points.min(axis=0), points.max(axis=0)
    pad = margin * float(np.max(high - low))
    low, high = low - pad, high + pad
    return np.vstack([low, np.diag(high - low)])


def region_lattice(
    region: str, points: np.ndarray, size: tuple[int, int, int] = DEFAULT_SIZE, margin: float = 0.05,
    weights: np.ndarray | None = None,
) -> RegionLattice:  # fmt: skip
    """The lattice of a region whose vertices are ``points (V, 3)``: its padded bounding box, and
    ``weights (l, m, n)`` (all ones by default). ValueError naming the region when it has no
    vertex or its box is degenerate (a single point)."""
    if len(points) == 0:
        raise ValueError(f"region {region!r}: has no vertex to build a lattice around")
    weights = np.ones(size) if weights is None else np.asarray(weights, dtype=np.float64)
    if weights.shape != tuple(size):
        raise ValueError(f"region {region!r}: lattice weights of shape {weights.shape}, expected {tuple(size)}")
    lattice = RegionLattice(region, bounding_box(points, margin), weights)
    lattice.local(np.asarray(points[:1], dtype=np.float32))  # a degenerate box fails here, naming the region
    return lattice


def fit_displacements(
    local: np.ndarray,
    targets: np.ndarray,
    size: tuple[int, int, int],
    weights: np.ndarray | None = None,
    prior: np.ndarray | None = None,
) -> np.ndarray:
    """Control displacements ``(l, m, n, 3)`` whose rational FFD best reproduces the
    displacements ``targets (V, 3)`` at local coordinates ``local (V, 3)``; control points the
    vertices hardly determine stay near ``prior (l, m, n, 3)`` (core ``ffd_fit``, regularised)."""
    return _core.ffd_fit(
        np.asarray(local, dtype=np.float32), np.asarray(targets, dtype=np.float32), list(size), weights, prior=prior
    )


def corners(control_points: np.ndarray) -> np.ndarray:
    """(2, 2, 2, 3) corner control points of a lattice: where its volume passes exactly."""
    return np.ascontiguousarray(control_points[[0, -1]][:, [0, -1]][:, :, [0, -1]])


def evaluate(local: np.ndarray, control_points: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Rational FFD ``(V, 3)`` of ``control_points (l, m, n, 3)`` at ``local (V, 3)`` (core ``ffd_evaluate``)."""
    return _core.ffd_evaluate(np.asarray(local, dtype=np.float32), control_points, weights)
