"""A face ready to animate by regions: lattices, MPAs, and one animator per level of detail.

:class:`FaceRig` holds the full face, its regions, one lattice per region and the MPAs. Its
:meth:`FaceRig.animator` prepares the runtime of one level (seeds/004, Section 4.2): the level's
vertices and their region labels, the active regions of the active tree (MPAs that touch no
active region are skipped, vertices of inactive regions stay at rest) and which regions use a
2x2x2 instead of a 3x3x3 lattice. A frame is then one small matrix product (MPA intensities to
control displacements) and one call of the core's ``ffd_displace`` over the level's vertices.

Shapes: ``V`` vertices of the full face, ``V'`` of a level, ``N`` MPAs, ``C`` control points.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

import numpy as np

from .. import _core
from .lattice import DEFAULT_SIZE, REDUCED_SIZE, RegionLattice, corners, evaluate, fit_displacements, region_lattice
from .mpa import Mpa
from .regions import FaceRegions


class FaceRig:
    """The full face with regions, lattices and MPAs.

    Parameters
    ----------
    positions : (V, 3) rest positions, asset units.
    faces : (M, 3) int32 triangles.
    regions : labels covering the V vertices (None is refused with a message offering labels
        grown from the face's motion, :func:`animlod.face_lod.grow_regions`).
    mpas : the MPAs; each displacement array must match its region's lattice size.
    lattice_weights : region -> (3, 3, 3) rational weights (ones where not given).
    margin : lattice boxes are the regions' bounding boxes grown by this fraction.

    Raises ValueError naming the element: labels that do not cover the mesh, an MPA on a region
    that does not exist (or has no vertex), displacements of the wrong shape, a degenerate box.
    """

    def __init__(
        self,
        positions: np.ndarray,
        faces: np.ndarray,
        regions: FaceRegions | None,
        mpas: Sequence[Mpa] = (),
        lattice_weights: dict[str, np.ndarray] | None = None,
        margin: float = 0.05,
    ) -> None:
        self.positions = np.ascontiguousarray(positions, dtype=np.float32)
        self.faces = np.ascontiguousarray(faces, dtype=np.int32)
        if regions is None:
            raise ValueError(
                "region labels: the face has none, and region-based animation needs them; grow labels from its motion "
                "with animlod.face_lod.grow_regions(motion_of_frames(frames) or motion_of_targets(targets, "
                "weights), faces)"
            )
        regions.check_vertex_count(len(self.positions))
        self.regions = regions
        lattice_weights = lattice_weights or {}
        for name in lattice_weights:
            regions.index(name, "lattice weights")
        self.lattices: dict[str, RegionLattice] = {}
        self.local = np.zeros_like(self.positions)
        for index, name in enumerate(regions.names):
            members = np.flatnonzero(regions.vertex_regions == index)
            if members.size == 0:
                continue
            lattice = region_lattice(name, self.positions[members], DEFAULT_SIZE, margin, lattice_weights.get(name))
            self.lattices[name] = lattice
            self.local[members] = lattice.local(self.positions[members])
        self.mpas: list[Mpa] = []
        for mpa in mpas:
            self.add_mpa(mpa)
        self._reduced: dict[tuple[int, str], np.ndarray] = {}

    @property
    def mpa_names(self) -> list[str]:
        return [mpa.name for mpa in self.mpas]

    def add_mpa(self, mpa: Mpa) -> None:
        """Add an MPA after checking its regions and shapes (ValueError naming MPA and region)."""
        if mpa.name in self.mpa_names:
            raise ValueError(f"MPA {mpa.name!r}: defined twice")
        for region, delta in mpa.displacements.items():
            self.regions.index(region, f"MPA {mpa.name!r}")
            if region not in self.lattices:
                raise ValueError(f"MPA {mpa.name!r}: region {region!r} has no vertex to move")
            expected = self.lattices[region].size + (3,)
            if np.shape(delta) != expected:
                raise ValueError(f"MPA {mpa.name!r}, region {region!r}: displacements of shape {np.shape(delta)}, "
                                 f"expected {expected}")  # fmt: skip
            if not np.all(np.isfinite(delta)):
                raise ValueError(f"MPA {mpa.name!r}, region {region!r}: non-finite displacement")
        self.mpas.append(Mpa(mpa.name, {r: np.asarray(d, dtype=np.float64) for r, d in mpa.displacements.items()}))

    def mpa_index(self, name: str) -> int:
        try:
            return self.mpa_names.index(name)
        except ValueError:
            raise ValueError(f"face rig: no MPA named {name!r}") from None

    def region_points(self, region: str) -> tuple[np.ndarray, np.ndarray]:
        """Rest positions ``(V_r, 3)`` and local coordinates ``(V_r, 3)`` of a region's vertices."""
        members = self.regions.vertex_regions == self.regions.index(region)
        return self.positions[members], self.local[members]

    def mpa_from_field(
        self, name: str, regions: Sequence[str], field: Callable[[np.ndarray], np.ndarray],
        min_displacement: float = 0.0,
    ) -> Mpa:  # fmt: skip
        """An MPA whose control displacements reproduce a displacement ``field`` as well as each
        region's lattice can: least squares over the region's vertices, starting from the field
        at the control points (where the vertices say little, the control points keep it).

        Parameters
        ----------
        name : MPA name.
        regions : the regions it acts on (ValueError naming the MPA for an unknown one).
        field : ``field(points (V, 3)) -> (V, 3)`` displacement at intensity 1, asset units.
        min_displacement : regions where the field never exceeds this (asset units) are left out.
        """
        displacements = {}
        for region in regions:
            self.regions.index(region, f"MPA {name!r}")
            if region not in self.lattices:
                raise ValueError(f"MPA {name!r}: region {region!r} has no vertex to move")
            points, local = self.region_points(region)
            targets = np.asarray(field(points.astype(np.float64)), dtype=np.float64)
            if np.max(np.linalg.norm(targets, axis=1), initial=0.0) <= min_displacement:
                continue
            lattice = self.lattices[region]
            controls = lattice.control_points()
            prior = np.asarray(field(controls.reshape(-1, 3)), dtype=np.float64).reshape(controls.shape)
            displacements[region] = fit_displacements(local, targets, lattice.size, lattice.weights, prior)
        return Mpa(name, displacements)

    def reduced_displacements(self, mpa: int, region: str) -> np.ndarray:
        """(2, 2, 2, 3) displacements of a 2x2x2 lattice on ``region`` fitted by least squares to
        what MPA ``mpa``'s 3x3x3 lattice does to the region's vertices (Section 4.2.2)."""
        key = (mpa, region)
        if key not in self._reduced:
            _, local = self.region_points(region)
            lattice = self.lattices[region]
            delta = self.mpas[mpa].displacements[region]
            moved = evaluate(local, delta, lattice.weights)
            self._reduced[key] = fit_displacements(local, moved, REDUCED_SIZE, prior=corners(delta))
        return self._reduced[key]

    def animator(
        self,
        positions: np.ndarray | None = None,
        vertex_regions: np.ndarray | None = None,
        active: Iterable[str] | None = None,
        reduced: Iterable[str] = (),
    ) -> LevelAnimator:
        """The runtime of one level.

        Parameters
        ----------
        positions : (V', 3) rest positions of the level (the full face when None).
        vertex_regions : (V',) region index of each of its vertices (the full face's when None).
        active : regions animated at this level (all when None); the others stay at rest.
        reduced : regions that use a 2x2x2 lattice fitted to their 3x3x3 one.
        """
        if positions is None:
            positions, vertex_regions = self.positions, self.regions.vertex_regions
        positions = np.ascontiguousarray(positions, dtype=np.float32)
        vertex_regions = np.asarray(vertex_regions, dtype=np.int32)
        if vertex_regions.shape != (len(positions),):
            raise ValueError(f"level: {vertex_regions.shape} region labels for {len(positions)} vertices")
        active_names = set(self.regions.names if active is None else active)
        reduced_names = set(reduced)
        for name in active_names | reduced_names:
            self.regions.index(name, "level")
        moving = [name for name in self.regions.names if name in active_names and name in self.lattices]
        moving = [name for name in moving if any(name in mpa.displacements for mpa in self.mpas)]
        return LevelAnimator(self, positions, vertex_regions, moving, reduced_names)


class LevelAnimator:
    """Deforms one level of a face from MPA intensities (built by :meth:`FaceRig.animator`).

    Attributes
    ----------
    rest : (V', 3) float32 rest positions (read-only).
    regions : names of the animated regions, in lattice order.
    sizes : (R', 3) int32 lattice size of each animated region.
    active_mpas : (N',) indices of the MPAs that touch an animated region (the others are skipped).
    """

    def __init__(
        self, rig: FaceRig, rest: np.ndarray, vertex_regions: np.ndarray, regions: list[str], reduced: set[str]
    ) -> None:
        self.rest = rest
        self.rest.flags.writeable = False
        self.mpa_count = len(rig.mpas)
        self.regions = regions
        sizes = [REDUCED_SIZE if name in reduced else DEFAULT_SIZE for name in regions]
        self.sizes = np.array(sizes, np.int32).reshape(-1, 3)
        counts = np.prod(self.sizes, axis=1)
        starts = np.concatenate([[0], np.cumsum(counts)])
        control_count = int(starts[-1])
        # Local coordinates of this level's vertices in their region's box; -1: not animated.
        self.local = np.zeros_like(rest)
        self.vertex_lattice = np.full(len(rest), -1, np.int32)
        weights = np.ones(control_count)
        for lattice_index, name in enumerate(regions):
            members = vertex_regions == rig.regions.index(name)
            self.vertex_lattice[members] = lattice_index
            self.local[members] = rig.lattices[name].local(rest[members])
            if name not in reduced:
                weights[starts[lattice_index] : starts[lattice_index + 1]] = rig.lattices[name].weights.ravel()
        self.weights = weights
        # One row per MPA that moves an animated region: its control displacements, flattened.
        rows, used = [], []
        for m, mpa in enumerate(rig.mpas):
            row = np.zeros((control_count, 3))
            for lattice_index, name in enumerate(regions):
                if name not in mpa.displacements:
                    continue
                delta = rig.reduced_displacements(m, name) if name in reduced else mpa.displacements[name]
                row[starts[lattice_index] : starts[lattice_index + 1]] = delta.reshape(-1, 3)
            if np.any(row):
                rows.append(row.ravel())
                used.append(m)
        self.active_mpas = np.array(used, dtype=np.int64)
        self.basis = np.array(rows).reshape(len(used), control_count * 3)
        self.control_count = control_count

    @property
    def animates(self) -> bool:
        """False when no MPA moves any vertex of this level (every frame is the rest pose)."""
        return self.active_mpas.size > 0

    def frame(self, intensities: np.ndarray) -> np.ndarray:
        """(V', 3) float32 positions for ``intensities (N,)`` of every MPA of the rig. When nothing
        is animated, the read-only rest array itself (no work at all, as the paper's coarsest level)."""
        if not self.animates:
            return self.rest
        displacements = (np.asarray(intensities)[self.active_mpas] @ self.basis).reshape(self.control_count, 3)
        return _core.ffd_displace(self.rest, self.local, self.vertex_lattice, self.sizes, displacements, self.weights)

    def frames(self, intensities: np.ndarray) -> np.ndarray:
        """(T, V', 3) float32 positions for ``intensities (T, N)``, all frames in one core call."""
        intensities = np.asarray(intensities, dtype=np.float64)
        if intensities.ndim != 2 or intensities.shape[1] != self.mpa_count:
            raise ValueError(f"intensities: expected shape (T, {self.mpa_count}), got {intensities.shape}")
        if not self.animates:
            return np.broadcast_to(self.rest, (len(intensities),) + self.rest.shape).copy()
        displacements = intensities[:, self.active_mpas] @ self.basis
        displacements = displacements.reshape(len(intensities), self.control_count, 3)
        return _core.ffd_displace(self.rest, self.local, self.vertex_lattice, self.sizes, displacements, self.weights)

    def targets(self) -> np.ndarray:
        """(N, V', 3) float32 displacement of every MPA at intensity 1 (zero for skipped MPAs): the
        level as blendshapes, exact because the FFD is linear in the control displacements."""
        out = np.zeros((self.mpa_count,) + self.rest.shape, np.float32)
        if self.animates:
            out[self.active_mpas] = self.frames(np.eye(self.mpa_count)[self.active_mpas]) - self.rest
        return out
