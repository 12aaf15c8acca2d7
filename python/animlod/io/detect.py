"""Which reader a path needs, decided once for every CLI command."""

from __future__ import annotations

import glob
import itertools
import os
from collections.abc import Iterator
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


def holds_frames(folder: Path) -> bool:
    """Whether ``folder`` holds an OBJ/PLY frame, which makes it one frame sequence (decided by
    names: a folder of thousands of frames costs no stat)."""
    try:
        with os.scandir(folder) as entries:
            return any(entry.is_file() and Path(entry.name).suffix.lower() in MESH_SUFFIXES for entry in entries)
    except OSError:
        return False


def assets_in(folder: Path) -> Iterator[Path]:
    """The model files (glTF, VRM, BVH, NPZ) and frame folders below ``folder``, in a stable
    order: each folder's files by name, then its frame folders, then the rest of its folders
    (hidden ones skipped; a frame folder is not searched further)."""
    for root, folders, files in os.walk(folder):
        folders.sort()
        here = Path(root)
        for name in sorted(files):
            if Path(name).suffix.lower() in MODEL_SUFFIXES:
                yield here / name
        framed = [name for name in folders if holds_frames(here / name)]
        yield from (here / name for name in framed)
        folders[:] = [name for name in folders if name not in framed and not name.startswith(".")]


def _check_frame_folder(folder: Path) -> None:
    """FormatError for a folder that holds no OBJ/PLY frame but models or frame folders: a folder
    is read as one frame sequence, and the assets inside would otherwise meet "no frame found"."""
    if holds_frames(folder):
        return  # a frame sequence, whose reader checks each frame
    assets = [path.relative_to(folder).as_posix() for path in itertools.islice(assets_in(folder), 4)]
    if assets:
        shown = ", ".join(assets[:3]) + (" and more" if len(assets) > 3 else "")
        raise FormatError(
            folder,
            "folder",
            f"holds no .obj or .ply frame but {shown}: pass one of them (a folder is read as one frame "
            "sequence; animlod batch and animlod info take a folder of assets)",
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
