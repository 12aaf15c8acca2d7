"""A PLY sequence's per-vertex texture coordinates (s, t and the other names exporters give them)
and normals (nx, ny, nz) reach every level `simplify` writes, as an OBJ sequence's vt and vn
lines do; they were dropped with a warning."""

from __future__ import annotations

import numpy as np
import pytest
from simplify_inputs import twisting_cylinder, wrapped_texture

from animlod.cli import main
from animlod.io.meshseq import write_mesh
from animlod.io.obj import ObjTexture
from animlod.io.ply import read_ply, read_ply_attributes, write_ply


def _ply_wedges(faces: np.ndarray, uvs: np.ndarray, corners: np.ndarray):
    """A PLY vertex per (position, texture coordinate) pair of the corners, as exporters split a
    mesh at its UV seams: each wedge's position index, its texture coordinate and the faces over
    the wedges."""
    pairs, corner_wedge = np.unique(np.stack([faces.ravel(), corners.ravel()], axis=1), axis=0, return_inverse=True)
    return pairs[:, 0], uvs[pairs[:, 1]], corner_wedge.reshape(faces.shape).astype(np.int32)


@pytest.fixture(scope="module")
def textured_ply_sequence(tmp_path_factory):
    folder = tmp_path_factory.mktemp("ply") / "shot"
    folder.mkdir()
    rest, twisted = twisting_cylinder()
    positions, uvs, faces = _ply_wedges(rest.faces, *wrapped_texture(rest))
    for index, frame in enumerate(twisted):
        write_ply(folder / f"shot_{index}.ply", frame[positions], faces, uvs=uvs)
    return folder, rest


def test_a_ply_sequences_texture_coordinates_reach_every_level(textured_ply_sequence, tmp_path, capsys):
    folder, rest = textured_ply_sequence
    for source in (folder, folder / "shot_0.ply"):  # a sequence, and one mesh file
        assert main(["simplify", str(source), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    assert main(["info", str(folder)]) == 0
    printed = capsys.readouterr()
    assert "not read" not in printed.err
    assert "vertices: 276 with their texture coordinates" in printed.out  # the seam's copies are rows of their own
    height, bottom = np.ptp(rest.frames[0][:, 1]), rest.frames[0][:, 1].min()
    for level in (1, 2, 3):
        frames = sorted((tmp_path / "out" / f"shot_lod{level}").iterdir())
        assert [path.name for path in frames] == [f"shot_{index}.ply" for index in range(5)]
        for path in [*frames, tmp_path / "out" / f"shot_0_lod{level}.ply"]:
            positions, faces, uvs, _, _ = read_ply_attributes(path)
            assert uvs is not None and len(np.unique(positions, axis=0)) < len(positions)  # the seam stays open
            # The twist keeps each point's height, so v (the height at rest) holds in every frame.
            np.testing.assert_allclose(uvs[faces, 1] * height, positions[faces, 1] - bottom, atol=1e-3 * height)


@pytest.mark.parametrize("names", [("u", "v"), ("texture_u", "texture_v"), ("texture_s", "texture_t")])
def test_texture_coordinates_are_read_by_every_name_exporters_give_them(tmp_path, names):
    path = tmp_path / "quad.ply"
    path.write_text(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        f"property float {names[0]}\nproperty float {names[1]}\nproperty uchar red\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        "0 0 0 0 0 9\n1 0 0 1 0 9\n1 1 0 1 1 9\n0 1 0 0 0.5 9\n4 0 1 2 3\n"
    )
    with pytest.warns(UserWarning, match=r"its properties vertex red are not read"):
        vertices, faces, uvs, _, _ = read_ply_attributes(path)
    np.testing.assert_array_equal(uvs, [[0, 0], [1, 0], [1, 1], [0, 0.5]])
    assert faces.tolist() == [[0, 1, 2], [0, 2, 3]]
    with pytest.warns(UserWarning, match=rf"vertex {names[0]}, vertex {names[1]}, vertex red are not read"):
        read_ply(path)  # geometry alone: the texture coordinates are named among what it leaves


def test_texture_coordinates_are_written_in_both_encodings_and_checked(tmp_path):
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], np.float32)
    faces = np.array([[0, 1, 2], [1, 3, 2]], np.int32)
    uvs = np.array([[0.1, 0.2], [0.3, 0.4], [0.5, 0.6], [0.7, 0.8]], np.float32)
    for binary in (True, False):
        write_ply(tmp_path / f"t{binary}.ply", vertices, faces, binary=binary, uvs=uvs)
        np.testing.assert_array_equal(read_ply_attributes(tmp_path / f"t{binary}.ply")[2], uvs)
    write_ply(tmp_path / "plain.ply", vertices, faces)
    assert read_ply_attributes(tmp_path / "plain.ply")[2] is None
    with pytest.raises(ValueError, match="uvs: expected"):
        write_ply(tmp_path / "bad.ply", vertices, faces, uvs=uvs[:3])
    # Per corner as an OBJ's: written per vertex where each vertex's corners agree, else refused.
    per_corner = np.concatenate([uvs, [[0.9, 0.9]]]).astype(np.float32)
    write_mesh(tmp_path / "agree.ply", vertices, faces, ObjTexture(per_corner, faces))
    np.testing.assert_array_equal(read_ply_attributes(tmp_path / "agree.ply")[2], uvs)
    with pytest.raises(ValueError, match="texture: vertex 1 has two values at its corners"):
        write_mesh(tmp_path / "two.ply", vertices, faces, ObjTexture(per_corner, np.array([[0, 1, 2], [4, 3, 2]])))
    assert not (tmp_path / "two.ply").exists()


@pytest.mark.parametrize("textured", [False, True])
def test_a_ply_sequences_smooth_normals_are_rebuilt_on_every_level(tmp_path, textured):
    """Smooth normals per vertex, the same on a UV seam's two copies (rows of their own in a PLY
    file, one point of the surface)."""
    from animlod.normals import vertex_normals

    rest, twisted = twisting_cylinder()
    if textured:
        positions, uvs, faces = _ply_wedges(rest.faces, *wrapped_texture(rest))
    else:
        positions, uvs, faces = np.arange(rest.vertex_count), None, rest.faces
    (tmp_path / "shot").mkdir()
    for index, frame in enumerate(twisted):
        normals = vertex_normals(frame, rest.faces)[positions]
        write_ply(tmp_path / "shot" / f"shot_{index}.ply", frame[positions], faces, uvs=uvs, normals=normals)
    assert main(["simplify", str(tmp_path / "shot"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    for path in sorted((tmp_path / "out" / "shot_lod2").iterdir()):
        level_positions, level_faces, level_uvs, level_normals, _ = read_ply_attributes(path)
        assert (level_uvs is not None) == textured and level_normals is not None
        points, point = np.unique(level_positions, axis=0, return_inverse=True)
        assert (len(points) < len(level_positions)) == textured  # the seam's copies
        np.testing.assert_allclose(level_normals, vertex_normals(points, point[level_faces])[point], atol=1e-6)


def test_a_flat_shaded_ply_sequences_normals_are_named_and_not_written(tmp_path, capsys):
    rest, twisted = twisting_cylinder(frames=2)
    corners = rest.faces.ravel()
    faces = np.arange(corners.size, dtype=np.int32).reshape(-1, 3)  # a row per corner: flat shading
    (tmp_path / "flat").mkdir()
    for index, frame in enumerate(twisted):
        edges = frame[rest.faces[:, 1:]] - frame[rest.faces[:, :1]]
        normals = np.repeat(np.cross(edges[:, 0], edges[:, 1]), 3, axis=0)
        write_ply(tmp_path / "flat" / f"f_{index}.ply", frame[corners], faces, normals=normals)
    assert main(["simplify", str(tmp_path / "flat"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    assert "its normals are not written: they shade it flat or with hard edges" in capsys.readouterr().err
    assert read_ply_attributes(tmp_path / "out" / "flat_lod1" / "f_0.ply")[3] is None


def _quad_ply(path, extra_names: str, extra_rows: list[str]) -> None:
    """An ascii PLY quad (two triangles) with more vertex properties (``extra_names``, e.g.
    "float nx", one line each) and their values per vertex row."""
    properties = "".join(f"property {name}\n" for name in extra_names.split(",") if name)
    rows = "".join(f"{xyz} {extra}\n" for xyz, extra in zip(["0 0 0", "1 0 0", "1 1 0", "0 1 0"], extra_rows))
    path.write_text(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        f"{properties}element face 1\nproperty list uchar int vertex_indices\nend_header\n{rows}4 0 1 2 3\n"
    )


def main_info(path, capsys) -> str:
    assert main(["info", str(path)]) == 0
    return capsys.readouterr().out


def test_bad_attribute_values_cost_the_attribute_not_the_sequence(tmp_path, capsys):
    """One NaN normal (a zero-area face's, as exporters leave them), non-finite texture coordinates
    or texture coordinates written as lists refused the whole sequence, whose geometry was read
    before the attributes were."""
    (tmp_path / "nan_normal").mkdir()
    (tmp_path / "nan_uv").mkdir()
    (tmp_path / "list_uv").mkdir()
    for index in range(2):
        _quad_ply(tmp_path / "nan_normal" / f"f{index}.ply", "float nx,float ny,float nz",
                  ["0 0 1", "0 0 1", "nan nan nan", "0 0 1"])  # fmt: skip
        _quad_ply(tmp_path / "nan_uv" / f"f{index}.ply", "float s,float t", ["0 0", "1 0", "inf 1", "0 1"])
        _quad_ply(tmp_path / "list_uv" / f"f{index}.ply", "list uchar float s,list uchar float t",
                  ["1 0 1 0", "1 1 1 0", "1 1 1 1", "1 0 1 1"])  # fmt: skip
    for name, said in (("nan_normal", ""), ("nan_uv", "vertex 2: its texture coordinates [inf, 1.0] are not finite"),
                       ("list_uv", "its properties vertex s, vertex t are not read")):  # fmt: skip
        assert main(["info", str(tmp_path / name)]) == 0
        assert main(["simplify", str(tmp_path / name), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
        printed = capsys.readouterr()
        assert said in printed.err and "error" not in printed.err
    assert "normals: smooth, rebuilt on each level" in main_info(tmp_path / "nan_normal", capsys)


def test_a_zero_normal_does_not_make_a_smooth_mesh_hard_edged(tmp_path, capsys):
    _quad_ply(tmp_path / "zero.ply", "float nx,float ny,float nz", ["0 0 1", "0 0 1", "0 0 0", "0 0 1"])
    assert "normals: smooth, rebuilt on each level" in main_info(tmp_path / "zero.ply", capsys)


def test_info_says_a_ply_sequences_flat_normals_are_not_written(tmp_path, capsys):
    corners = ["0 0 0", "1 0 0", "1 1 0", "0 0 0", "1 1 0", "0 1 0"]  # a row per corner: flat shading
    normals = ["0 0 1"] * 3 + ["0 0.6 0.8"] * 3
    properties = "".join(f"property float {name}\n" for name in ("x", "y", "z", "nx", "ny", "nz"))
    text = f"ply\nformat ascii 1.0\nelement vertex 6\n{properties}"
    text += "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    text += "".join(f"{c} {n}\n" for c, n in zip(corners, normals)) + "3 0 1 2\n3 3 4 5\n"
    (tmp_path / "flat.ply").write_text(text)
    said = main_info(tmp_path / "flat.ply", capsys)  # two faces: too few to tell flat from hard edges
    assert "not written to the levels (PLY files: one normal per vertex)" in said


def test_attributes_that_only_later_frames_have_are_named(tmp_path, capsys):
    # The first frame's warning spoke for the sequence: one without extra properties hid the
    # colours and normals of every later frame.
    (tmp_path / "seq").mkdir()
    _quad_ply(tmp_path / "seq" / "f0.ply", "", ["", "", "", ""])
    _quad_ply(tmp_path / "seq" / "f1.ply", "uchar red", ["9", "9", "9", "9"])
    assert main(["simplify", str(tmp_path / "seq"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    assert "f1.ply: its properties vertex red are not read" in capsys.readouterr().err
