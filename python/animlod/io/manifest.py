"""A JSON manifest of a LoD chain, for runtimes that pick a level by its error.

Each level lists its file(s), its size (faces and/or joints) and its error in the asset's
units; a runtime projects the error to pixels (``error / distance * focal_length_px``) and
draws the coarsest level under its pixel budget (see :meth:`animlod.model.LodChain.level_for`).
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence

from .atomic import atomic_write

MANIFEST_VERSION = 1


def write_lod_manifest(path: str | os.PathLike, kind: str, levels: Sequence[dict]) -> None:
    """Write ``{"format": "animlod-lod", "version", "kind", "levels": [...]}`` atomically.

    ``levels`` are finest first; each must hold at least ``"error"`` (asset units, finite, not
    decreasing from level to level is not required but expected).
    """
    for index, level in enumerate(levels):
        if "error" not in level:
            raise ValueError(f"{os.fspath(path)}: level {index}: no 'error'")
    document = {"format": "animlod-lod", "version": MANIFEST_VERSION, "kind": kind, "levels": list(levels)}
    with atomic_write(path, "w", encoding="utf-8") as handle:
        json.dump(document, handle, indent=2)
        handle.write("\n")
