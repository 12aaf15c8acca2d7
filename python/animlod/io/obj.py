"""Wavefront OBJ geometry: ``v`` and ``f`` lines read (1-based or negative indices, ``a/b/c``
corners, polygons fan-triangulated, ``#`` comments also at a line's end, a statement continued
on the next line after a ``\\`` that ends its line; with :func:`read_obj_textured` also ``vt``
and ``vn`` lines and the corners' indices into them, and colours (``v x y z r g b``); other
statements such as ``g``, ``usemtl`` are ignored, with a warning for unread ``vt``, ``vn`` and
``usemtl`` and for faces in several objects or groups (``o``, ``g``); statements may be
indented) and written, with texture coordinates, normals and colours where given. Parsing works
on the whole file's bytes with numpy: there is no Python loop over lines, vertices or faces. A
sequence's later frames that repeat the first frame's statements but for their ``v`` lines are
read from those alone (:class:`ObjTemplate`)."""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._core import decimal_rows
from .atomic import atomic_write
from .errors import FormatError, UnreadAttributesWarning
from .polygon_mesh import (
    all_finite,
    check_face_indices,
    check_finite_vertices,
    checked_for_writing,
    fan_triangulate,
    parse_numbers,
    polygon_mask,
    polygon_of_triangle,
)
from .tokens import parse_all, token_starts, tokens_per_line
from .vertex_colours import OBJ_COLOUR_NAMES, VertexColours


class ObjTexture(NamedTuple):
    """An OBJ mesh's texture coordinates: ``uvs (T, 2) float32``, the ``vt`` lines' u and v (v 0
    where a line gives u alone), and ``corners (M, 3) int32``, each triangle corner's index into
    ``uvs`` (the triangles of the faces, in their order)."""

    uvs: np.ndarray
    corners: np.ndarray


class ObjMaterials(NamedTuple):
    """An OBJ mesh's materials: ``libraries``, what its ``mtllib`` lines name (as written);
    ``names``, the materials its ``usemtl`` lines set; ``faces (M,) int32``, each triangle's
    index into ``names`` (-1 before the first ``usemtl``)."""

    libraries: tuple[str, ...]
    names: tuple[str, ...]
    faces: np.ndarray


class ObjNormals(NamedTuple):
    """An OBJ mesh's normals: ``normals (N, 3) float32``, the ``vn`` lines, and ``corners (M, 3)
    int32``, each triangle corner's index into ``normals``."""

    normals: np.ndarray
    corners: np.ndarray


class TexturedMesh(NamedTuple):
    """A mesh file with what :func:`read_obj_textured` (and ``meshseq.read_mesh_textured``) reads
    beside its geometry, each None where the file has none."""

    vertices: np.ndarray
    faces: np.ndarray
    texture: ObjTexture | None
    normals: ObjNormals | None
    colours: VertexColours | None
    materials: ObjMaterials | None


def read_obj(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read the ``v`` and ``f`` lines of a Wavefront OBJ file.

    Returns ``vertices (V, 3) float32`` (extra values such as w or colours are dropped) and
    ``faces (M, 3) int32``, 0-based, polygons fan-triangulated in file order.

    A backslash that ends a line (spaces or tabs may follow it) continues the statement on the
    next line, as the OBJ specification allows; errors name the line the statement starts on. A
    ``#`` comment ends at its line's end, even after a backslash (a Windows path such as
    ``# saved to C:\\models\\`` does not swallow the next statement).
    A UTF-8 byte order mark at the file's start is skipped; after a UTF-16 one the file is read as
    UTF-16.

    Raises
    ------
    FormatError
        Naming the line and vertex or face for a malformed or non-finite coordinate, a face
        index outside the vertices defined so far, or faces that all have fewer than three
        corners (some such faces among polygons are left out with a warning).
    """
    mesh, _ = _read_obj(path, textured=False)
    return mesh.vertices, mesh.faces


def read_obj_textured(path: str | os.PathLike, normals: bool = True) -> TexturedMesh:
    """:func:`read_obj` with the texture coordinates, normals, colours and materials: also the
    ``vt`` lines and each corner's texture index (``v/vt`` or ``v/vt/vn``), and the ``vn`` lines and each
    corner's normal index (``v/vt/vn`` or ``v//vn``); each None where the file has none, or where
    some corners have one and others not (with an :class:`UnreadAttributesWarning`). FormatError
    also names a malformed ``vt`` or ``vn`` line and an index outside them. ``normals=False``
    leaves the ``vn`` lines unread, without a warning (a sequence's later frames, whose normals
    the levels do not take). Where every ``v`` line has six values (or every one seven), those
    after z are the vertex's colour (r, g, b, a); None otherwise, or, with a warning, where only
    some lines have one or one is not finite. The
    ``usemtl`` lines give each triangle its material (:class:`ObjMaterials`, with the ``mtllib``
    lines' libraries)."""
    return _read_obj(path, textured=True, normals=normals)[0]


def read_obj_template(path: str | os.PathLike, textured: bool) -> tuple[TexturedMesh, ObjTemplate | None]:
    """The first frame of a sequence: :func:`read_obj` (``textured`` False, the geometry alone) or
    :func:`read_obj_textured` (with normals), and the file as the template its later frames are
    read by (:meth:`ObjTemplate.read`); None where it has faces of fewer than three corners, whose
    warning every frame gives."""
    return _read_obj(path, textured, normals=textured)


class _Statements(NamedTuple):
    """Which lines of an OBJ file's text (:class:`_ObjLines`) hold each statement read, (L,) bool
    each."""

    v: np.ndarray
    f: np.ndarray
    l: np.ndarray  # noqa: E741 (the statement's name)
    vt: np.ndarray
    vn: np.ndarray
    mtllib: np.ndarray


@dataclass(frozen=True, eq=False)
class ObjTemplate:
    """An OBJ file read as the first frame of a sequence (:func:`read_obj_template`), by which a
    later frame is read from its ``v`` lines alone where its other lines are this file's byte for
    byte (comments, continuations and indents taken out) and its ``v``, ``vn`` and ``mtllib``
    lines stand where this file's do (so that a message names the line as a full read would):
    exporters write every frame's faces, texture coordinates and materials alike, and Blender a
    material library of each frame's own name."""

    textured: bool
    lines: _ObjLines
    statements: _Statements
    mesh: TexturedMesh  # its faces, texture coordinates and materials are every fitting frame's

    @cached_property
    def _kept(self) -> np.ndarray:
        """(L,) bool: the lines a later frame repeats byte for byte: all but its own (``v``),
        those a sequence's later frames leave unread (``vn``) and those read from each frame
        (``mtllib``)."""
        return ~(self.statements.v | self.statements.vn | self.statements.mtllib)

    @cached_property
    def _kept_bytes(self) -> bytes:
        """This file's kept lines, one after another: a fitting frame's are these bytes."""
        return self.lines.block(self._kept)

    def fits(self, lines: _ObjLines, statements: _Statements) -> bool:
        """Whether a later frame's ``lines`` (holding ``statements``) read as this file's but for
        their ``v``, ``vn`` and ``mtllib`` lines, which stand where this file's do: one bytes
        comparison, no parse."""
        mine = self.statements
        return (all(np.array_equal(getattr(statements, tag), getattr(mine, tag)) for tag in ("v", "vn", "mtllib"))
                and lines.block(self._kept) == self._kept_bytes)  # fmt: skip

    def read(self, path: str | os.PathLike) -> tuple[TexturedMesh, ObjTemplate]:
        """A later frame of the sequence, as :func:`read_obj` (``textured`` False, in a
        TexturedMesh) or :func:`read_obj_textured` with ``normals=False`` read it, errors and
        warnings alike: from its ``v`` (and ``mtllib``) lines alone, with this file's faces, texture
        coordinates and materials, where it :meth:`fits`; by a full read otherwise. Also the
        template to read the next frame by: this one where the frame fits, else the frame itself
        (a rest pose first, whose normals Blender merges into fewer ``vn`` lines, then frames
        alike), but this one where the frame has faces of fewer than three corners and so makes no
        template (:func:`read_obj_template`)."""
        mesh, template = _read_obj(path, self.textured, template=self)
        return mesh, template or self


def _read_obj(
    path: str | os.PathLike, textured: bool, normals: bool = False, template: ObjTemplate | None = None
) -> tuple[TexturedMesh, ObjTemplate | None]:
    """:func:`read_obj`, and with ``textured`` its texture coordinates, colours, materials and,
    with ``normals``, its normals (:func:`read_obj_textured`); and the file as a template
    (:func:`read_obj_template`). Where ``template`` fits the file, its ``v`` lines alone are read
    (:meth:`ObjTemplate.read`)."""
    path = Path(path)
    lines = _obj_lines(path)
    statements = _Statements(*(lines.tagged(tag) for tag in (b"v", b"f", b"l", b"vt", b"vn", b"mtllib")))
    reused = template is not None and template.fits(lines, statements)
    vertex_lines, face_lines, polylines = (np.flatnonzero(selected) + 1 for selected in statements[:3])
    vertex_block = lines.block(statements.v)
    values_per_vertex = _row_sizes(vertex_block, len(vertex_lines))
    _warn_unread_attributes(path, vt=not textured and bool(statements.vt.any()),
                            vn=not textured and bool(statements.vn.any()),
                            colours=not textured and bool(np.any(values_per_vertex >= 6)),
                            usemtl=not textured and bool(lines.tagged(b"usemtl").any()))  # fmt: skip
    if not len(vertex_lines):
        _require_obj_statement(path, lines.data)
    if not len(face_lines) and len(polylines):  # Inkscape's axes, OpenFOAM's edge curves
        reason = f"{len(polylines)} polylines ('l') and no face: animlod simplifies surfaces"
        raise FormatError(path, f"line {polylines[0]}", reason)

    def name_vertex(vertex: int) -> str:
        return f"vertex {vertex} (line {vertex_lines[vertex]})"

    channels = _colour_channels(path, values_per_vertex) if textured else 0
    values = _vertex_values(path, vertex_block, values_per_vertex, channels, name_vertex)
    channels = values.shape[1] - 3  # 0 where a colour did not parse
    vertices = values[:, :3].astype(np.float32)
    check_finite_vertices(path, vertices, name_vertex)
    colours = None
    if channels:
        rows = all_finite(path, values[:, 3:].astype(np.float32), "colours", name_vertex)
        colours = None if rows is None else VertexColours(rows[None], OBJ_COLOUR_NAMES[:channels], ("f4",) * channels)
    if reused:
        materials = template.mesh.materials
        if materials is not None:  # the file may name a library of its own (Blender: one per frame)
            materials = materials._replace(libraries=_libraries(lines, statements.mtllib))
        return template.mesh._replace(vertices=vertices, normals=None, colours=colours, materials=materials), template

    def name_face(face: int) -> str:
        return f"face {face} (line {face_lines[face]})"

    face_block = lines.block(statements.f)
    sizes = _row_sizes(face_block, len(face_lines))
    uniform = _uniform_corners(face_block, sizes)
    vertex_numbers = face_block if uniform is None else uniform[:, 0]
    if uniform is None and b"/" in face_block:
        vertex_numbers = _vertex_numbers(face_block)
        sizes = _row_sizes(vertex_numbers, len(face_lines))
    polygons = sizes >= 3  # pybullet's samurai_monastry.obj has 201 faces of two vertices among its 125k
    if sizes.size:
        first = int(np.argmin(polygons))  # the first face of fewer than 3 vertices, named in the warning
        refusal = f"needs at least 3 vertices, has {sizes[first]}; so does every face"
        polygons = polygon_mask(path, sizes, name_face(first), refusal)
    owner = np.repeat(np.arange(sizes.size), sizes)
    corners = _FaceCorners(path, face_block, sizes, owner, face_lines, name_face, uniform)
    resolved = corners.resolved(vertex_numbers, vertex_lines, len(vertices), ("vertex", "vertices"))
    faces = fan_triangulate(resolved[polygons[owner]], sizes[polygons])
    _warn_unread_names(path, lines, face_lines)
    mesh = TexturedMesh(vertices, faces, None, None, None, None)
    if textured:

        def per_triangle(selected: np.ndarray, attribute: _Attribute) -> tuple | None:
            """The attribute's values and each triangle corner's index into them, or None."""
            if not selected.any():
                return None
            found = _corner_attribute(path, attribute, lines.block(selected), np.flatnonzero(selected) + 1, corners)
            return found and (found[0], fan_triangulate(found[1][polygons[owner]], sizes[polygons]))

        texture = per_triangle(statements.vt, _TEXTURE)
        corner_normals = per_triangle(statements.vn, _NORMALS) if normals else None
        materials = _materials(lines, statements.mtllib, face_lines[polygons], sizes[polygons] - 2)
        mesh = TexturedMesh(vertices, faces, texture and ObjTexture(*texture),
                            corner_normals and ObjNormals(*corner_normals), colours, materials)  # fmt: skip
    return mesh, ObjTemplate(textured, lines, statements, mesh) if polygons.all() else None


def face_of_triangle(path: str | os.PathLike, triangle: int) -> str:
    """The face (and its line) that triangle ``triangle`` of :func:`read_obj`'s faces comes from,
    named as the reader's errors name faces: for a fault found in the triangles after the file was
    read."""
    lines = _obj_lines(Path(path))
    selected = lines.tagged(b"f")
    face_lines = np.flatnonzero(selected) + 1
    face = polygon_of_triangle(_row_sizes(_vertex_numbers(lines.block(selected)), len(face_lines)), triangle)
    return f"face {face} (line {face_lines[face]})"


def _vertex_numbers(face_block: bytes) -> bytes:
    """Face lines with each corner's ``/vt/vn`` dropped: its vertex number alone."""
    return re.sub(rb"/\S*", b"", face_block)


def _obj_lines(path: Path) -> _ObjLines:
    """The lines of the OBJ file at ``path`` as its statements are read (:func:`_obj_text`), and
    not indented: an indented statement still counts; line numbers stay."""
    lines = _ObjLines(_obj_text(path))
    if _IS_BLANK[lines.codes[lines.starts]].any():
        lines = _ObjLines(re.sub(rb"(?m)^[ \t]+", b"", lines.data))
    return lines


def _obj_text(path: Path) -> bytes:
    """The text of the OBJ file at ``path``: UTF-8 (a UTF-16 file converted), LF line ends,
    without comments and continuations, every statement on the line it starts on."""
    data = path.read_bytes()
    if data.startswith((b"\xfe\xff", b"\xff\xfe")):  # UTF-16 after its byte order mark (assimp's box_UTF16BE.obj)
        try:
            data = data.decode("utf-16").encode("utf-8")
        except UnicodeDecodeError as error:
            raise FormatError(path, f"byte {error.start}", "not UTF-16 text after its byte order mark") from None
    nul = data.find(b"\0")
    if nul >= 0:
        raise FormatError(path, f"byte {nul}", "NUL byte: an OBJ file is text, this looks like binary data")
    if data.startswith(b"\xef\xbb\xbf"):  # a UTF-8 byte order mark (.NET, Notepad) before the first statement
        data = data[3:]
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    if b"#" in data:  # a comment may also end a statement ("f 1 2 3 # cap"); line numbers stay
        data = re.sub(rb"#[^\n]*", b"", data)
    if b"\\" in data:
        data = _join_continued_lines(data)
    return data


def _materials(
    lines: _ObjLines, mtllib: np.ndarray, face_lines: np.ndarray, triangles: np.ndarray
) -> ObjMaterials | None:
    """The materials of the usemtl lines for the faces on ``face_lines`` (1-based), each fanned
    into ``triangles``; the libraries of the ``mtllib`` lines. None without a usemtl line."""
    named = _names_in_effect(lines, b"usemtl", face_lines)
    if named is None:
        return None
    names, in_effect = named
    used = np.array([name.decode("utf-8", "replace") for name in names], dtype=object)
    distinct, first, material = np.unique(used, return_index=True, return_inverse=True)
    order = np.argsort(first)  # the materials in the order of first use
    rank = np.empty(first.size, np.int32)
    rank[order] = np.arange(first.size)
    per_face = np.where(in_effect >= 0, rank[material.ravel()][np.maximum(in_effect, 0)], -1).astype(np.int32)
    return ObjMaterials(_libraries(lines, mtllib), tuple(distinct[order].tolist()), np.repeat(per_face, triangles))


def _libraries(lines: _ObjLines, mtllib: np.ndarray) -> tuple[str, ...]:
    """The material libraries the ``mtllib`` lines name, as written."""
    return tuple(found.decode("utf-8", "replace").strip() for found in lines.names(mtllib, len(b"mtllib")))


def _colour_channels(path: Path, sizes: np.ndarray) -> int:
    """How many colour channels the ``v`` lines (``sizes`` values each) hold after x, y, z: 3
    where every line has six values, 4 where every one has seven; 0 where no line has six or
    more, and, with a warning, where only some lines have them or every one has more."""
    if not sizes.size or sizes.max() < 6:
        return 0
    if np.any(sizes != sizes[0]):
        reason = f"{np.count_nonzero(sizes >= 6)} of its {sizes.size} v lines have more than x, y, z, others not"
    elif sizes[0] - 3 not in (3, 4):
        reason = f"its v lines have {sizes[0]} values, not x, y, z and r, g, b (and a)"
    else:
        return int(sizes[0]) - 3
    _warn_unread_colours(path, reason)
    return 0


def _vertex_values(
    path: Path, block: bytes, sizes: np.ndarray, channels: int, name_vertex: Callable[[int], str]
) -> np.ndarray:
    """(V, 3 + channels) float64: each ``v`` line's x, y, z and its ``channels`` colour values
    (``sizes`` values each), in one parse. A coordinate that does not parse is a FormatError as
    ever; a colour value that does not parse costs only the colours (a warning), and gives (V, 3)."""
    try:
        return _leading_values(path, block, sizes, 3 + channels, 3, name_vertex, "coordinates")
    except FormatError as error:
        if not channels:
            raise
        coordinates = _leading_values(path, block, sizes, 3, 3, name_vertex, "coordinates")  # raises for theirs
        _warn_unread_colours(path, str(error).removeprefix(f"{path}: "))
        return coordinates


def _warn_unread_colours(path: Path, reason: str) -> None:
    warnings.warn(f"{path}: {reason}: its colours are not read, and the levels are written without them",
                  UnreadAttributesWarning, stacklevel=5)  # fmt: skip


@dataclass(frozen=True)
class _FaceCorners:
    """The corners of an OBJ file's ``f`` lines (``block``, as written): ``sizes`` per face,
    ``owner`` the face of each corner, the faces' ``lines``, how messages name a face, and
    ``uniform``, every corner's numbers where all are written alike (:func:`_uniform_corners`)."""

    path: Path
    block: bytes
    sizes: np.ndarray
    owner: np.ndarray
    lines: np.ndarray
    name_face: Callable[[int], str]
    uniform: np.ndarray | None

    def field(self, field: int) -> tuple[bytes | np.ndarray, int]:
        """The corners' numbers in their ``field`` (1: vt, 2: vn) for :meth:`resolved`, and how
        many corners have one: ``uniform``'s, or the ``f`` lines with each corner cut to the field
        (:func:`_corner_field`), parsed once the attribute's own lines are read."""
        if self.uniform is None:
            return _corner_field(self.block, field)
        if field >= self.uniform.shape[1]:
            return b"", 0
        return self.uniform[:, field], len(self.owner)

    def resolved(
        self, numbers: bytes | np.ndarray, item_lines: np.ndarray, count: int, indexed: tuple[str, str]
    ) -> np.ndarray:
        """Every corner's 0-based index into the ``count`` items defined on ``item_lines`` (v, vt
        or vn lines), from ``numbers``, one per corner, or the ``f`` lines holding one number per
        corner: negative indices count back from the last item defined above the face's line.
        FormatError names the face of a corner that does not parse or lies outside the items."""
        written = numbers if isinstance(numbers, np.ndarray) else _untagged_values(numbers, np.int64, self.sizes)
        if written is None:
            tokens, starts = _row_tokens(numbers, self.sizes)
            written = parse_numbers(self.path, np.delete(tokens, starts), np.int64,
                                    lambda corner: self.name_face(self.owner[corner]))  # fmt: skip
        defined = np.searchsorted(item_lines, self.lines)[self.owner]
        resolved = np.where(written > 0, written - 1, np.where(written < 0, defined + written, -1))
        check_face_indices(self.path, resolved, written, self.owner, count, self.name_face, indexed)
        return resolved


class _Attribute(NamedTuple):
    """A per-corner attribute of the ``f`` lines: the ``field`` of a corner it is indexed by (1:
    vt, 2: vn), the values its lines give (``width``, of which ``minimum`` are required) and its
    names in messages."""

    tag: str
    field: int
    width: int
    minimum: int
    item: str  # one line's values, in "texture coordinate 3 (line 9)"
    items: tuple[str, str]  # the index's and the lines' names, in "texture index ... outside the texture coordinates"
    kind: str  # in "12 of 40 face corners have texture coordinates (vt)"


_TEXTURE = _Attribute("vt", 1, 2, 1, "texture coordinate", ("texture", "texture coordinates"), "texture coordinates")
_NORMALS = _Attribute("vn", 2, 3, 3, "normal", ("normal", "normals"), "normals")


def _corner_attribute(
    path: Path, attribute: _Attribute, block: bytes, lines: np.ndarray, corners: _FaceCorners
) -> tuple[np.ndarray, np.ndarray] | None:
    """The ``attribute``'s lines (``block``: u and v of ``vt``, a w dropped; x, y, z of ``vn``) as
    float32, and every face corner's 0-based index into them; None, with a warning, where some
    corners have an index and others none."""
    index_numbers, indexed = corners.field(attribute.field)
    if indexed < corners.sizes.sum():
        if indexed:
            warnings.warn(f"{path}: {indexed} of {corners.sizes.sum()} face corners have {attribute.kind} "
                          f"({attribute.tag}), the others none: read without them", UnreadAttributesWarning,
                          stacklevel=4)  # fmt: skip
        return None

    def name_row(row: int) -> str:
        return f"{attribute.item} {row} (line {lines[row]})"

    sizes = _row_sizes(block, len(lines))
    values = _leading_values(path, block, sizes, attribute.width, attribute.minimum, name_row, "values")
    check_finite_vertices(path, values.astype(np.float32), name_row)
    return values.astype(np.float32), corners.resolved(index_numbers, lines, len(values), attribute.items)


def write_obj(
    path: str | os.PathLike,
    vertices: np.ndarray,
    faces: np.ndarray,
    texture: ObjTexture | None = None,
    normals: ObjNormals | None = None,
    colours: VertexColours | None = None,
    materials: ObjMaterials | None = None,
    shared: ObjSharedText | None = None,
) -> ObjSharedText:
    """Write ``vertices (V, 3)`` and ``faces (M, 3)`` as OBJ ``v``/``f`` lines, atomically; with
    ``texture`` also its ``vt`` lines, with ``normals`` its ``vn`` lines, and each corner's
    indices into them (``v/vt``, ``v//vn`` or ``v/vt/vn``); with one frame's ``colours`` (three
    or four channels) each ``v`` line's r, g, b (a) after its x, y, z; with ``materials`` (one
    per face) its ``mtllib`` lines, and the faces in runs of one material, each after its
    ``usemtl`` line (the faces of none first).

    Returns the text the file shares with other frames of its sequence (:class:`ObjSharedText`);
    given as ``shared`` to the next frame's call, it is written again without being formatted
    anew where that frame has the same ``faces``, ``texture`` and ``materials`` objects and its
    normals the same corner indices.

    Coordinates are written with 9 significant digits, which round-trips float32 exactly. A wrong
    shape, a coordinate that is not finite as float32 or a face index outside the vertices is a
    ValueError naming the file and the argument (``vertices``, ``faces``, ``texture``,
    ``normals`` or ``colours``); nothing is written.
    """
    vertices, checked_faces = checked_for_writing(path, vertices, faces)
    vertices = vertices.astype(np.float64)
    uvs, uv_corners = _checked_attribute(path, "texture", texture, 2, checked_faces.shape)
    normal_values, normal_corners = _checked_attribute(path, "normals", normals, 3, checked_faces.shape)
    if colours is not None:
        if len(colours.names) not in (3, 4):
            raise ValueError(f"{os.fspath(path)}: colours: an OBJ v line holds r, g, b and perhaps a, got "
                             f"{', '.join(colours.names)}")  # fmt: skip
        vertices = np.concatenate([vertices, np.stack(colours.stored(path, len(vertices)), axis=1)], axis=1)
    if shared is None or not shared.fits(faces, texture, materials, normal_corners):
        shared = ObjSharedText.made(path, faces, checked_faces, texture, uvs, uv_corners, normal_corners, materials)
    with atomic_write(path, "wb") as handle:
        handle.write(b"# written by animlod\n" + shared.header)
        handle.write(decimal_rows(vertices, "v "))
        handle.write(shared.uv_lines)
        if normal_values is not None:
            handle.write(decimal_rows(normal_values, "vn "))
        handle.write(shared.face_lines)
    return shared


def _checked_attribute(
    path: str | os.PathLike, name: str, attribute: ObjTexture | ObjNormals | None, width: int, shape: tuple
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """A texture's or normals' values (N, ``width``) as float64 and their corner indices (``shape``,
    the faces') as int64; ValueError naming the file and ``name`` where they do not fit. None and
    None without the attribute."""
    if attribute is None:
        return None, None
    values, indices = np.asarray(attribute[0], dtype=np.float64), np.asarray(attribute[1])
    fits = values.ndim == 2 and values.shape[1] == width and np.isfinite(values).all()
    fits = fits and indices.shape == shape and (not indices.size or 0 <= indices.min() <= indices.max())
    if not fits or indices.size and indices.max() >= len(values):
        raise ValueError(f"{os.fspath(path)}: {name}: expected finite values (N, {width}) and a (M, 3) "
                         f"corner index into them per face, got {values.shape} and {indices.shape}")  # fmt: skip
    return values, indices.astype(np.int64)


@dataclass(frozen=True, eq=False)
class ObjSharedText:
    """The text of an OBJ file that the other frames of its sequence repeat, formatted once
    (:func:`write_obj`): the ``mtllib`` lines (``header``), the ``vt`` lines and the faces (each
    run of one material after its ``usemtl`` line), made for the ``faces``, ``texture`` and
    ``materials`` objects and the normals' corner indices it holds."""

    faces: np.ndarray
    texture: ObjTexture | None
    materials: ObjMaterials | None
    normal_corners: np.ndarray | None
    header: bytes
    uv_lines: bytes
    face_lines: bytes

    def fits(
        self,
        faces: np.ndarray,
        texture: ObjTexture | None,
        materials: ObjMaterials | None,
        normal_corners: np.ndarray | None,
    ) -> bool:
        """Whether a frame of these objects, its normals with these corner indices, shares this text."""
        same_normals = (normal_corners is None) == (self.normal_corners is None) and (
            normal_corners is None or np.array_equal(normal_corners, self.normal_corners)
        )
        return faces is self.faces and texture is self.texture and materials is self.materials and same_normals

    @classmethod
    def made(
        cls,
        path: str | os.PathLike,
        faces: np.ndarray,
        checked_faces: np.ndarray,
        texture: ObjTexture | None,
        uvs: np.ndarray | None,
        uv_corners: np.ndarray | None,
        normal_corners: np.ndarray | None,
        materials: ObjMaterials | None,
    ) -> ObjSharedText:
        """The text of ``checked_faces`` (the ``faces`` object, checked) with the ``texture``'s
        values ``uvs`` and ``uv_corners``, the normals' corners and the ``materials``."""
        columns = [checked_faces.astype(np.int64) + 1] + [c + 1 for c in (uv_corners, normal_corners) if c is not None]
        corner = "%d" + ("/%d" if uv_corners is not None else "/" if normal_corners is not None else "")
        corner += "/%d" if normal_corners is not None else ""  # v//vn where there is no texture
        corners = np.stack(columns, axis=2).reshape(len(checked_faces), -1)
        runs, header = [(None, corners)], ""
        if materials is not None:
            if np.shape(materials.faces) != (len(checked_faces),) or np.any(materials.faces >= len(materials.names)):
                raise ValueError(f"{os.fspath(path)}: materials: expected a material (< {len(materials.names)}) "
                                 f"per face, got {np.shape(materials.faces)}")  # fmt: skip
            order = np.argsort(materials.faces, kind="stable")
            starts = np.flatnonzero(np.diff(materials.faces[order], prepend=-2))
            runs = [(materials.faces[order[start]], corners[order[start:end]])
                    for start, end in zip(starts, [*starts[1:], len(order)])]  # fmt: skip
            header = "".join(f"mtllib {library}\n" for library in materials.libraries)
        face_line = f"f {corner} {corner} {corner}\n"
        face_lines = "".join(
            (f"usemtl {materials.names[material]}\n" if material is not None and material >= 0 else "")
            + (face_line * len(run)) % tuple(run.ravel().tolist())
            for material, run in runs
        )
        uv_lines = b"" if uvs is None else decimal_rows(uvs, "vt ")
        return cls(faces, texture, materials, normal_corners, header.encode(), uv_lines, face_lines.encode())


# The statements of the OBJ specification (Appendix B1), geometry and grouping and display alike.
_OBJ_KEYWORDS = frozenset(
    b"v vt vn vp f l p o g s mg usemtl mtllib maplib usemap cstype deg bmat step curv curv2 surf parm "
    b"trim hole scrv sp end con bevel c_interp d_interp lod shadow_obj trace_obj ctech stech".split()
)


def _require_obj_statement(path: Path, data: bytes) -> None:
    """A file with no vertex whose first statement is no OBJ keyword is another format's text (a
    game's level map named .obj): say so, rather than that the mesh is empty."""
    for number, line in enumerate(data.split(b"\n"), start=1):
        words = line.split()
        if words and words[0] not in _OBJ_KEYWORDS:
            shown = words[0][:20].decode("utf-8", "replace")
            raise FormatError(path, f"line {number}", f"{shown!r} is not an OBJ statement: not a Wavefront OBJ file?")
        if words:
            return


def _join_continued_lines(data: bytes) -> bytes:
    """``data`` (LF line ends, no NUL byte) with every line that ends in a backslash joined to the
    next one. The newlines taken out are put back after the joined statement, as empty lines, so
    each statement keeps the number of the line it starts on and later lines keep theirs."""
    # Mark each continuation with a NUL (the file has none, it was checked): the usual "\\\n" by
    # bytes.replace, then those with spaces after the backslash, or ending the file, by a regex.
    data = data.replace(b"\\\n", b"\0")
    if b"\\" in data:
        data = re.sub(rb"\\[ \t]*(?:\n|\Z)", b"\0", data)
    codes = np.frombuffer(data, dtype=np.uint8)
    marks = np.flatnonzero(codes == 0)
    if not marks.size:
        return data
    newlines = np.flatnonzero(codes == ord("\n"))
    marks_before = np.searchsorted(marks, newlines)
    # A statement's end takes one newline more for each continuation since the newline before it.
    at = np.repeat(newlines + 1, np.diff(marks_before, prepend=0))
    joined = np.insert(codes, at, ord("\n"))
    joined[joined == 0] = ord(" ")
    tail = marks.size - (int(marks_before[-1]) if newlines.size else 0)  # continued into the file's end
    return joined.tobytes() + b"\n" * tail


def _corner_field(face_block: bytes, field: int) -> tuple[bytes, int]:
    """``face_block`` (``f`` lines, tags first) with each corner cut to its ``field`` (1: vt of
    ``v/vt/vn`` or ``v/vt``, the bytes after its first slash up to the next; 2: vn of ``v/vt/vn``
    or ``v//vn``, after the second), and how many corners have one."""
    codes = np.frombuffer(face_block, dtype=np.uint8)
    separator = np.isin(codes, np.frombuffer(b" \t\n", dtype=np.uint8))
    slash = codes == ord("/")
    slashes = np.cumsum(slash)
    in_corner = slashes - np.maximum.accumulate(np.where(separator, slashes, 0))  # slashes so far in its word
    index_follows = ~np.append(separator[1:] | slash[1:], True)  # "1/2": an index after the slash
    indexed = int(np.count_nonzero(slash & (in_corner == field) & index_follows))
    line_start = np.append(True, codes[:-1] == ord("\n"))
    keep = separator | line_start | ((in_corner == field) & ~slash)
    return codes[keep].tobytes(), indexed


def _uniform_corners(block: bytes, sizes: np.ndarray) -> np.ndarray | None:
    """(C, F) int64: the numbers each of the C corners of ``block`` (``f`` lines of ``sizes``
    corners, as written) holds, where every corner is written alike, F numbers parted by single
    slashes (``v/vt/vn``: F = 3; ``v``: F = 1), as exporters write them: one parse for all.
    None otherwise (``v//vn``, corners written differently, a number that does not parse, a
    vertical tab or form feed, which the fields' own reading parts otherwise), for
    :func:`_corner_field` to read or name field by field."""
    corners = int(sizes.sum())
    slashes = np.flatnonzero(np.frombuffer(block, dtype=np.uint8) == ord("/"))
    if not corners or slashes.size % corners or b"\x0b" in block or b"\x0c" in block:
        return None
    fields = slashes.size // corners + 1
    starts = token_starts(block)  # each face's tag, then its corners
    expected = np.full(starts.size, fields - 1)
    expected[np.cumsum(sizes + 1) - (sizes + 1)] = 0
    if not np.array_equal(np.diff(np.searchsorted(slashes, starts), append=slashes.size), expected):
        return None
    values = _untagged_values(block.replace(b"/", b" "), np.int64, sizes * fields)  # an empty field: too few
    return None if values is None else values.reshape(corners, fields)


def _warn_unread_attributes(path: Path, **unread_tags: bool) -> None:
    """Says that the file's ``vt`` or ``vn`` lines, the colours of its ``v`` lines or its
    materials (``usemtl`` lines), where flagged, are not read, so that levels written without
    them are no silent loss."""
    unread = [tag for tag, flagged in unread_tags.items() if flagged]
    if unread:
        kinds = {"vt": "texture coordinates (vt lines)", "vn": "normals (vn lines)", "colours": "colours (on v lines)",
                 "usemtl": "materials (usemtl lines)"}  # fmt: skip
        warnings.warn(f"{path}: its {' and '.join(kinds[tag] for tag in unread)} are not read, and the levels are "
                      "written without them", UnreadAttributesWarning, stacklevel=4)  # fmt: skip


def _warn_unread_names(path: Path, lines: _ObjLines, face_lines: np.ndarray) -> None:
    """Says that the faces of ``lines`` (on ``face_lines``, 1-based) fall into several objects or
    groups (the names of its ``o`` or ``g`` lines above them), which the mesh read does not keep
    apart: three objects become one unnamed mesh. Faces under one name alone (an exporter's
    ``o Cube`` for a file of one object) lose only the name, with no warning: the levels are
    named after the file."""
    if not len(face_lines):
        return
    counts = {}
    for tag, kind in ((b"o", "object"), (b"g", "group")):
        named = _names_in_effect(lines, tag, face_lines)
        if named is None:
            continue
        names, in_effect = named
        distinct = {names[index] for index in np.unique(in_effect[in_effect >= 0])}
        if len(distinct) > 1:
            counts[kind] = len(distinct)
    if counts:
        said = " and ".join(f"{count} {kind}s ({kind[0]} lines)" for kind, count in counts.items())
        warnings.warn(f"{path}: its faces fall into {said}, whose names are not read: the levels are written "
                      "as one mesh without them", UnreadAttributesWarning, stacklevel=4)  # fmt: skip


def _names_in_effect(lines: _ObjLines, tag: bytes, face_lines: np.ndarray) -> tuple[list[bytes], np.ndarray] | None:
    """The names on the ``tag`` lines (``usemtl``, ``o``, ``g``), and for each face on
    ``face_lines`` (1-based) the index of the last of those lines above it, -1 above the first;
    None where no line has the tag."""
    selected = lines.tagged(tag)
    if not selected.any():
        return None
    return lines.names(selected, len(tag)), np.searchsorted(np.flatnonzero(selected) + 1, face_lines) - 1


class _ObjLines:
    """The lines of an OBJ file's text (:func:`_obj_lines`): where each starts and how long it is
    (its newline included), so that statements are found by their first bytes alone, not by a
    scan of the whole text per statement."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.codes = np.frombuffer(data + b"\n" * 8, dtype=np.uint8)  # the last line's first 8 bytes, padded
        self.starts = np.concatenate(([0], np.flatnonzero(self.codes[: len(data)] == ord("\n")) + 1))
        self.lengths = np.diff(self.starts, append=len(data))
        # Each line's first 8 bytes as one number (those of the next line, or line ends, after a
        # short one): a tag is found by a comparison per line, not one per letter.
        self.heads = self.codes[self.starts[:, None] + np.arange(8)].view("<u8").ravel()

    def tagged(self, tag: bytes) -> np.ndarray:
        """(L,) bool: the lines that hold a ``tag`` statement (the tag, of up to 7 letters, then a
        space or a tab)."""
        mask = (1 << 8 * (len(tag) + 1)) - 1
        key = self.heads & np.uint64(mask)
        return (key == int.from_bytes(tag + b" ", "little")) | (key == int.from_bytes(tag + b"\t", "little"))

    def block(self, selected: np.ndarray) -> bytes:
        """The ``selected`` lines, one after another as in the text."""
        return self.codes[: len(self.data)][np.repeat(selected, self.lengths)].tobytes()

    def names(self, selected: np.ndarray, tag_length: int) -> list[bytes]:
        """What follows the tag on each ``selected`` line, white space stripped (a name or path)."""
        return [self.data[start + tag_length : start + length].strip()
                for start, length in zip(self.starts[selected].tolist(), self.lengths[selected].tolist())]  # fmt: skip


_IS_BLANK = np.zeros(256, dtype=bool)
_IS_BLANK[list(b" \t")] = True


def _leading_values(
    path: Path, block: bytes, sizes: np.ndarray, width: int, minimum: int, element: Callable[[int], str], what: str
) -> np.ndarray:
    """(L, width) float64: the first ``width`` values after the tag on each line of ``block``
    (``sizes`` values each, :func:`_row_sizes`), 0 where a line gives fewer (it must give
    ``minimum``); values past them are dropped unread. FormatError names the line (``element``)
    with too few values or a bad one."""
    _require_sizes(path, sizes, minimum, element, what)
    given = np.arange(width)[None] < sizes[:, None]
    values = _untagged_values(block, np.float64, sizes)
    if values is not None:
        first = np.cumsum(sizes) - sizes
        columns = values[np.where(given, first[:, None] + np.arange(width), 0)]
    else:  # find the bad one among the values read
        tokens, starts = _row_tokens(block, sizes)
        taken = tokens[np.where(given, starts[:, None] + 1 + np.arange(width), starts[:, None] + 1)]
        columns = parse_numbers(path, taken, np.float64, lambda token: element(token // width))
    return np.where(given, columns, 0.0)


def _row_sizes(block: bytes, line_count: int) -> np.ndarray:
    """The number of values after the tag on each of the ``line_count`` tag-led lines of ``block``.
    Rows are counted by line, not by tag token: ``v v 1 2`` is one row (whose "v" then fails to
    parse), not two."""
    return tokens_per_line(block)[:line_count] - 1


def _untagged_values(block: bytes, dtype: type, sizes: np.ndarray) -> np.ndarray | None:
    """Every value after the tags of ``block``'s lines (one tag for all: ``v``, ``vt``), in order,
    as ``dtype``; None when one does not parse (then :func:`_row_tokens` and
    :func:`parse_numbers` name it)."""
    codes = np.frombuffer(block, dtype=np.uint8).copy()
    starts = np.concatenate(([0], np.flatnonzero(codes[:-1] == ord("\n")) + 1))[: sizes.size]
    tag_length = len(block[:8].split(maxsplit=1)[0]) if block else 0
    codes[starts[:, None] + np.arange(tag_length)] = ord(" ")
    values = parse_all(codes.tobytes(), dtype)
    return values if values is not None and values.size == sizes.sum() else None


def _row_tokens(block: bytes, sizes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tokens of ``block`` and the index of each row's tag among them (rows of ``sizes`` values)."""
    counts = sizes + 1
    return np.array(block.split(), dtype=np.bytes_), np.cumsum(counts) - counts


def _require_sizes(path: Path, sizes: np.ndarray, minimum: int, element: Callable[[int], str], what: str) -> None:
    short = np.flatnonzero(sizes < minimum)
    if short.size:
        raise FormatError(path, element(short[0]), f"needs at least {minimum} {what}, has {sizes[short[0]]}")
