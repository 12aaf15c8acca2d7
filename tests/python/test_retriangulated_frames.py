"""Frames whose exporter split each frame's polygons along other diagonals (Blender's OBJ and PLY
exporters with "triangulate" on pick them from each frame's deformed shape): the same surface,
read with the first frame's triangles; frames whose faces differ otherwise are still refused."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from animlod.cli import main
from animlod.io import FormatError, read_mesh, read_sequence, write_ply
from animlod.io.meshseq import frame_files, read_textured_sequence
from animlod.io.vertex_colours import VertexColours

GRID = 4  # quads per side: 25 vertices, 16 quads, 32 triangles
FRAMES = 4


def _grid_positions(frame: int) -> np.ndarray:
    """(25, 3) float32: the grid bent and waved a little more in each frame."""
    u, v = np.meshgrid(np.linspace(0, 1, GRID + 1), np.linspace(0, 1, GRID + 1), indexing="xy")
    height = 0.3 * frame * np.sin(np.pi * u) * np.cos(2 * v + frame)
    return np.stack([u.ravel(), v.ravel(), height.ravel()], axis=1).astype(np.float32)


def _quads() -> np.ndarray:
    """(16, 4) the grid's quads, counter-clockwise seen from +z."""
    row, column = np.divmod(np.arange(GRID * GRID), GRID)
    corner = row * (GRID + 1) + column
    return np.stack([corner, corner + 1, corner + GRID + 2, corner + GRID + 1], axis=1)


def _triangles(frame: int) -> np.ndarray:
    """(32, 3): each quad split along a diagonal chosen per frame (the first frame's: a, c; frames 1
    and 3 split some along b, d), triangles started at another corner in frames 1 and 2."""
    quads = _quads()
    other_diagonal = (np.arange(len(quads)) * (frame + 1)) % 3 == 1 if frame else np.zeros(len(quads), bool)
    along_ac = quads[:, [[0, 1, 2], [0, 2, 3]]]
    along_bd = quads[:, [[0, 1, 3], [1, 2, 3]]]
    triangles = np.where(other_diagonal[:, None, None], along_bd, along_ac).reshape(-1, 3)
    rotation = (np.arange(len(triangles)) * frame) % 3  # the same triangle started at another corner
    return triangles[np.arange(len(triangles))[:, None], (rotation[:, None] + np.arange(3)) % 3]


def _write_obj(path: Path, positions: np.ndarray, triangles: np.ndarray, frame: int, vt: bool) -> None:
    """An OBJ frame; with ``vt``, a texture coordinate per position, its vt lines in an order of
    the frame's own (as an exporter numbers them by first use)."""
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in positions]
    corners = triangles + 1
    if vt:
        order = np.random.default_rng(frame).permutation(len(positions)) if frame else np.arange(len(positions))
        lines += [f"vt {x:.9g} {y:.9g}" for x, y in positions[order, :2]]
        vt_of_position = np.argsort(order) + 1
        lines += [" ".join(["f"] + [f"{p}/{vt_of_position[p - 1]}" for p in face]) for face in corners]
    else:
        lines += [f"f {a} {b} {c}" for a, b, c in corners]
    path.write_text("\n".join(lines) + "\n")


def _colours(frame: int) -> VertexColours:
    values = np.full((1, (GRID + 1) ** 2, 3), 40 * frame, np.float32)
    return VertexColours(values, ("red", "green", "blue"), ("u1", "u1", "u1"))


def _write_frames(folder: Path, fmt: str, with_uvs: bool = False) -> Path:
    """The deforming grid as FRAMES files, each triangulated its own way."""
    folder.mkdir()
    for frame in range(FRAMES):
        path = folder / f"grid_{frame + 1:03d}.{fmt}"
        positions, triangles = _grid_positions(frame), _triangles(frame)
        if fmt == "obj":
            _write_obj(path, positions, triangles, frame, with_uvs)
        else:
            uvs = positions[:, :2] if with_uvs else None
            write_ply(path, positions, triangles, uvs=uvs, colours=_colours(frame))
    return folder


def _read(folder: Path, textured: bool):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read = read_textured_sequence(folder) if textured else read_sequence(folder)
    return read, [str(warning.message) for warning in caught]


@pytest.mark.parametrize(("fmt", "with_uvs"), [("obj", False), ("obj", True), ("ply", False), ("ply", True)])
def test_frames_split_otherwise_are_read_with_the_first_frames_triangles(
    tmp_path: Path, fmt: str, with_uvs: bool
) -> None:
    folder = _write_frames(tmp_path / "grid", fmt, with_uvs)
    with warnings.catch_warnings():  # the files as written: each frame its own way
        warnings.simplefilter("ignore")
        written = [read_mesh(path)[1] for path in frame_files(folder)]
    assert [np.array_equal(faces, _triangles(0)) for faces in written] == [True, False, False, False]
    mesh, messages = _read(folder, textured=False)
    np.testing.assert_array_equal(mesh.faces, _triangles(0))
    for frame in range(FRAMES):
        np.testing.assert_array_equal(mesh.frames[frame], _grid_positions(frame))
    # One warning for the sequence, naming the first such frame and how many there are; frame 2's
    # triangles, only started at other corners, are the first frame's listed otherwise.
    about = [message for message in messages if "triangulate some polygons differently" in message]
    assert len(about) == 1
    assert about[0].startswith(f"{folder / 'grid_002.'}{fmt}: 2 of the 4 frames")
    assert "the first frame's triangles" in about[0]
    listed = [message for message in messages if "in another order or start them at other corners" in message]
    assert len(listed) == 1 and listed[0].startswith(f"{folder / 'grid_003.'}{fmt}: 1 of the 4 frames")


@pytest.mark.parametrize(("fmt", "with_uvs"), [("obj", False), ("obj", True), ("ply", True)])
def test_textured_frames_split_otherwise_keep_texture_and_colours(tmp_path: Path, fmt: str, with_uvs: bool) -> None:
    folder = _write_frames(tmp_path / "grid", fmt, with_uvs)
    read, messages = _read(folder, textured=True)
    assert not [message for message in messages if "written without" in message]  # nothing dropped
    mesh = read.mesh
    points = np.arange(len(mesh.frames[0])) if read.points is None else read.points
    # The first frame's triangles, on whatever vertices the texture split the positions into.
    np.testing.assert_array_equal(points[mesh.faces], _triangles(0))
    for frame in range(FRAMES):
        np.testing.assert_array_equal(mesh.frames[frame], _grid_positions(frame)[points])
    if with_uvs:
        np.testing.assert_array_equal(read.texture.uvs, _grid_positions(0)[points, :2])
    else:
        assert read.texture is None
    if fmt == "ply":  # each frame's own colours
        np.testing.assert_array_equal(read.colours.values[:, :, 0], 40 * np.arange(FRAMES)[:, None].repeat(25, 1))


@pytest.mark.parametrize(("fmt", "with_uvs"), [("obj", True), ("ply", False)])
def test_simplify_reads_frames_split_otherwise_and_writes_levels(
    tmp_path: Path, capsys: pytest.CaptureFixture, fmt: str, with_uvs: bool
) -> None:
    folder = _write_frames(tmp_path / "grid", fmt, with_uvs)
    assert main(["simplify", str(folder), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    levels = sorted(path for path in (tmp_path / "out").iterdir() if path.is_dir())
    assert levels and all(len(frame_files(level)) == FRAMES for level in levels)
    assert "triangulate some polygons differently" in capsys.readouterr().err


def _frame_with(fmt: str, folder: Path, faces: np.ndarray) -> Path:
    """``folder``'s third frame rewritten with ``faces``."""
    path = folder / f"grid_003.{fmt}"
    if fmt == "obj":
        _write_obj(path, _grid_positions(2), faces, 2, vt=False)
    else:
        write_ply(path, _grid_positions(2), faces, colours=_colours(2))
    return path


@pytest.mark.filterwarnings("ignore::animlod.io.obj.UnreadAttributesWarning")  # the PLY colours read_sequence skips
@pytest.mark.parametrize("fmt", ["obj", "ply"])
@pytest.mark.parametrize(
    "change",
    [
        "a triangle joining other vertices",
        "a quad turned over",  # its triangles against the winding
        "two triangles trading corners",  # the same vertices, but the triangles tile no polygon of the first frame
    ],
)
def test_frames_whose_faces_differ_otherwise_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture, fmt: str, change: str
) -> None:
    folder = _write_frames(tmp_path / "grid", fmt)
    faces = _triangles(2).copy()
    bad_face = 9
    if change == "a triangle joining other vertices":
        faces[bad_face] = [0, 6, 12]
    elif change == "a quad turned over":
        faces[bad_face - 1 : bad_face + 1] = faces[bad_face - 1 : bad_face + 1, ::-1]
        bad_face -= 1
    else:  # quad 4's first triangle and quad 5's, each with the other's third corner
        quads = _quads()
        faces[8:12] = [quads[4, [0, 1, 2]], quads[4, [0, 2, 3]], quads[5, [0, 1, 2]], quads[5, [0, 2, 3]]]
        faces[8, 2], faces[10, 2] = faces[10, 2], faces[8, 2]
        bad_face = 8
    path = _frame_with(fmt, folder, faces)
    # Each triangle is a face of the file: an OBJ face's line comes after the 25 v lines.
    face = f"face {bad_face} (line {bad_face + 26})" if fmt == "obj" else f"face {bad_face}"
    expected = (f"{path}: {face}: its triangle on vertices {faces[bad_face].tolist()} (counted from 0) is no "
                "triangle of the first frame grid_001.") + fmt  # fmt: skip
    with pytest.raises(FormatError) as caught:
        read_sequence(folder)
    assert str(caught.value).startswith(expected)
    assert "not a re-triangulation of the first frame's polygons" in str(caught.value)
    assert main(["simplify", str(folder), "-o", str(tmp_path / "out"), "--no-metrics"]) == 2
    assert f"animlod simplify: error: {expected}" in capsys.readouterr().err


def _closed_quad_box(cells: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A closed box of (6 * cells**2) quads on shared corners: positions and (Q, 4) quads, each
    counter-clockwise seen from outside."""
    steps = np.linspace(-1.0, 1.0, cells + 1)
    index: dict[tuple, int] = {}
    quads = []
    for axis in range(3):
        for side in (-1.0, 1.0):
            for i in range(cells):
                for j in range(cells):
                    quad = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        point = [0.0, 0.0, 0.0]
                        point[axis], point[(axis + 1) % 3], point[(axis + 2) % 3] = side, steps[i + di], steps[j + dj]
                        quad.append(index.setdefault(tuple(point), len(index)))
                    quads.append(quad if side > 0 else quad[::-1])
    return np.array(list(index), dtype=np.float32), np.array(quads)


def test_a_closed_mesh_with_every_diagonal_turned_is_the_same_surface(tmp_path: Path) -> None:
    # Every quad of a closed box split along its other diagonal: the changed triangles are the whole
    # surface and have no boundary, as in the case below, but each quad's corners are on its own.
    positions, quads = _closed_quad_box()
    write_ply(tmp_path / "box_1.ply", positions, quads[:, [[0, 1, 2], [0, 2, 3]]].reshape(-1, 3))
    write_ply(tmp_path / "box_2.ply", positions * 1.5, quads[:, [[0, 1, 3], [1, 2, 3]]].reshape(-1, 3))
    with pytest.warns(UserWarning, match="triangulate some polygons differently"):
        mesh = read_sequence(tmp_path)
    np.testing.assert_array_equal(mesh.frames[1], positions * 1.5)


def test_a_closed_mesh_whose_vertices_are_numbered_otherwise_is_refused(tmp_path: Path) -> None:
    # Each frame's vertices listed in another order with its faces renumbered to match: on a closed
    # mesh the changed triangles (all of them) had no boundary and used every vertex, which the test
    # took for a re-triangulation, and 217 of 218 vertices were read at another vertex's place (a
    # hunt over Blender's PLY exports found it on front-projected texture coordinates).
    positions, quads = _closed_quad_box()
    triangles = quads[:, [[0, 1, 2], [0, 2, 3]]].reshape(-1, 3)
    number = np.random.default_rng(0).permutation(len(positions))  # each vertex's number in frame 2
    moved = np.empty_like(positions)
    moved[number] = positions + [1.0, 0.0, 0.0]
    write_ply(tmp_path / "box_1.ply", positions, triangles)
    write_ply(tmp_path / "box_2.ply", moved, number[triangles])
    with pytest.raises(FormatError, match="are not a re-triangulation of the first frame's polygons"):
        read_sequence(tmp_path)
