"""Animation regions of a face and their importance (seeds/004, Sections 3.1 and 4.1.1).

A region is a set of adjacent vertices (and so of faces) that one control lattice deforms: the
basic unit of muscle simulation. Regions are grouped into independent region groups (the paper
chose face mask, ears, eyes and teeth) and each group has an importance weight that scales the
simplification cost of its vertices (``Eval(vertex) = Wr x (...)``, Section 4.1.1): low for the
ears, eyeballs and teeth, which take many triangles but seldom draw attention; high for the
mobile face mask.

Shapes: ``V`` vertices, ``M`` faces, ``R`` regions.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np


@dataclass
class RegionGroup:
    """Regions simplified with one importance weight (Section 4.1.1: "regions with the same
    importance weight are grouped together").

    Attributes
    ----------
    name : group name, e.g. "face_mask".
    regions : names of its regions.
    importance : > 0, multiplies the AQEM cost of the group's vertices.
    """

    name: str
    regions: list[str]
    importance: float


@dataclass
class FaceRegions:
    """Region labels of a face mesh.

    Attributes
    ----------
    names : R unique region names.
    vertex_regions : (V,) int32 region index of every vertex, each in [0, R).
    groups : region groups; every region is in exactly one.
    """

    names: list[str]
    vertex_regions: np.ndarray
    groups: list[RegionGroup] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.names = [str(name) for name in self.names]
        if len(set(self.names)) != len(self.names):
            repeated = next(name for name in self.names if self.names.count(name) > 1)
            raise ValueError(f"regions: name {repeated!r} is used twice")
        labels = np.asarray(self.vertex_regions)
        if labels.ndim != 1:
            raise ValueError(f"region labels: expected shape (V,), got {labels.shape}")
        if labels.size and labels.dtype.kind not in "iu":
            raise ValueError(f"region labels: expected integers, got dtype {labels.dtype}")
        outside = np.flatnonzero((labels < 0) | (labels >= len(self.names)))
        if outside.size:
            vertex = int(outside[0])
            raise ValueError(
                f"region labels do not cover the mesh: vertex {vertex} has label {int(labels[vertex])}, "
                f"expected 0 to {len(self.names) - 1} ({outside.size} vertices unlabelled)"
            )
        self.vertex_regions = labels.astype(np.int32)
        if not self.groups:
            self.groups = [RegionGroup("all", list(self.names), 1.0)]
        owner: dict[str, str] = {}
        for group in self.groups:
            if not (np.isfinite(group.importance) and group.importance > 0.0):
                raise ValueError(f"region group {group.name!r}: importance must be > 0, got {group.importance}")
            for region in group.regions:
                self.index(region, f"region group {group.name!r}")
                if region in owner:
                    raise ValueError(f"region {region!r}: in groups {owner[region]!r} and {group.name!r}")
                owner[region] = group.name
        missing = [name for name in self.names if name not in owner]
        if missing:
            raise ValueError(f"region {missing[0]!r}: in no region group")

    @property
    def region_count(self) -> int:
        return len(self.names)

    def check_vertex_count(self, vertex_count: int, element: str = "mesh") -> None:
        """ValueError unless there is one label per vertex of a ``vertex_count``-vertex mesh."""
        if len(self.vertex_regions) != vertex_count:
            raise ValueError(
                f"region labels do not cover the {element}: "
                f"{len(self.vertex_regions)} labels for {vertex_count} vertices"
            )

    def index(self, name: str, element: str = "face") -> int:
        """Index of region ``name``; ValueError naming ``element`` and the region if there is none."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(f"{element}: no region named {name!r}; the face has {', '.join(self.names)}") from None

    def indices(self, names: Iterable[str], element: str = "face") -> np.ndarray:
        """(k,) int32 indices of ``names``, each checked."""
        return np.array([self.index(name, element) for name in names], dtype=np.int32)

    def mask(self, names: Iterable[str]) -> np.ndarray:
        """(V,) bool: vertices in any of the regions ``names``."""
        return np.isin(self.vertex_regions, self.indices(names))

    def group_of(self, region: str) -> RegionGroup:
        return next(group for group in self.groups if region in group.regions)

    def vertex_importance(self) -> np.ndarray:
        """(V,) float32 importance of each vertex: its region group's weight."""
        per_region = np.array([self.group_of(name).importance for name in self.names], dtype=np.float32)
        return per_region[self.vertex_regions]

    def face_regions(self, faces: np.ndarray) -> np.ndarray:
        """(M,) int32 region of each face: the label most of its corners share; when all three
        differ, the label of its first corner."""
        corners = self.vertex_regions[np.asarray(faces)]
        second_agrees = corners[:, 1] == corners[:, 2]
        return np.where(second_agrees, corners[:, 1], corners[:, 0]).astype(np.int32)

    def subset(self, kept_vertices: np.ndarray) -> FaceRegions:
        """Labels of a simplified level whose vertex i is input vertex ``kept_vertices[i]``."""
        return FaceRegions(self.names, self.vertex_regions[np.asarray(kept_vertices)], self.groups)

    def with_importance(self, importance: dict[str, float]) -> FaceRegions:
        """A copy with the importance of the named groups replaced (ValueError for an unknown group)."""
        known = {group.name for group in self.groups}
        for name in importance:
            if name not in known:
                raise ValueError(f"no region group named {name!r}; groups: {', '.join(sorted(known))}")
        groups = [
            RegionGroup(g.name, list(g.regions), float(importance.get(g.name, g.importance))) for g in self.groups
        ]
        return FaceRegions(self.names, self.vertex_regions, groups)


def region_groups(names: Sequence[str], groups: dict[str, tuple[Sequence[str], float]]) -> list[RegionGroup]:
    """Groups from ``{group: (regions, importance)}``; regions of ``names`` not listed form a
    group "other" of importance 1."""
    listed = {region for regions, _ in groups.values() for region in regions}
    result = [RegionGroup(name, list(regions), float(weight)) for name, (regions, weight) in groups.items()]
    rest = [name for name in names if name not in listed]
    if rest:
        result.append(RegionGroup("other", rest, 1.0))
    return result
