"""Which reader a path needs, decided once for every CLI command."""

from __future__ import annotations

import glob
import itertools
import json
import os
import re
from collections import Counter
from collections.abc import Iterator
from pathlib import Path, PurePosixPath

from .errors import FormatError
from .frame_order import natural_key
from .meshseq import MESH_SUFFIXES, frame_files, is_frame_name

# A .vrm is a VRM avatar (VRoid, UniVRM): a binary glTF whose VRM extensions animlod carries.
GLTF_SUFFIXES = (".glb", ".gltf", ".vrm")
MODEL_SUFFIXES = (*GLTF_SUFFIXES, ".bvh", ".npz")
GLB_OUTPUT_SUFFIXES = (".glb", ".vrm")
# The folder where animlod batch keeps its state under OUT: it marks a batch output, never an input.
BATCH_STATE = ".animlod-batch"
# The record animlod batch writes into each asset's folder, listing the asset's outputs.
ASSET_RECORD = ".animlod-asset.json"


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
    advice = f"; {_CONVERT_ADVICE}" if suffix in _OTHER_MODEL_SUFFIXES else ""
    raise FormatError(text, "file", f"unknown type {suffix or '(no suffix)'}; expected {expected}{advice}")


def holds_frames(folder: Path) -> bool:
    """Whether ``folder`` holds an OBJ/PLY file: one frame sequence, or separate meshes (see
    :func:`separate_meshes`); decided by names, so a folder of thousands of frames costs no stat."""
    try:
        with os.scandir(folder) as entries:
            return any(is_frame_name(entry.name) and entry.is_file() for entry in entries)
    except OSError:
        return False


def assets_in(folder: Path) -> Iterator[Path]:
    """The model files (glTF, VRM, BVH, NPZ) and frame folders in and below ``folder`` (itself
    too when it holds frames), in a stable order: a folder's frames, then its files by name, then
    its folders. A folder whose OBJ/PLY files are separate meshes (:func:`separate_meshes`) gives
    each of them instead. Skipped: hidden files and folders, links to no file (dangling or
    looping) and batch outputs (a batch's output folder inside the library, an asset's outputs
    where the library is, or holds, the output folder): no output is read back as input."""
    for here, files in _library_folders(folder):
        frames = [here / name for name in files if is_frame_name(name)]
        if frames and separate_meshes(frames):
            yield from sorted(frames, key=natural_key)
        elif frames:
            yield here
        yield from (here / name for name in files if Path(name).suffix.lower() in MODEL_SUFFIXES)


# Model formats animlod does not read, which a library folder may hold beside its glTF files.
_OTHER_MODEL_SUFFIXES = (
    ".fbx", ".dae", ".blend", ".usd", ".usda", ".usdc", ".usdz", ".abc", ".3ds", ".max", ".ma", ".mb", ".c4d",
    ".stl", ".x", ".md5mesh", ".md5anim", ".lwo", ".ase", ".off", ".3mf",
)  # fmt: skip


_CONVERT_ADVICE = "convert to glTF first (with Blender, or assimp export FILE OUT.glb)"


def unread_models_note(folder: Path) -> str | None:
    """What ``folder`` holds in and below it of model formats animlod does not read (FBX,
    Collada, Blender, USD...), which :func:`assets_in` leaves out, and what to do; None if nothing."""
    counts = Counter(
        suffix
        for _, files in _library_folders(folder)
        for name in files
        if (suffix := Path(name).suffix.lower()) in _OTHER_MODEL_SUFFIXES
    )
    if not counts:
        return None
    total = sum(counts.values())
    if total == 1:
        return f"1 model file in a format animlod does not read ({next(iter(counts))}); {_CONVERT_ADVICE}"
    kinds = ", ".join(f"{count} {suffix}" for suffix, count in sorted(counts.items()))
    return f"{total} model files in formats animlod does not read ({kinds}); {_CONVERT_ADVICE}"


def _library_folders(folder: Path) -> Iterator[tuple[Path, list[str]]]:
    """Each folder in and below ``folder`` with its files (by name, hidden ones left out), skipping
    hidden folders, batch output folders and the outputs an asset record lists."""
    for root, folders, files in os.walk(folder):
        here = Path(root)
        outputs = recorded_outputs(here) if ASSET_RECORD in files else set()
        if outputs is None:  # a record it cannot read: anything here may be an output
            folders.clear()
            continue
        taken = (name for name in sorted(files) if not name.startswith(".") and name not in outputs)
        yield here, [name for name in taken if (here / name).is_file()]
        folders[:] = sorted(
            name
            for name in folders
            if not name.startswith(".") and name not in outputs and not (here / name / BATCH_STATE).exists()
        )


def read_asset_record(folder: Path) -> dict | None:
    """The asset record (:data:`ASSET_RECORD`) in ``folder`` that animlod batch wrote, or None
    (absent or unreadable)."""
    try:
        record = json.loads((folder / ASSET_RECORD).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return record if isinstance(record, dict) else None


def recorded_outputs(folder: Path) -> set[str] | None:
    """The names in ``folder`` of the outputs its asset record (:data:`ASSET_RECORD`) lists: the
    files and folders an asset of animlod batch wrote there. None when it holds no record that
    can be read."""
    record = read_asset_record(folder)
    try:
        paths = [PurePosixPath(path) for path in record["result"]["outputs"]]
    except (TypeError, KeyError):  # no record (None), or one without a list of paths
        return None
    if any(path.is_absolute() or not path.parts or path.parts[0] == ".." for path in paths):
        return None  # animlod writes an asset's outputs inside its folder: not a record of its
    return {path.parts[0] for path in paths}


# A file stem that ends in a number, and the text before it: "mesh_0048" -> "mesh_".
_NUMBERED = re.compile(r"(.*?)\d+")
# Statement lines of an OBJ that make vertices and faces ("v 1 2 3", "f 1 2 3").
_OBJ_VERTEX, _OBJ_FACE = re.compile(rb"(?m)^[ \t]*v[ \t]"), re.compile(rb"(?m)^[ \t]*f[ \t]")
_PLY_COUNT = re.compile(rb"element[ \t]+(vertex|face)[ \t]+(\d+)")


def separate_meshes(paths: list[Path]) -> bool:
    """Whether the OBJ/PLY files of one folder are separate meshes (a library of props) rather than
    the frames of one sequence: their vertex or face counts differ (a PLY's header, an OBJ's
    ``v`` and ``f`` lines: counted, not parsed), and their names are not numbered frames of one
    name (all of them ending in a number after the same text, as ``mesh_0001.obj``,
    ``mesh_0002.obj``, or all but one and at least three, beside a rest mesh), which stay one
    sequence so that a broken frame is reported as such. Two numbered files beside a third
    (``rock_1``, ``rock_2``, ``tree``) are told apart by their counts."""
    if len(paths) < 2:
        return False
    prefixes = Counter(match.group(1) for path in paths if (match := _NUMBERED.fullmatch(path.stem)))
    numbered = prefixes.most_common(1)[0][1] if prefixes else 0
    if numbered == len(paths) or numbered >= max(3, len(paths) - 1):
        return False
    first = _element_counts(paths[0])
    return any(_element_counts(path) != first for path in paths[1:])  # props differ at once: two reads


def _element_counts(path: Path) -> tuple[int, int] | None:
    """(vertices, faces) of an OBJ/PLY file as its lines or header give them; None if unreadable."""
    try:
        if path.suffix.lower() == ".ply":
            with open(path, "rb") as handle:
                header = handle.read(1 << 16).split(b"end_header", 1)[0]
            counts = dict(_PLY_COUNT.findall(header))
            return int(counts.get(b"vertex", -1)), int(counts.get(b"face", -1))
        data = path.read_bytes()
    except OSError:
        return None
    return len(_OBJ_VERTEX.findall(data)), len(_OBJ_FACE.findall(data))


def _check_frame_folder(folder: Path) -> None:
    """FormatError for a folder that holds no OBJ/PLY frame but models or frame folders, or whose
    OBJ/PLY files are separate meshes: a folder is read as one frame sequence, and the assets
    inside would otherwise meet "no frame found" or a frame whose faces differ from the first's."""
    if holds_frames(folder):
        frames = frame_files(folder)
        if separate_meshes(frames):
            shown = ", ".join(path.name for path in frames[:3]) + (" and more" if len(frames) > 3 else "")
            raise FormatError(
                folder,
                "folder",
                f"holds {len(frames)} separate meshes ({shown}: their vertex or face counts differ), not the "
                "frames of one sequence: pass one of them, or the folder to animlod batch (each an asset)",
            )
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
    unread = unread_models_note(folder)
    if unread:
        raise FormatError(folder, "folder", f"holds no .obj or .ply frame, but {unread}")


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
