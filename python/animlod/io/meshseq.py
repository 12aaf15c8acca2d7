"""OBJ and PLY frame sequences: one mesh file per frame, every frame with the same faces.

Only geometry is read (:mod:`.obj`, :mod:`.ply`).
"""

from __future__ import annotations

import glob
import os
import re
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..model import AnimatedMesh
from .atomic import atomic_folder
from .errors import FormatError
from .obj import UnreadAttributesWarning, read_obj, write_obj
from .ply import read_ply, write_ply

MESH_SUFFIXES = (".obj", ".ply")

# ---------------------------------------------------------------------------------------------
# Sequences


def read_sequence(source: str | os.PathLike | Sequence[str | os.PathLike], fps: float | None = None) -> AnimatedMesh:
    """Read OBJ/PLY frames that share one connectivity into an :class:`~animlod.model.AnimatedMesh`.

    Parameters
    ----------
    source : a folder (every .obj and .ply file in it, in natural order: frame2 before
        frame10), a glob pattern (its matches in natural order), a single file, or a list of
        files (in the order given).
    fps : frames per second of the sequence, or None for a set of poses.

    Returns
    -------
    AnimatedMesh with ``frames (F, V, 3) float32`` and the first file's ``faces (M, 3) int32``.

    Raises
    ------
    FormatError
        When no frame is found, a file cannot be read, or a frame's vertex count or faces
        differ from the first frame's (naming the file and the first differing face).
    """
    paths = sequence_paths(source)
    first_vertices, faces = read_mesh(paths[0])
    # A file without triangles is no frame of a mesh (random bytes named .obj parse as one).
    if not len(faces):
        what = "no vertices and no faces" if not len(first_vertices) else f"{len(first_vertices)} vertices but no faces"
        raise FormatError(paths[0], "mesh", f"{what}; a frame needs triangles")
    frames = np.empty((len(paths),) + first_vertices.shape, dtype=np.float32)
    frames[0] = first_vertices
    with warnings.catch_warnings():  # the first frame's warning speaks for the sequence
        warnings.simplefilter("ignore", UnreadAttributesWarning)
        for index, path in enumerate(paths[1:], start=1):
            vertices, frame_faces = read_mesh(path)
            _check_same_connectivity(path, vertices, frame_faces, paths[0], faces, len(first_vertices))
            frames[index] = vertices
    return AnimatedMesh(faces, frames, fps=fps)


def write_sequence(
    folder: str | os.PathLike,
    mesh: AnimatedMesh,
    fmt: str = "obj",
    stem: str = "frame",
    names: Sequence[str] | None = None,
) -> list[Path]:
    """Write every frame of ``mesh`` to ``folder/{stem}_{index:04d}.{fmt}``, or to
    ``folder/{name}.{fmt}`` with the frames' ``names``, the folder atomically.

    The frames are written into a temporary folder beside ``folder``, which is renamed to
    ``folder`` once every frame is written (:func:`~animlod.io.atomic.atomic_folder`): an
    interrupted run never leaves a folder short of frames under the final name. An existing
    ``folder`` is replaced as a whole. ``fmt`` is "obj" or "ply" (binary little-endian).
    Returns the written paths in frame order. ValueError for another ``fmt``, or ``names`` that
    are not one file name per frame, distinct regardless of case.
    """
    if fmt not in ("obj", "ply"):
        raise ValueError(f"{os.fspath(folder)}: fmt: must be 'obj' or 'ply', got {fmt!r}")
    if names is None:
        width = max(4, len(str(mesh.frame_count - 1)))
        names = [f"{stem}_{index:0{width}d}" for index in range(mesh.frame_count)]
    elif not frame_names_fit(names, mesh.frame_count):
        raise ValueError(f"{os.fspath(folder)}: names: {len(names)} names for {mesh.frame_count} frames, or names "
                         "that repeat (regardless of case) or are not plain file names")  # fmt: skip
    names = [f"{name}.{fmt}" for name in names]
    with atomic_folder(folder) as temporary:
        for name, vertices in zip(names, mesh.frames):
            write_mesh(temporary / name, vertices, mesh.faces)
    return [Path(folder) / name for name in names]


def frame_names_fit(names: Sequence[str], frames: int) -> bool:
    """Whether ``names`` can name ``frames`` frame files of one folder: one each, plain file names
    (no folder, not hidden), distinct regardless of case (as case-insensitive file systems see them)."""
    plain = all(name and Path(name).name == name and not name.startswith(".") for name in names)
    return plain and len(names) == frames and len({name.casefold() for name in names}) == frames


# A number in a frame name, with its sign where a minus follows a separator.
_NUMBER = re.compile(r"((?:(?<=[._ ])-)?\d+)")


def sequence_paths(source: str | os.PathLike | Sequence[str | os.PathLike]) -> list[Path]:
    """The frame files :func:`read_sequence` reads for ``source``, in its order; FormatError when
    there is none."""
    if not isinstance(source, (str, os.PathLike)):
        paths = [Path(path) for path in source]
        if not paths:
            raise FormatError("<list>", "source", "the list of frames is empty")
        return paths
    location = Path(source)
    if location.is_dir():
        paths = frame_files(location)
    elif location.is_file():  # before the pattern test: "take[1].obj" is a file name
        return [location]
    elif glob.has_magic(os.fspath(source)):
        paths = sorted((Path(match) for match in glob.glob(os.fspath(source))), key=natural_key)
    else:
        raise FormatError(source, "source", "is not a folder, a glob pattern or an existing file")
    if not paths:
        raise FormatError(source, "source", "no .obj or .ply frame found")
    return paths


def is_frame_name(name: str) -> bool:
    """Whether a file called ``name`` is an OBJ/PLY frame: hidden files (``._frame_0001.obj``,
    the resource forks macOS copies leave beside every file) are not."""
    return not name.startswith(".") and Path(name).suffix.lower() in MESH_SUFFIXES


def frame_files(folder: str | os.PathLike) -> list[Path]:
    """The OBJ/PLY frames of ``folder``, in natural order (see :func:`natural_key`)."""
    found = (path for path in Path(folder).iterdir() if is_frame_name(path.name) and path.is_file())
    return sorted(found, key=natural_key)


def natural_key(path: Path) -> tuple[list[object], str]:
    """Sort key that orders embedded numbers by value (frame2 < frame10) and letters regardless
    of case, then by full path. A minus sign after a separator is the number's
    (``frame.-001.obj``, before frame 0, as Houdini numbers frames before the first); after
    anything else it separates (``mesh-001`` is frame 1)."""
    parts = _NUMBER.split(path.name)  # text, number, text, ...: the numbers at odd places
    return [int(part) if index % 2 else part.lower() for index, part in enumerate(parts)], str(path)


def _check_same_connectivity(
    path: Path, vertices: np.ndarray, faces: np.ndarray, first_path: Path, first_faces: np.ndarray, vertex_count: int
) -> None:
    first = f"the first frame {first_path.name}"
    if len(vertices) != vertex_count:
        raise FormatError(path, "vertices", f"{len(vertices)} vertices, but {first} has {vertex_count}")
    if faces.shape != first_faces.shape:
        raise FormatError(path, "faces", f"{len(faces)} triangles, but {first} has {len(first_faces)}")
    differs = np.any(faces != first_faces, axis=1)
    if differs.any():
        face = int(np.argmax(differs))
        reason = f"vertices {faces[face].tolist()} (counted from 0) differ from {first_faces[face].tolist()} in {first}"
        raise FormatError(path, f"face {face}", reason)


# ---------------------------------------------------------------------------------------------
# Single meshes


def read_mesh(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read one .obj or .ply file: ``vertices (V, 3) float32`` and triangle ``faces (M, 3) int32``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".obj":
        return read_obj(path)
    if suffix == ".ply":
        return read_ply(path)
    raise FormatError(path, "file name", f"expected one of {', '.join(MESH_SUFFIXES)}")


def write_mesh(path: str | os.PathLike, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Write one .obj or .ply (binary) file, chosen by the suffix of ``path``."""
    suffix = Path(path).suffix.lower()
    if suffix == ".obj":
        write_obj(path, vertices, faces)
    elif suffix == ".ply":
        write_ply(path, vertices, faces)
    else:
        raise ValueError(f"{os.fspath(path)}: expected one of {', '.join(MESH_SUFFIXES)}")
