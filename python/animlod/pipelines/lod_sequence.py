"""A deforming mesh sequence in (OBJ/PLY frames or NPZ), its AQEM levels out in the same format.

Each level is written beside the others: ``<stem>_lod<i>/`` frame folders for OBJ/PLY frames
(each frame under its input file's name), ``<stem>_lod<i>.obj`` (or ``.ply``) for one mesh file,
``<stem>_lod<i>.npz`` for NPZ input, and measured against the input frame by frame (symmetric
Hausdorff and RMS distance relative to the bounding-box diagonal), on at most 64 frames evenly
spaced over a longer sequence. A sequence's texture coordinates (OBJ ``vt`` lines, PLY vertices'
s, t) are carried: each (position, texture coordinate) pair of its corners is a vertex, the copies
of a position along a UV seam welded by AQEM and kept apart where their coordinates differ, and
written back as ``vt`` lines or per PLY vertex. Its normals (OBJ ``vn``, PLY nx, ny, nz) are
rebuilt on each level frame from the level's own faces, shaded as the input is (flat, hard
edges, or smooth; PLY levels smooth only, one normal per vertex), and written back. Its vertex
colours (PLY red, green, blue, alpha; OBJ ``v x y z r g b``), each frame's where they change,
are interpolated along the collapses and written back as stored (PLY uchar stays uchar). An OBJ
sequence's materials go with each level face's source face and are written as ``usemtl`` runs
under ``mtllib`` lines that name the input's libraries from the level's folder.
"""

from __future__ import annotations

import math
import os
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..aqem import Preparation, SimplifiedLevel, simplify_animated
from ..io.atomic import check_writable_folder
from ..io.detect import input_kind, input_stem
from ..io.errors import FormatError, UnreadAttributesWarning
from ..io.meshseq import SequenceTexture, normals_fit
from ..io.obj import ObjMaterials
from ..io.vertex_colours import VertexColours
from ..metrics import SurfaceError, surface_error
from ..model import AnimatedMesh, whole_number
from ..normals import Shading
from .level_chain import chain_notes, coarser_level_count

# Frames of a longer sequence measured by default, evenly spaced: every frame of a 300-frame,
# 20k-triangle sequence took 61 s to measure against 2.3 s to simplify.
MEASURED_FRAMES = 64


@dataclass
class SequenceLevel:
    """One written level: its path, faces, AQEM error and measured surface error."""

    path: Path
    faces: int
    target_faces: int
    reached: bool
    aqem_error: float  # asset units, the largest collapse error (RMS plane distance)
    surface: dict[str, float] | None  # mean/max over frames of Hausdorff and RMS, relative; None unmeasured
    error: float | None = None  # asset units, max over frames of the Hausdorff distance; None unmeasured


@dataclass
class SequenceReport:
    """The result of :func:`simplify_sequence`: its ``levels`` are those written, up to the last
    one coarser than the one before it (see :mod:`.level_chain`); ``notes`` say which levels fell
    short of their targets and which were not written."""

    source: str
    original: AnimatedMesh
    levels: list[SequenceLevel]
    preparation: Preparation
    seconds: float  # the simplification (all levels), without reading, writing or measuring
    frames_used: int  # frames whose quadrics drove it (fewer than the sequence's when limited)
    frames_measured: int  # frames the surface errors are over (0: not measured)
    vertex_weights: np.ndarray  # (V,) Eq. 6 weight of each input vertex, 1 outside motion features
    notes: list[str]


def simplify_sequence(
    source: str | os.PathLike,
    output: str | os.PathLike,
    ratios: Sequence[float] = (0.5, 0.25, 0.1),
    *,
    measure: bool = True,
    measured_frames: int | None = MEASURED_FRAMES,
    progress: Callable[[int, int], None] | None = None,
    measuring: Callable[[int, int], None] | None = None,
    **aqem_options: object,
) -> SequenceReport:
    """Simplify the sequence at ``source`` (a folder, glob or file of OBJ/PLY frames, or an NPZ)
    and write its levels into the folder ``output``, up to the last level coarser than the one
    before it (a max error or the topology can stop the collapses; ``notes`` say so).

    ``aqem_options`` are keyword arguments of :func:`animlod.simplify_animated`; ``progress``
    receives its (done, total) collapse counts, ``measuring`` the (done, total) levels measured
    (on long sequences the measurement takes longer than the simplification). The surface errors
    are over at most ``measured_frames`` frames, evenly spaced from the first to the last (None:
    every frame). Raises FormatError for unreadable input, ValueError for ``measured_frames`` < 1,
    OSError before any work where ``output`` cannot take the levels (a file at or above it: NotADirectoryError;
    a folder that takes no new file).
    """
    if measured_frames is not None:
        measured_frames = whole_number("measured_frames", measured_frames, 1)
    check_writable_folder(output)  # before the work, not when the first level is written
    kind = input_kind(source)
    texture = None  # the sequence's texture coordinates, carried as AQEM attributes
    shading = None  # how the sequence's normals shade it, for the levels' rebuilt normals
    colours = None  # its vertex colours, carried as AQEM attributes too
    materials = None  # its OBJ materials, one per face
    points = None  # the files' position each vertex stands on, where split at seams
    if kind == "npz":
        from ..io.npz import read_npz

        original = read_npz(source)
    elif kind == "sequence":
        from ..io.meshseq import read_textured_sequence

        original, texture, shading, colours, materials, points = read_textured_sequence(source)
    else:
        raise FormatError(os.fspath(source), "file", f"a {kind} file is not a mesh sequence")
    started = time.perf_counter()
    # The report keeps no collapse record, whose positions would take 12 bytes per collapse and frame.
    aqem_options = {**aqem_options, "record_positions": False}
    if texture is not None or colours is not None:  # a point of the edge in every frame, where its attributes are
        aqem_options = {"placement": "on_edge", **aqem_options}
    carried = _CarriedAttributes.of(original, texture, colours, materials, points)
    per_vertex, per_point = carried.columns()
    if materials is not None:  # copies of a position in two materials never merge, as in glTF
        aqem_options = {"face_groups": materials.faces + 1, **aqem_options}
    result = simplify_animated(original, ratios, progress=progress, attributes=per_vertex,
                               position_attributes=per_point, **aqem_options)  # fmt: skip
    seconds = time.perf_counter() - started
    folder, stem, fmt = Path(output), input_stem(source), _level_format(kind, source)
    if shading is not None and not normals_fit(fmt.suffix, shading):
        warnings.warn(f"{os.fspath(source)}: its normals are not written: they shade it flat or with hard edges, "
                      "and the levels are PLY files, whose vertices hold one normal each", UnreadAttributesWarning,
                      stacklevel=2)  # fmt: skip
        shading = None
    if materials is not None and fmt.suffix != "obj":
        warnings.warn(f"{os.fspath(source)}: its materials are not written: the levels are PLY files, which have "
                      "none", UnreadAttributesWarning, stacklevel=2)  # fmt: skip
    frames = _measured_frames(original.frame_count, measured_frames) if measure else np.arange(0)
    written = result.levels[: coarser_level_count(result.levels, ratios)]
    max_error = float(aqem_options.get("max_error", math.inf))
    notes = chain_notes(result.levels, len(written), max_error)
    levels = []
    for index, level in enumerate(written, start=1):
        if measure and measuring is not None:
            measuring(index - 1, len(written))
        path = _write_level(fmt, folder / f"{stem}_lod{index}", level.mesh, carried.of_level(level), shading)
        measured = _surface_error(*(_frames_of(mesh, frames) for mesh in (original, level.mesh))) if measure else None
        surface = measured.summary() if measured is not None else None
        error = float(measured.hausdorff.max()) if measured is not None else None
        faces, target = level.mesh.face_count, level.target_face_count
        levels.append(SequenceLevel(path, faces, target, level.reached, level.error, surface, error))
    if measure and measuring is not None:
        measuring(len(written), len(written))
    return SequenceReport(os.fspath(source), original, levels, result.preparation, seconds, len(result.frames_used),
                          len(frames), result.vertex_weights, notes)  # fmt: skip


@dataclass(frozen=True)
class _CarriedAttributes:
    """The sequence's vertex attributes AQEM interpolates along its collapses: the texture
    coordinates per vertex (a UV seam's copies apart), and every frame's colours. Colours are
    carried per point where every copy of a position has its colour (an OBJ file's, which its
    ``v`` lines hold; a PLY file's split at UV seams), so that a seam's copies keep one colour as
    the point moves; per vertex where copies differ (a colour seam, kept sharp)."""

    texture: SequenceTexture | None
    colours: VertexColours | None
    colours_by_point: bool
    materials: ObjMaterials | None
    points: np.ndarray | None

    @classmethod
    def of(
        cls,
        mesh: AnimatedMesh,
        texture: SequenceTexture | None,
        colours: VertexColours | None,
        materials: ObjMaterials | None,
        points: np.ndarray | None,
    ) -> _CarriedAttributes:
        """The attributes of ``mesh`` carried: its ``texture``, ``colours``, faces' ``materials``
        and the files' ``points`` its vertices stand on (each may be None)."""
        by_point = False
        if colours is not None:  # copies of a position in the first frame: those AQEM may weld
            flat = _frame_columns(colours.values)
            _, first, copy_of = np.unique(mesh.frames[0], axis=0, return_index=True, return_inverse=True)
            by_point = bool(np.array_equal(flat, flat[first[copy_of.ravel()]]))
        return cls(texture, colours, by_point, materials, points)

    def columns(self) -> tuple[np.ndarray | None, np.ndarray | None]:
        """(V, A) per-vertex and (V, B) per-point float32 columns (each None for none): u, v where
        textured, and each frame's colour channels, with the one or the other."""
        per_vertex = [] if self.texture is None else [self.texture.uvs]
        per_point = []
        if self.colours is not None:
            (per_point if self.colours_by_point else per_vertex).append(_frame_columns(self.colours.values))
        return tuple(np.concatenate(parts, axis=1, dtype=np.float32) if parts else None
                     for parts in (per_vertex, per_point))  # fmt: skip

    def of_level(self, level: SimplifiedLevel) -> _LevelSurface:
        """A level's texture coordinates and colours, from its interpolated attributes, and its
        faces' materials, those of the input faces they come from."""
        texture = colours = materials = None
        points = None if self.points is None else self.points[level.kept_vertices]
        if self.texture is not None:  # split at its seams: points is the texture's
            texture = SequenceTexture(level.attributes[:, :2], points)
        if self.colours is not None:
            frames, _, channels = self.colours.values.shape
            columns = level.position_attributes if self.colours_by_point else level.attributes[:, -frames * channels :]
            values = columns.reshape(-1, frames, channels).transpose(1, 0, 2)
            colours = replace(self.colours, values=np.ascontiguousarray(values))
        if self.materials is not None:
            materials = self.materials._replace(faces=self.materials.faces[level.face_sources])
        return _LevelSurface(texture, colours, materials, points)


class _LevelSurface(NamedTuple):
    """What a level is written with beside its positions and faces (each None for none)."""

    texture: SequenceTexture | None
    colours: VertexColours | None
    materials: ObjMaterials | None
    points: np.ndarray | None  # the files' position each vertex stands on, where split at seams


def _frame_columns(values: np.ndarray) -> np.ndarray:
    """(K, V, C) values per frame and vertex as (V, K * C) columns."""
    frames, vertices, channels = values.shape
    return values.transpose(1, 0, 2).reshape(vertices, frames * channels)


def _measured_frames(frame_count: int, limit: int | None) -> np.ndarray:
    """The frames measured: every one, or ``limit`` evenly spaced from the first to the last (the
    first is where the measured points are drawn)."""
    if limit is None or frame_count <= limit:
        return np.arange(frame_count)
    return np.round(np.linspace(0, frame_count - 1, limit)).astype(np.int64)  # at least 1 apart: distinct


def _frames_of(mesh: AnimatedMesh, frames: np.ndarray) -> AnimatedMesh:
    return mesh if len(frames) == mesh.frame_count else AnimatedMesh(mesh.faces, mesh.frames[frames])


# Points measured per chunk of frames: each frame holds its vertices and the samples in float64,
# twice (both ways), so 2M points keep a chunk near 100 MB whatever the sequence's length.
_MEASURED_POINTS_PER_CHUNK = 2_000_000
_SAMPLES = 10000


def _surface_error(original: AnimatedMesh, level: AnimatedMesh) -> SurfaceError:
    """:func:`~animlod.metrics.surface_error` of ``level`` against ``original``, measured over
    chunks of frames: all frames at once held every frame's points in float64, 1.4 GB for 1000
    frames of a 441-vertex cloth. Each chunk after the first starts with frame 0 again, which the
    points are drawn on, so every frame is measured at the same points as in one call."""
    per_frame = original.vertex_count + level.vertex_count + 2 * _SAMPLES
    chunk = max(1, _MEASURED_POINTS_PER_CHUNK // per_frame)
    if original.frame_count <= chunk + 1:
        return surface_error(original, level, samples=_SAMPLES)
    parts = []
    for start in range(0, original.frame_count, chunk):
        frames = np.r_[0, start : min(start + chunk, original.frame_count)] if start else np.arange(chunk)
        pair = [AnimatedMesh(mesh.faces, mesh.frames[frames]) for mesh in (original, level)]
        measured = surface_error(*pair, samples=_SAMPLES)
        parts.append(
            [values[1:] if start else values for values in (measured.hausdorff, measured.rms, measured.diagonal)]
        )
    return SurfaceError(*(np.concatenate(arrays) for arrays in zip(*parts)))


@dataclass(frozen=True)
class _LevelFormat:
    """How the levels are written: ``suffix`` "npz", "obj" or "ply"; ``one_file`` for a single
    mesh or an NPZ, else a folder of frames per level, each frame under its input file's name
    (``frame_names``, without the suffix), or numbered where those names would collide."""

    suffix: str
    one_file: bool
    frame_names: list[str] | None = None
    source_folder: Path | None = None  # where the frames are, which OBJ material libraries name files from


def _level_format(kind: str, source: str | os.PathLike) -> _LevelFormat:
    """The input's format: NPZ, one OBJ/PLY file, or frames (PLY when a frame is PLY)."""
    if kind == "npz":
        return _LevelFormat("npz", True)
    from ..io.meshseq import frame_names_fit, level_format, sequence_paths

    # The frames read, not the source's name: "frames/*" holds PLY frames without saying so.
    paths = sequence_paths(source)
    suffix = level_format(paths)
    names = [path.stem for path in paths]  # two frames of one name (a.obj, a.ply; a glob over folders): numbered
    return _LevelFormat(suffix, isinstance(source, str | os.PathLike) and Path(source).is_file(),
                        names if frame_names_fit(names, len(paths)) else None, paths[0].parent)  # fmt: skip


def _write_level(
    fmt: _LevelFormat, target: Path, mesh: AnimatedMesh, surface: _LevelSurface, shading: Shading | None
) -> Path:
    """Write a level as ``fmt`` says, with its texture coordinates, rebuilt normals, colours and
    materials if any; its path. A file's suffix is appended, not swapped:
    ``walk.v2_lod1`` has the suffix ``.v2_lod1`` (every level of walk.v2.npz was written to
    walk.npz)."""
    written_in = target if not fmt.one_file else target.parent
    materials = None if fmt.suffix != "obj" else _libraries_from(surface.materials, fmt.source_folder, written_in)
    if not fmt.one_file:
        from ..io.meshseq import write_sequence

        write_sequence(target, mesh, fmt.suffix, names=fmt.frame_names, texture=surface.texture, shading=shading,
                       colours=surface.colours, materials=materials, points=surface.points)  # fmt: skip
        return target
    path = target.with_name(f"{target.name}.{fmt.suffix}")
    if fmt.suffix == "npz":
        from ..io.npz import write_npz

        write_npz(path, mesh)
    else:  # one mesh in, one mesh out
        from ..io.meshseq import frame_layout

        layout = frame_layout(mesh, surface.texture, fmt.suffix, normals=shading is not None, points=surface.points)
        layout.write(path, mesh, 0, shading, surface.colours, materials)
    return path


def _libraries_from(materials: ObjMaterials | None, source: Path | None, written_in: Path) -> ObjMaterials | None:
    """``materials`` with their libraries (named from the input's ``source`` folder) named from
    the folder the level is ``written_in``: the levels use the input's .mtl files where they are."""
    if materials is None or source is None:
        return materials
    libraries = tuple(library if os.path.isabs(library) else
                      Path(os.path.relpath(source / library, written_in.absolute())).as_posix()
                      for library in materials.libraries)  # fmt: skip
    return materials._replace(libraries=libraries)
