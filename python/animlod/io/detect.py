"""Which reader a path needs, decided once for every CLI command."""

from __future__ import annotations

import glob
import itertools
import os
from collections.abc import Iterator
from pathlib import Path

from .errors import FormatError
from .meshseq import MESH_SUFFIXES, is_frame_name

# A .vrm is a VRM avatar (VRoid, UniVRM): a binary glTF whose VRM extensions animlod carries.
GLTF_SUFFIXES = (".glb", ".gltf", ".vrm")
MODEL_SUFFIXES = (*GLTF_SUFFIXES, ".bvh", ".npz")
GLB_OUTPUT_SUFFIXES = (".glb", ".vrm")
# The folder where animlod batch keeps its state under OUT: it marks a batch output, never an input.
BATCH_STATE = ".animlod-batch"


def is_pattern(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a glob pattern: it has ``*?[`` and names no file (``take[1].glb`` can
    be a file's name)."""
    text = os.fspath(path)
    return glob.has_magic(text) and not os.path.lexists(text)


def input_kind(path: str | os.PathLike) -> str:
    """``"bvh"``, ``"gltf"``, ``"npz"`` or ``"sequence"`` (a folder, glob or single OBJ/PLY).

    Raises FormatError when the path does not exist or its type is not one animlod reads.
    """
    text = os.fspath(path)
    candidate = Path(text)
    if is_pattern(text):
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
            return any(is_frame_name(entry.name) and entry.is_file() for entry in entries)
    except OSError:
        return False


def assets_in(folder: Path) -> Iterator[Path]:
    """The model files (glTF, VRM, BVH, NPZ) and frame folders in and below ``folder`` (itself
    too when it holds frames), in a stable order: a folder's frames, then its files by name, then
    its folders. Skipped: hidden files and folders, links to no file (dangling or looping) and
    batch output folders (an output inside the library is not read back as input)."""
    for root, folders, files in os.walk(folder):
        here = Path(root)
        if any(is_frame_name(name) and (here / name).is_file() for name in files):  # holds_frames, from the walk's list
            yield here
        for name in sorted(files):
            if not name.startswith(".") and Path(name).suffix.lower() in MODEL_SUFFIXES and (here / name).is_file():
                yield here / name
        folders[:] = sorted(
            name for name in folders if not name.startswith(".") and not (here / name / BATCH_STATE).exists()
        )


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
    if is_pattern(text):
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
