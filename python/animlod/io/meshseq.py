"""OBJ and PLY frame sequences: one mesh file per frame, every frame with the same faces (or
the same polygons split along other diagonals, read with the first frame's triangles).

Geometry is read (:mod:`.obj`, :mod:`.ply`), and with :func:`read_textured_sequence` the
sequence's texture coordinates (an OBJ's ``vt``, a PLY's per-vertex s, t), how its normals
shade it (``vn``; nx, ny, nz) and its vertex colours (each frame's, :mod:`.vertex_colours`),
which :func:`write_sequence` writes back (normals rebuilt from each written frame's faces).
"""

from __future__ import annotations

import glob
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from enum import Enum, auto
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..model import AnimatedMesh
from ..normals import Shading, corner_normals, shading_of, unit_vectors, vertex_normals
from .atomic import atomic_folder
from .errors import FormatError
from .frame_order import in_frame_order
from .obj import (
    ObjMaterials,
    ObjNormals,
    ObjSharedText,
    ObjTemplate,
    ObjTexture,
    TexturedMesh,
    UnreadAttributesWarning,
    read_obj,
    read_obj_template,
    read_obj_textured,
    write_obj,
)
from .obj import face_of_triangle as obj_face_of_triangle
from .ply import face_of_triangle as ply_face_of_triangle
from .ply import read_ply, read_ply_attributes, write_ply
from .polygon_splits import triangle_change
from .vertex_colours import VertexColours
from .vertex_renumbering import first_frame_order

MESH_SUFFIXES = (".obj", ".ply")

# ---------------------------------------------------------------------------------------------
# Sequences


def read_sequence(source: str | os.PathLike | Sequence[str | os.PathLike], fps: float | None = None) -> AnimatedMesh:
    """Read OBJ/PLY frames that share one connectivity into an :class:`~animlod.model.AnimatedMesh`.

    Parameters
    ----------
    source : a folder (every .obj and .ply file in it, in natural order: frame2 before
        frame10, and sub-frames such as mesh.1.25.obj by value), a glob pattern (its matches in
        the same order), a single file, or a list of files (in the order given).
    fps : frames per second of the sequence, or None for a set of poses.

    Returns
    -------
    AnimatedMesh with ``frames (F, V, 3) float32`` and the first file's ``faces (M, 3) int32``.
    A frame whose triangles differ from the first frame's only in where its polygons are split
    (or at which corner a triangle starts), as exporters that triangulate each deformed frame
    write them, is the same surface: it is read with the first frame's triangles, and one
    UserWarning says how many frames are.

    Raises
    ------
    FormatError
        When no frame is found, a file cannot be read, or a frame's vertex count or faces
        differ from the first frame's otherwise (naming the file and the first differing face).
    """
    return _read_frames(sequence_paths(source), fps, textured=False)[0]


@dataclass(frozen=True)
class SequenceTexture:
    """The texture coordinates of a sequence read with them (:func:`read_textured_sequence`).
    Each vertex of its mesh is one (position, texture coordinate) pair of the files' corners, so
    that the copies of a position along a UV seam are vertices of their own.

    uvs : (V, 2) float32 per vertex of the mesh.
    points : (V,) int32 the position (0-based ``v`` line of the files) each vertex stands on.
    """

    uvs: np.ndarray
    points: np.ndarray


class TexturedSequence(NamedTuple):
    """A sequence with what :func:`read_textured_sequence` reads beside its frames, each None
    where the frames have none."""

    mesh: AnimatedMesh
    texture: SequenceTexture | None
    shading: Shading | None
    colours: VertexColours | None
    materials: ObjMaterials | None
    points: np.ndarray | None = None  # (V,) int32 the files' position each vertex stands on, where split


def read_textured_sequence(
    source: str | os.PathLike | Sequence[str | os.PathLike], fps: float | None = None
) -> TexturedSequence:
    """:func:`read_sequence` with the sequence's texture coordinates (OBJ ``vt`` lines, PLY
    vertices' s, t): the mesh then has a vertex per (position, texture coordinate) pair of the
    corners (:class:`SequenceTexture`). None, and the files' positions as the vertices, where the
    frames have none, or where one frame's differ from the first's (with an
    :class:`~animlod.io.obj.UnreadAttributesWarning`). Third, where the first frame has normals
    (OBJ ``vn``, PLY nx, ny, nz), how they shade it (:class:`~animlod.normals.Shading`: flat, hard edges or smooth,
    and whether they point against the winding); else None. Fourth, where every frame has vertex
    colours stored alike (PLY red, green, blue and alpha; OBJ ``v x y z r g b``), each mesh
    vertex's colours: one set where every frame's are the first's, else one per frame
    (:class:`~animlod.io.vertex_colours.VertexColours`); else None (with an
    :class:`~animlod.io.obj.UnreadAttributesWarning` where some frames have them). Fifth, the
    first frame's OBJ materials, one per face of the mesh (:class:`~animlod.io.obj.ObjMaterials`);
    a position used by faces of two materials is then a vertex per material, as at a UV seam.
    Sixth, where the mesh's vertices are such copies, the files' position each stands on
    (``points``); else None. Read its fields by name: more may come. A frame whose polygons are
    split otherwise than the first frame's (:func:`read_sequence`) is read with the first frame's
    triangles, texture coordinates, normals and materials, and its own positions and colours."""
    return _read_frames(sequence_paths(source), fps, textured=True)


def _read_frames(paths: list[Path], fps: float | None, textured: bool) -> TexturedSequence:
    """The frames of ``paths`` (:func:`read_sequence`), and with ``textured`` their texture
    coordinates, normals' shading, colours and materials (:func:`read_textured_sequence`)."""

    with warnings.catch_warnings(record=True) as first_warnings:
        warnings.simplefilter("always")
        first_mesh, template = _read_first_frame(paths[0], textured)
        first_vertices, faces, texture, normals, colours, materials = first_mesh
    for warning in first_warnings:
        warnings.warn(warning.message, stacklevel=3)
    # A file without triangles is no frame of a mesh (random bytes named .obj parse as one).
    if not len(faces):
        what = "no vertices and no faces" if not len(first_vertices) else f"{len(first_vertices)} vertices but no faces"
        raise FormatError(paths[0], "mesh", f"{what}; a frame needs triangles")
    frames = np.empty((len(paths),) + first_vertices.shape, dtype=np.float32)
    frames[0] = first_vertices
    first_texture, differing = texture, None  # the first frame whose texture coordinates are not the first's
    recoloured = None  # the first frame whose faces have other materials than the first frame's
    first_uvs = None if texture is None else texture.uvs  # a PLY's per vertex, where read
    first_uvs_read = textured  # read_sequence reads them only for a frame to match (below)
    frame_colours = _ColourFrames(paths[0], colours, len(paths))
    # Frames whose triangles are the first frame's listed otherwise, or its polygons split otherwise.
    otherwise: dict[_Triangles, list[Path]] = {_Triangles.LISTED_OTHERWISE: [], _Triangles.SPLIT_OTHERWISE: []}
    reordered: list[Path] = []  # frames whose vertices are numbered in another order than the first frame's
    with warnings.catch_warnings(record=True) as later_warnings:  # the first frame's speak for the sequence
        warnings.simplefilter("always")
        for index, path in enumerate(paths[1:], start=1):
            frame, template = _read_later_frame(path, textured, template)
            vertices, frame_faces, frame_texture, _, colours, frame_materials = frame
            # A PLY frame's texture coordinates are per vertex: where its triangles are not the
            # first frame's, others than the first's tell of vertices numbered otherwise, and
            # which vertex is which (read for this alone where the sequence is read without them).
            order, renumbered = None, False
            if path.suffix.lower() == ".ply" and not np.array_equal(frame_faces, faces):
                if not first_uvs_read:
                    first_uvs, first_uvs_read = _quiet_ply_uvs(paths[0]), True
                if textured or first_uvs is None:  # read with the frame, or not needed: none to match
                    frame_uvs = None if frame_texture is None else frame_texture.uvs
                else:
                    frame_uvs = _quiet_ply_uvs(path)
                renumbered = (
                    first_uvs is not None and frame_uvs is not None and not np.array_equal(first_uvs, frame_uvs)
                )
                order = first_frame_order(faces, first_uvs, frame_faces, frame_uvs) if renumbered else None
            if order is not None:
                vertices, frame_faces, frame_texture, colours = _in_first_order(
                    order, vertices, frame_faces, frame_texture, colours
                )
                reordered.append(path)
                renumbered = False
            standing = _check_same_surface(
                path, vertices, frame_faces, paths[0], faces, len(first_vertices), renumbered
            )
            if standing is not _Triangles.SAME:
                otherwise[standing].append(path)
            frames[index] = vertices
            frame_colours.add(index, path, colours)
            if textured and differing is None and not _same_texture(texture, frame_texture, faces, frame_faces):
                differing, differing_texture, texture = path, frame_texture, None
            if textured and recoloured is None and not _same_materials(materials, frame_materials, faces, frame_faces):
                recoloured = path
    unread = [w for w in later_warnings if issubclass(w.category, UnreadAttributesWarning)]
    if unread and not any(issubclass(w.category, UnreadAttributesWarning) for w in first_warnings):
        warnings.warn(unread[0].message, stacklevel=3)  # a later frame's own, where the first has none
    for warning in later_warnings:  # any other, as each frame gave it
        if not issubclass(warning.category, UnreadAttributesWarning):
            warnings.warn(warning.message, stacklevel=3)
    if reordered:
        warnings.warn(f"{reordered[0]}: {len(reordered)} of the {len(paths)} frames (this the first) number their "
                      f"vertices in another order than the first frame {paths[0].name}, as Blender's PLY exporter does "
                      "where it splits a polygon otherwise; each vertex is matched by its texture coordinates at the "
                      "corners of its polygon", stacklevel=3)  # fmt: skip
    first_frame = f"the first frame {paths[0].name}"
    for kind, how in ((_Triangles.SPLIT_OTHERWISE, f"triangulate some polygons differently from {first_frame}, as "
                                                   "exporters that triangulate each frame do"),
                      (_Triangles.LISTED_OTHERWISE, f"list the triangles of {first_frame} in another order or start "
                                                    "them at other corners")):  # fmt: skip
        if otherwise[kind]:
            warnings.warn(f"{otherwise[kind][0]}: {len(otherwise[kind])} of the {len(paths)} frames (this the first) "
                          f"{how}; every frame is read with the first frame's triangles", stacklevel=3)  # fmt: skip
    if recoloured is not None:
        warnings.warn(f"{recoloured}: gives some faces other materials than {paths[0].name}: every frame is read "
                      f"with the materials of {paths[0].name}", UnreadAttributesWarning, stacklevel=3)  # fmt: skip
    if differing is not None:
        first = paths[0].name
        if differing_texture is None:
            what = f"has no texture coordinates, and {first} has"
        elif first_texture is None:
            what = f"has texture coordinates, and {first} has none"
        else:
            what = f"has texture coordinates other than {first}'s"
        warnings.warn(f"{differing}: {what}: the levels are written without them", UnreadAttributesWarning,
                      stacklevel=3)  # fmt: skip
    colours = frame_colours.read()
    shading = None if normals is None else _shading_of(first_vertices, faces, normals)
    # A vertex per (position, texture coordinate, material) that a corner uses: copies of a point
    # at a UV seam or a material border, which AQEM welds and keeps apart.
    corner_keys = [faces.ravel()]
    if texture is not None:
        corner_keys.append(texture.corners.ravel())
    if materials is not None:
        corner_keys.append(np.repeat(materials.faces, 3))
    if len(corner_keys) == 1:
        return TexturedSequence(AnimatedMesh(faces, frames, fps=fps), None, shading, colours, materials)
    wedges, corner_wedge = np.unique(np.stack(corner_keys, axis=1), axis=0, return_inverse=True)
    points = wedges[:, 0].astype(np.int32)
    split = AnimatedMesh(corner_wedge.reshape(faces.shape).astype(np.int32), frames[:, points], fps=fps)
    if colours is not None:
        colours = replace(colours, values=colours.values[:, points])
    texture = None if texture is None else SequenceTexture(texture.uvs[wedges[:, 1]], points)
    return TexturedSequence(split, texture, shading, colours, materials, points)


def _read_first_frame(path: Path, textured: bool) -> tuple[TexturedMesh, ObjTemplate | None]:
    """A sequence's first frame, with its normals where ``textured`` (they tell the shading the
    levels rebuild), and for an OBJ file the template its later OBJ frames are read by."""
    if path.suffix.lower() == ".obj":
        return read_obj_template(path, textured)
    return read_mesh_textured(path) if textured else _geometry_of(path), None


def _read_later_frame(
    path: Path, textured: bool, template: ObjTemplate | None
) -> tuple[TexturedMesh, ObjTemplate | None]:
    """A later frame of a sequence, without normals, and the template to read the next by; an
    OBJ frame by the ``template`` of an OBJ frame before it (:meth:`~.obj.ObjTemplate.read`),
    which reads only the ``v`` lines of a frame that repeats the rest of it."""
    if template is not None and path.suffix.lower() == ".obj":
        return template.read(path)
    return read_mesh_textured(path, normals=False) if textured else _geometry_of(path), template


class _ColourFrames:
    """The vertex colours of a sequence's frames, gathered as they are read: every frame's where
    each has colours stored as the first frame's; red, green and blue alone, with a warning naming
    the first frame that differs, where some frames store an alpha and others none (or another
    type of it); none, with a warning, where a frame has no colours or stores a colour channel
    otherwise."""

    def __init__(self, first_path: Path, first: VertexColours | None, frame_count: int) -> None:
        self.first_path, self.first = first_path, first
        self.values = None if first is None else np.empty((frame_count, *first.values.shape[1:]), np.float32)
        if self.values is not None:
            self.values[0] = first.values[0]
        self.dropped: str | None = None  # why they are not read: the first frame that differs, and how
        self.narrowed: str | None = None  # which channels are not read: the first frame that differs

    def add(self, index: int, path: Path, colours: VertexColours | None) -> None:
        """Take frame ``index``'s colours (read from ``path``)."""
        if self.dropped or (self.first is None and colours is None):
            return
        if self.first is not None and self.first.same_layout(colours):
            self.values[index] = colours.values[0]
            return
        first = self.first_path.name
        if colours is None:
            what = f"has no vertex colours that can be read, and {first} has"
        elif self.first is None:
            what = f"has vertex colours, and {first} has none"
        else:
            what = f"stores its vertex colours as {colours.layout()}, and {first} as {self.first.layout()}"
            shared = self._shared(colours)
            if shared:  # an alpha alone differs: keep the rest
                left = ", ".join(dict.fromkeys(n for n in (*self.first.names, *colours.names) if n not in shared))
                self.narrowed = self.narrowed or f"{path}: {what}: the levels are written without {left}"
                keep = [self.first.names.index(name) for name in shared]
                self.first = VertexColours(self.first.values[..., keep], tuple(shared),
                                           tuple(self.first.types[k] for k in keep))  # fmt: skip
                self.values = self.values[..., keep]
                self.values[index] = colours.values[0][:, [colours.names.index(name) for name in shared]]
                return
        self.dropped, self.values = f"{path}: {what}: the levels are written without them", None

    def _shared(self, colours: VertexColours) -> list[str]:
        """The channels of the colours kept so far that ``colours`` stores alike (same name, same
        type, as many vertices), in their order, where they hold the three colour channels: the
        alpha alone may go."""
        if colours.values.shape[1] != self.first.values.shape[1]:
            return []
        theirs = dict(zip(colours.names, colours.types))
        shared = [name for name, kind in zip(self.first.names, self.first.types) if theirs.get(name) == kind]
        return shared if set(self.first.names[:3]) <= set(shared) else []

    def read(self) -> VertexColours | None:
        """The frames' colours: one set where every frame's are the first's, else one per frame;
        None, with the warning saying why, where a frame differs in having them or in every
        channel."""
        for message in (self.narrowed, self.dropped):
            if message:
                warnings.warn(message, UnreadAttributesWarning, stacklevel=4)
        if self.values is None:
            return None
        values = self.values[:1] if np.all(self.values == self.values[:1]) else self.values
        return replace(self.first, values=values)


def _shading_of(vertices: np.ndarray, faces: np.ndarray, normals: ObjNormals) -> Shading:
    """How a frame's normals shade it (:func:`~animlod.normals.shading_of` over its (position,
    normal) pairs)."""
    pairs = np.stack([faces.ravel(), normals.corners.ravel()], axis=1)
    split, corner = np.unique(pairs, axis=0, return_inverse=True)
    return shading_of(vertices[split[:, 0]], normals.normals[split[:, 1]], corner.reshape(faces.shape))


def rebuilt_normals(positions: np.ndarray, faces: np.ndarray, shading: Shading) -> ObjNormals:
    """The normals of one frame ``positions (P, 3)`` from its own ``faces``, shaded as ``shading``
    says (:func:`read_textured_sequence`): one per position where smooth, else one per distinct
    corner normal; against the winding where the input's were."""
    if shading.crease >= np.pi:
        normals = ObjNormals(vertex_normals(positions, faces), faces)
    else:
        # Rounded before they are told apart: coplanar faces' sums differ in their last bits, which
        # wrote a flat box's 6 normals as up to 37 vn lines.
        rounded = np.round(corner_normals(positions, faces, shading.crease), 6)
        values, index = np.unique(rounded, axis=0, return_inverse=True)
        normals = ObjNormals(unit_vectors(values), index.reshape(faces.shape).astype(np.int32))
    return normals._replace(normals=-normals.normals) if shading.inward else normals


def _same_texture(
    first: ObjTexture | None, other: ObjTexture | None, first_faces: np.ndarray, faces: np.ndarray
) -> bool:
    """Whether a frame's texture coordinates (None: it has none) are the first frame's; where its
    ``faces`` split the first frame's polygons otherwise, whether they pair the same positions with
    the same texture coordinates, as the mesh's vertices are those pairs (an exporter that
    triangulates each frame numbers its ``vt`` lines in another order too)."""
    if first is None or other is None:
        return first is other
    if np.array_equal(first_faces, faces):
        return np.array_equal(first.corners, other.corners) and np.array_equal(first.uvs, other.uvs)
    pairs = (np.unique(np.column_stack([f.ravel(), t.uvs[t.corners.ravel()]]), axis=0)
             for f, t in ((first_faces, first), (faces, other)))  # fmt: skip
    return np.array_equal(*pairs)


def _same_materials(
    first: ObjMaterials | None, other: ObjMaterials | None, first_faces: np.ndarray, faces: np.ndarray
) -> bool:
    """Whether a frame's faces have the first frame's materials, by name (None: no usemtl line);
    frames whose triangles are not the first frame's as they stand (listed or split otherwise)
    are not compared."""
    if first is None or other is None:
        return first is other
    if not np.array_equal(first_faces, faces):
        return True

    def names(materials: ObjMaterials) -> np.ndarray:  # each face's material name, "" for none
        return np.array([*materials.names, ""], dtype=object)[materials.faces]

    return np.array_equal(names(first), names(other))


def write_sequence(
    folder: str | os.PathLike,
    mesh: AnimatedMesh,
    fmt: str = "obj",
    stem: str = "frame",
    names: Sequence[str] | None = None,
    texture: SequenceTexture | None = None,
    shading: Shading | None = None,
    colours: VertexColours | None = None,
    materials: ObjMaterials | None = None,
    points: np.ndarray | None = None,
) -> list[Path]:
    """Write every frame of ``mesh`` to ``folder/{stem}_{index:04d}.{fmt}``, or to
    ``folder/{name}.{fmt}`` with the frames' ``names``, the folder atomically; with ``texture``
    its texture coordinates (:func:`frame_layout`); with ``shading`` each frame's normals rebuilt
    from its faces, shaded so (:func:`rebuilt_normals`; smooth only for PLY, whose vertices hold
    one normal each); with ``colours`` each frame's vertex colours (one set for every frame, or
    one per frame); with ``materials`` (OBJ only) each face's material; with ``points`` the
    position each vertex is a copy of, copies written as one OBJ ``v`` (:func:`obj_layout`).

    The frames are written into a temporary folder beside ``folder``, which is renamed to
    ``folder`` once every frame is written (:func:`~animlod.io.atomic.atomic_folder`): an
    interrupted run never leaves a folder short of frames under the final name. An existing
    ``folder`` is replaced as a whole. ``fmt`` is "obj" or "ply" (binary little-endian).
    Returns the written paths in frame order. ValueError for another ``fmt``, ``names`` that
    are not one file name per frame, distinct regardless of case, a ``texture`` of another
    vertex count, a ``shading`` other than smooth for PLY, or ``colours`` of another vertex or
    frame count.
    """
    if fmt not in ("obj", "ply"):
        raise ValueError(f"{os.fspath(folder)}: fmt: must be 'obj' or 'ply', got {fmt!r}")
    if texture is not None and len(texture.uvs) != mesh.vertex_count:
        raise ValueError(f"{os.fspath(folder)}: texture: {len(texture.uvs)} texture coordinates for "
                         f"{mesh.vertex_count} vertices")  # fmt: skip
    if colours is not None and (colours.values.shape[1] != mesh.vertex_count
                                or len(colours.values) not in (1, mesh.frame_count)):  # fmt: skip
        raise ValueError(f"{os.fspath(folder)}: colours: {colours.values.shape[:2]} (frames, vertices) of colours "
                         f"for {mesh.frame_count} frames of {mesh.vertex_count} vertices")  # fmt: skip
    if shading is not None and not normals_fit(fmt, shading):
        raise ValueError(f"{os.fspath(folder)}: shading: a PLY file holds a normal per vertex, smooth shading only")
    if names is None:
        width = max(4, len(str(mesh.frame_count - 1)))
        names = [f"{stem}_{index:0{width}d}" for index in range(mesh.frame_count)]
    elif not frame_names_fit(names, mesh.frame_count):
        raise ValueError(f"{os.fspath(folder)}: names: {len(names)} names for {mesh.frame_count} frames, or names "
                         "that repeat (regardless of case) or are not plain file names")  # fmt: skip
    names = [f"{name}.{fmt}" for name in names]
    layout = frame_layout(mesh, texture, fmt, normals=shading is not None, points=points)
    with atomic_folder(folder) as temporary:
        shared = None  # the text an OBJ frame shares with the next (write_obj)
        for frame, name in enumerate(names):
            shared = layout.write(temporary / name, mesh, frame, shading, colours, materials, shared)
    return [Path(folder) / name for name in names]


@dataclass(frozen=True)
class FrameLayout:
    """How a mesh's frames are written as OBJ or PLY files (:func:`frame_layout`).

    written : (P,) the vertices whose positions are written, in order.
    faces : (M, 3) the faces over the written positions.
    texture : the texture coordinates with each corner's index, or None.
    welded : (P,) for PLY files written with normals, the group of the written vertices that
        stand at one place in every frame (a seam's copies, rows of their own), which share a
        smooth normal; None for OBJ files, whose seam's copies share a position.
    """

    written: np.ndarray
    faces: np.ndarray
    texture: ObjTexture | None
    welded: np.ndarray | None = None

    def normals(self, positions: np.ndarray, shading: Shading) -> ObjNormals:
        """A frame's normals rebuilt from its written ``positions``, shaded as ``shading`` says
        (:func:`rebuilt_normals`); for a PLY file smooth ones (:func:`normals_fit`), per vertex and
        the same across a seam."""
        if self.welded is None:
            return rebuilt_normals(positions, self.faces, shading)
        points = np.zeros((int(self.welded.max(initial=-1)) + 1, 3), np.float64)
        points[self.welded] = positions
        return ObjNormals(rebuilt_normals(points, self.welded[self.faces], shading).normals[self.welded], self.faces)

    def write(
        self,
        path: Path,
        mesh: AnimatedMesh,
        frame: int,
        shading: Shading | None,
        colours: VertexColours | None,
        materials: ObjMaterials | None = None,
        shared: ObjSharedText | None = None,
    ) -> ObjSharedText | None:
        """Write ``mesh``'s ``frame`` to ``path`` (:func:`write_mesh`) laid out so, with its
        normals rebuilt where ``shading`` is given, its ``colours`` and its faces' ``materials``;
        an OBJ file with the text it ``shared`` with the frame before, which it returns for the
        next."""
        positions = mesh.frames[frame][self.written]
        normals = None if shading is None else self.normals(positions, shading)
        written_colours = None if colours is None else colours.of_frame(frame, self.written)
        return write_mesh(path, positions, self.faces, self.texture, normals, written_colours, materials, shared)


def frame_layout(
    mesh: AnimatedMesh,
    texture: SequenceTexture | None,
    fmt: str,
    normals: bool,
    points: np.ndarray | None = None,
) -> FrameLayout:
    """How ``mesh``'s frames are written as ``fmt`` ("obj" or "ply") files with ``texture``, and
    with ``normals`` or without; ``points`` where its vertices are copies of the files' positions
    (``texture.points`` where textured). A PLY file holds a texture coordinate and a normal per
    vertex, so every vertex is written; an OBJ file's are per corner (:func:`obj_layout`)."""
    if fmt != "ply":
        return FrameLayout(*obj_layout(mesh, texture, points))
    uvs = None if texture is None else ObjTexture(texture.uvs, mesh.faces)
    if not normals:
        return FrameLayout(np.arange(mesh.vertex_count), mesh.faces, uvs)
    paths = mesh.frames.transpose(1, 0, 2).reshape(mesh.vertex_count, -1)  # each vertex's place in every frame
    welded = np.unique(paths, axis=0, return_inverse=True)[1].ravel().astype(np.int64)
    return FrameLayout(np.arange(mesh.vertex_count), mesh.faces, uvs, welded)


def level_format(paths: Sequence[Path]) -> str:
    """The format ("obj" or "ply") the levels of the frames ``paths`` are written in: PLY when a
    frame is PLY (a PLY frame cannot be written as OBJ with what OBJ adds), else OBJ."""
    return "ply" if any(path.suffix.lower() == ".ply" for path in paths) else "obj"


def normals_fit(fmt: str, shading: Shading) -> bool:
    """Whether ``fmt`` files hold normals shaded as ``shading`` says: a PLY vertex holds one normal,
    so smooth shading only; an OBJ corner has its own."""
    return fmt != "ply" or shading.crease >= np.pi


def obj_layout(
    mesh: AnimatedMesh, texture: SequenceTexture | None, points: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, ObjTexture | None]:
    """How ``mesh``'s frames are written as OBJ files with ``texture``: the vertices whose
    positions are written (in vertex order), the faces over those positions and the texture
    coordinates with each corner's index; the vertices of one point (``points``, else
    ``texture.points``) that stand at one place in every frame (a seam's copies) share one
    position. Without either: every vertex."""
    points = texture.points if points is None and texture is not None else points
    if points is None:
        return np.arange(mesh.vertex_count), mesh.faces, None
    keys = np.concatenate([points[:, None], mesh.frames.transpose(1, 0, 2).reshape(mesh.vertex_count, -1)],
                          axis=1, dtype=np.float64)  # fmt: skip
    _, first, group = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)  # positions in the order of their first vertex
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    position = rank[group.ravel()].astype(np.int32)
    return first[order], position[mesh.faces], None if texture is None else ObjTexture(texture.uvs, mesh.faces)


def frame_names_fit(names: Sequence[str], frames: int) -> bool:
    """Whether ``names`` can name ``frames`` frame files of one folder: one each, plain file names
    (no folder, not hidden), distinct regardless of case (as case-insensitive file systems see them)."""
    plain = all(name and Path(name).name == name and not name.startswith(".") for name in names)
    return plain and len(names) == frames and len({name.casefold() for name in names}) == frames


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
        paths = in_frame_order(Path(match) for match in glob.glob(os.fspath(source)))
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
    """The OBJ/PLY frames of ``folder``, in the order of their frame numbers (:func:`~.frame_order.in_frame_order`)."""
    return in_frame_order(path for path in Path(folder).iterdir() if is_frame_name(path.name) and path.is_file())


def _in_first_order(
    order: np.ndarray,
    vertices: np.ndarray,
    faces: np.ndarray,
    texture: ObjTexture | None,
    colours: VertexColours | None,
) -> tuple[np.ndarray, np.ndarray, ObjTexture | None, VertexColours | None]:
    """A PLY frame's vertices, faces, texture coordinates and colours (each None where not read)
    with its vertices in the first frame's order (``order``: :func:`~.vertex_renumbering.first_frame_order`)."""
    inverse = np.empty_like(order)
    inverse[order] = np.arange(order.size)
    faces = order[faces].astype(faces.dtype)
    texture = None if texture is None else ObjTexture(texture.uvs[inverse], faces)
    colours = None if colours is None else replace(colours, values=colours.values[:, inverse])
    return vertices[inverse], faces, texture, colours


def _quiet_ply_uvs(path: Path) -> np.ndarray | None:
    """A PLY file's per-vertex texture coordinates, or None, without warnings about the properties
    not read: :func:`read_sequence` reads them only to match renumbered frames."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_ply_attributes(path)[2]


class _Triangles(Enum):
    """How a later frame's triangles stand to the first frame's."""

    SAME = auto()  # the first frame's as they stand
    LISTED_OTHERWISE = auto()  # the first frame's, in another order or started at other corners
    SPLIT_OTHERWISE = auto()  # the first frame's polygons split along other diagonals


def _check_same_surface(
    path: Path,
    vertices: np.ndarray,
    faces: np.ndarray,
    first_path: Path,
    first_faces: np.ndarray,
    vertex_count: int,
    renumbered: bool = False,
) -> _Triangles:
    """Check a frame's vertex count and triangles against the first frame's (FormatError naming
    the file and the face of the first differing triangle where they differ, and with
    ``renumbered`` that its vertices' texture coordinates differ too), and say how its triangles
    stand to the first frame's (:func:`~.polygon_splits.triangle_change`)."""
    first = f"the first frame {first_path.name}"
    if len(vertices) != vertex_count:
        raise FormatError(path, "vertices", f"{len(vertices)} vertices, but {first} has {vertex_count}")
    if faces.shape != first_faces.shape:
        raise FormatError(path, "faces", f"{len(faces)} triangles, but {first} has {len(first_faces)}")
    if np.array_equal(faces, first_faces):
        return _Triangles.SAME
    change = triangle_change(faces, first_faces, vertex_count)
    if change.listed_otherwise:
        return _Triangles.LISTED_OTHERWISE
    triangle = change.stray
    if triangle is not None:
        reason = (f"its triangle on vertices {faces[triangle].tolist()} (counted from 0) is no triangle of "
                  f"{first}, and the frame's triangles are not a re-triangulation of the first frame's "
                  "polygons")  # fmt: skip
        if renumbered:
            reason += ("; its vertices' texture coordinates differ from the first frame's too, as where an exporter "
                       "numbers each frame's vertices in another order")  # fmt: skip
        face = (obj_face_of_triangle if path.suffix.lower() == ".obj" else ply_face_of_triangle)(path, triangle)
        raise FormatError(path, face, reason)
    return _Triangles.SPLIT_OTHERWISE


# ---------------------------------------------------------------------------------------------
# Single meshes


def read_mesh_textured(path: str | os.PathLike, normals: bool = True) -> TexturedMesh:
    """:func:`read_mesh` with the file's texture coordinates and, with ``normals``, its normals,
    each an index per corner into its values: an OBJ's ``vt`` and ``vn`` lines
    (:func:`~.obj.read_obj_textured`), a PLY's per-vertex s, t and nx, ny, nz
    (:func:`~.ply.read_ply_attributes`); and its vertex colours and (OBJ) materials."""
    suffix = Path(path).suffix.lower()
    if suffix == ".obj":
        return read_obj_textured(path, normals)
    if suffix != ".ply":
        return _geometry_of(path)  # refused, naming the suffixes read
    vertices, faces, uvs, normal_rows, colours = read_ply_attributes(path)
    return TexturedMesh(vertices, faces, None if uvs is None else ObjTexture(uvs, faces),
                        None if normal_rows is None or not normals else ObjNormals(normal_rows, faces), colours,
                        None)  # fmt: skip


def _geometry_of(path: str | os.PathLike) -> TexturedMesh:
    """:func:`read_mesh` in the shape of :func:`read_mesh_textured`."""
    return TexturedMesh(*read_mesh(path), None, None, None, None)


def read_mesh(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read one .obj or .ply file: ``vertices (V, 3) float32`` and triangle ``faces (M, 3) int32``."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".obj":
        return read_obj(path)
    if suffix == ".ply":
        return read_ply(path)
    raise FormatError(path, "file name", f"expected one of {', '.join(MESH_SUFFIXES)}")


def write_mesh(
    path: str | os.PathLike,
    vertices: np.ndarray,
    faces: np.ndarray,
    texture: ObjTexture | None = None,
    normals: ObjNormals | None = None,
    colours: VertexColours | None = None,
    materials: ObjMaterials | None = None,
    shared: ObjSharedText | None = None,
) -> ObjSharedText | None:
    """Write one .obj or .ply (binary) file, chosen by the suffix of ``path``, with ``texture``
    and ``normals``, each an index per corner into its values (a PLY file's are one per vertex:
    ValueError where a vertex's corners have two), one frame's vertex ``colours``, and (OBJ:
    a PLY file has none) the faces' ``materials``. An OBJ file reuses the text it ``shared``
    with the frame before and returns it (:func:`~.obj.write_obj`); a PLY file returns None."""
    suffix = Path(path).suffix.lower()
    if suffix == ".obj":
        return write_obj(path, vertices, faces, texture, normals, colours, materials, shared)
    if suffix == ".ply":
        uvs, normal_rows = (
            None if given is None else _per_vertex(path, name, len(vertices), faces, *given)
            for name, given in (("texture", texture), ("normals", normals))
        )
        write_ply(path, vertices, faces, uvs=uvs, normals=normal_rows, colours=colours)
        return None
    raise ValueError(f"{os.fspath(path)}: expected one of {', '.join(MESH_SUFFIXES)}")


def _per_vertex(
    path: str | os.PathLike, name: str, vertex_count: int, faces: np.ndarray, values: np.ndarray, corners: np.ndarray
) -> np.ndarray:
    """``values[corners]`` (an index per corner of ``faces``) as one value per vertex (zeros for a
    vertex no face uses); ValueError naming the first vertex whose corners have two."""
    if corners is faces and len(values) == vertex_count:  # indexed by vertex already (frame_layout's)
        return values
    corner_values = values[corners].reshape(faces.size, -1)
    per_vertex = np.zeros((vertex_count, corner_values.shape[1]), np.float32)
    per_vertex[faces.ravel()] = corner_values
    differing = np.flatnonzero(np.any(per_vertex[faces.ravel()] != corner_values, axis=1))
    if differing.size:
        vertex = int(faces.ravel()[differing[0]])
        raise ValueError(f"{os.fspath(path)}: {name}: vertex {vertex} has two values at its corners, and a PLY file "
                         "holds one per vertex")  # fmt: skip
    return per_vertex
