"""Where a chain of AQEM levels ends, and the notes that say why it is short.

A level short of its target (a max error, or no legal collapse left) holds the mesh where the
collapses stopped, and so do the levels after it; a level whose target the level before meets
already (a mesh of a few triangles) is the same mesh too. Written, they were copies of one mesh:
a glTF chain with screen coverages of their own, a sequence with folders that differ only in
name. Both pipelines write the levels up to the last one coarser than the one before it and say
what they left out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ..aqem import SimplifiedLevel


def coarser_level_count(levels: Sequence[SimplifiedLevel], ratios: Sequence[float]) -> int:
    """How many of ``levels`` (made for face ``ratios``) lead the chain, each coarser than the one
    before (the input for the first): the count before the first level that made no collapse of
    its own, short of its target or there without one (a mesh of a few triangles), but for a ratio
    of 1, which asks for the input's faces (the input through the pipeline, its normals rebuilt)."""
    collapses = 0  # the input's
    for count, (level, ratio) in enumerate(zip(levels, ratios, strict=True)):
        if level.collapse_count == collapses and not (level.reached and ratio >= 1.0):
            return count
        collapses = level.collapse_count
    return len(levels)


def _short_level_note(number: int, level: SimplifiedLevel, max_error: float) -> str | None:
    """``level N: stopped at F faces (target T): why`` for level ``number`` when it fell short of
    its target; None when it reached it."""
    if level.reached:
        return None
    faces, target = level.mesh.face_count, level.target_face_count
    if level.stopped_by_max_error:
        why = f"max error {max_error:g} reached (the next collapse's AQEM error exceeds it); "
        why += f"this level's largest AQEM error: {level.error:.3g}"
    else:
        why = "no legal collapse left (seams, locked spots or the topology's minimum)"
    return f"level {number}: stopped at {faces} faces (target {target}): {why}"


def _unwritten_levels_note(levels: Sequence[SimplifiedLevel], written: int, max_error: float = math.inf) -> str | None:
    """``levels N, ... (targets ...) not written: ...`` for the levels after the first ``written``
    (see :func:`coarser_level_count`); None when every level is written."""
    dropped = levels[written:]
    if not dropped:
        return None
    numbers = ", ".join(str(number) for number in range(written + 1, len(levels) + 1))
    targets = ", ".join(str(level.target_face_count) for level in dropped)
    plural = "s" if len(dropped) > 1 else ""
    same = f"level {written}" if written else "the input"
    cause = "no legal collapse was left"
    if dropped[0].stopped_by_max_error:
        cause = f"the max error {max_error:g} stopped the collapses"
    elif dropped[0].reached:
        cause = f"the target{plural} need{'' if plural else 's'} no collapse"
    return (
        f"level{plural} {numbers} (target{plural} {targets}) not written: the same mesh as {same} "
        f"({dropped[0].mesh.face_count} faces), where {cause}"
    )


def chain_notes(levels: Sequence[SimplifiedLevel], written: int, max_error: float = math.inf) -> list[str]:
    """The notes on a chain of ``levels`` of which the first ``written`` are written: each written
    level short of its target, then the levels left out."""
    notes = [_short_level_note(number, level, max_error) for number, level in enumerate(levels[:written], start=1)]
    notes.append(_unwritten_levels_note(levels, written, max_error))
    return [note for note in notes if note]
