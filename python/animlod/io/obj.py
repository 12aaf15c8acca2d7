"""Wavefront OBJ geometry: ``v`` and ``f`` lines read (1-based or negative indices, ``a/b/c``
corners, polygons fan-triangulated, ``#`` comments also at a line's end, a statement continued
on the next line after a ``\\`` that ends its line; with :func:`read_obj_textured` also ``vt``
and ``vn`` lines and the corners' indices into them, and colours (``v x y z r g b``); other
statements such as ``g``, ``usemtl`` are ignored, with a warning for unread ``vt``, ``vn`` and
``usemtl`` and for faces in several objects or groups (``o``, ``g``); statements may be
indented) and written, with texture coordinates, normals and colours where given. Parsing works
on the whole file's bytes with numpy: there is no Python loop over lines, vertices or faces."""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

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
)
from .tokens import parse_all, tokens_per_line
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
    mesh = _read_obj(path, textured=False)
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
    return _read_obj(path, textured=True, normals=normals)


def _read_obj(path: str | os.PathLike, textured: bool, normals: bool = False) -> TexturedMesh:
    """:func:`read_obj`, and with ``textured`` its texture coordinates, colours, materials and,
    with ``normals``, its normals (:func:`read_obj_textured`)."""
    path = Path(path)
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
    data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    if b"#" in data:  # a comment may also end a statement ("f 1 2 3 # cap"); line numbers stay
        data = re.sub(rb"#[^\n]*", b"", data)
    if b"\\" in data:
        data = _join_continued_lines(data)
    if data.startswith((b" ", b"\t")) or b"\n " in data or b"\n\t" in data:
        data = re.sub(rb"(?m)^[ \t]+", b"", data)  # an indented statement still counts; line numbers stay
    statements = _obj_statements(data, (b"v", b"f", b"l", b"vt", b"vn"))
    (vertex_block, vertex_lines), (face_block, face_lines), (_, polylines), uv_statements, normal_statements = (
        statements
    )
    values_per_vertex = _row_sizes(vertex_block, len(vertex_lines))
    _warn_unread_attributes(path, vt=not textured and len(uv_statements[1]) > 0,
                            vn=not textured and len(normal_statements[1]) > 0,
                            colours=not textured and bool(np.any(values_per_vertex >= 6)),
                            usemtl=not textured and re.search(rb"(?m)^usemtl[ \t]", data) is not None)  # fmt: skip
    if not len(vertex_lines):
        _require_obj_statement(path, data)
    if not len(face_lines) and len(polylines):  # Inkscape's axes, OpenFOAM's edge curves
        reason = f"{len(polylines)} polylines ('l') and no face: animlod simplifies surfaces"
        raise FormatError(path, f"line {polylines[0]}", reason)

    def name_vertex(vertex: int) -> str:
        return f"vertex {vertex} (line {vertex_lines[vertex]})"

    channels = _colour_channels(path, values_per_vertex) if textured else 0
    values = _vertex_values(path, vertex_block, len(vertex_lines), channels, name_vertex)
    channels = values.shape[1] - 3  # 0 where a colour did not parse
    vertices = values[:, :3].astype(np.float32)
    check_finite_vertices(path, vertices, name_vertex)
    colours = None
    if channels:
        rows = all_finite(path, values[:, 3:].astype(np.float32), "colours", name_vertex)
        colours = None if rows is None else VertexColours(rows[None], OBJ_COLOUR_NAMES[:channels], ("f4",) * channels)

    def name_face(face: int) -> str:
        return f"face {face} (line {face_lines[face]})"

    texture_block = face_block
    if b"/" in face_block:
        face_block = re.sub(rb"/\S*", b"", face_block)  # v of v/vt/vn
    sizes = _row_sizes(face_block, len(face_lines))
    polygons = sizes >= 3  # pybullet's samurai_monastry.obj has 201 faces of two vertices among its 125k
    if sizes.size:
        first = int(np.argmin(polygons))  # the first face of fewer than 3 vertices, named in the warning
        refusal = f"needs at least 3 vertices, has {sizes[first]}; so does every face"
        polygons = polygon_mask(path, sizes, name_face(first), refusal)
    owner = np.repeat(np.arange(sizes.size), sizes)
    corners = _FaceCorners(path, sizes, owner, face_lines, name_face)
    resolved = corners.resolved(face_block, vertex_lines, len(vertices), ("vertex", "vertices"))
    faces = fan_triangulate(resolved[polygons[owner]], sizes[polygons])
    _warn_unread_names(path, data, face_lines)
    if not textured:
        return TexturedMesh(vertices, faces, None, None, None, None)

    def per_triangle(statements: tuple[bytes, np.ndarray], attribute: _Attribute) -> tuple | None:
        """The attribute's values and each triangle corner's index into them, or None."""
        block, lines = statements
        found = _corner_attribute(path, attribute, block, lines, texture_block, corners) if len(lines) else None
        return found and (found[0], fan_triangulate(found[1][polygons[owner]], sizes[polygons]))

    texture = per_triangle(uv_statements, _TEXTURE)
    corner_normals = per_triangle(normal_statements, _NORMALS) if normals else None
    materials = _materials(data, face_lines[polygons], sizes[polygons] - 2)
    return TexturedMesh(vertices, faces, texture and ObjTexture(*texture),
                        corner_normals and ObjNormals(*corner_normals), colours, materials)  # fmt: skip


def _materials(data: bytes, face_lines: np.ndarray, triangles: np.ndarray) -> ObjMaterials | None:
    """The materials of ``data``'s usemtl lines for the faces on ``face_lines`` (1-based), each
    fanned into ``triangles``; its mtllib lines' libraries. None without a usemtl line."""
    named = _names_in_effect(data, b"usemtl", face_lines)
    if named is None:
        return None
    names, in_effect = named
    used = np.array([name.decode("utf-8", "replace") for name in names], dtype=object)
    distinct, first, material = np.unique(used, return_index=True, return_inverse=True)
    order = np.argsort(first)  # the materials in the order of first use
    rank = np.empty(first.size, np.int32)
    rank[order] = np.arange(first.size)
    per_face = np.where(in_effect >= 0, rank[material.ravel()][np.maximum(in_effect, 0)], -1).astype(np.int32)
    libraries = re.findall(rb"(?m)^mtllib[ \t]+([^\n]*)", data)
    return ObjMaterials(tuple(found.decode("utf-8", "replace").strip() for found in libraries),
                        tuple(distinct[order].tolist()), np.repeat(per_face, triangles))  # fmt: skip


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
    path: Path, block: bytes, count: int, channels: int, name_vertex: Callable[[int], str]
) -> np.ndarray:
    """(count, 3 + channels) float64: each ``v`` line's x, y, z and its ``channels`` colour
    values, in one parse. A coordinate that does not parse is a FormatError as ever; a colour
    value that does not parse costs only the colours (a warning), and gives (count, 3)."""
    try:
        return _leading_values(path, block, count, 3 + channels, 3, name_vertex, "coordinates")
    except FormatError as error:
        if not channels:
            raise
        coordinates = _leading_values(path, block, count, 3, 3, name_vertex, "coordinates")  # raises for theirs
        _warn_unread_colours(path, str(error).removeprefix(f"{path}: "))
        return coordinates


def _warn_unread_colours(path: Path, reason: str) -> None:
    warnings.warn(f"{path}: {reason}: its colours are not read, and the levels are written without them",
                  UnreadAttributesWarning, stacklevel=5)  # fmt: skip


@dataclass(frozen=True)
class _FaceCorners:
    """The corners of an OBJ file's ``f`` lines: ``sizes`` per face, ``owner`` the face of each
    corner, the faces' ``lines`` and how messages name a face."""

    path: Path
    sizes: np.ndarray
    owner: np.ndarray
    lines: np.ndarray
    name_face: Callable[[int], str]

    def resolved(self, block: bytes, item_lines: np.ndarray, count: int, indexed: tuple[str, str]) -> np.ndarray:
        """Every corner's 0-based index into the ``count`` items defined on ``item_lines`` (v, vt
        or vn lines), from ``block`` (the ``f`` lines, one number per corner): negative indices count
        back from the last item defined above the face's line. FormatError names the face of a
        corner that does not parse or lies outside the items."""
        written = _untagged_values(block, np.int64, self.sizes)
        if written is None:
            tokens, starts = _row_tokens(block, self.sizes)
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
    path: Path, attribute: _Attribute, block: bytes, lines: np.ndarray, face_block: bytes, corners: _FaceCorners
) -> tuple[np.ndarray, np.ndarray] | None:
    """The ``attribute``'s lines (``block``: u and v of ``vt``, a w dropped; x, y, z of ``vn``) as
    float32, and every face corner's 0-based index into them (``face_block``: the ``f`` lines as
    written); None, with a warning, where some corners have an index and others none."""
    index_block, indexed = _corner_field(face_block, attribute.field)
    if indexed < corners.sizes.sum():
        if indexed:
            warnings.warn(f"{path}: {indexed} of {corners.sizes.sum()} face corners have {attribute.kind} "
                          f"({attribute.tag}), the others none: read without them", UnreadAttributesWarning,
                          stacklevel=4)  # fmt: skip
        return None

    def name_row(row: int) -> str:
        return f"{attribute.item} {row} (line {lines[row]})"

    values = _leading_values(path, block, len(lines), attribute.width, attribute.minimum, name_row, "values")
    check_finite_vertices(path, values.astype(np.float32), name_row)
    return values.astype(np.float32), corners.resolved(index_block, lines, len(values), attribute.items)


def write_obj(
    path: str | os.PathLike,
    vertices: np.ndarray,
    faces: np.ndarray,
    texture: ObjTexture | None = None,
    normals: ObjNormals | None = None,
    colours: VertexColours | None = None,
    materials: ObjMaterials | None = None,
) -> None:
    """Write ``vertices (V, 3)`` and ``faces (M, 3)`` as OBJ ``v``/``f`` lines, atomically; with
    ``texture`` also its ``vt`` lines, with ``normals`` its ``vn`` lines, and each corner's
    indices into them (``v/vt``, ``v//vn`` or ``v/vt/vn``); with one frame's ``colours`` (three
    or four channels) each ``v`` line's r, g, b (a) after its x, y, z; with ``materials`` (one
    per face) its ``mtllib`` lines, and the faces in runs of one material, each after its
    ``usemtl`` line (the faces of none first).

    Coordinates are written with 9 significant digits, which round-trips float32 exactly. A wrong
    shape, a coordinate that is not finite as float32 or a face index outside the vertices is a
    ValueError naming the file and the argument (``vertices``, ``faces``, ``texture``,
    ``normals`` or ``colours``); nothing is written.
    """
    vertices, faces = checked_for_writing(path, vertices, faces)
    vertices, faces = vertices.astype(np.float64), faces.astype(np.int64) + 1
    columns, corner, lines = [faces], "%d", ""
    for name, attribute, tag, width in (("texture", texture, "vt", 2), ("normals", normals, "vn", 3)):
        if attribute is None:
            corner += "/" if tag == "vt" and normals is not None else ""  # v//vn
            continue
        values, indices = np.asarray(attribute[0], dtype=np.float64), np.asarray(attribute[1])
        fits = values.ndim == 2 and values.shape[1] == width and np.isfinite(values).all()
        fits = fits and indices.shape == faces.shape and (not indices.size or 0 <= indices.min() <= indices.max())
        if not fits or indices.size and indices.max() >= len(values):
            raise ValueError(f"{os.fspath(path)}: {name}: expected finite values (N, {width}) and a (M, 3) "
                             f"corner index into them per face, got {values.shape} and {indices.shape}")  # fmt: skip
        lines += ((tag + " %.9g" * width + "\n") * len(values)) % tuple(values.ravel())
        columns.append(indices.astype(np.int64) + 1)
        corner += "/%d"
    vertex_line = "v %.9g %.9g %.9g\n"
    if colours is not None:
        if len(colours.names) not in (3, 4):
            raise ValueError(f"{os.fspath(path)}: colours: an OBJ v line holds r, g, b and perhaps a, got "
                             f"{', '.join(colours.names)}")  # fmt: skip
        vertices = np.concatenate([vertices, np.stack(colours.stored(path, len(vertices)), axis=1)], axis=1)
        vertex_line = "v" + " %.9g" * vertices.shape[1] + "\n"
    corners = np.stack(columns, axis=2).reshape(len(faces), -1)
    runs, header = [(None, corners)], ""
    if materials is not None:
        if np.shape(materials.faces) != (len(faces),) or np.any(materials.faces >= len(materials.names)):
            raise ValueError(f"{os.fspath(path)}: materials: expected a material (< {len(materials.names)}) per "
                             f"face, got {np.shape(materials.faces)}")  # fmt: skip
        order = np.argsort(materials.faces, kind="stable")
        starts = np.flatnonzero(np.diff(materials.faces[order], prepend=-2))
        runs = [(materials.faces[order[start]], corners[order[start:end]])
                for start, end in zip(starts, [*starts[1:], len(order)])]  # fmt: skip
        header = "".join(f"mtllib {library}\n" for library in materials.libraries)
    face_line = f"f {corner} {corner} {corner}\n"
    with atomic_write(path, "w", encoding="utf-8", newline="\n") as handle:
        handle.write("# written by animlod\n" + header)
        handle.write((vertex_line * len(vertices)) % tuple(vertices.ravel()))
        handle.write(lines)
        for material, run in runs:
            if material is not None and material >= 0:
                handle.write(f"usemtl {materials.names[material]}\n")
            handle.write((face_line * len(run)) % tuple(run.ravel()))


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


def _warn_unread_names(path: Path, data: bytes, face_lines: np.ndarray) -> None:
    """Says that the faces of ``data`` (on ``face_lines``, 1-based) fall into several objects or
    groups (the names of its ``o`` or ``g`` lines above them), which the mesh read does not keep
    apart: three objects become one unnamed mesh. Faces under one name alone (an exporter's
    ``o Cube`` for a file of one object) lose only the name, with no warning: the levels are
    named after the file."""
    if not len(face_lines) or re.search(rb"(?m)^[og][ \t]", data) is None:  # one scan where most files end
        return
    counts = {}
    for tag, kind in ((b"o", "object"), (b"g", "group")):
        named = _names_in_effect(data, tag, face_lines)
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


def _names_in_effect(data: bytes, tag: bytes, face_lines: np.ndarray) -> tuple[list[bytes], np.ndarray] | None:
    """The names on ``data``'s ``tag`` lines (``usemtl``, ``o``, ``g``), and for each face on
    ``face_lines`` (1-based) the index of the last of those lines above it, -1 above the first;
    None where no line has the tag."""
    found = list(re.finditer(rb"(?m)^" + tag + rb"[ \t]+([^\n]*)", data))
    if not found:
        return None
    newlines = np.flatnonzero(np.frombuffer(data, np.uint8) == ord("\n"))
    lines = np.searchsorted(newlines, [match.start() for match in found]) + 1
    return [match.group(1).strip() for match in found], np.searchsorted(lines, face_lines) - 1


def _obj_statements(data: bytes, tags: tuple[bytes, ...]) -> list[tuple[bytes, np.ndarray]]:
    """For each tag of one or two letters: the bytes of all lines starting with it, and their
    1-based line numbers."""
    codes = np.frombuffer(data + b"\n\n\n", dtype=np.uint8)  # padding: every line start has three bytes
    line_starts = np.concatenate(([0], np.flatnonzero(codes[: len(data)] == ord("\n")) + 1))
    line_lengths = np.diff(line_starts, append=len(data))
    separators = np.frombuffer(b" \t", dtype=np.uint8)
    result = []
    for tag in tags:
        selected = np.isin(codes[line_starts + len(tag)], separators)
        for offset, letter in enumerate(tag):
            selected &= codes[line_starts + offset] == letter
        result.append((codes[: len(data)][np.repeat(selected, line_lengths)].tobytes(), np.flatnonzero(selected) + 1))
    return result


def _leading_values(
    path: Path, block: bytes, line_count: int, width: int, minimum: int, element: Callable[[int], str], what: str
) -> np.ndarray:
    """(line_count, width) float64: the first ``width`` values after the tag on each line of
    ``block``, 0 where a line gives fewer (it must give ``minimum``); values past them are dropped
    unread. FormatError names the line (``element``) with too few values or a bad one."""
    sizes = _row_sizes(block, line_count)
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
    """Every value after the tags of ``block``'s lines, in order, as ``dtype``; None when one does
    not parse (then :func:`_row_tokens` and :func:`parse_numbers` name it)."""
    codes = np.frombuffer(block, dtype=np.uint8).copy()
    codes[np.concatenate(([0], np.flatnonzero(codes[:-1] == ord("\n")) + 1))[: sizes.size]] = ord(" ")
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
