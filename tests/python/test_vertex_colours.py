"""An OBJ or PLY sequence's vertex colours (PLY red, green, blue, alpha; OBJ ``v x y z r g b``)
reach every level `simplify` writes, stored as the input stores them and each frame's where they
change; they were dropped (PLY, with a warning) or lost without a word (OBJ)."""

from __future__ import annotations

import numpy as np
import pytest
from simplify_inputs import twisting_cylinder, wrapped_texture

from animlod.cli import main
from animlod.io import VertexColours
from animlod.io.meshseq import read_textured_sequence, write_mesh
from animlod.io.obj import ObjTexture, read_obj, read_obj_textured, write_obj
from animlod.io.ply import read_ply_attributes, write_ply


def _height_colours(heights: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """(V, 4) RGBA 0-255 that follow the height linearly: red up, green down, blue and alpha flat."""
    rising = (heights - heights.min()) / np.ptp(heights)
    return np.stack([250 * rising * scale, 250 * (1 - rising), np.full_like(rising, 40), np.full_like(rising, 200)], 1)


def _write_frames(folder, suffix, frames, faces, colours, texture=None):
    """One file per frame; ``colours`` a VertexColours with one set or one per frame."""
    folder.mkdir()
    for index, frame in enumerate(frames):
        write_mesh(folder / f"shot_{index}.{suffix}", frame, faces, texture, None, colours.of_frame(index))


def _check_colours_follow_height(positions, colours, heights_range, scale=1.0, tolerance=1.0):
    """The twist keeps each point's height, so a colour that follows the height at rest still
    does at every level vertex of every frame (interpolated along the collapsed edges)."""
    bottom, height = heights_range
    expected = _height_colours(np.concatenate([positions[:, 1], [bottom, bottom + height]]), scale)[:-2]
    np.testing.assert_allclose(colours, expected[:, : colours.shape[1]], atol=tolerance)


@pytest.mark.parametrize("textured", [False, True])
def test_a_ply_sequences_colours_reach_every_level_as_uchar(tmp_path, textured, capsys):
    rest, twisted = twisting_cylinder()
    heights = rest.frames[0][:, 1]
    texture = ObjTexture(*wrapped_texture(rest)) if textured else None
    faces, frames, rgba = rest.faces, twisted, _height_colours(heights)
    if textured:  # a PLY vertex per (position, texture coordinate) pair, as exporters split a mesh
        pairs, corner = np.unique(np.stack([faces.ravel(), texture.corners.ravel()], 1), axis=0, return_inverse=True)
        faces, frames, rgba = corner.reshape(faces.shape), twisted[:, pairs[:, 0]], rgba[pairs[:, 0]]
        texture = ObjTexture(texture.uvs[pairs[:, 1]], faces)
    colours = VertexColours(rgba[None].astype(np.float32), ("red", "green", "blue", "alpha"), ("u1",) * 4)
    _write_frames(tmp_path / "shot", "ply", frames, faces, colours, texture)
    _write_frames(tmp_path / "plain", "ply", frames, faces, VertexColours(rgba[None, :, :0], (), ()), texture)
    assert main(["info", str(tmp_path / "shot")]) == 0
    assert "vertex colours: red, green, blue, alpha (uchar)" in capsys.readouterr().out
    for source in ("shot", "plain", "shot/shot_0.ply"):  # with colours, without, and one mesh file
        on_edge = ["--placement", "on_edge"] if source == "plain" else []  # where a colour is a point's
        assert main(["simplify", str(tmp_path / source), "-o", str(tmp_path / "out"), "--no-metrics", *on_edge]) == 0
    assert "not read" not in capsys.readouterr().err
    measure = (heights.min(), np.ptp(heights))
    for level in (1, 2, 3):
        for index in range(len(frames)):
            path = tmp_path / "out" / f"shot_lod{level}" / f"shot_{index}.ply"
            header = path.read_bytes().split(b"end_header")[0]
            assert b"property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n" in header
            positions, level_faces, _, _, read = read_ply_attributes(path)
            assert read.values.shape == (1, len(positions), 4)
            _check_colours_follow_height(positions, read.values[0], measure)
            # A UV seam's copies of a point keep one colour as the point moves.
            _, first, copy_of = np.unique(positions, axis=0, return_index=True, return_inverse=True)
            np.testing.assert_array_equal(read.values[0], read.values[0][first[copy_of.ravel()]])
            # Colours ride along: the same collapses as the sequence without them.
            plain_positions, plain_faces, _, _, _ = read_ply_attributes(
                tmp_path / "out" / f"plain_lod{level}" / path.name
            )
            np.testing.assert_array_equal(positions, plain_positions)
            np.testing.assert_array_equal(level_faces, plain_faces)
        positions, _, _, _, read = read_ply_attributes(tmp_path / "out" / f"shot_0_lod{level}.ply")
        _check_colours_follow_height(positions, read.values[0], measure)


def test_an_obj_sequences_colours_change_per_frame_and_reach_every_level(tmp_path, capsys):
    rest, twisted = twisting_cylinder()
    heights = rest.frames[0][:, 1]
    # Each frame's colours its own: red brightens frame by frame (a capture's lighting changes).
    scales = np.linspace(0.2, 1.0, len(twisted))
    values = np.stack([_height_colours(heights, scale)[:, :3] / 255 for scale in scales]).astype(np.float32)
    _write_frames(tmp_path / "shot", "obj", twisted, rest.faces, VertexColours(values, ("r", "g", "b"), ("f4",) * 3))
    assert main(["info", str(tmp_path / "shot")]) == 0
    assert "vertex colours: r, g, b (float), each frame's own" in capsys.readouterr().out
    assert main(["simplify", str(tmp_path / "shot"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    for level in (1, 2, 3):
        for index, scale in enumerate(scales):
            positions, _, _, _, read, _ = read_obj_textured(tmp_path / "out" / f"shot_lod{level}" / f"shot_{index}.obj")
            assert read.names == ("r", "g", "b") and read.types == ("f4",) * 3
            _check_colours_follow_height(positions, read.values[0] * 255, (heights.min(), np.ptp(heights)), scale)


def test_colour_seams_stay_sharp(tmp_path):
    """A PLY exporter splits a vertex where two colours meet: the copies weld for the collapses
    and keep their own colours, so no level vertex takes a mix of the two."""
    rest, twisted = twisting_cylinder()
    angle = np.arctan2(rest.frames[0][:, 2], rest.frames[0][:, 0])
    red_face = np.sin(angle[rest.faces]).mean(axis=1) > 0  # half of the cylinder red, the other blue
    corner_colour = np.repeat(red_face, 3)
    pairs, corner = np.unique(np.stack([rest.faces.ravel(), corner_colour], 1), axis=0, return_inverse=True)
    rgb = np.where(pairs[:, 1:] == 1, [255.0, 0, 0], [0, 0, 255.0]).astype(np.float32)
    colours = VertexColours(rgb[None], ("red", "green", "blue"), ("u1",) * 3)
    _write_frames(tmp_path / "split", "ply", twisted[:, pairs[:, 0]], corner.reshape(-1, 3), colours)
    assert main(["simplify", str(tmp_path / "split"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    for level in (1, 2, 3):
        positions, _, _, _, read = read_ply_attributes(tmp_path / "out" / f"split_lod{level}" / "shot_2.ply")
        assert {tuple(row) for row in read.values[0].tolist()} == {(255, 0, 0), (0, 0, 255)}
        assert len(np.unique(positions, axis=0)) < len(positions)  # the seam's copies kept apart


def test_a_uv_seams_copies_keep_one_colour(tmp_path):
    """A file vertex's colour, copied to each side of a UV seam (an OBJ's v line; a PLY exporter's
    split vertices), is one colour of one point: it moves with the point, and both copies say so
    (each side interpolated alone, copies of one point drifted up to 19 uchar steps apart here)."""
    rest, twisted = twisting_cylinder()
    texture = ObjTexture(*wrapped_texture(rest))
    pairs, corner = np.unique(np.stack([rest.faces.ravel(), texture.corners.ravel()], 1), axis=0, return_inverse=True)
    rough = np.random.default_rng(5).uniform(0, 255, (rest.vertex_count, 3)).round().astype(np.float32)
    colours = VertexColours(rough[pairs[:, 0]][None], ("red", "green", "blue"), ("u1",) * 3)
    faces = corner.reshape(-1, 3).astype(np.int32)
    _write_frames(tmp_path / "seam", "ply", twisted[:, pairs[:, 0]], faces, colours,
                  ObjTexture(texture.uvs[pairs[:, 1]], faces))  # fmt: skip
    assert main(["simplify", str(tmp_path / "seam"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    for level in (1, 2, 3):
        positions, _, uvs, _, read = read_ply_attributes(tmp_path / "out" / f"seam_lod{level}" / "shot_4.ply")
        _, first, copy_of = np.unique(positions, axis=0, return_index=True, return_inverse=True)
        assert len(first) < len(positions) and len(np.unique(uvs[:, 0])) > 1  # the seam is there
        np.testing.assert_array_equal(read.values[0], read.values[0][first[copy_of.ravel()]])


def test_frames_whose_colours_disagree_leave_them_out_with_a_warning(tmp_path):
    rest, twisted = twisting_cylinder()
    rgb = VertexColours(
        _height_colours(rest.frames[0][:, 1])[None, :, :3].astype(np.float32), ("red", "green", "blue"), ("u1",) * 3
    )
    _write_frames(tmp_path / "shot", "ply", twisted, rest.faces, rgb)
    write_ply(tmp_path / "shot" / "shot_3.ply", twisted[3], rest.faces)
    with pytest.warns(
        UserWarning,
        match=r"shot_3.ply: has no vertex colours that can be read, and shot_0.ply has: the levels are written",
    ):
        mesh, _, _, colours, _, _ = read_textured_sequence(tmp_path / "shot")
    assert colours is None and mesh.frame_count == 5
    as_float = VertexColours(rgb.values, rgb.names, ("u1", "u1", "f4"))
    write_ply(tmp_path / "shot" / "shot_3.ply", twisted[3], rest.faces, colours=as_float)
    with pytest.warns(
        UserWarning,
        match=r"shot_3.ply: stores its vertex colours as red, green, blue \(float, uchar\), and shot_0.ply as "
        r"red, green, blue \(uchar\)",
    ):
        assert read_textured_sequence(tmp_path / "shot")[3] is None


def test_an_alpha_on_some_frames_only_leaves_the_colours_without_it(tmp_path):
    """Until 2026-12-07 a frame with an alpha beside frames without one dropped every colour."""
    rest, twisted = twisting_cylinder()
    stored = _height_colours(rest.frames[0][:, 1])[None, :, :3].round().astype(np.float32)  # as uchar keeps them
    rgb = VertexColours(stored, ("red", "green", "blue"), ("u1",) * 3)
    rgba = VertexColours(np.concatenate([rgb.values, np.full((*rgb.values.shape[:2], 1), 128, np.float32)], axis=2),
                         ("red", "green", "blue", "alpha"), ("u1",) * 4)  # fmt: skip
    for order, (first, other) in enumerate(((rgb, rgba), (rgba, rgb))):
        folder = tmp_path / f"order{order}"
        _write_frames(folder, "ply", twisted, rest.faces, first)
        write_ply(folder / "shot_3.ply", twisted[3], rest.faces, colours=other)
        with pytest.warns(
            UserWarning,
            match=rf"shot_3.ply: stores its vertex colours as {', '.join(other.names)} \(uchar\), and shot_0.ply as "
            rf"{', '.join(first.names)} \(uchar\): the levels are written without alpha",
        ):
            colours = read_textured_sequence(folder)[3]
        assert colours.names == ("red", "green", "blue") and colours.types == ("u1",) * 3
        np.testing.assert_array_equal(colours.values, rgb.values)


def test_colours_are_read_by_the_names_and_types_files_store_them_in(tmp_path):
    header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    face = "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
    rows = "0 0 0 {}\n1 0 0 {}\n0 1 0 {}\n3 0 1 2\n"
    # assimp's float-color.ply: float channels with alpha.
    path = tmp_path / "float.ply"
    channels = "property float red\nproperty float green\nproperty float blue\nproperty float alpha\n"
    path.write_text(header + channels + face + rows.format("1 0 0 1", "0 1 0 0.5", "0 0 1 0"))
    colours = read_ply_attributes(path)[4]
    assert colours.names == ("red", "green", "blue", "alpha") and colours.types == ("f4",) * 4
    np.testing.assert_array_equal(colours.values[0], [[1, 0, 0, 1], [0, 1, 0, 0.5], [0, 0, 1, 0]])
    path = tmp_path / "diffuse.ply"
    channels = "property uchar diffuse_red\nproperty uchar diffuse_green\nproperty uchar diffuse_blue\n"
    path.write_text(header + channels + face + rows.format("1 2 3", "4 5 6", "7 8 9"))
    colours = read_ply_attributes(path)[4]
    assert colours.names == ("diffuse_red", "diffuse_green", "diffuse_blue") and colours.types == ("u1",) * 3
    path = tmp_path / "nan.ply"
    path.write_text(header + "property float red\nproperty float green\nproperty float blue\n" + face
                    + rows.format("1 0 0", "nan 0 0", "0 0 1"))  # fmt: skip
    with pytest.warns(UserWarning) as warned:
        assert read_ply_attributes(path)[4] is None
    assert [str(w.message).split(": ", 1)[1] for w in warned] == [
        "vertex 1: its colours [nan, 0.0, 0.0] are not finite; the levels are written without colours"
    ]


def test_colours_are_written_in_their_type_in_both_encodings_and_checked(tmp_path):
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    faces = np.array([[0, 1, 2]], np.int32)
    interpolated = np.array([[254.6, 0.4, 300, 0.25], [-3, 127.5, 12, 2**31], [1, 2, 3, -(2**31)]], np.float32)
    # Each channel in its own type: uchar rounded and clipped, a double alpha, a full-range int.
    as_double = [[255, 0, 255, 0.25], [0, 128, 12, 2**31], [1, 2, 3, -(2**31)]]
    as_int = [[255, 0, 255, 0], [0, 128, 12, 2**31 - 1], [1, 2, 3, -(2**31)]]
    for types, expected in ((("u1", "u1", "u1", "f8"), as_double), (("u1", "u1", "u1", "i4"), as_int)):
        colours = VertexColours(interpolated[None], ("red", "green", "blue", "alpha"), types)
        for binary in (True, False):
            path = tmp_path / f"c{binary}{types[3]}.ply"
            write_ply(path, vertices, faces, binary=binary, colours=colours)
            read = read_ply_attributes(path)[4]
            assert read.types == types
            np.testing.assert_array_equal(read.values[0], np.float32(expected))
    header = (tmp_path / "cFalsef8.ply").read_text()
    assert "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty double alpha\n" in header
    with pytest.raises(ValueError, match="colours: expected"):
        write_ply(
            tmp_path / "bad.ply", vertices, faces, colours=VertexColours(interpolated[None, :2], ("red",), ("u1",))
        )
    assert not (tmp_path / "bad.ply").exists()
    for channels in (3, 4):
        floats = VertexColours(interpolated[None, :, :channels] / 255, tuple("rgba"[:channels]), ("f4",) * channels)
        write_obj(tmp_path / "c.obj", vertices, faces, colours=floats)
        assert len((tmp_path / "c.obj").read_text().splitlines()[1].split()) == 4 + channels  # v x y z r g b [a]
        np.testing.assert_allclose(read_obj_textured(tmp_path / "c.obj")[4].values[0], floats.values[0])
    with pytest.raises(ValueError, match="colours: an OBJ v line holds r, g, b and perhaps a"):
        write_obj(
            tmp_path / "two.obj", vertices, faces, colours=VertexColours(np.zeros((1, 3, 2)), ("r", "g"), ("f4",) * 2)
        )


def test_obj_v_lines_hold_colours_where_every_one_has_six_or_seven_values(tmp_path):
    faces = "f 1 2 3\n"
    for name, lines, channels in (("six", "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\n", 3),
                                  ("seven", "v 0 0 0 1 0 0 1\nv 1 0 0 0 1 0 1\nv 0 1 0 0 0 1 0.5\n", 4),
                                  ("w", "v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\n", 0)):  # fmt: skip
        (tmp_path / f"{name}.obj").write_text(lines + faces)
        vertices, _, _, _, colours, _ = read_obj_textured(tmp_path / f"{name}.obj")
        np.testing.assert_array_equal(vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
        assert (0 if colours is None else colours.values.shape[2]) == channels
    np.testing.assert_array_equal(read_obj_textured(tmp_path / "seven.obj")[4].values[0][:, 3], [1, 1, 0.5])
    # Colours on some lines only, or one that is no number: read without them, aloud; geometry as ever.
    for name, lines, reason in (
        ("mixed", "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\n", "2 of its 3 v lines have more"),
        ("hex", "v 0 0 0 0x10 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\n", r"vertex 0 \(line 1\)"),
    ):
        (tmp_path / f"{name}.obj").write_text(lines + faces)
        with pytest.warns(UserWarning, match=rf"{name}.obj: {reason}.*its colours are not read"):
            vertices, _, _, _, colours, _ = read_obj_textured(tmp_path / f"{name}.obj")
        assert colours is None and len(vertices) == 3
    with pytest.warns(UserWarning, match=r"six.obj: its colours \(on v lines\) are not read"):
        read_obj(tmp_path / "six.obj")  # geometry alone, as tdag and face read a sequence
