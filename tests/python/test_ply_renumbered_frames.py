"""PLY frames that number their vertices in another order than the first frame, as Blender's PLY
exporter does with "Triangulate Faces" where a quad's diagonal changes with the frame's shape
(io/vertex_renumbering.py): until 2026-12-07 such sequences were refused."""

from __future__ import annotations

import numpy as np
import pytest

from animlod.io.errors import FormatError
from animlod.io.meshseq import read_sequence, read_textured_sequence
from animlod.io.ply import read_ply
from animlod.io.vertex_renumbering import first_frame_order

SIDE = 5  # points per side of the grid of quads


def _grid_frames(frames: int, parts: int = 1) -> np.ndarray:
    """(frames, parts * SIDE * SIDE, 3) positions of ``parts`` grids side by side (loose parts),
    that bend more in each frame."""
    x, y = np.meshgrid(np.linspace(0.0, 1.0, SIDE), np.linspace(0.0, 1.0, SIDE), indexing="ij")
    flat = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    bend = np.stack([np.zeros(x.size), np.zeros(x.size), np.sin(3.0 * x.ravel()) * y.ravel()], axis=1)
    grids = np.concatenate([flat + [2.0 * part, 0.0, 0.0] for part in range(parts)])
    return np.stack([grids + 0.2 * k * np.tile(bend, (parts, 1)) for k in range(frames)])


def _write_exported_frame(path, positions: np.ndarray, flipped: np.ndarray, mirrored: bool = False) -> None:
    """One frame as the exporter writes it: each quad of each grid (``positions`` hold SIDE * SIDE
    points a grid) split along a-c, or b-d where ``flipped`` (started at d), and the points numbered in the order
    the triangles first use them, each with its texture coordinates (its place on its grid: loose
    parts alike have the same; ``mirrored``: the grid's two halves have the same, mirrored)."""
    triangles = []
    cells = [
        (part, i, j) for part in range(len(positions) // SIDE**2) for i in range(SIDE - 1) for j in range(SIDE - 1)
    ]
    for quad, (part, i, j) in enumerate(cells):
        a, b, c, d = part * SIDE**2 + np.array(
            [i * SIDE + j, (i + 1) * SIDE + j, (i + 1) * SIDE + j + 1, i * SIDE + j + 1]
        )
        triangles += [(d, a, b), (b, c, d)] if flipped[quad] else [(a, b, c), (a, c, d)]
    corners = np.array(triangles).ravel()
    points = corners[np.sort(np.unique(corners, return_index=True)[1])]  # in the order of first use
    number = np.empty(len(positions), np.int64)
    number[points] = np.arange(points.size)
    uvs = np.stack(np.divmod(points % SIDE**2, SIDE), axis=1) / (SIDE - 1)
    if mirrored:
        uvs[:, 0] = np.abs(uvs[:, 0] - 0.5)
    lines = ["ply", "format ascii 1.0", f"element vertex {points.size}", "property float x", "property float y",
             "property float z", "property float s", "property float t", f"element face {len(triangles)}",
             "property list uchar uint vertex_indices", "end_header"]  # fmt: skip
    lines += [" ".join(f"{value:.7g}" for value in (*positions[p], *uv)) for p, uv in zip(points, uvs)]
    lines += [f"3 {' '.join(str(n) for n in number[list(triangle)])}" for triangle in triangles]
    path.write_text("\n".join(lines) + "\n")


def _sequence(folder, frames: int = 3, parts: int = 1, mirrored: bool = False):
    """A folder of exported frames of ``parts`` grids, later frames with other diagonals (so other
    numbers) in some quads; and the grids' positions in each frame."""
    positions = _grid_frames(frames, parts)
    quads = parts * (SIDE - 1) ** 2
    for k in range(frames):
        flipped = np.arange(quads) % (k + 2) == 1
        _write_exported_frame(folder / f"frame_{k:03d}.ply", positions[k], flipped, mirrored)
    return folder, positions


def test_frames_numbered_otherwise_are_read_in_the_first_frames_order(tmp_path):
    folder, positions = _sequence(tmp_path)
    with pytest.warns(UserWarning, match="number their vertices in another order than the first frame"):
        mesh, texture, *_ = read_textured_sequence(folder)
    # Each vertex's texture coordinates name its grid point: it stands where that point does in every frame.
    point = np.rint(texture.uvs[:, 0] * (SIDE - 1)).astype(int) * SIDE + np.rint(texture.uvs[:, 1] * (SIDE - 1)).astype(
        int
    )
    np.testing.assert_allclose(mesh.frames, positions[:, point], atol=1e-6)
    assert mesh.face_count == 2 * (SIDE - 1) ** 2


def test_frames_whose_texture_coordinates_do_not_match_are_still_refused(tmp_path):
    folder, _ = _sequence(tmp_path, frames=2)
    later = folder / "frame_001.ply"
    text = later.read_text().split("\n")
    start = text.index("end_header") + 1
    for line in range(start, start + SIDE * SIDE):  # every s shifted: no vertex of the first frame's
        x, y, z, s, t = text[line].split()
        text[line] = f"{x} {y} {z} {float(s) + 0.01:.7g} {t}"
    later.write_text("\n".join(text))
    with pytest.raises(FormatError, match="numbers each frame's vertices in another order"):
        read_textured_sequence(folder)


def test_an_n_gon_fanned_from_another_corner_is_matched():
    # A 16-gon's 14 triangles fanned from corner 0, then from corner 7, each frame numbering its
    # vertices by first use: the corners a frame's face uses are up to 13 faces away in the first
    # frame's (a 32-gon cap of a Blender cylinder was refused: the matching looked 2 faces away).
    corners = 16
    uvs = np.stack([np.cos(np.arange(corners)), np.sin(np.arange(corners))], axis=1)

    def fan(start: int) -> tuple[np.ndarray, np.ndarray]:
        """The fan's triangles over the vertices numbered by first use, and each vertex's corner."""
        triangles = np.array([[start, start + i, start + i + 1] for i in range(1, corners - 1)]) % corners
        used = triangles.ravel()[np.sort(np.unique(triangles.ravel(), return_index=True)[1])]
        number = np.empty(corners, np.int64)
        number[used] = np.arange(corners)
        return number[triangles], used

    (first_faces, first_corner), (faces, corner) = fan(0), fan(7)
    order = first_frame_order(first_faces, uvs[first_corner], faces, uvs[corner])
    np.testing.assert_array_equal(first_corner[order], corner)  # each vertex matched to its own corner


@pytest.mark.parametrize("parts, mirrored", [(1, False), (3, False), (3, True)])
def test_a_sequence_read_without_texture_coordinates_matches_them_too(tmp_path, parts, mirrored):
    # read_sequence (tdag build, face) reads positions alone; the texture coordinates still tell
    # which vertex is which, and the vertices keep the files' first-frame numbering; also where
    # loose grids alike, or mirrored halves, repeat texture coordinates nearby.
    folder, positions = _sequence(tmp_path, parts=parts, mirrored=mirrored)
    with pytest.warns(UserWarning, match="number their vertices in another order than the first frame"):
        mesh = read_sequence(folder)
    first, _ = read_ply(folder / "frame_000.ply")
    point = [int(np.argmin(np.linalg.norm(positions[0] - vertex, axis=1))) for vertex in first]
    np.testing.assert_allclose(mesh.frames, positions[:, point], atol=1e-6)


def test_repeated_texture_coordinates_are_told_apart_by_the_neighbours_matches():
    # Two loose quads alike (the same texture coordinates A, B, C, D), both split along b-d from d
    # in the later frame: a and b of each meet no corner of their own, and each has two candidates
    # nearby, one per quad; the one beside its neighbour d's match is it.
    a, b, c, d = (np.array([0.0, 0.0]), np.array([1.0, 0.0]), np.array([1.0, 1.0]), np.array([0.0, 1.0]))
    first_faces = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    first_uvs = np.array([a, b, c, d, a, b, c, d])
    faces = np.array([[0, 1, 2], [2, 3, 0], [4, 5, 6], [6, 7, 4]])  # d, a, b, c numbered by first use
    uvs = np.array([d, a, b, c, d, a, b, c])
    assert first_frame_order(first_faces, first_uvs, faces, uvs).tolist() == [3, 0, 1, 2, 7, 4, 5, 6]
