"""One result record for every pipeline job: the files written and one row per level.

Each job of :mod:`animlod.pipelines` (``simplify_asset``, ``character_asset``, ``motion_asset``)
returns an :class:`AssetResult`, whatever its technique, so that the command line prints it, the
batch runner files it in its catalogue (one row per asset and level) and a rerun reads it back
(:meth:`AssetResult.to_dict` / :meth:`AssetResult.from_dict` round-trip through JSON).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path

# A job's progress callback: (fraction done in [0, 1] or None when unknown, what it is doing).
Progress = Callable[[float | None, str], None]


@dataclass
class LevelRow:
    """One level of one part of an asset.

    level : 0 is the input, 1, 2, ... coarser.
    part : what the level belongs to when an asset has several (a glTF drawable's label); "" otherwise.
    triangles : faces drawn at this level (None for a motion-only job).
    joints : joints animated at this level (None where the job leaves the skeleton alone).
    error : asset units, the level's measured error (max over measured frames: surface Hausdorff
        distance for meshes, joint position error for motion); None when the job did not measure it.
    relative_error : ``error`` over the asset's size (bounding-box diagonal, or figure height for motion).
    seconds : time spent on this level alone, where the job can tell (None when one run made every level).
    """

    level: int
    part: str = ""
    triangles: int | None = None
    joints: int | None = None
    error: float | None = None
    relative_error: float | None = None
    seconds: float | None = None


@dataclass
class AssetResult:
    """What one job did to one asset.

    job : the job's name (``"simplify"``, ``"character"``, ``"motion"`` or a custom job's path).
    source : the input as given.
    outputs : every file or folder written, finest level first.
    levels : one row per level and part, level 0 (the input) included.
    seconds : wall time of the whole job (reading, building, measuring, writing).
    notes : things the user should know (targets not reached, joints kept, ...).
    """

    job: str
    source: str
    outputs: list[Path]
    levels: list[LevelRow]
    seconds: float
    notes: list[str] = field(default_factory=list)

    def to_dict(self, relative_to: str | os.PathLike | None = None) -> dict:
        """A JSON-ready dict; output paths relative to ``relative_to`` when given. Non-finite
        errors become None (JSON has no inf)."""
        base = Path(relative_to) if relative_to is not None else None
        outputs = [os.fspath(path.relative_to(base) if base is not None else path) for path in self.outputs]
        levels = []
        for row in self.levels:
            values = asdict(row)
            for key in ("error", "relative_error", "seconds"):
                if values[key] is not None and not math.isfinite(values[key]):
                    values[key] = None
            levels.append(values)
        return {
            "job": self.job,
            "source": self.source,
            "outputs": outputs,
            "levels": levels,
            "seconds": self.seconds,
            "notes": list(self.notes),
        }

    @classmethod
    def from_dict(cls, data: dict, relative_to: str | os.PathLike | None = None) -> AssetResult:
        """The inverse of :meth:`to_dict` (output paths joined to ``relative_to`` when given)."""
        base = Path(relative_to) if relative_to is not None else None
        outputs = [base / path if base is not None else Path(path) for path in data["outputs"]]
        return cls(
            job=str(data["job"]),
            source=str(data["source"]),
            outputs=outputs,
            levels=[LevelRow(**row) for row in data["levels"]],
            seconds=float(data["seconds"]),
            notes=[str(note) for note in data.get("notes", [])],
        )
