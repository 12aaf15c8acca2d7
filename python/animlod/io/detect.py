"""Which reader a path needs, decided once for every CLI command."""

from __future__ import annotations

import glob
import os
from pathlib import Path

from .errors import FormatError
from .meshseq import MESH_SUFFIXES

# A .vrm is a VRM avatar (VRoid, UniVRM): a binary glTF whose VRM extensions animlod carries.
GLTF_SUFFIXES = (".glb", ".gltf", ".vrm")
MODEL_SUFFIXES = (*GLTF_SUFFIXES, ".bvh", ".npz")
GLB_OUTPUT_SUFFIXES = (".glb", ".vrm")


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
        _check_frame_folder(candidate)
        return "sequence"
    if not candidate.exists():
        raise FormatError(text, "file", "does not exist")
    suffix = candidate.suffix.lower()
    if suffix == ".bvh":
        return "bvh"
    if suffix in GLTF_SUFFIXES:
        return "gltf"
    if suffix == ".npz":
        return "npz"
    if suffix in MESH_SUFFIXES:
        return "sequence"
    expected = ".bvh, .glb, .gltf, .npz, .obj, .ply, .vrm or a folder"
    raise FormatError(text, "file", f"unknown type {suffix or '(no suffix)'}; expected {expected}")


def models_in(folder: Path) -> list[Path]:
    """The model files (glTF, VRM, BVH, NPZ) in ``folder``, in name order."""
    return [path for path in sorted(folder.iterdir()) if path.suffix.lower() in MODEL_SUFFIXES]


def _check_frame_folder(folder: Path) -> None:
    """FormatError for a folder that holds models but no OBJ/PLY frame: a folder is read as one
    frame sequence, and the models inside would otherwise meet "no frame found"."""
    if any(path.suffix.lower() in MESH_SUFFIXES for path in folder.iterdir()):
        return  # a frame sequence, whose reader checks each frame
    models = [path.name for path in models_in(folder)]
    if models:
        shown = ", ".join(models[:3]) + (f" and {len(models) - 3} more" if len(models) > 3 else "")
        raise FormatError(
            folder,
            "folder",
            f"holds no .obj or .ply frame but {shown}: pass a file (a folder is read as one frame sequence; "
            "animlod batch takes a folder of models)",
        )


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


def glb_name(source: str | os.PathLike, tag: str) -> str:
    """``<stem><tag>.glb``, the name of a binary glTF written from ``source`` (see
    :func:`input_stem`); ``.vrm`` for a VRM avatar's, the suffix VRM tools look for."""
    suffix = ".vrm" if Path(os.fspath(source)).suffix.lower() == ".vrm" else ".glb"
    return f"{input_stem(source)}{tag}{suffix}"
