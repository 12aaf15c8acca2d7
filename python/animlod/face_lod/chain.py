"""Levels of detail of a region-animated face (seeds/004, Section 4): geometry, animation, deformation.

:func:`build_face_lod` makes

- **geometry levels** by AQEM over the frames of the face's animation, every vertex's cost scaled
  by its region group's importance (Section 4.1.1), so moving regions are protected and ears,
  eyeballs and teeth go first; the region label of every kept vertex is its input label;
- **animation levels** from the active tree (Section 4.2.1);
- **deformation levels**: at geometry level g >= 1 a region's 3x3x3 lattice is replaced by the
  2x2x2 lattice fitted to it (Section 4.2.2) when what that loses is no more than the geometry
  already lost (the largest 2x2x2 fit error over the region's MPAs at intensity 1 is at most the
  level's geometric error, the Hausdorff distance of its rest mesh to the full one), or as
  listed explicitly;
- the **dependency** of Figure 6: each geometry level has a finest animation level it allows;
- and the error of every level in asset units, from which :mod:`.selection` derives screen
  coverage thresholds.

Shapes: ``V`` vertices, ``M`` faces, ``T`` animation frames.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..aqem import check_aqem_options, simplify_animated
from ..metrics import hausdorff_distance
from ..model import AnimatedMesh, spread_frames
from .active_tree import ActiveTree
from .mpa import MpaAnimation
from .regions import FaceRegions
from .rig import FaceRig, LevelAnimator

# The paper's face: 2,313 triangles at level 0, 1,533 at level 1 and 357 at level 2 (Table 1).
PAPER_RATIOS = (1533 / 2313, 357 / 2313)


@dataclass
class FaceLodOptions:
    """How :func:`build_face_lod` builds the levels.

    Attributes
    ----------
    ratios : sizes of the geometry levels after the full face, as fractions of its triangles.
    face_counts : the same as triangle counts; replaces ``ratios`` when given.
    animation_floor : per geometry level (the full face included), the finest active tree level
        it may animate; default: 0 for the full face, the empty level for the coarsest, and
        min(g, tree levels - 2) between.
    reduced_lattices : per geometry level, the regions that use a 2x2x2 lattice; default: the
        fit-error rule (none at level 0).
    max_frames : animation frames AQEM looks at, at most (evenly spaced, the rest pose first).
    use_motion_features : AQEM's motion-feature weights (Eq. 6) on top of region importance.
    region_importance : False gives every vertex importance 1 (the plain AQEM baseline).
    """

    ratios: Sequence[float] = PAPER_RATIOS
    face_counts: Sequence[int] | None = None
    animation_floor: Sequence[int] | None = None
    reduced_lattices: Sequence[Sequence[str]] | None = None
    max_frames: int = 40
    use_motion_features: bool = True
    region_importance: bool = True


@dataclass
class GeometryLevel:
    """One mesh level of a face.

    Attributes
    ----------
    faces : (M', 3) int32.
    rest : (V', 3) float32 rest positions.
    kept_vertices : (V',) int32 input vertex of each vertex.
    regions : labels of the level (the input labels of the kept vertices).
    face_regions : (M',) int32 region of each face.
    aqem_error : AQEM's error of the level, asset units (0 for the full face).
    geometric_error : Hausdorff distance between the level's rest mesh and the full face's,
        asset units (0 for the full face).
    animation_floor : the finest active tree level this geometry allows.
    reduced : regions that use a 2x2x2 lattice at this level.
    """

    faces: np.ndarray
    rest: np.ndarray
    kept_vertices: np.ndarray
    regions: FaceRegions
    face_regions: np.ndarray
    aqem_error: float
    geometric_error: float
    animation_floor: int
    reduced: frozenset[str]

    @property
    def triangle_count(self) -> int:
        return int(len(self.faces))

    @property
    def vertex_count(self) -> int:
        return int(len(self.rest))


@dataclass
class FaceLodChain:
    """Geometry levels, the active tree and the rig that animates them.

    Attributes
    ----------
    rig : the full face.
    tree : the active tree.
    geometry : geometry levels, finest first (level 0 is the full face).
    reduction_error : region -> largest distance (asset units) between its 3x3x3 and fitted
        2x2x2 lattices over its MPAs at intensity 1 and its vertices.
    """

    rig: FaceRig
    tree: ActiveTree
    geometry: list[GeometryLevel]
    reduction_error: dict[str, float]
    _animators: dict[tuple[int, int], LevelAnimator] = field(default_factory=dict, repr=False)

    def animation_level(self, geometry_level: int, wanted: int) -> int:
        """The active tree level used at ``geometry_level`` when ``wanted`` is asked for: never
        finer than the geometry allows (Figure 6)."""
        return min(max(wanted, self.geometry[geometry_level].animation_floor), self.tree.level_count - 1)

    def animator(self, geometry_level: int, animation_level: int | None = None) -> LevelAnimator:
        """The runtime of a geometry level at an animation level (default: the finest it allows)."""
        level = self.geometry[geometry_level]
        wanted = level.animation_floor if animation_level is None else animation_level
        animation = self.animation_level(geometry_level, wanted)
        key = (geometry_level, animation)
        if key not in self._animators:
            self._animators[key] = self.rig.animator(
                level.rest, level.regions.vertex_regions, self.tree.active(animation), level.reduced
            )
        return self._animators[key]


def build_face_lod(
    rig: FaceRig, tree: ActiveTree, animation: MpaAnimation, options: FaceLodOptions | None = None
) -> FaceLodChain:
    """Geometry, animation and deformation levels of a region-animated face.

    Parameters
    ----------
    rig : the full face, its regions and MPAs.
    tree : the active tree over the rig's regions.
    animation : MPA intensities whose frames AQEM preserves (its MPA names must be the rig's).
    options : level sizes and rules.

    Raises ValueError naming the element for an animation on other MPAs, floors or reduced
    lattices of the wrong length or naming unknown regions, and whatever AQEM rejects.
    """
    options = options or FaceLodOptions()
    if animation.mpa_names != rig.mpa_names:
        raise ValueError("face LoD: the animation's MPAs are not the rig's (same names, same order expected)")
    full = rig.animator()
    # Phase 1: the frames AQEM sees: the rest pose, then evenly spaced animation frames.
    picked = spread_frames(animation.frame_count, max(1, options.max_frames - 1))
    frames = np.concatenate([rig.positions[None], full.frames(animation.intensities[picked])])
    importance = rig.regions.vertex_importance() if options.region_importance else None
    if options.face_counts is not None:
        counts = [int(c) for c in options.face_counts]
    else:  # the core sees counts only: a ratio outside (0, 1] would become a count it takes
        check_aqem_options(list(options.ratios))
        counts = [max(4, round(ratio * len(rig.faces))) for ratio in options.ratios]
    # Phase 2: geometry levels.
    result = simplify_animated(
        AnimatedMesh(rig.faces, frames),
        target_face_counts=counts,
        importance=importance,
        use_motion_features=options.use_motion_features,
        record_positions=False,
    )
    level_count = 1 + len(counts)
    floors = _floors(options.animation_floor, level_count, tree)
    reduction_error = _reduction_errors(rig)
    rest = AnimatedMesh(rig.faces, rig.positions[None])
    geometric = [0.0] + [
        hausdorff_distance(rest, AnimatedMesh(level.mesh.faces, level.mesh.frames[:1]), samples=5000)
        for level in result.levels
    ]
    reduced_sets = _reduced(options.reduced_lattices, rig, reduction_error, geometric)
    geometry = [
        GeometryLevel(rig.faces, rig.positions, np.arange(len(rig.positions), dtype=np.int32), rig.regions,
                      rig.regions.face_regions(rig.faces), 0.0, 0.0, floors[0], reduced_sets[0])
    ]  # fmt: skip
    for index, level in enumerate(result.levels, start=1):
        labels = rig.regions.subset(level.kept_vertices)
        geometry.append(
            GeometryLevel(
                faces=level.mesh.faces,
                rest=level.mesh.frames[0],
                kept_vertices=level.kept_vertices,
                regions=labels,
                face_regions=labels.face_regions(level.mesh.faces),
                aqem_error=level.error,
                geometric_error=geometric[index],
                animation_floor=floors[index],
                reduced=reduced_sets[index],
            )
        )
    return FaceLodChain(rig, tree, geometry, reduction_error)


def _floors(given: Sequence[int] | None, level_count: int, tree: ActiveTree) -> list[int]:
    coarsest = tree.level_count - 1
    if given is None:
        return [0] + [min(g, max(coarsest - 1, 0)) for g in range(1, level_count - 1)] + [coarsest][: level_count - 1]
    floors = [int(f) for f in given]
    if len(floors) != level_count:
        raise ValueError(f"animation floors: {len(floors)} given for {level_count} geometry levels")
    for index, floor in enumerate(floors):
        if not 0 <= floor <= coarsest:
            raise ValueError(
                f"animation floor of geometry level {index}: {floor} is not an active tree level (0 to {coarsest})"
            )
    return floors


def _reduction_errors(rig: FaceRig) -> dict[str, float]:
    """Largest vertex distance between each region's 3x3x3 MPA displacements and their 2x2x2 fit."""
    from .lattice import evaluate

    errors: dict[str, float] = {}
    for m, mpa in enumerate(rig.mpas):
        for region, delta in mpa.displacements.items():
            _, local = rig.region_points(region)
            exact = evaluate(local, delta, rig.lattices[region].weights)
            reduced = evaluate(local, rig.reduced_displacements(m, region))
            distance = float(np.linalg.norm(exact - reduced, axis=1).max(initial=0.0))
            errors[region] = max(errors.get(region, 0.0), distance)
    return errors


def _reduced(
    given: Sequence[Sequence[str]] | None, rig: FaceRig, errors: dict[str, float], geometric: list[float]
) -> list[frozenset[str]]:
    if given is not None:
        if len(given) != len(geometric):
            raise ValueError(f"reduced lattices: {len(given)} region lists given for {len(geometric)} geometry levels")
        for index, names in enumerate(given):
            for name in names:
                rig.regions.index(name, f"reduced lattices of geometry level {index}")
        return [frozenset(names) for names in given]
    return [frozenset()] + [
        frozenset(region for region, error in errors.items() if error <= tolerance) for tolerance in geometric[1:]
    ]
