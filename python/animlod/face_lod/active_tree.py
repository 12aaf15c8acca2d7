"""The active tree: which regions are animated at each level (seeds/004, Section 4.2.1, Figure 7).

Each level of the tree holds a set of regions; a level's set contains every coarser level's
set, the finest level (0) holds every animated region and the coarsest holds none ("when the
model is far enough, no animation is needed"). At level k only the regions of set k are
active: their MPAs are processed, every other region stays at rest. A level change is a shrink
(regions leave the active set) or an expansion (regions join it).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from .regions import FaceRegions


@dataclass
class Transition:
    """What a change of active level does: regions to stop and to start animating."""

    deactivated: frozenset[str]
    activated: frozenset[str]

    @property
    def kind(self) -> str:
        """ "shrink", "expand" or "none"."""
        if self.deactivated:
            return "shrink"
        return "expand" if self.activated else "none"


class ActiveTree:
    """Nested region sets, finest (most regions) first, the last one empty.

    Parameters
    ----------
    levels : the region names active at each level.
    regions : when given, every name is checked against it (ValueError naming the level and
        the region).

    Raises ValueError when a level holds a region its finer level does not (the sets must be
    nested), or when the coarsest level is not empty.
    """

    def __init__(self, levels: Sequence[Sequence[str]], regions: FaceRegions | None = None) -> None:
        if not levels:
            raise ValueError("active tree: needs at least one level (the empty one)")
        self.levels = [frozenset(level) for level in levels]
        for index, level in enumerate(self.levels):
            if regions is not None:
                for name in sorted(level):
                    regions.index(name, f"active tree level {index}")
            if index and not level <= self.levels[index - 1]:
                extra = sorted(level - self.levels[index - 1])[0]
                raise ValueError(
                    f"active tree level {index}: region {extra!r} is not active at level {index - 1}; "
                    "each level must hold only regions of the level before it"
                )
        if self.levels[-1]:
            raise ValueError(f"active tree: the coarsest level ({len(self.levels) - 1}) must animate no region")

    @property
    def level_count(self) -> int:
        return len(self.levels)

    def active(self, level: int) -> frozenset[str]:
        """Regions animated at ``level`` (clamped to the coarsest)."""
        return self.levels[min(max(level, 0), len(self.levels) - 1)]

    def transition(self, from_level: int, to_level: int) -> Transition:
        """Regions that stop and start being animated when the level changes."""
        before, after = self.active(from_level), self.active(to_level)
        return Transition(deactivated=before - after, activated=after - before)

    def level_of(self, region: str) -> int:
        """The coarsest level at which ``region`` is still active (-1 when it never is); the
        paper's "the higher the level a region belongs to, the more mobile and/or visually
        important its movement is"."""
        found = -1
        for index, level in enumerate(self.levels):
            if region in level:
                found = index
        return found
