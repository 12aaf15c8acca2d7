"""A JSON manifest of a LoD chain, for runtimes that pick a level by its error.

Each level lists its file(s), its size (faces and/or joints) and its error in the asset's
units; a runtime projects the error to pixels (``error / distance * focal_length_px``) and
draws the coarsest level under its pixel budget (see :meth:`animlod.model.LodChain.level_for`).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from .atomic import atomic_write
from .errors import FormatError
from .json_limits import finite_json_text, load_json

MANIFEST_FORMAT = "animlod-lod"
MANIFEST_VERSION = 1
# Optional level fields that must be whole numbers >= 0 when present.
_COUNT_FIELDS = ("faces", "triangles", "joints", "vertices")


def write_lod_manifest(path: str | os.PathLike, kind: str, levels: Sequence[dict]) -> None:
    """Write ``{"format": "animlod-lod", "version", "kind", "levels": [...]}`` atomically.

    ``levels`` are finest first; each must hold at least ``"error"`` (asset units, finite, not
    decreasing from level to level is not required but expected).
    """
    for index, level in enumerate(levels):
        if "error" not in level:
            raise ValueError(f"{os.fspath(path)}: level {index}: no 'error'")
    document = {"format": MANIFEST_FORMAT, "version": MANIFEST_VERSION, "kind": kind, "levels": list(levels)}
    try:
        text = finite_json_text(document, indent=2)
    except ValueError as error:
        raise ValueError(f"{os.fspath(path)}: {error}") from None
    with atomic_write(path, "w", encoding="utf-8") as handle:
        handle.write(text + "\n")


def read_lod_manifest(path: str | os.PathLike) -> dict[str, Any]:
    """Read and check a manifest written by :func:`write_lod_manifest`.

    Returns the document: ``kind`` (str) and ``levels``, a non-empty list of dicts, each with a
    finite ``error`` >= 0 (asset units), file names in ``files`` (list of str) or ``file`` (str),
    and optional counts (faces, triangles, joints, vertices) that are whole numbers >= 0.

    Raises
    ------
    FormatError
        Naming the file, the level and the field for anything else (not JSON, nested too
        deeply, another format, a newer version).
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as error:
        raise FormatError(path, "file", f"cannot read ({error.strerror})") from None
    document = load_json(path, data)
    if not isinstance(document, dict) or document.get("format") != MANIFEST_FORMAT:
        raise FormatError(path, "format", f"not an animlod LoD manifest (expected format {MANIFEST_FORMAT!r})")
    version = document.get("version")
    if not _whole(version) or not 1 <= version <= MANIFEST_VERSION:
        raise FormatError(path, "version", f"{version!r} is not a version this reader knows (1 to {MANIFEST_VERSION})")
    if not isinstance(document.get("kind"), str):
        raise FormatError(path, "kind", f"expected a string, got {document.get('kind')!r}")
    levels = document.get("levels")
    if not isinstance(levels, list) or not levels:
        raise FormatError(path, "levels", "expected a non-empty list of levels")
    for index, level in enumerate(levels):
        _check_level(path, f"level {index}", level)
    return document


def _check_level(path: Path, element: str, level: Any) -> None:
    if not isinstance(level, dict):
        raise FormatError(path, element, f"expected an object, got {type(level).__name__}")
    error = level.get("error")
    if isinstance(error, bool) or not isinstance(error, (int, float)) or not (math.isfinite(error) and error >= 0):
        raise FormatError(path, f"{element} error", f"expected a finite number >= 0, got {error!r}")
    files = level.get("files", [level["file"]] if "file" in level else [])
    if not isinstance(files, list) or not all(isinstance(name, str) and name for name in files):
        raise FormatError(path, f"{element} files", "expected file names (non-empty strings)")
    for field in _COUNT_FIELDS:
        if field in level and not (_whole(level[field]) and level[field] >= 0):
            raise FormatError(path, f"{element} {field}", f"expected a whole number >= 0, got {level[field]!r}")


def _whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)
