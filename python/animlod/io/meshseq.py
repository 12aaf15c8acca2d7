"""OBJ and PLY frame sequences: one mesh file per frame, every frame with the same faces.

Only geometry is read: OBJ ``v`` and ``f`` lines (1-based or negative indices, ``a/b/c``
corners, polygons fan-triangulated, ``#`` comments also at a line's end, a statement continued
on the next line after a ``\\`` that ends its line; other statements such as ``vt``, ``vn``,
``g``, ``usemtl`` are ignored) and PLY ``vertex`` x, y, z with the ``face``
list ``vertex_indices`` (ascii, binary_little_endian, binary_big_endian; other elements and
properties are skipped). Statements may be indented. Parsing works on the whole file's bytes
with numpy: there is no Python loop over lines, vertices or faces.
"""

from __future__ import annotations

import glob
import os
import re
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..model import AnimatedMesh
from .atomic import atomic_folder, atomic_write
from .errors import FormatError
from .tokens import integer_tokens, parse_all, parses, tokens_per_line

MESH_SUFFIXES = (".obj", ".ply")
_PLY_TYPES = {
    name: code
    for names, code in [
        (("char", "int8"), "i1"),
        (("uchar", "uint8"), "u1"),
        (("short", "int16"), "i2"),
        (("ushort", "uint16"), "u2"),
        (("int", "int32"), "i4"),
        (("uint", "uint32"), "u4"),
        (("float", "float32"), "f4"),
        (("double", "float64"), "f8"),
    ]
    for name in names
}
_PLY_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
_FACE_LIST_NAMES = ("vertex_indices", "vertex_index")
# Prefix of the field of a binary row holding a list's length, followed by the list's name; the
# spaces keep it apart from any PLY property name.
_LIST_SIZE_FIELD = "list size of "


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
    for index, path in enumerate(paths[1:], start=1):
        vertices, frame_faces = read_mesh(path)
        _check_same_connectivity(path, vertices, frame_faces, paths[0], faces, len(first_vertices))
        frames[index] = vertices
    return AnimatedMesh(faces, frames, fps=fps)


def write_sequence(folder: str | os.PathLike, mesh: AnimatedMesh, fmt: str = "obj", stem: str = "frame") -> list[Path]:
    """Write every frame of ``mesh`` to ``folder/{stem}_{index:04d}.{fmt}``, the folder atomically.

    The frames are written into a temporary folder beside ``folder``, which is renamed to
    ``folder`` once every frame is written (:func:`~animlod.io.atomic.atomic_folder`): an
    interrupted run never leaves a folder short of frames under the final name. An existing
    ``folder`` is replaced as a whole. ``fmt`` is "obj" or "ply" (binary little-endian).
    Returns the written paths in frame order.
    """
    if fmt not in ("obj", "ply"):
        raise ValueError(f"{os.fspath(folder)}: fmt: must be 'obj' or 'ply', got {fmt!r}")
    width = max(4, len(str(mesh.frame_count - 1)))
    names = [f"{stem}_{index:0{width}d}.{fmt}" for index in range(mesh.frame_count)]
    with atomic_folder(folder) as temporary:
        for name, vertices in zip(names, mesh.frames):
            write_mesh(temporary / name, vertices, mesh.faces)
    return [Path(folder) / name for name in names]


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
        reason = f"{faces[face].tolist()} differs from {first_faces[face].tolist()} in {first}"
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
    (vertex_block, vertex_lines), (face_block, face_lines), (_, polylines) = _obj_statements(data, (b"v", b"f", b"l"))
    if not len(vertex_lines):
        _require_obj_statement(path, data)
    if not len(face_lines) and len(polylines):  # Inkscape's axes, OpenFOAM's edge curves
        reason = f"{len(polylines)} polylines ('l') and no face: animlod simplifies surfaces"
        raise FormatError(path, f"line {polylines[0]}", reason)

    def name_vertex(vertex: int) -> str:
        return f"vertex {vertex} (line {vertex_lines[vertex]})"

    sizes = _row_sizes(vertex_block, len(vertex_lines))
    _require_sizes(path, sizes, 3, name_vertex, "coordinates")
    values = _untagged_values(vertex_block, np.float64, sizes)
    if values is not None:
        vertices = values[(np.cumsum(sizes) - sizes)[:, None] + np.arange(3)]
    else:  # find the bad one among x, y, z (extra values are dropped unread)
        tokens, starts = _row_tokens(vertex_block, sizes)
        columns = tokens[starts[:, None] + np.arange(1, 4)]
        vertices = _parse_numbers(path, columns, np.float64, lambda token: name_vertex(token // 3))
    vertices = vertices.astype(np.float32)
    _check_finite_vertices(path, vertices, name_vertex)

    def name_face(face: int) -> str:
        return f"face {face} (line {face_lines[face]})"

    if b"/" in face_block:
        face_block = re.sub(rb"/\S*", b"", face_block)  # v of v/vt/vn
    sizes = _row_sizes(face_block, len(face_lines))
    polygons = sizes >= 3  # pybullet's samurai_monastry.obj has 201 faces of two vertices among its 125k
    if sizes.size:
        first = int(np.argmin(polygons))  # the first face of fewer than 3 vertices, named in the warning
        refusal = f"needs at least 3 vertices, has {sizes[first]}; so does every face"
        polygons = _polygons(path, sizes, name_face(first), refusal)
    owner = np.repeat(np.arange(sizes.size), sizes)
    written = _untagged_values(face_block, np.int64, sizes)
    if written is None:
        tokens, starts = _row_tokens(face_block, sizes)
        written = _parse_numbers(path, np.delete(tokens, starts), np.int64, lambda corner: name_face(owner[corner]))
    # Negative indices count back from the last vertex defined above the face's line.
    defined = np.searchsorted(vertex_lines, face_lines)[owner]
    resolved = np.where(written > 0, written - 1, np.where(written < 0, defined + written, -1))
    _check_face_indices(path, resolved, written, owner, len(vertices), name_face)
    return vertices, _fan_triangulate(resolved[polygons[owner]], sizes[polygons])


def _polygons(path: Path, sizes: np.ndarray, element: str, refusal: str) -> np.ndarray:
    """(M,) bool: the faces of three vertices or more. Points and lines written among the faces
    have no surface: they are left out with a warning naming ``element``, and a file of nothing
    else is refused there with ``refusal``."""
    polygons = sizes >= 3
    if sizes.size and not polygons.any():
        raise FormatError(path, element, refusal)
    if not polygons.all():
        short = sizes.size - int(polygons.sum())
        warnings.warn(f"{path}: {element}: {short} of {sizes.size} faces have fewer than 3 vertices (points or "
                      "lines); left out", stacklevel=4)  # fmt: skip
    return polygons


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


def write_obj(path: str | os.PathLike, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Write ``vertices (V, 3)`` and ``faces (M, 3)`` as OBJ ``v``/``f`` lines, atomically.

    Coordinates are written with 9 significant digits, which round-trips float32 exactly. A wrong
    shape, a coordinate that is not finite as float32 or a face index outside the vertices is a
    ValueError naming the file and the argument (``vertices`` or ``faces``); nothing is written.
    """
    vertices, faces = _checked(path, vertices, faces)
    vertices, faces = vertices.astype(np.float64), faces.astype(np.int64) + 1
    with atomic_write(path, "w", encoding="ascii", newline="\n") as handle:
        handle.write("# written by animlod\n")
        handle.write(("v %.9g %.9g %.9g\n" * len(vertices)) % tuple(vertices.ravel()))
        handle.write(("f %d %d %d\n" * len(faces)) % tuple(faces.ravel()))


def _checked(path: str | os.PathLike, vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``vertices (V, 3) float32`` and ``faces (M, 3) int32`` checked as AnimatedMesh checks a
    frame (shapes, finite values, indices in range); otherwise a ValueError that names the file
    and the argument (``out.obj: vertices: vertex 2 [nan, 0.0, 0.0] is not finite``)."""
    given = np.asarray(vertices)
    if not (given.ndim == 2 and given.shape[1] == 3):
        raise ValueError(f"{os.fspath(path)}: vertices: expected shape (V, 3), got {given.shape}")
    try:
        with np.errstate(over="ignore"):  # 1e39 becomes inf, refused below
            positions = np.ascontiguousarray(given, dtype=np.float32)
    except (TypeError, ValueError):
        raise ValueError(f"{os.fspath(path)}: vertices: expected numbers, got dtype {given.dtype}") from None
    finite = np.isfinite(positions).all(axis=1)
    if not finite.all():
        vertex = int(np.argmin(finite))
        reason = f"vertex {vertex} {given[vertex].tolist()} is not finite as float32"
        raise ValueError(f"{os.fspath(path)}: vertices: {reason}")
    try:
        mesh = AnimatedMesh(faces, positions[None])  # checks the faces against the vertex count
    except ValueError as error:
        raise ValueError(f"{os.fspath(path)}: {error}") from None
    return mesh.frames[0], mesh.faces


def _obj_statements(data: bytes, tags: tuple[bytes, ...]) -> list[tuple[bytes, np.ndarray]]:
    """For each one-letter tag: the bytes of all lines starting with it, and their 1-based line numbers."""
    codes = np.frombuffer(data + b"\n\n", dtype=np.uint8)  # padding: every line start has two bytes
    line_starts = np.concatenate(([0], np.flatnonzero(codes[: len(data)] == ord("\n")) + 1))
    line_lengths = np.diff(line_starts, append=len(data))
    separated = np.isin(codes[line_starts + 1], np.frombuffer(b" \t", dtype=np.uint8))
    result = []
    for tag in tags:
        selected = (codes[line_starts] == tag[0]) & separated
        result.append((codes[: len(data)][np.repeat(selected, line_lengths)].tobytes(), np.flatnonzero(selected) + 1))
    return result


def _row_sizes(block: bytes, line_count: int) -> np.ndarray:
    """The number of values after the tag on each of the ``line_count`` tag-led lines of ``block``.
    Rows are counted by line, not by tag token: ``v v 1 2`` is one row (whose "v" then fails to
    parse), not two."""
    return tokens_per_line(block)[:line_count] - 1


def _untagged_values(block: bytes, dtype: type, sizes: np.ndarray) -> np.ndarray | None:
    """Every value after the tags of ``block``'s lines, in order, as ``dtype``; None when one does
    not parse (then :func:`_row_tokens` and :func:`_parse_numbers` name it)."""
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


def _parse_numbers(path: Path, tokens: np.ndarray, dtype: type, element: Callable[[int], str]) -> np.ndarray:
    """Convert byte-string tokens to ``dtype``; on failure name the element holding the first bad token."""
    try:
        return tokens.astype(dtype)
    except (ValueError, OverflowError):
        flat = tokens.ravel()
        bad = next(index for index, token in enumerate(flat) if not parses(token, dtype))
        text = flat[bad].decode(errors="replace")
        raise FormatError(path, element(bad), f"{text!r} is not a number or out of range") from None


def _check_finite_vertices(path: Path, vertices: np.ndarray, element: Callable[[int], str]) -> None:
    finite = np.isfinite(vertices).all(axis=1)
    if not finite.all():
        vertex = int(np.argmin(finite))
        raise FormatError(path, element(vertex), f"coordinates {vertices[vertex].tolist()} are not finite")


def _check_face_indices(
    path: Path,
    indices: np.ndarray,
    written: np.ndarray,
    owner: np.ndarray,
    vertex_count: int,
    element: Callable[[int], str],
) -> None:
    """``indices`` are 0-based corners, ``written`` as in the file, ``owner`` the face of each corner."""
    outside = np.flatnonzero((indices < 0) | (indices >= vertex_count))
    if outside.size:
        corner = outside[0]
        reason = f"vertex index {written[corner]} is outside the {vertex_count} vertices"
        raise FormatError(path, element(int(owner[corner])), reason)


def _within_runs(sizes: np.ndarray) -> np.ndarray:
    """For runs of the given lengths back to back, each item's place in its run: 0, 1, .., n - 1."""
    return np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)


def _fan_triangulate(corners: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """Triangles ``(sum(sizes - 2), 3) int32`` fanning each polygon from its first corner.

    ``corners`` holds the vertex indices of all polygons back to back, ``sizes`` their lengths.
    """
    first = np.cumsum(sizes) - sizes
    triangle_counts = sizes - 2
    polygon = np.repeat(np.arange(sizes.size), triangle_counts)
    step = _within_runs(triangle_counts)
    base = first[polygon]
    return np.stack([corners[base], corners[base + step + 1], corners[base + step + 2]], axis=1).astype(np.int32)


# ---------------------------------------------------------------------------------------------
# PLY


@dataclass
class _PlyProperty:
    name: str
    type_code: str  # numpy type code without byte order, e.g. "f4"
    count_code: str | None = None  # set for list properties: the type of the length prefix


@dataclass
class _PlyElement:
    name: str
    count: int
    properties: list[_PlyProperty] = field(default_factory=list)


def read_ply(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray]:
    """Read the vertex positions and faces of a PLY file (ascii or binary).

    Returns ``vertices (V, 3) float32`` from vertex x, y, z and ``faces (M, 3) int32`` from the
    face list ``vertex_indices`` (or ``vertex_index``), fan-triangulated (polygons of any sizes,
    mixed); no face element gives ``(0, 3)``.

    Raises
    ------
    FormatError
        For an unreadable header, a body shorter than the header announces, a missing x/y/z,
        a non-finite coordinate or a face index out of range.
    """
    path = Path(path)
    data = path.read_bytes()
    byte_order, elements, body = _read_ply_header(path, data)
    if byte_order is None:
        values = _read_ply_ascii(path, data[body:], elements)
    else:
        values = _read_ply_binary(path, data, body, elements, byte_order)
    vertex = values.get("vertex", {})
    missing = [axis for axis in "xyz" if axis not in vertex or isinstance(vertex[axis], tuple)]
    if missing:
        raise FormatError(path, "element vertex", f"has no scalar property {missing[0]}")
    vertices = np.stack([vertex[axis] for axis in "xyz"], axis=1).astype(np.float32)
    _check_finite_vertices(path, vertices, lambda index: f"vertex {index}")
    face = values.get("face", {})
    face_list = next((face[name] for name in _FACE_LIST_NAMES if isinstance(face.get(name), tuple)), None)
    if face_list is None:
        if any(element.name == "face" and element.count for element in elements):
            raise FormatError(path, "element face", "has no list property vertex_indices")
        return vertices, np.zeros((0, 3), dtype=np.int32)
    sizes, corners = face_list
    if corners.dtype.kind == "f":
        raise FormatError(path, "element face", "vertex index list has float items; indices must be integers")

    # assimp writes a mesh's points and lines into the face element.
    refusal = f"all {sizes.size} faces have fewer than 3 vertices (points or lines)"
    polygons = _polygons(path, sizes, "element face", refusal)
    kept = np.flatnonzero(polygons)
    corners, sizes = corners[np.repeat(polygons, sizes)], sizes[kept]

    def name_face(face_index: int) -> str:
        return f"face {kept[face_index]}"

    corners = corners.astype(np.int64)
    _check_face_indices(path, corners, corners, np.repeat(np.arange(sizes.size), sizes), len(vertices), name_face)
    return vertices, _fan_triangulate(corners, sizes)


def write_ply(path: str | os.PathLike, vertices: np.ndarray, faces: np.ndarray, binary: bool = True) -> None:
    """Write ``vertices (V, 3)`` as float x, y, z and ``faces (M, 3)`` as uchar/int lists, atomically.

    ``binary=True`` writes binary_little_endian (exact); ``binary=False`` ascii with 9
    significant digits (exact for float32). Bad input is refused as :func:`write_obj` refuses it.
    """
    vertices, faces = _checked(path, vertices, faces)
    vertices, faces = vertices.astype("<f4"), faces.astype(np.int64)
    header = (
        f"ply\nformat {'binary_little_endian' if binary else 'ascii'} 1.0\ncomment written by animlod\n"
        f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    if binary:
        face_rows = np.empty(len(faces), dtype=[("size", "u1"), ("indices", "<i4", (3,))])
        face_rows["size"] = 3
        face_rows["indices"] = faces
        body = vertices.tobytes() + face_rows.tobytes()
    else:
        text = ("%.9g %.9g %.9g\n" * len(vertices)) % tuple(vertices.astype(np.float64).ravel())
        text += ("3 %d %d %d\n" * len(faces)) % tuple(faces.ravel())
        body = text.encode("ascii")
    with atomic_write(path, "wb") as handle:
        handle.write(header.encode("ascii") + body)


def _read_ply_header(path: Path, data: bytes) -> tuple[str | None, list[_PlyElement], int]:
    """Parse the header: byte order ("<", ">", None for ascii), the elements, and where the body starts."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise FormatError(path, "header", "not a PLY header (must start with 'ply' and close with 'end_header')")
    body = data.find(b"\n", end)
    body = len(data) if body < 0 else body + 1
    byte_order: str | None = None
    format_seen = False
    elements: list[_PlyElement] = []
    lines = data[:end].decode("ascii", errors="replace").replace("\r", "").split("\n")
    for number, line in enumerate(lines[1:], start=2):
        words = line.split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        element = f"header line {number}"
        if words[0] == "format" and len(words) == 3 and words[1] in _PLY_FORMATS:
            byte_order, format_seen = _PLY_FORMATS[words[1]], True
        elif words[0] == "element" and len(words) == 3 and words[2].isascii() and words[2].isdigit():
            # Every row takes at least a byte (binary) or a line (ascii): more rows than the file
            # has bytes cannot be there, and would overflow numpy's counts for empty rows.
            if int(words[2]) > len(data):
                reason = f"element {words[1]!r} declares {words[2]} rows, more than the file's {len(data)} bytes"
                raise FormatError(path, element, reason)
            elements.append(_PlyElement(words[1], int(words[2])))
        elif words[0] == "property" and elements:
            prop = _ply_property(path, element, words)
            if any(other.name == prop.name for other in elements[-1].properties):
                raise FormatError(path, element, f"property {prop.name!r} is declared twice in {elements[-1].name!r}")
            elements[-1].properties.append(prop)
        elif words[0] in ("format", "element", "property") or elements:
            raise FormatError(path, element, f"cannot read {line.strip()!r}")
        else:
            # Not a PLY keyword: Blender 2.4's exporter wrote its comment without one (assimp's
            # Wuson.ply); assimp skips such lines, and so does this one, aloud, before the first
            # element only: among the elements it may be a damaged property, and the rows would
            # be read with the wrong layout.
            reason = f"skipped {line.strip()!r}, which starts with no PLY keyword"
            warnings.warn(f"{path}: {element}: {reason}", stacklevel=4)
    if not format_seen:
        raise FormatError(path, "header", "no 'format ascii|binary_little_endian|binary_big_endian 1.0' line")
    return byte_order, elements, body


def _ply_property(path: Path, element: str, words: list[str]) -> _PlyProperty:
    if len(words) == 3 and words[1] in _PLY_TYPES:
        return _PlyProperty(words[2], _PLY_TYPES[words[1]])
    if len(words) == 5 and words[1] == "list" and words[2] in _PLY_TYPES and words[3] in _PLY_TYPES:
        return _PlyProperty(words[4], _PLY_TYPES[words[3]], count_code=_PLY_TYPES[words[2]])
    raise FormatError(path, element, f"cannot read property {' '.join(words)!r}")


# Parsed element values: property name -> (N,) array, or (sizes (N,), items) for a list property.
_ElementValues = dict[str, "np.ndarray | tuple[np.ndarray, np.ndarray]"]


def _read_ply_binary(
    path: Path, data: bytes, offset: int, elements: list[_PlyElement], byte_order: str
) -> dict[str, _ElementValues]:
    """Read each element as one structured numpy array where its rows have one size (no list, or
    lists each of one length throughout, as a mesh of triangles with MeshLab's texcoord lists);
    otherwise with :func:`_read_rows_of_lists`."""
    values: dict[str, _ElementValues] = {}
    for element in elements:
        fields, lengths = _first_row_fields(path, data, offset, element, byte_order)
        row = np.dtype(fields)
        fits = offset + row.itemsize * element.count <= len(data)
        table = np.frombuffer(data, row, element.count, offset) if fits else None
        if lengths and (table is None or any(np.any(table[_LIST_SIZE_FIELD + name] != n) for name, n in lengths)):
            values[element.name], offset = _read_rows_of_lists(path, data, offset, element, byte_order)
            continue
        if table is None:
            raise FormatError(path, f"element {element.name}", f"file ends before its {element.count} rows")
        offset += row.itemsize * element.count
        values[element.name] = {prop.name: table[prop.name] for prop in element.properties if prop.count_code is None}
        for name, length in lengths:
            values[element.name][name] = (np.full(element.count, length, dtype=np.int64), table[name].ravel())
    return values


def _first_row_fields(
    path: Path, data: bytes, offset: int, element: _PlyElement, byte_order: str
) -> tuple[list[tuple], list[tuple[str, int]]]:
    """The numpy fields of the element's rows if each list has the length it has in the first row
    (MeshLab adds texcoord lists to faces), and those lengths by list name (0 without rows)."""
    fields: list[tuple] = []
    lengths: list[tuple[str, int]] = []
    position = offset
    for prop in element.properties:
        item = np.dtype(byte_order + prop.type_code)
        if prop.count_code is None:
            fields.append((prop.name, item))
            position += item.itemsize
            continue
        count = np.dtype(byte_order + prop.count_code)
        length = 0
        if element.count:
            if position + count.itemsize > len(data):
                raise FormatError(path, f"element {element.name}", "file ends inside the element")
            length = int(np.frombuffer(data, count, 1, position)[0])
            # Each item takes at least a byte, so a longer list cannot fit in the rest of the file.
            if not 0 <= length <= len(data) - offset:
                reason = f"list length {length} is negative or longer than the rest of the file"
                raise FormatError(path, f"element {element.name} row 0", reason)
        fields += [(_LIST_SIZE_FIELD + prop.name, count), (prop.name, item, (length,))]
        lengths.append((prop.name, length))
        position += count.itemsize + length * item.itemsize
    return fields, lengths


def _read_rows_of_lists(
    path: Path, data: bytes, offset: int, element: _PlyElement, byte_order: str
) -> tuple[_ElementValues, int]:
    """A binary element whose rows differ in size (lists of varying lengths: triangles and quads
    as Blender writes them, MeshLab's texcoord lists), and the offset after it. A row starts
    where the one before it ends, so every byte a row could start at is given the start of the
    row after it, and the rows' starts follow by pointer doubling: log2(rows) numpy passes, no
    loop over the rows."""
    props = element.properties
    kinds = [(np.dtype(byte_order + p.count_code) if p.count_code else None, np.dtype(byte_order + p.type_code))
             for p in props]  # fmt: skip
    smallest = sum((count or item).itemsize for count, item in kinds)  # a row of empty lists
    candidates = len(data) - offset - smallest + 1  # bytes at which a row could still start
    if not element.count:
        return {p.name: (np.zeros(0, np.int64), np.zeros(0)) if p.count_code else np.zeros(0) for p in props}, offset
    if candidates <= 0:
        raise FormatError(path, f"element {element.name}", "file ends inside the element")
    raw = np.frombuffer(data, np.uint8, len(data) - offset, offset)
    index = np.int32 if len(raw) < 2**31 - 1 else np.int64  # the byte-sized arrays in half the memory

    def read(at: np.ndarray, dtype: np.dtype) -> np.ndarray:  # a value of dtype at each byte offset
        at = np.clip(at, 0, raw.size - dtype.itemsize)  # a start that is no row may point past the end
        return raw[at[:, None] + np.arange(dtype.itemsize, dtype=index)].copy().view(dtype).ravel()

    Places = list[tuple[np.ndarray, "np.ndarray | None"]]

    def walk(starts: np.ndarray, limit: int, record: bool) -> tuple[np.ndarray, Places]:
        """Each row's end (``limit`` where it would end past it or has a negative length), and
        with ``record`` per property where it starts and (lists) its length."""
        cursor, places = starts.copy(), []
        for count, item in kinds:
            if count is None:
                if record:
                    places.append((cursor, None))
                cursor = np.minimum(cursor + item.itemsize, limit).astype(starts.dtype)
            else:
                sizes = read(cursor, count).astype(np.int64)
                if record:
                    places.append((cursor + count.itemsize, sizes))
                ahead = cursor + count.itemsize + np.maximum(sizes, 0) * item.itemsize
                cursor = np.where(sizes < 0, limit, np.minimum(ahead, limit)).astype(starts.dtype)
        return cursor, places

    # Past the last possible start, and a negative size, lead to a sink that leads to itself.
    following, _ = walk(np.arange(candidates, dtype=index), candidates, record=False)
    jump = np.append(following, index(candidates))
    starts = np.zeros(element.count, np.int64)
    rows = np.arange(element.count)
    step = 0
    while (1 << step) < element.count:  # starts[i] = next^i(0): apply next^(2^k) for each bit k of i
        odd = (rows >> step) & 1 == 1
        starts[odd] = jump[starts[odd]]
        jump = jump[jump]
        step += 1
    ends, places = walk(starts, len(raw) + 1, record=True)
    if (
        np.any(starts == candidates)
        or offset + int(ends[-1]) > len(data)
        or any(sizes is not None and np.any(sizes < 0) for _, sizes in places)
    ):
        raise FormatError(path, f"element {element.name}", f"file ends before its {element.count} rows")
    element_values: _ElementValues = {}
    for prop, (_, item), (at, sizes) in zip(props, kinds, places):
        if sizes is None:
            element_values[prop.name] = read(at, item)
            continue
        items_at = np.repeat(at, sizes) + _within_runs(sizes) * item.itemsize
        element_values[prop.name] = (sizes, read(items_at, item))
    return element_values, offset + int(ends[-1])


class _AsciiTokens:
    """The whitespace-separated tokens of an ascii PLY body as numbers, converted in one pass of
    numpy's parser. Only when a token does not parse that way (a bad one, to name; an integer from
    2**53 up) are they split into bytes objects: a Python object per token took 770 MB for a body
    of 1M faces."""

    def __init__(self, body: bytes, count: int) -> None:
        self.body = body
        numbers = parse_all(body, np.float64)
        self.numbers = numbers if numbers is not None and numbers.size == count else None
        self.integral: np.ndarray | None = None  # per token: written as an integer
        self.split: np.ndarray | None = None  # the tokens as bytes, when needed

    def parse(self, path: Path, at: np.ndarray, dtype: type, element: Callable[[int], str]) -> np.ndarray:
        """The tokens at indices ``at`` as ``dtype`` (np.float64 or np.int64); FormatError naming
        ``element(i)`` for the first, ``at[i]``, that is no such number."""
        if self.numbers is not None:
            values = self.numbers[at]
            if dtype is np.float64:
                return values
            if self.integral is None:
                self.integral = integer_tokens(self.body)
            if np.all(self.integral[at]) and np.all(np.abs(values) < 2.0**53):  # exact in float64
                return values.astype(np.int64)
        if self.split is None:
            self.split = np.array(self.body.split(), dtype=np.bytes_)
        return _parse_numbers(path, self.split[at], dtype, element)


def _read_ply_ascii(path: Path, body: bytes, elements: list[_PlyElement]) -> dict[str, _ElementValues]:
    """Read an ascii body: one line per row, elements one after the other."""
    body = body.replace(b"\r", b"")
    counts = tokens_per_line(body)
    rows = np.flatnonzero(counts)  # blank lines are skipped
    tokens = _AsciiTokens(body, int(counts.sum()))
    row_start = np.cumsum(counts[rows]) - counts[rows]
    values: dict[str, _ElementValues] = {}
    first_row = 0
    for element in elements:
        if first_row + element.count > rows.size:
            reason = f"file ends after {rows.size - first_row} of its {element.count} rows"
            raise FormatError(path, f"element {element.name}", reason)
        chosen = slice(first_row, first_row + element.count)
        starts, lengths = row_start[chosen], counts[rows[chosen]]
        element_values: _ElementValues = {}

        def name_row(row: int, element: _PlyElement = element) -> str:
            return f"element {element.name} row {row}"

        # Property by property, each row's next token: a list's items push the rest right. A row
        # must reach the next list's length (or its last scalar) before that length is known.
        properties = element.properties
        reach = [next((i - k + 1 for i in range(k, len(properties)) if properties[i].count_code), len(properties) - k)
                 for k in range(len(properties))]  # fmt: skip
        cursor, ends = starts.copy(), starts + lengths
        for k, prop in enumerate(properties):
            dtype = np.float64 if prop.type_code.startswith("f") else np.int64
            short = np.flatnonzero(cursor + reach[k] > ends)
            if short.size:
                row = short[0]
                bound = "at least " if any(later.count_code for later in properties[k:]) else ""
                reason = f"has {lengths[row]} values, expected {bound}{cursor[row] - starts[row] + reach[k]}"
                raise FormatError(path, name_row(row), reason)
            if prop.count_code is None:
                element_values[prop.name] = tokens.parse(path, cursor, dtype, name_row)
                cursor = cursor + 1
                continue
            sizes = tokens.parse(path, cursor, np.int64, name_row)
            negative = np.flatnonzero(sizes < 0)
            if negative.size:
                raise FormatError(path, name_row(negative[0]), f"list length {sizes[negative[0]]} is negative")
            over = np.flatnonzero(cursor + 1 + sizes > ends)
            if over.size:
                row = over[0]
                reason = f"has {lengths[row]} values, expected {cursor[row] + 1 + sizes[row] - starts[row]}"
                raise FormatError(path, name_row(row), reason)
            owner = np.repeat(np.arange(element.count), sizes)
            items = np.repeat(cursor + 1, sizes) + _within_runs(sizes)
            parsed = tokens.parse(path, items, dtype, lambda item, owner=owner: name_row(owner[item]))
            element_values[prop.name] = (sizes, parsed)
            cursor = cursor + 1 + sizes
        wrong = np.flatnonzero(cursor != ends)
        if wrong.size:
            row = wrong[0]
            raise FormatError(path, name_row(row), f"has {lengths[row]} values, expected {cursor[row] - starts[row]}")
        values[element.name] = element_values
        first_row += element.count
    return values
