"""PLY geometry: ``vertex`` x, y, z, the vertices' texture coordinates (s, t or its aliases),
normals (nx, ny, nz) and colours (red, green, blue, alpha or their aliases), and the ``face``
list ``vertex_indices`` read (ascii,
binary_little_endian, binary_big_endian; other elements and properties are skipped, with a
warning for the vertices' and faces' other properties) and written.
Parsing works on the whole file's bytes with numpy: there is no Python loop over rows."""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

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
    polygon_of_triangle,
    within_runs,
)
from .tokens import integer_tokens, parse_all, tokens_per_line
from .vertex_colours import PLY_COLOUR_NAMES, PLY_TYPE_NAMES, VertexColours

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
# A vertex's texture coordinates under the names exporters give them (Blender's s, t first, as
# Blender's importer looks for them); the first pair a file has is read.
_TEXTURE_NAMES = (("s", "t"), ("u", "v"), ("texture_u", "texture_v"), ("texture_s", "texture_t"))
_NORMAL_NAMES = ("nx", "ny", "nz")
# Prefix of the field of a binary row holding a list's length, followed by the list's name; the
# spaces keep it apart from any PLY property name.
_LIST_SIZE_FIELD = "list size of "


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
    vertices, faces, _, _, _ = _read_ply(Path(path), attributes=False)
    return vertices, faces


def read_ply_attributes(
    path: str | os.PathLike,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None, VertexColours | None]:
    """:func:`read_ply`, the vertices' texture coordinates ``uvs (V, 2) float32`` from the first of
    the scalar property pairs s, t / u, v / texture_u, texture_v / texture_s, texture_t the
    vertex element has, their normals ``(V, 3) float32`` from nx, ny, nz, and their colours from
    red, green, blue (or diffuse_red, ...) and alpha where it has one, as stored (each None where
    it has none). Texture coordinates or colours with a non-finite value are left out with a
    warning naming the vertex; a non-finite normal reads as zero (no direction)."""
    return _read_ply(Path(path), attributes=True)


def face_of_triangle(path: str | os.PathLike, triangle: int) -> str:
    """The face element that triangle ``triangle`` of :func:`read_ply`'s faces comes from, named as
    the reader's errors name faces: for a fault found in the triangles after the file was read."""
    _, values = _ply_values(Path(path))
    face = values["face"]
    sizes, _ = next(face[name] for name in _FACE_LIST_NAMES if isinstance(face.get(name), tuple))
    return f"face {polygon_of_triangle(sizes, triangle)}"


def _ply_values(path: Path) -> tuple[list[_PlyElement], dict[str, _ElementValues]]:
    """A PLY file's elements as its header declares them, and their values."""
    data = path.read_bytes()
    byte_order, elements, body = _read_ply_header(path, data)
    if byte_order is None:
        return elements, _read_ply_ascii(path, data[body:], elements)
    return elements, _read_ply_binary(path, data, body, elements, byte_order)


def _read_ply(
    path: Path, attributes: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None, VertexColours | None]:
    elements, values = _ply_values(path)
    vertex = values.get("vertex", {})
    missing = [axis for axis in "xyz" if axis not in vertex or isinstance(vertex[axis], tuple)]
    if missing:
        raise FormatError(path, "element vertex", f"has no scalar property {missing[0]}")
    vertices = np.stack([vertex[axis] for axis in "xyz"], axis=1).astype(np.float32)
    check_finite_vertices(path, vertices, lambda index: f"vertex {index}")
    scalar = {name for name, column in vertex.items() if not isinstance(column, tuple)}  # a list is not read
    texture_names = next((pair for pair in _TEXTURE_NAMES if scalar.issuperset(pair)), ()) if attributes else ()
    normal_names = _NORMAL_NAMES if attributes and scalar.issuperset(_NORMAL_NAMES) else ()
    uvs = np.stack([vertex[name] for name in texture_names], axis=1).astype(np.float32) if texture_names else None
    uvs = all_finite(path, uvs, "texture coordinates", _name_vertex)  # carried to the levels, so all or none
    normals = np.stack([vertex[name] for name in normal_names], axis=1).astype(np.float32) if normal_names else None
    if normals is not None:  # they only tell how the levels' rebuilt normals shade: a bad one tells nothing
        normals[~np.isfinite(normals).all(axis=1)] = 0.0
    colour_names = _colour_names(scalar) if attributes else ()
    colours = _vertex_colours(path, elements, vertex, colour_names) if colour_names else None
    read = ("x", "y", "z", *texture_names, *normal_names, *colour_names)
    face = values.get("face", {})
    face_list = next((face[name] for name in _FACE_LIST_NAMES if isinstance(face.get(name), tuple)), None)
    read_names = (("vertex", read), ("face", _FACE_LIST_NAMES))
    unread = [
        f"{element} {name}" for element, read in read_names for name in values.get(element, {}) if name not in read
    ]
    if unread:  # colours, texture coordinates of a face's corners, a face's flags
        warnings.warn(f"{path}: its properties {', '.join(unread)} are not read, and the levels are written without "
                      "them", UnreadAttributesWarning, stacklevel=3)  # fmt: skip
    if face_list is None:
        if any(element.name == "face" and element.count for element in elements):
            raise FormatError(path, "element face", "has no list property vertex_indices")
        return vertices, np.zeros((0, 3), dtype=np.int32), uvs, normals, colours
    sizes, corners = face_list
    if corners.dtype.kind == "f":
        raise FormatError(path, "element face", "vertex index list has float items; indices must be integers")

    # assimp writes a mesh's points and lines into the face element.
    refusal = f"all {sizes.size} faces have fewer than 3 vertices (points or lines)"
    polygons = polygon_mask(path, sizes, "element face", refusal)
    kept = np.flatnonzero(polygons)
    corners, sizes = corners[np.repeat(polygons, sizes)], sizes[kept]

    def name_face(face_index: int) -> str:
        return f"face {kept[face_index]}"

    corners = corners.astype(np.int64)
    check_face_indices(path, corners, corners, np.repeat(np.arange(sizes.size), sizes), len(vertices), name_face)
    return vertices, fan_triangulate(corners, sizes), uvs, normals, colours


def _name_vertex(index: int) -> str:
    return f"vertex {index}"


def _colour_names(scalar: set[str]) -> tuple[str, ...]:
    """The first of :data:`PLY_COLOUR_NAMES`' sets whose red, green and blue are among the vertex
    element's ``scalar`` properties, with its alpha where that is one too; () for none."""
    names = next((names for names in PLY_COLOUR_NAMES if scalar.issuperset(names[:3])), ())
    return names if not names or names[3] in scalar else names[:3]


def _vertex_colours(
    path: Path, elements: list[_PlyElement], vertex: _ElementValues, names: tuple[str, ...]
) -> VertexColours | None:
    """The vertices' colours ``names``, each with the type it is stored in; None, with a
    warning, where one is not finite."""
    declared = {prop.name: prop.type_code for prop in next(e for e in elements if e.name == "vertex").properties}
    values = np.stack([vertex[name] for name in names], axis=1).astype(np.float32)
    values = all_finite(path, values, "colours", _name_vertex)
    return None if values is None else VertexColours(values[None], names, tuple(declared[name] for name in names))


def write_ply(
    path: str | os.PathLike,
    vertices: np.ndarray,
    faces: np.ndarray,
    binary: bool = True,
    uvs: np.ndarray | None = None,
    normals: np.ndarray | None = None,
    colours: VertexColours | None = None,
) -> None:
    """Write ``vertices (V, 3)`` as float x, y, z (with ``uvs (V, 2)``, the vertices' texture
    coordinates, as float s, t, ``normals (V, 3)`` as float nx, ny, nz, and one frame's
    ``colours`` under their names and in their type) and ``faces (M, 3)`` as uchar/int lists,
    atomically.

    ``binary=True`` writes binary_little_endian (exact); ``binary=False`` ascii with 9
    significant digits (exact for float32; 17 for double colours). Bad input is refused as :func:`write_obj` refuses it,
    and ``uvs``, ``normals`` or ``colours`` of another vertex count or not finite with ValueError.
    """
    vertices, faces = checked_for_writing(path, vertices, faces)
    columns = [("x", vertices[:, 0]), ("y", vertices[:, 1]), ("z", vertices[:, 2])]
    for name, values, names in (("uvs", uvs, ("s", "t")), ("normals", normals, _NORMAL_NAMES)):
        if values is None:
            continue
        values = np.asarray(values)
        if values.shape != (len(vertices), len(names)) or not np.isfinite(values).all():
            shape = (len(vertices), len(names))
            raise ValueError(f"{os.fspath(path)}: {name}: expected {shape} finite values, got {values.shape}")
        columns += [(names[axis], values[:, axis].astype(np.float32)) for axis in range(len(names))]
    if colours is not None:
        columns += list(zip(colours.names, colours.stored(path, len(vertices))))
    row = np.dtype([(name, values.dtype.newbyteorder("<")) for name, values in columns])
    vertex_rows = np.empty(len(vertices), row)
    for name, values in columns:
        vertex_rows[name] = values
    faces = faces.astype(np.int64)
    property_lines = "".join(f"property {PLY_TYPE_NAMES[row[name].str[1:]]} {name}\n" for name in row.names)
    header = (
        f"ply\nformat {'binary_little_endian' if binary else 'ascii'} 1.0\ncomment written by animlod\n"
        f"element vertex {len(vertices)}\n{property_lines}"
        f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    if binary:
        face_rows = np.empty(len(faces), dtype=[("size", "u1"), ("indices", "<i4", (3,))])
        face_rows["size"] = 3
        face_rows["indices"] = faces
        body = vertex_rows.tobytes() + face_rows.tobytes()
    else:
        digits = {4: "%.9g", 8: "%.17g"}  # each float round-trips
        line = " ".join(digits[row[name].itemsize] if row[name].kind == "f" else "%d" for name in row.names) + "\n"
        table = np.stack([vertex_rows[name].astype(np.float64) for name in row.names], axis=1)
        text = (line * len(vertex_rows)) % tuple(table.ravel().tolist())
        text += ("3 %d %d %d\n" * len(faces)) % tuple(faces.ravel().tolist())
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
        items_at = np.repeat(at, sizes) + within_runs(sizes) * item.itemsize
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
        return parse_numbers(path, self.split[at], dtype, element)


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
            items = np.repeat(cursor + 1, sizes) + within_runs(sizes)
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
