"""Which reader a path needs, decided once for every CLI command."""

from __future__ import annotations

import glob
import os
from pathlib import Path

from .errors import FormatError
from .meshseq import MESH_SUFFIXES


def input_kind(path: str | os.PathLike) -> str:
    """``"bvh"``, ``"gltf"``, ``"npz"`` or ``"sequence"`` (a folder, glob or single OBJ/PLY).

    Raises FormatError when the path does not exist or its type is not one animlod reads.
    """
    text = os.fspath(path)
    candidate = Path(text)
    if glob.has_magic(text):
        if not glob.glob(text):
            raise FormatError(text, "pattern", "matches no file")
        return "sequence"
    if candidate.is_dir():
        return "sequence"
    if not candidate.exists():
        raise FormatError(text, "file", "does not exist")
    suffix = candidate.suffix.lower()
    if suffix == ".bvh":
        return "bvh"
    if suffix in (".glb", ".gltf"):
        return "gltf"
    if suffix == ".npz":
        return "npz"
    if suffix in MESH_SUFFIXES:
        return "sequence"
    expected = ".bvh, .glb, .gltf, .npz, .obj, .ply or a folder"
    raise FormatError(text, "file", f"unknown type {suffix or '(no suffix)'}; expected {expected}")


def input_stem(path: str | os.PathLike) -> str:
    """A name for outputs derived from ``path``: a file's stem, a folder's name, or for a glob
    the name of the folder its pattern starts in (``frames/*.obj`` -> ``frames``)."""
    text = os.fspath(path)
    if glob.has_magic(text):
        fixed = Path(text)
        while glob.has_magic(str(fixed)):
            fixed = fixed.parent
        return fixed.resolve().name or "mesh"
    candidate = Path(text)
    return (candidate.resolve().name if candidate.is_dir() else candidate.stem) or "mesh"
