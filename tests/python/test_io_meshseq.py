"""OBJ and PLY frame sequences: parsing details, round trips, real sequences, bad input."""

from __future__ import annotations

import dataclasses
import re
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from animlod import _core
from animlod.io import (
    FormatError,
    meshseq,
    obj,
    ply,
    read_mesh,
    read_obj,
    read_ply,
    read_sequence,
    write_mesh,
    write_obj,
    write_ply,
    write_sequence,
)
from animlod.io.obj import UnreadAttributesWarning
from animlod.io.ply import read_ply_attributes
from animlod.model import AnimatedMesh

# A unit square (quad) and a triangle on top, written with CRLF, comments, texture/normal
# statements, a/b/c corners and a negative (relative) index.
OBJ_TEXT = (
    "# square and roof\r\n"
    "o house\r\n"
    "v 0 0 0\r\n"
    "v 1 0 0\r\n"
    "v 1 1 0\r\n"
    "v 0 1 0\r\n"
    "vt 0 0\r\n"
    "vn 0 0 1\r\n"
    "f 1/1/1 2/1/1 3/1/1 4/1/1\r\n"
    "v 0.5 1.5 0 1.0\r\n"
    "f 4//1 3//1 -1//1\r\n"
)
EXPECTED_VERTICES = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 1.5, 0]], dtype=np.float32)
EXPECTED_FACES = np.array([[0, 1, 2], [0, 2, 3], [3, 2, 4]], dtype=np.int32)


def _write(path: Path, content: str | bytes) -> Path:
    path.write_bytes(content.encode() if isinstance(content, str) else content)
    return path


def _moving_mesh(frame_count: int = 3, seed: int = 0) -> AnimatedMesh:
    rng = np.random.default_rng(seed)
    frames = rng.normal(size=(frame_count, 5, 3)).astype(np.float32)
    return AnimatedMesh(EXPECTED_FACES, frames, fps=24.0)


def test_obj_statements_corners_quads_and_negative_indices(tmp_path: Path) -> None:
    vertices, faces = read_obj(_write(tmp_path / "house.obj", OBJ_TEXT))
    np.testing.assert_array_equal(vertices, EXPECTED_VERTICES)
    np.testing.assert_array_equal(faces, EXPECTED_FACES)
    assert vertices.dtype == np.float32 and faces.dtype == np.int32


def test_obj_texture_coordinates_and_normals_are_said_to_be_unread(tmp_path: Path) -> None:
    """OBJ frames with ``vt`` and ``vn`` lines: levels were written without them and nothing said
    so. One warning names the first frame; frames without them give none."""
    textured = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn\t0 0 1\nf 1/1/1 2/2/1 3/3/1\n"  # a tab too
    for index in range(3):
        (tmp_path / "textured" / f"frame{index}.obj").parent.mkdir(exist_ok=True)
        (tmp_path / "textured" / f"frame{index}.obj").write_text(textured)
    with pytest.warns(UnreadAttributesWarning) as caught:
        read_sequence(tmp_path / "textured")
    assert (
        len(caught) == 1
        and "frame0.obj" in str(caught[0].message)
        and "(vt lines) and normals (vn lines)" in str(caught[0].message)
    )
    (tmp_path / "plain.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", UnreadAttributesWarning)
        read_obj(tmp_path / "plain.obj")


def test_obj_texture_coordinates_are_read_per_corner(tmp_path: Path) -> None:
    """vt lines (u alone: v 0) and each corner's texture index, negative ones counting back from
    the last vt above the face; a quad fanned as its positions are."""
    text = ("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1 0\nvt\t0.5\nvn 0 0 1\n"
            "f 1/1/1 2/2/1 3/3/1 4/4/1\nf 1/5 3/-3 4/-2\n")  # fmt: skip
    (tmp_path / "quad.obj").write_text(text)
    with pytest.warns(UnreadAttributesWarning, match=r"4 of 7 face corners have normals \(vn\), the others none"):
        vertices, faces, texture, normals, _, _ = obj.read_obj_textured(tmp_path / "quad.obj")
    assert normals is None
    np.testing.assert_array_equal(faces, [[0, 1, 2], [0, 2, 3], [0, 2, 3]])
    np.testing.assert_array_equal(texture.uvs, [[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0]])
    np.testing.assert_array_equal(texture.corners, [[0, 1, 2], [0, 2, 3], [4, 2, 3]])
    # Round trip: written as v/vt corners, read back the same.
    obj.write_obj(tmp_path / "again.obj", vertices, faces, texture)
    again_vertices, again_faces, again, _, _, _ = obj.read_obj_textured(tmp_path / "again.obj")
    for read, written in ((again_vertices, vertices), (again_faces, faces), (again.uvs, texture.uvs),
                          (again.corners, texture.corners)):  # fmt: skip
        np.testing.assert_array_equal(read, written)


def test_a_frame_written_with_the_text_of_the_frame_before_is_written_as_alone(tmp_path: Path) -> None:
    """write_obj formats the vt and face lines once for a sequence's frames; a frame whose normals
    split otherwise, or of other faces, texture or materials, gets text of its own."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]], np.float32)
    faces = np.array([[0, 1, 2], [1, 3, 2]], np.int32)
    texture = obj.ObjTexture(np.array([[0, 0], [1, 0], [0, 1], [1, 1]], np.float32), faces)
    materials = obj.ObjMaterials(("a.mtl",), ("skin", "cloth"), np.array([1, 0], np.int32))
    smooth = obj.ObjNormals(np.array([[0, 0, 1], [0, 0.6, 0.8]], np.float32), np.array([[0, 0, 0], [0, 1, 0]]))
    split = obj.ObjNormals(smooth.normals, np.array([[0, 0, 0], [1, 1, 1]]))
    shared = obj.write_obj(tmp_path / "f0.obj", positions, faces, texture, smooth, None, materials)
    cases = {
        "same": (positions + 1, faces, texture, smooth, materials),
        "normals split otherwise": (positions, faces, texture, split, materials),
        "other faces": (positions, faces[:, ::-1].copy(), texture, smooth, materials),
        "other texture": (positions, faces, texture._replace(uvs=texture.uvs[::-1].copy()), smooth, materials),
        "no materials": (positions, faces, texture, smooth, None),
    }
    for case, (frame, frame_faces, frame_texture, frame_normals, frame_materials) in cases.items():
        after = obj.write_obj(tmp_path / "f1.obj", frame, frame_faces, frame_texture, frame_normals, None,
                              frame_materials, shared)  # fmt: skip
        obj.write_obj(tmp_path / "alone.obj", frame, frame_faces, frame_texture, frame_normals, None, frame_materials)
        assert (tmp_path / "f1.obj").read_bytes() == (tmp_path / "alone.obj").read_bytes(), case
        assert (after is shared) == (case == "same"), case


def test_obj_numbers_are_written_as_python_formats_them() -> None:
    # The core's lines (std::to_chars) against Python's own .9g, which the writer used before them:
    # float32 values of every magnitude, zeros of both signs, and halfway cases of the 9th digit.
    rng = np.random.default_rng(8)
    values = (rng.normal(size=30000) * 10.0 ** rng.uniform(-40, 40, 30000)).astype(np.float32).astype(np.float64)
    values = np.concatenate([values, [0.0, -0.0, 1.0, 0.1, 1e-5, 1e-4, 123456789.5, 1234567890.0, 2.0**-149]])
    values = values[: len(values) // 3 * 3].reshape(-1, 3)
    expected = "".join(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in values.tolist()).encode()
    assert _core.decimal_rows(values, "v ") == expected
    assert (
        _core.decimal_rows(values[:, :2], "vt ", 17)
        == "".join(f"vt {u:.17g} {v:.17g}\n" for u, v in values[:, :2].tolist()).encode()
    )
    with pytest.raises(ValueError, match=r"values: expected shape \(N, K\), got \(3,\)"):
        _core.decimal_rows(np.zeros(3), "v ")


def test_obj_normals_are_read_per_corner_and_written_back(tmp_path: Path) -> None:
    """vn lines and each corner's normal index (v//vn, v/vt/vn; negative ones counting back), and
    both attributes written back as v/vt/vn corners."""
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvn 0 0.6 0.8\nf 1//1 2//2 3//-1\nf 2//1 4//2 3//-2\n"
    (tmp_path / "quad.obj").write_text(text)
    vertices, faces, texture, normals, _, _ = obj.read_obj_textured(tmp_path / "quad.obj")
    assert texture is None
    np.testing.assert_array_equal(normals.normals, np.float32([[0, 0, 1], [0, 0.6, 0.8]]))
    np.testing.assert_array_equal(normals.corners, [[0, 1, 1], [0, 1, 0]])
    uvs = obj.ObjTexture(np.array([[0, 0], [1, 1]], np.float32), np.array([[0, 1, 0], [1, 1, 0]], np.int32))
    obj.write_obj(tmp_path / "again.obj", vertices, faces, uvs, normals)
    assert "f 1/1/1 2/2/2 3/1/2" in (tmp_path / "again.obj").read_text()
    _, _, again_uvs, again_normals, _, _ = obj.read_obj_textured(tmp_path / "again.obj")
    for read, written in zip((*again_uvs, *again_normals), (*uvs, *normals)):
        np.testing.assert_array_equal(read, written)
    (tmp_path / "bad.obj").write_text(text.replace("3//-2", "3//5"))
    with pytest.raises(FormatError, match=re.escape("face 1 (line 8): normal index 5 is outside the 2 normals")):
        obj.read_obj_textured(tmp_path / "bad.obj")


def test_flat_normals_of_coplanar_faces_are_written_once() -> None:
    # Coplanar faces' area-weighted sums differ in their last bits: a flat box's 6 normals were
    # written as up to 37 vn lines.
    from animlod.normals import Shading

    rng = np.random.default_rng(3)
    ring = 2 * np.pi * (np.arange(12) + rng.uniform(0.0, 0.5, 12)) / 12
    xy = np.c_[rng.uniform(0.5, 2.0, 12) * np.cos(ring), rng.uniform(0.5, 2.0, 12) * np.sin(ring)]
    plane = np.c_[np.r_[[[0.0, 0.0]], xy], np.r_[0.0, 0.3 * xy[:, 0] + 0.7 * xy[:, 1]]].astype(np.float32)
    fan = np.stack([np.zeros(12, int), 1 + np.arange(12), 1 + (np.arange(12) + 1) % 12], axis=1).astype(np.int32)
    normals = meshseq.rebuilt_normals(plane, fan, Shading(0.0, False))
    assert len(normals.normals) == 1 and np.linalg.norm(normals.normals[0]) == pytest.approx(1.0, abs=1e-6)


@pytest.mark.parametrize(
    "faces, problem",
    [
        ("f 1/1 2/2 3/9\n", "face 0 (line 7): texture index 9 is outside the 3 texture coordinates"),
        ("f 1/1 2/2 3/x\n", "face 0 (line 7)"),
        ("vt 0 nan\nf 1/1 2/2 3/3\n", "texture coordinate 3 (line 7)"),
    ],
)
def test_bad_texture_coordinates_name_the_line(tmp_path: Path, faces: str, problem: str) -> None:
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n" + faces)
    with pytest.raises(FormatError, match=re.escape(problem)):
        obj.read_obj_textured(tmp_path / "bad.obj")


def test_a_texture_coordinates_extra_values_are_dropped_as_a_vertexs_are(tmp_path: Path) -> None:
    (tmp_path / "extra.obj").write_text(
        "v 0 0 0 1 abc\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0 0 abc\nvt 0.5\nf 1/1 2/2 3/3\n"
    )
    _, _, texture, _, _, _ = obj.read_obj_textured(tmp_path / "extra.obj")
    np.testing.assert_array_equal(texture.uvs, [[0, 0], [1, 0], [0.5, 0]])


def test_texture_coordinates_on_some_corners_only_are_left_out_with_a_warning(tmp_path: Path) -> None:
    (tmp_path / "mixed.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 2 4 3\n")
    with pytest.warns(UnreadAttributesWarning, match="3 of 6 face corners have texture coordinates"):
        _, faces, texture, _, _, _ = obj.read_obj_textured(tmp_path / "mixed.obj")
    assert texture is None and len(faces) == 2


def test_a_textured_sequence_has_a_vertex_per_position_and_texture_coordinate(tmp_path: Path) -> None:
    """A seam: vertices 0 and 2 carry two texture coordinates each, so 4 positions give 6
    vertices. Frames whose texture coordinates differ from the first's are read without them."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], np.float32)
    faces = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 0]], np.int32)
    texture = obj.ObjTexture(np.array([[0, 0], [1, 0], [0, 1], [1, 1], [0.5, 0.5], [0.2, 0.2]], np.float32),
                             np.array([[0, 1, 2], [1, 3, 2], [4, 3, 5]], np.int32))  # fmt: skip
    (tmp_path / "seam").mkdir()
    for index in range(3):
        obj.write_obj(tmp_path / "seam" / f"f{index}.obj", positions + index, faces, texture)
    mesh, split, shading, _, _, _ = meshseq.read_textured_sequence(tmp_path / "seam")
    assert mesh.vertex_count == 6 and shading is None and mesh.frame_count == 3
    np.testing.assert_array_equal(mesh.frames[2], positions[split.points] + 2)
    np.testing.assert_array_equal(split.uvs[mesh.faces], texture.uvs[texture.corners])
    # Written back: one v per position, the seam's two texture coordinates apart.
    paths = write_sequence(tmp_path / "out", mesh, texture=split)
    vertices, written_faces, written, _, _, _ = obj.read_obj_textured(paths[1])
    np.testing.assert_array_equal(vertices[written_faces], positions[faces] + 1)
    np.testing.assert_array_equal(written.uvs[written.corners], texture.uvs[texture.corners])
    # As PLY: a row per vertex, the seam's copies each with its own texture coordinate.
    ply_paths = write_sequence(tmp_path / "ply", mesh, fmt="ply", texture=split)
    ply_vertices, ply_faces, ply_uvs, _, _ = read_ply_attributes(ply_paths[1])
    np.testing.assert_array_equal(ply_vertices, positions[split.points] + 1)
    np.testing.assert_array_equal(ply_uvs[ply_faces], texture.uvs[texture.corners])
    # A frame with other texture coordinates: none are carried, and a warning says why.
    obj.write_obj(tmp_path / "seam" / "f2.obj", positions, faces, texture._replace(uvs=texture.uvs[::-1].copy()))
    with pytest.warns(UnreadAttributesWarning, match=r"f2.obj: has texture coordinates other than f0.obj's"):
        mesh, split, _, _, _, _ = meshseq.read_textured_sequence(tmp_path / "seam")
    assert split is None and mesh.vertex_count == 4
    # The first frame without them, the others with: the same.
    obj.write_obj(tmp_path / "seam" / "f0.obj", positions, faces)
    with pytest.warns(UnreadAttributesWarning, match=r"f1.obj: has texture coordinates, and f0.obj has none"):
        mesh, split, _, _, _, _ = meshseq.read_textured_sequence(tmp_path / "seam")
    assert split is None


def test_ascii_ply_with_mixed_polygons_and_extra_properties(tmp_path: Path) -> None:
    text = (
        "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\n"
        "element vertex 5\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\nproperty uchar red\r\n"
        "element face 2\r\nproperty uchar flags\r\nproperty list uchar int vertex_indices\r\nproperty float quality\r\n"
        "end_header\r\n"
        "0 0 0 255\r\n1 0 0 0\r\n1 1 0 0\r\n0 1 0 0\r\n0.5 1.5 0 9\r\n"
        "7 4 0 1 2 3 0.5\r\n"
        "7 3 3 2 4 0.25\r\n"
    )
    # The colour and the faces' flags and quality were dropped without a word.
    with pytest.warns(
        UnreadAttributesWarning, match="its properties vertex red, face flags, face quality are not read"
    ):
        vertices, faces = read_ply(_write(tmp_path / "house.ply", text))
    np.testing.assert_array_equal(vertices, EXPECTED_VERTICES)
    np.testing.assert_array_equal(faces, EXPECTED_FACES)


def test_binary_big_endian_ply(tmp_path: Path) -> None:
    header = (
        "ply\nformat binary_big_endian 1.0\nelement vertex 5\nproperty double x\nproperty double y\n"
        "property double z\nelement face 3\nproperty list uchar uint vertex_index\nend_header\n"
    )
    faces = np.zeros(3, dtype=[("size", "u1"), ("indices", ">u4", (3,))])
    faces["size"], faces["indices"] = 3, EXPECTED_FACES
    body = EXPECTED_VERTICES.astype(">f8").tobytes() + faces.tobytes()
    vertices, read_faces = read_ply(_write(tmp_path / "house.ply", header.encode() + body))
    np.testing.assert_array_equal(vertices, EXPECTED_VERTICES)
    np.testing.assert_array_equal(read_faces, EXPECTED_FACES)


def _polygon_ply(binary: bool, sizes: np.ndarray, corners: np.ndarray, vertices: np.ndarray, uv: bool = False) -> bytes:
    """A PLY of polygons of the given sizes, each face with a uchar before its list and a float
    after it, as exporters add flags and quality; with ``uv`` also a texcoord list (two floats a
    corner, as MeshLab writes them) after the corners."""
    header = (
        f"ply\nformat {'binary_little_endian' if binary else 'ascii'} 1.0\nelement vertex {len(vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(sizes)}\nproperty uchar flags\nproperty list uchar int vertex_indices\n"
        + ("property list uchar float texcoord\n" if uv else "")
        + "property float quality\nend_header\n"
    ).encode()
    rows = np.split(corners, np.cumsum(sizes)[:-1])
    uvs = [np.linspace(0.0, 1.0, 2 * len(r), dtype=np.float32) for r in rows] if uv else [None] * len(rows)
    if not binary:
        lines = [" ".join(map(str, v)) for v in vertices]
        for r, w in zip(rows, uvs):
            texcoord = f" {len(w)} {' '.join(map(str, w))}" if uv else ""
            lines.append(f"7 {len(r)} {' '.join(map(str, r))}{texcoord} 0.5")
        return header + ("\n".join(lines) + "\n").encode()
    faces = b"".join(
        b"\x07" + bytes([len(r)]) + r.astype("<i4").tobytes()
        + (bytes([len(w)]) + w.astype("<f4").tobytes() if uv else b"") + np.float32(0.5).tobytes()
        for r, w in zip(rows, uvs)
    )  # fmt: skip
    return header + vertices.astype("<f4").tobytes() + faces


@pytest.mark.parametrize("uv", [False, True])
def test_binary_ply_with_mixed_polygons_reads_like_the_ascii_one(tmp_path: Path, uv: bool) -> None:
    # Blender writes quads and triangles in one binary list, MeshLab a texcoord list beside it;
    # a row's place follows from the lengths of all rows before it.
    rng = np.random.default_rng(5)
    sizes = rng.integers(3, 6, 1000)
    vertices = rng.random((50, 3)).astype(np.float32)
    corners = rng.integers(0, 50, int(sizes.sum()))
    ascii_ply = read_ply(_write(tmp_path / "a.ply", _polygon_ply(False, sizes, corners, vertices, uv)))
    binary = _write(tmp_path / "b.ply", _polygon_ply(True, sizes, corners, vertices, uv))
    for got, expected in zip(read_ply(binary), ascii_ply):
        np.testing.assert_array_equal(got, expected)
    assert len(ascii_ply[1]) == int((sizes - 2).sum())
    cut = _write(tmp_path / "cut.ply", binary.read_bytes()[:-3])
    assert _error(cut) == f"{cut}: element face: file ends before its 1000 rows"


def test_binary_ply_with_lists_of_one_length_is_one_table(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # Triangles with MeshLab's texcoord list beside them: every row has one size, so the rows are
    # one structured array. Following the rows byte by byte took 1.6 GB and 11 s for 1M faces.
    rng = np.random.default_rng(6)
    vertices = rng.random((50, 3)).astype(np.float32)
    triangles, mixed = np.full(1000, 3), rng.integers(3, 6, 1000)
    expected = {}
    for name, sizes in (("triangles", triangles), ("mixed", mixed)):
        corners = rng.integers(0, 50, int(sizes.sum()))
        ascii_ply = _write(tmp_path / f"{name}_ascii.ply", _polygon_ply(False, sizes, corners, vertices, uv=True))
        expected[name] = read_ply(ascii_ply)
        _write(tmp_path / f"{name}.ply", _polygon_ply(True, sizes, corners, vertices, uv=True))

    def row_by_row(*args: object) -> None:
        raise AssertionError("read row by row")

    monkeypatch.setattr(ply, "_read_rows_of_lists", row_by_row)
    for got, wanted in zip(read_ply(tmp_path / "triangles.ply"), expected["triangles"]):
        np.testing.assert_array_equal(got, wanted)
    with pytest.raises(AssertionError, match="read row by row"):  # control: rows of several sizes
        read_ply(tmp_path / "mixed.ply")
    monkeypatch.undo()
    for got, wanted in zip(read_ply(tmp_path / "mixed.ply"), expected["mixed"]):
        np.testing.assert_array_equal(got, wanted)


@pytest.mark.parametrize("binary", [True, False])
def test_ply_write_read_is_exact(tmp_path: Path, binary: bool) -> None:
    mesh = _moving_mesh()
    write_ply(tmp_path / "f.ply", mesh.frames[1], mesh.faces, binary=binary)
    vertices, faces = read_ply(tmp_path / "f.ply")
    np.testing.assert_array_equal(vertices, mesh.frames[1])
    np.testing.assert_array_equal(faces, mesh.faces)


@pytest.mark.parametrize("fmt", ["obj", "ply"])
def test_sequence_round_trip_is_exact(tmp_path: Path, fmt: str) -> None:
    mesh = _moving_mesh(frame_count=4)
    paths = write_sequence(tmp_path / "seq", mesh, fmt=fmt, stem="pose")
    assert [path.name for path in paths] == [f"pose_{index:04d}.{fmt}" for index in range(4)]
    assert sorted(path.name for path in (tmp_path / "seq").iterdir()) == [path.name for path in paths]  # no temp files
    back = read_sequence(tmp_path / "seq", fps=24.0)
    np.testing.assert_array_equal(back.frames, mesh.frames)
    np.testing.assert_array_equal(back.faces, mesh.faces)
    assert back.fps == 24.0


def test_folder_and_glob_use_natural_order_and_lists_keep_theirs(tmp_path: Path) -> None:
    mesh = _moving_mesh(frame_count=3)
    for name, vertices in zip(["f10.obj", "f2.obj", "f1.obj"], mesh.frames[::-1]):
        write_mesh(tmp_path / f"{name[:-4]}_0000.obj", vertices, mesh.faces)
    # Frames are f1 = frame 0, f2 = frame 1, f10 = frame 2.
    np.testing.assert_array_equal(read_sequence(tmp_path).frames, mesh.frames)
    np.testing.assert_array_equal(read_sequence(str(tmp_path / "f*_0000.obj")).frames, mesh.frames)
    listed = [tmp_path / "f10_0000.obj", tmp_path / "f1_0000.obj"]
    np.testing.assert_array_equal(read_sequence(listed).frames, mesh.frames[[2, 0]])
    np.testing.assert_array_equal(read_sequence(tmp_path / "f2_0000.obj").frames, mesh.frames[[1]])
    # Hidden files are no frames (macOS leaves "._" resource forks beside every file it copies),
    # and a frame whose name looks like a pattern is a file.
    (tmp_path / "._f1_0000.obj").write_bytes(b"\x00\x05\x16\x07")
    np.testing.assert_array_equal(read_sequence(tmp_path).frames, mesh.frames)
    (tmp_path / "f2_0000.obj").rename(tmp_path / "take[2].obj")
    np.testing.assert_array_equal(read_sequence(tmp_path / "take[2].obj").frames, mesh.frames[[1]])


@pytest.mark.parametrize(
    ("names", "order"),
    [
        (["frame.0001.obj", "frame.-001.obj", "frame.0000.obj", "frame.-002.obj"], [3, 1, 2, 0]),  # Houdini
        (["cloth_1.obj", "cloth_-1.obj", "cloth_0.obj"], [1, 2, 0]),
        (["mesh-002.obj", "mesh-001.obj", "mesh-010.obj"], [1, 0, 2]),  # a dash after a letter separates
    ],
)
def test_frames_numbered_below_zero_come_first(tmp_path: Path, names: list[str], order: list[int]) -> None:
    """Negative frame numbers sorted after every other frame: a sequence started before frame 0
    was read with its first frames last."""
    for name in names:
        (tmp_path / name).write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    assert [path.name for path in meshseq.frame_files(tmp_path)] == [names[index] for index in order]


@pytest.mark.parametrize(
    ("names", "order"),
    [
        # Houdini's sub-frames ($FF): natural order read 0.5 before 0.25, and 1.25 before 1.
        (["mesh.1.obj", "mesh.0.5.obj", "mesh.1.25.obj", "mesh.0.25.obj", "mesh.0.75.obj"], [3, 1, 4, 0, 2]),
        (["mesh.-0.5.obj", "mesh.0.obj", "mesh.-1.obj", "mesh.0.25.obj"], [2, 0, 1, 3]),
        # Houdini's default name, $HIPNAME.$OS.$FF, of a node whose name ends in a digit.
        (
            [
                "untitled.rop_geometry1.1.25.obj",
                "untitled.rop_geometry1.2.obj",
                "untitled.rop_geometry1.1.obj",
                "untitled.rop_geometry1.1.5.obj",
            ],
            [2, 0, 3, 1],
        ),
        # Whole frames written with a fraction of zeros.
        (["mesh.1.5.obj", "mesh.1.0.obj", "mesh.2.0.obj", "mesh.1.25.obj"], [1, 3, 0, 2]),
        # 2.1 and 2.10 are one value as decimals: versions, in natural order.
        (["v2.10.obj", "v2.2.obj", "v2.1.obj", "v2.9.obj", "v2.obj"], [4, 2, 1, 3, 0]),
        # Every name with a fraction: a shot and its frames, in natural order.
        (["shot.1.10.obj", "shot.1.2.obj", "shot.1.9.obj"], [1, 2, 0]),
        # Other prefixes: separate names, in natural order.
        (["a.0.5.obj", "b.0.25.obj"], [0, 1]),
    ],
)
def test_sub_frames_are_read_in_the_order_of_their_values(tmp_path: Path, names: list[str], order: list[int]) -> None:
    for name in names:
        (tmp_path / name).write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    expected = [names[index] for index in order]
    assert [path.name for path in meshseq.frame_files(tmp_path)] == expected
    assert [path.name for path in meshseq.sequence_paths(str(tmp_path / "*.obj"))] == expected


# --- later OBJ frames read from their v lines alone ---------------------------------------------


def _grid_frame(frame: int) -> str:
    """Frame ``frame`` of a textured, coloured 3 x 3 grid as exporters write a sequence: its
    comment, positions, colours, normals and material library its own (Blender names one after
    each frame), every other line the first frame's byte for byte. The last quad's corners at
    positions 5, 6 and 9 take texture coordinates of their own (a seam); two materials."""
    rng = np.random.default_rng(frame)
    grid = np.stack(np.meshgrid(np.arange(3), np.arange(3)), axis=-1).reshape(-1, 2)
    positions = np.column_stack([grid, rng.normal(size=9)])
    colours = rng.uniform(size=(9, 3))
    uvs = np.concatenate([grid / 2, [[0.9, 0.5], [0.9, 0.9], [0.5, 0.9]]])
    lines = [f"# frame {frame}", f"mtllib grid_{frame}.mtl", "o grid"]
    lines += ["v " + " ".join(f"{value:.6g}" for value in row) for row in np.column_stack([positions, colours])]
    lines += [f"vt {u:.6g} {v:.6g}" for u, v in uvs]
    lines += [f"vn 0 {0.1 * frame:.6g} 1"]
    lines += ["usemtl skin", "f 1/1/1 2/2/1 5/5/1 4/4/1", "f 2/2/1 3/3/1 6/6/1 5/5/1"]
    lines += ["usemtl cloth", "f 4/4/1 5/5/1 8/8/1 7/7/1", "f 5/10/1 6/11/1 9/12/1 8/8/1"]
    return "\n".join(lines) + "\n"


def _grid_frames(folder: Path, count: int = 3) -> list[Path]:
    folder.mkdir()
    return [_write(folder / f"f{frame}.obj", _grid_frame(frame)) for frame in range(count)]


def _spy_on_fits(monkeypatch: pytest.MonkeyPatch) -> list[bool]:
    """Whether each later frame read since fitted the first frame's template (read from its v lines
    alone)."""
    fitted, fits = [], obj.ObjTemplate.fits
    monkeypatch.setattr(obj.ObjTemplate, "fits", lambda *args: fitted.append(fits(*args)) or fitted[-1])
    return fitted


def _assert_same_read(read: object, other: object) -> None:
    """Two reads equal part by part: arrays (with their types), names, flags."""
    if dataclasses.is_dataclass(read) or isinstance(read, tuple):
        assert type(read) is type(other)
        parts = (dataclasses.astuple(value) if dataclasses.is_dataclass(value) else value for value in (read, other))
        for mine, theirs in zip(*parts, strict=True):
            _assert_same_read(mine, theirs)
    else:
        assert np.asarray(read).dtype == np.asarray(other).dtype
        np.testing.assert_array_equal(read, other)


@pytest.mark.parametrize("textured", [False, True])
def test_later_obj_frames_read_from_their_v_lines_alone_read_as_in_full(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, textured: bool
) -> None:
    paths = _grid_frames(tmp_path / "grid", 4)
    read = meshseq.read_textured_sequence if textured else read_sequence
    fitted = _spy_on_fits(monkeypatch)
    with warnings.catch_warnings(record=True) as quick_warnings:
        warnings.simplefilter("always")
        quick = read(paths)
    assert fitted == [True, True, True]  # the comments differ: they are no statement
    monkeypatch.setattr(obj.ObjTemplate, "fits", lambda *args: False)
    with warnings.catch_warnings(record=True) as full_warnings:
        warnings.simplefilter("always")
        full = read(paths)
    _assert_same_read(quick, full)
    assert [str(w.message) for w in quick_warnings] == [str(w.message) for w in full_warnings]
    if textured:  # each frame's own positions and colours, the seam's copies and the materials
        assert quick.mesh.vertex_count == 13 and len(quick.colours.values) == 4  # seam and material copies
        np.testing.assert_array_equal(quick.mesh.frames[3], obj.read_obj_textured(paths[3]).vertices[quick.points])
        later = obj.read_obj_template(paths[0], textured=True)[1].read(paths[2])[0]
        assert later.materials.libraries == ("grid_2.mtl",) == obj.read_obj_textured(paths[2]).materials.libraries


def test_frames_alike_after_a_first_frame_of_its_own_are_read_from_their_v_lines(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Blender merges equal normals: its rest pose, exported first, has fewer vn lines than the
    frames after it. The frame after a frame that did not fit is read by that frame's lines."""
    paths = _grid_frames(tmp_path / "grid", 4)
    _write(paths[0], paths[0].read_text().replace("vn 0 0 1\n", "vn 0 0 1\nvn 0 1 0\n"))
    fitted = _spy_on_fits(monkeypatch)
    quick = meshseq.read_textured_sequence(paths)
    assert fitted == [False, True, True]
    monkeypatch.setattr(obj.ObjTemplate, "fits", lambda *args: False)
    _assert_same_read(quick, meshseq.read_textured_sequence(paths))


def test_a_later_frame_whose_faces_or_texture_differ_is_read_in_full(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The same number of lines, the v lines where the first frame's are: the bytes tell them apart.
    paths = _grid_frames(tmp_path / "grid")
    text = paths[2].read_text()
    _write(paths[2], text.replace("f 1/1/1 2/2/1 5/5/1 4/4/1", "f 2/2/1 5/5/1 4/4/1 1/1/1"))  # the other diagonal
    fitted = _spy_on_fits(monkeypatch)
    with pytest.warns(UserWarning, match=r"f2.obj: 1 of the 3 frames \(this the first\) triangulate some polygons"):
        sequence = meshseq.read_textured_sequence(paths)
    assert fitted == [True, False] and sequence.texture is not None
    _write(paths[2], text.replace("vt 0.5 0\n", "vt 0.5 0.25\n"))
    with pytest.warns(UnreadAttributesWarning, match=r"f2.obj: has texture coordinates other than f0.obj's"):
        sequence = meshseq.read_textured_sequence(paths)
    assert sequence.texture is None and sequence.mesh.vertex_count == 12  # the materials' copies alone
    _write(paths[2], text.replace("mtllib grid_2.mtl", "f 1/1/1 2/2/1 5/5/1"))  # a face for the library
    with pytest.raises(FormatError, match=r"f2.obj: "):
        meshseq.read_textured_sequence(paths)
    assert fitted[-1] is False


def test_a_later_frame_that_gives_faces_other_materials_is_named(tmp_path: Path) -> None:
    paths = _grid_frames(tmp_path / "grid")
    _write(paths[1], paths[1].read_text().replace("usemtl skin", "usemtl cloth"))
    with pytest.warns(UnreadAttributesWarning, match=r"f1.obj: gives some faces other materials than f0.obj"):
        sequence = meshseq.read_textured_sequence(paths)
    assert sequence.materials.names == ("skin", "cloth")  # the first frame's


@pytest.mark.parametrize(("value", "reason"), [("x1", "'x1' is not a number or out of range"), ("nan", "are not")])
def test_a_bad_v_line_in_a_later_frame_names_that_file_and_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, value: str, reason: str
) -> None:
    paths = _grid_frames(tmp_path / "grid")
    lines = paths[1].read_text().splitlines(keepends=True)
    lines[5] = f"v 2 {value} 0 0.5 0.5 0.5\n"  # vertex 2, after the comment, mtllib and o lines
    _write(paths[1], "".join(lines))
    fitted = _spy_on_fits(monkeypatch)
    with pytest.raises(FormatError) as caught:
        meshseq.read_textured_sequence(paths)
    assert fitted == [True]  # read from its v lines alone
    assert str(caught.value).startswith(f"{paths[1]}: vertex 2 (line 6): ") and reason in str(caught.value)


@pytest.mark.parametrize("replaced", ["# frame 1", "vn 0 0.1 1"])
def test_a_later_frame_with_another_number_of_v_lines_is_refused(tmp_path: Path, replaced: str) -> None:
    # As many lines as the first frame; where a vn line gives way, the lines kept are the first's.
    paths = _grid_frames(tmp_path / "grid")
    _write(paths[1], paths[1].read_text().replace(replaced, "v 9 9 9 0 0 0"))
    message = f"{paths[1]}: vertices: 10 vertices, but the first frame f0.obj has 9"
    for read in (read_sequence, meshseq.read_textured_sequence):
        with pytest.raises(FormatError) as caught:
            read(paths)
        assert str(caught.value) == message


# --- real sequences (SOURCES.md) ------------------------------------------------------------


@pytest.mark.parametrize(
    ("folder", "frames", "vertices", "faces"),
    [("crane", 12, 10002, 20000), ("face-poses", 4, 29299, 57836)],
)
def test_real_sequence_loads_with_documented_stats(
    data_dir: Path, folder: str, frames: int, vertices: int, faces: int
) -> None:
    mesh = read_sequence(data_dir / "meshseq" / folder)
    assert mesh.frames.shape == (frames, vertices, 3)
    assert mesh.faces.shape == (faces, 3)
    assert mesh.faces.min() == 0 and mesh.faces.max() == vertices - 1


def test_crane_first_vertex_matches_the_file(data_dir: Path) -> None:
    mesh = read_sequence(data_dir / "meshseq" / "crane")
    # mesh_0048.obj: the first "v" line is "v 0.498967 0.482328 -0.258473", the first "f" "f 15 57 9818".
    np.testing.assert_array_equal(mesh.frames[0, 0], np.float32([0.498967, 0.482328, -0.258473]))
    np.testing.assert_array_equal(mesh.faces[0], [14, 56, 9817])


# --- bad input --------------------------------------------------------------------------------


def _error(path: Path) -> str:
    with pytest.raises(FormatError) as caught:
        read_sequence(path) if path.is_dir() else read_mesh(path)
    return str(caught.value)


def test_obj_face_index_out_of_range(tmp_path: Path) -> None:
    path = _write(tmp_path / "bad.obj", OBJ_TEXT.replace("f 4//1 3//1 -1//1", "f 4 3 6"))
    assert _error(path) == f"{path}: face 1 (line 11): vertex index 6 is outside the 5 vertices"


@pytest.mark.parametrize("index", ["0", "-6"])
def test_obj_zero_or_too_negative_index(tmp_path: Path, index: str) -> None:
    path = _write(tmp_path / "bad.obj", OBJ_TEXT.replace("-1//1", f"{index}//1"))
    assert _error(path) == f"{path}: face 1 (line 11): vertex index {index} is outside the 5 vertices"


def test_comments_at_the_end_of_obj_statements_are_ignored(tmp_path: Path) -> None:
    commented = "".join(line.rstrip("\r\n") + "  # note\n" for line in OBJ_TEXT.splitlines(True))
    vertices, faces = read_obj(_write(tmp_path / "commented.obj", commented))
    np.testing.assert_array_equal(vertices, EXPECTED_VERTICES)
    np.testing.assert_array_equal(faces, EXPECTED_FACES)


def test_obj_lines_ending_in_a_backslash_continue_on_the_next(tmp_path: Path) -> None:
    # The OBJ specification lets a backslash end a line to continue the statement (spaces may
    # follow it); a comment ends at its line's end even after one, like this Windows path.
    continued = (
        OBJ_TEXT.replace("# square and roof", "# saved to C:\\models\\")
        .replace("v 1 0 0", "v 1 \\\r\n  0 \\ \t\r\n0")
        .replace("f 1/1/1 2/1/1", "f 1/1/1 \\\r\n2/1/1")
        .replace("f 4//1 3//1 -1//1", "f 4//1 3//1 \\  # the roof\r\n-1//1")
    )
    vertices, faces = read_obj(_write(tmp_path / "continued.obj", continued))
    np.testing.assert_array_equal(vertices, EXPECTED_VERTICES)
    np.testing.assert_array_equal(faces, EXPECTED_FACES)
    # Errors name the line a statement starts on; the lines after it keep their numbers.
    path = _write(tmp_path / "bad.obj", continued.replace("-1//1", "6"))
    assert _error(path) == f"{path}: face 1 (line 14): vertex index 6 is outside the 5 vertices"
    path = _write(tmp_path / "bad.obj", continued.replace("v 1 1 0", "v 1 x1 0"))
    assert _error(path) == f"{path}: vertex 2 (line 7): 'x1' is not a number or out of range"
    # A backslash that ends the file continues onto nothing.
    vertices, faces = read_obj(_write(tmp_path / "last.obj", OBJ_TEXT + "f 1 2 \\\n3 \\"))
    np.testing.assert_array_equal(faces, np.concatenate([EXPECTED_FACES, [[0, 1, 2]]]))


def test_obj_faces_with_two_corners_are_left_out_with_a_warning(tmp_path: Path) -> None:
    # pybullet's samurai_monastry.obj has 201 two-vertex faces among its 125k.
    path = _write(tmp_path / "lines.obj", OBJ_TEXT.replace("f 4//1 3//1 -1//1", "f 4 3"))
    with pytest.warns(UserWarning, match=r"lines.obj: face 1 \(line 11\): 1 of 2 faces have fewer than 3 vertices"):
        vertices, faces = read_obj(path)
    np.testing.assert_array_equal(faces, EXPECTED_FACES[:2])  # the square fanned, the roof line left out
    only = _write(tmp_path / "only.obj", "v 0 0 0\nv 1 0 0\nf 1 2\nf 2 1\n")
    assert _error(only) == f"{only}: face 0 (line 3): needs at least 3 vertices, has 2; so does every face"
    bad = _write(tmp_path / "bad.obj", OBJ_TEXT.replace("f 4//1 3//1 -1//1", "f 4 9"))
    assert _error(bad) == f"{bad}: face 1 (line 11): vertex index 9 is outside the 5 vertices"  # still checked


@pytest.mark.parametrize(
    ("value", "reason"), [("nan", "are not finite"), ("1e999", "are not finite"), ("x1", "'x1' is not a number")]
)
def test_obj_bad_coordinate(tmp_path: Path, value: str, reason: str) -> None:
    path = _write(tmp_path / "bad.obj", OBJ_TEXT.replace("v 1 1 0", f"v 1 {value} 0"))
    message = _error(path)
    assert message.startswith(f"{path}: vertex 2 (line 5): ") and reason in message


def test_frames_with_different_vertex_counts(tmp_path: Path) -> None:
    _write(tmp_path / "a_1.obj", OBJ_TEXT)
    _write(tmp_path / "a_2.obj", OBJ_TEXT.replace("v 0.5 1.5 0 1.0\r\n", "v 0.5 1.5 0\r\nv 9 9 9\r\n"))
    assert _error(tmp_path) == f"{tmp_path / 'a_2.obj'}: vertices: 6 vertices, but the first frame a_1.obj has 5"


@pytest.mark.parametrize(
    ("old", "new", "face", "vertices"),
    [
        ("f 4//1 3//1 -1//1", "f 4 2 5", "face 1 (line 11)", [3, 1, 4]),  # the triangle after the quad's two
        ("f 1/1/1 2/1/1 3/1/1 4/1/1", "f 1/1/1 2/1/1 5/1/1 4/1/1", "face 0 (line 9)", [0, 1, 4]),  # the quad's first
    ],
)
def test_frames_with_different_faces(tmp_path: Path, old: str, new: str, face: str, vertices: list[int]) -> None:
    _write(tmp_path / "a_1.obj", OBJ_TEXT)
    _write(tmp_path / "a_2.obj", OBJ_TEXT.replace(old, new))
    message = _error(tmp_path)
    # The face and its line as the file has them; the triangle's vertices counted from 0 unlike OBJ's
    # own indices (f 4 2 5), and said so.
    expected = (f"{face}: its triangle on vertices {vertices} (counted from 0) is no triangle of the first frame "
                "a_1.obj, and the frame's triangles are not a re-triangulation of the first frame's "
                "polygons")  # fmt: skip
    assert message == f"{tmp_path / 'a_2.obj'}: {expected}"


@pytest.mark.filterwarnings("ignore:.*fewer than 3 vertices")
@pytest.mark.parametrize("binary", [None, False, True])  # None: OBJ
def test_a_face_that_differs_is_named_as_the_file_lists_it(tmp_path: Path, binary: bool | None) -> None:
    # A line of two corners, a pentagon (three triangles) and a triangle: the triangle is the
    # file's third face and the reader's fourth triangle.
    vertices = np.random.default_rng(1).random((7, 3)).astype(np.float32)
    sizes, corners = np.array([2, 5, 3]), np.array([0, 1, 0, 1, 2, 3, 4, 4, 3, 5])
    moved = corners.copy()
    moved[-1] = 6
    for name, rows in (("a_1", corners), ("a_2", moved)):
        if binary is None:
            faces = np.split(rows + 1, np.cumsum(sizes)[:-1])
            text = "".join(f"v {x} {y} {z}\n" for x, y, z in vertices) + "".join(
                "f " + " ".join(map(str, face)) + "\n" for face in faces
            )
            _write(tmp_path / f"{name}.obj", text)
        else:
            _write(tmp_path / f"{name}.ply", _polygon_ply(binary, sizes, rows, vertices))
    face = "face 2 (line 10)" if binary is None else "face 2"
    assert _error(tmp_path).startswith(f"{next(tmp_path.glob('a_2.*'))}: {face}: its triangle on vertices [4, 3, 6]")


def test_frames_that_list_the_first_frames_triangles_otherwise_are_said_to(tmp_path: Path) -> None:
    _write(tmp_path / "a_1.obj", OBJ_TEXT)
    moved = OBJ_TEXT.replace("f 1/1/1 2/1/1 3/1/1 4/1/1\r\n", "").replace("f 4//1 3//1 -1//1", "f 3 5 4\r\nf 1 2 3 4")
    _write(tmp_path / "a_2.obj", moved)
    with pytest.warns(UserWarning) as caught:
        mesh = read_sequence(tmp_path)
    about = [str(w.message) for w in caught if "triangles" in str(w.message)]
    assert about == [f"{tmp_path / 'a_2.obj'}: 1 of the 2 frames (this the first) list the triangles of the first "
                     "frame a_1.obj in another order or start them at other corners; every frame is read with the "
                     "first frame's triangles"]  # fmt: skip
    np.testing.assert_array_equal(mesh.faces, EXPECTED_FACES)


@pytest.mark.parametrize(
    ("content", "element"),
    [
        (b"\x00\x01garbage", "header: not a PLY header"),
        (b"ply\nformat ascii 1.0\nelement vertex three\nend_header\n", "header line 3: cannot read 'element"),
        (b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float3 x\nend_header\n", "header line 4: cannot read"),
        (b"ply\nelement vertex 0\nend_header\n", "header: no 'format"),
        (
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nprope\xffty float y\nend_header\n",
            "header line 5: cannot",
        ),
    ],
)
def test_unreadable_ply_header(tmp_path: Path, content: bytes, element: str) -> None:
    path = _write(tmp_path / "bad.ply", content)
    assert _error(path).startswith(f"{path}: {element}")


def test_ply_header_line_without_a_keyword_is_skipped_with_a_warning(tmp_path: Path) -> None:
    # Blender 2.4 wrote its "comment" line without the keyword (assimp's test set, Wuson.ply).
    mesh = _moving_mesh()
    write_ply(tmp_path / "clean.ply", mesh.frames[0], mesh.faces, binary=False)
    text = (tmp_path / "clean.ply").read_bytes().replace(b"format ascii 1.0\n", b"format ascii 1.0\nCreated by X\n", 1)
    path = _write(tmp_path / "blender24.ply", text)
    with pytest.warns(UserWarning, match=r"blender24.ply: header line 3: skipped 'Created by X', which starts with no"):
        vertices, faces = read_ply(path)
    clean_vertices, clean_faces = read_ply(tmp_path / "clean.ply")
    np.testing.assert_array_equal(vertices, clean_vertices)
    np.testing.assert_array_equal(faces, clean_faces)


def test_truncated_binary_ply(tmp_path: Path) -> None:
    mesh = _moving_mesh()
    write_ply(tmp_path / "whole.ply", mesh.frames[0], mesh.faces)
    path = _write(tmp_path / "cut.ply", (tmp_path / "whole.ply").read_bytes()[:-5])
    assert _error(path) == f"{path}: element face: file ends before its 3 rows"


def test_ply_face_index_out_of_range(tmp_path: Path) -> None:
    mesh = _moving_mesh()
    write_ply(tmp_path / "ok.ply", mesh.frames[0], mesh.faces)
    # The file ends with the last corner of the last face as a little-endian int32.
    path = _write(tmp_path / "bad.ply", (tmp_path / "ok.ply").read_bytes()[:-4] + np.int32(7).tobytes())
    assert _error(path) == f"{path}: face 2: vertex index 7 is outside the 5 vertices"


@pytest.mark.parametrize("write", [write_obj, write_ply, write_mesh])
def test_writers_reject_bad_meshes_naming_the_file_and_argument(tmp_path: Path, write: Callable) -> None:
    # The errors named "frames" (the AnimatedMesh the writers built), an argument they do not take.
    path = tmp_path / ("bad.ply" if write is write_ply else "bad.obj")
    not_finite = "is not finite as float32"
    cases = [
        (np.zeros((4, 2)), [[0, 1, 2]], "vertices: expected shape (V, 3), got (4, 2)"),
        (np.full((3, 3), "x"), [[0, 1, 2]], "vertices: expected numbers, got dtype <U1"),
        ([[0, 0, 0], [1, 0, 0], [np.nan, 0, 0]], [[0, 1, 2]], f"vertices: vertex 2 [nan, 0.0, 0.0] {not_finite}"),
        ([[0, 0, 0], [1, 0, 0], [1e39, 0, 0]], [[0, 1, 2]], f"vertices: vertex 2 [1e+39, 0.0, 0.0] {not_finite}"),
        (EXPECTED_VERTICES, [[0, 1, 5]], "faces: face 0 [0, 1, 5] has an index outside [0, 5)"),
        (EXPECTED_VERTICES, [[0, 1]], "faces: expected shape (M, 3), got (1, 2)"),
    ]
    for vertices, faces, message in cases:
        with pytest.raises(ValueError) as caught:
            write(path, vertices, faces)
        assert str(caught.value) == f"{path}: {message}"
    assert not list(tmp_path.iterdir())


def test_ascii_ply_row_with_wrong_length(tmp_path: Path) -> None:
    mesh = _moving_mesh()
    write_ply(tmp_path / "ok.ply", mesh.frames[0], mesh.faces, binary=False)
    text = (tmp_path / "ok.ply").read_text().replace("3 3 2 4", "3 3 2")
    path = _write(tmp_path / "bad.ply", text)
    assert _error(path) == f"{path}: element face row 2: has 3 values, expected 4"


def test_empty_or_missing_source(tmp_path: Path) -> None:
    assert _error(tmp_path) == f"{tmp_path}: source: no .obj or .ply frame found"
    with pytest.raises(FormatError, match="is not a folder, a glob pattern or an existing file"):
        read_sequence(tmp_path / "nothing")


def test_indented_obj_reads_like_the_unindented_one(tmp_path: Path) -> None:
    indented = "".join(("  " if index % 2 else "\t ") + line for index, line in enumerate(OBJ_TEXT.splitlines(True)))
    vertices, faces = read_obj(_write(tmp_path / "indented.obj", indented))
    np.testing.assert_array_equal(vertices, EXPECTED_VERTICES)
    np.testing.assert_array_equal(faces, EXPECTED_FACES)
    # Line numbers in errors still count the file's lines.
    path = _write(tmp_path / "bad.obj", indented.replace("-1//1", "6"))
    assert _error(path) == f"{path}: face 1 (line 11): vertex index 6 is outside the 5 vertices"


def test_obj_face_index_too_large_for_int64(tmp_path: Path) -> None:
    path = _write(tmp_path / "bad.obj", OBJ_TEXT.replace("f 4//1 3//1 -1//1", "f 1 2 99999999999999999999"))
    message = _error(path)
    assert message == f"{path}: face 1 (line 11): '99999999999999999999' is not a number or out of range"


def _ascii_ply(face_property: str, face_rows: str) -> str:
    return (
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face 2\n{face_property}\nend_header\n0 0 0\n1 0 0\n0 1 0\n{face_rows}"
    )


def test_ascii_ply_list_count_too_large_for_int64(tmp_path: Path) -> None:
    text = _ascii_ply("property list uchar int vertex_indices", "3 0 1 2\n99999999999999999999 0 1 2\n")
    path = _write(tmp_path / "bad.ply", text)
    assert _error(path) == f"{path}: element face row 1: '99999999999999999999' is not a number or out of range"


def test_ascii_ply_numbers_are_parsed_in_bulk(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A valid ascii body is converted in one numpy pass: splitting it into a bytes object per
    # token took 1.07 GB (peak) for 1M faces with texcoord lists. Only a token that pass cannot
    # take goes the token-by-token way, which names it.
    rng = np.random.default_rng(7)
    sizes, vertices = rng.integers(3, 6, 200), rng.random((20, 3)).astype(np.float32)
    corners = rng.integers(0, 20, int(sizes.sum()))
    text = _polygon_ply(False, sizes, corners, vertices, uv=True).decode()
    binary = read_ply(_write(tmp_path / "b.ply", _polygon_ply(True, sizes, corners, vertices, uv=True)))

    def token_by_token(*args: object) -> None:
        raise AssertionError("parsed token by token")

    monkeypatch.setattr(ply, "parse_numbers", token_by_token)
    for got, expected in zip(read_ply(_write(tmp_path / "a.ply", text)), binary):
        np.testing.assert_array_equal(got, expected)
    monkeypatch.undo()
    # An integer property written as a float, or too large to be exact as a float64, is still
    # refused or kept exactly; a bad coordinate is still named.
    faces = "3 0 1 2\n3 0 1 {}\n"
    cases = [
        ("2.0", "element face row 1: '2.0' is not a number or out of range"),
        ("1e0", "element face row 1: '1e0' is not a number or out of range"),
        ("9007199254740993", "face 1: vertex index 9007199254740993 is outside the 3 vertices"),
    ]
    for written, reason in cases:
        path = _write(tmp_path / "bad.ply", _ascii_ply("property list uchar int vertex_indices", faces.format(written)))
        assert _error(path) == f"{path}: {reason}"
    path = _write(tmp_path / "bad.ply", _ascii_ply("property list uchar int vertex_indices", "3 0 1 2\n3 0 1 2\n"))
    path.write_text(path.read_text().replace("1 0 0\n", "1 x 0\n"))
    assert _error(path) == f"{path}: element vertex row 1: 'x' is not a number or out of range"


def test_ascii_ply_short_last_row_before_its_list(tmp_path: Path) -> None:
    properties = "property uchar flags\nproperty uchar group\nproperty list uchar int vertex_indices"
    path = _write(tmp_path / "bad.ply", _ascii_ply(properties, "0 0 3 0 1 2\n7\n"))
    assert _error(path) == f"{path}: element face row 1: has 1 values, expected at least 3"


@pytest.mark.parametrize("binary", [False, True])
def test_ply_float_vertex_indices_are_refused(tmp_path: Path, binary: bool) -> None:
    header = _ascii_ply("property list uchar float vertex_indices", "").replace(
        "format ascii", "format binary_little_endian" if binary else "format ascii"
    )
    if binary:
        header = header.replace("0 0 0\n1 0 0\n0 1 0\n", "")
        face = np.array([3], "u1").tobytes() + np.array([0.7, 1.2, 2.9], "<f4").tobytes()
        content = header.encode() + np.eye(3, dtype="<f4")[[2, 0, 1]].tobytes() + face * 2
    else:
        content = (header + "3 0.7 1.2 2.9\n3 0 1 2\n").encode()
    path = _write(tmp_path / "bad.ply", content)
    assert _error(path) == f"{path}: element face: vertex index list has float items; indices must be integers"


def _binary_ply_with_list_length(count_type: str, length: int) -> bytes:
    header = _ascii_ply(f"property list {count_type} int vertex_indices", "").replace("0 0 0\n1 0 0\n0 1 0\n", "")
    header = header.replace("format ascii", "format binary_little_endian").replace("element face 2", "element face 1")
    face = np.array([length], {"char": "i1", "uint": "<u4"}[count_type]).tobytes() + np.arange(3, dtype="<i4").tobytes()
    return header.encode() + np.eye(3, dtype="<f4").tobytes() + face


@pytest.mark.parametrize(("count_type", "length"), [("char", -1), ("uint", 4_000_000_000)])
def test_binary_ply_list_length_negative_or_past_the_end(tmp_path: Path, count_type: str, length: int) -> None:
    path = _write(tmp_path / "bad.ply", _binary_ply_with_list_length(count_type, length))
    reason = f"list length {length} is negative or longer than the rest of the file"
    assert _error(path) == f"{path}: element face row 0: {reason}"


def test_ascii_ply_negative_list_length(tmp_path: Path) -> None:
    text = _ascii_ply("property list char int vertex_indices", "3 0 1 2\n-1\n")
    path = _write(tmp_path / "bad.ply", text)
    assert _error(path) == f"{path}: element face row 1: list length -1 is negative"


def test_ply_property_declared_twice(tmp_path: Path) -> None:
    text = _ascii_ply("property list uchar int vertex_indices", "3 0 1 2\n3 0 1 2\n").replace(
        "property float z\n", "property float z\nproperty float x\n"
    )
    path = _write(tmp_path / "bad.ply", text)
    assert _error(path) == f"{path}: header line 7: property 'x' is declared twice in 'vertex'"


def test_binary_ply_scalar_named_like_an_internal_field(tmp_path: Path) -> None:
    header = _ascii_ply("property uchar _size\nproperty list uchar int vertex_indices", "").replace(
        "0 0 0\n1 0 0\n0 1 0\n", ""
    )
    header = header.replace("format ascii", "format binary_little_endian").replace("element face 2", "element face 1")
    face = np.array([9, 3], "u1").tobytes() + np.array([2, 0, 1], "<i4").tobytes()
    path = _write(tmp_path / "named.ply", header.encode() + np.eye(3, dtype="<f4").tobytes() + face)
    vertices, faces = read_ply(path)
    np.testing.assert_array_equal(vertices, np.eye(3))
    np.testing.assert_array_equal(faces, [[2, 0, 1]])


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-be"])
def test_utf16_obj_after_its_byte_order_mark_reads_as_utf8(tmp_path: Path, encoding: str) -> None:
    mesh = _moving_mesh(1)
    write_obj(tmp_path / "plain.obj", mesh.frames[0], mesh.faces)
    text = (tmp_path / "plain.obj").read_text()
    wide = ("\ufeff" + text).encode("utf-16-be") if encoding == "utf-16-be" else text.encode("utf-16")
    vertices, faces = read_obj(_write(tmp_path / "wide.obj", wide))
    np.testing.assert_array_equal(vertices, read_obj(tmp_path / "plain.obj")[0])
    np.testing.assert_array_equal(faces, mesh.faces)
    with pytest.raises(FormatError, match=r"cut.obj: byte \d+: not UTF-16 text after its byte order mark"):
        read_obj(_write(tmp_path / "cut.obj", wide[:-1]))


def test_points_and_lines_in_a_ply_face_element_are_left_out_with_a_warning(tmp_path: Path) -> None:
    # assimp's PLY exporter writes a mesh's points and lines as faces of one or two vertices.
    mixed = _write(tmp_path / "mixed.ply", _ascii_ply("property list uchar int vertex_indices", "2 0 1\n3 0 1 2\n"))
    with pytest.warns(UserWarning, match=r"mixed.ply: element face: 1 of 2 faces have fewer than 3 vertices"):
        vertices, faces = read_ply(mixed)
    np.testing.assert_array_equal(faces, [[0, 1, 2]])
    lines = _write(tmp_path / "lines.ply", _ascii_ply("property list uchar int vertex_indices", "2 0 1\n1 2\n"))
    assert _error(lines) == f"{lines}: element face: all 2 faces have fewer than 3 vertices (points or lines)"


def test_obj_materials_not_carried_are_named(tmp_path):
    """An OBJ file's materials (mtllib, usemtl) are not written to the levels: a textured scan's
    levels came out untextured without a word."""
    text = "mtllib scan.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl skin\nf 1 2 3\n  usemtl\tcloth\nf 2 4 3\n"
    (tmp_path / "scan.obj").write_text(text)
    with pytest.warns(UnreadAttributesWarning, match=r"scan.obj: its materials \(usemtl lines\) are not read"):
        assert read_sequence(tmp_path / "scan.obj").face_count == 2
    (tmp_path / "named.obj").write_text(text.replace("usemtl", "g"))  # groups alone are no material
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_sequence(tmp_path / "named.obj")
    assert not [w for w in caught if "(usemtl lines)" in str(w.message)]  # the groups' own: test_obj_groups.py
