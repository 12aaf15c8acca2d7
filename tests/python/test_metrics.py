"""Surface error metrics: exact values on shapes whose distances are known."""

from __future__ import annotations

import numpy as np
import pytest
from simplify_inputs import ellipsoid

from animlod import _core, simplify_animated
from animlod.metrics import frame_hausdorff, hausdorff_distance, hausdorff_distances, sample_surface, surface_error
from animlod.model import AnimatedMesh


def flat_square(offsets: np.ndarray) -> AnimatedMesh:
    """The unit square in z = offset per frame, two triangles."""
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    frames = np.repeat(square[None], len(offsets), axis=0)
    frames[:, :, 2] = np.asarray(offsets, np.float32)[:, None]
    return AnimatedMesh([[0, 1, 2], [0, 2, 3]], frames)


def test_a_mesh_has_no_error_against_itself():
    mesh = ellipsoid(frames=2)
    error = surface_error(mesh, mesh, samples=500)
    np.testing.assert_allclose(error.hausdorff, 0.0, atol=1e-6)
    np.testing.assert_allclose(error.rms, 0.0, atol=1e-6)


def test_an_offset_square_is_exactly_its_offset_away_in_every_frame():
    original = flat_square(np.zeros(3))
    moved = flat_square(np.array([0.0, 0.25, 0.5]))
    error = surface_error(original, moved, samples=300)
    np.testing.assert_allclose(error.hausdorff, [0.0, 0.25, 0.5], atol=1e-6)
    np.testing.assert_allclose(error.rms, [0.0, 0.25, 0.5], atol=1e-6)
    np.testing.assert_allclose(error.diagonal, np.sqrt(2.0), rtol=1e-6)
    summary = error.summary()
    assert summary["hausdorff_max"] == pytest.approx(0.5 / np.sqrt(2.0), rel=1e-6)
    assert summary["rms_mean"] == pytest.approx(0.25 / np.sqrt(2.0), rel=1e-6)


def test_samples_follow_the_surface_and_are_reproducible():
    mesh = ellipsoid(frames=3)
    samples = sample_surface(mesh, 1000, seed=3)
    again = sample_surface(mesh, 1000, seed=3)
    np.testing.assert_array_equal(samples.faces, again.faces)
    np.testing.assert_allclose(samples.barycentric.sum(axis=1), 1.0)
    assert samples.barycentric.min() >= 0.0
    # Frame 2 stretches x by 2: the samples' x doubles with it.
    np.testing.assert_allclose(samples.positions(mesh, 2)[:, 0], 2.0 * samples.positions(mesh, 0)[:, 0], atol=1e-6)


def test_frame_counts_must_match():
    with pytest.raises(ValueError, match="simplified: 2 frames, the original has 3"):
        surface_error(flat_square(np.zeros(3)), flat_square(np.zeros(2)))


def test_hausdorff_distance_is_the_largest_of_surface_error_to_the_bit():
    original = ellipsoid(frames=4)
    level = simplify_animated(original, (0.1,)).levels[0].mesh
    largest = surface_error(original, level, samples=2000, seed=4).hausdorff.max()
    assert largest > 0.0
    for at_least in (0.0, 0.5 * largest, 0.999 * largest, largest, 2.0 * largest):
        assert hausdorff_distance(original, level, samples=2000, seed=4, at_least=at_least) == max(at_least, largest)
    with pytest.raises(ValueError, match="simplified: 2 frames, the original has 3"):
        hausdorff_distance(flat_square(np.zeros(3)), flat_square(np.zeros(2)))
    with pytest.raises(ValueError, match="at_least: nan, expected a distance >= 0"):
        hausdorff_distance(original, level, at_least=float("nan"))
    # Several levels of one original at once: each as alone, from its own floor.
    levels = [result.mesh for result in simplify_animated(original, (0.5, 0.1)).levels]
    floors = [0.0, 2.0 * largest]
    alone = [hausdorff_distance(original, each, samples=2000, seed=4, at_least=f) for each, f in zip(levels, floors)]
    assert hausdorff_distances(original, levels, samples=2000, seed=4, at_least=floors) == alone
    assert hausdorff_distances(original, []) == []
    with pytest.raises(ValueError, match="at_least: 1 values for 2 simplified meshes"):
        hausdorff_distances(original, levels, at_least=[0.0])


def test_frame_hausdorff_is_surface_errors_hausdorff_to_the_bit():
    # The face levels' worst frame relative to its own size, without the RMS's full distances.
    original = ellipsoid(frames=4)
    level = simplify_animated(original, (0.1,)).levels[0].mesh
    full = surface_error(original, level, samples=2000, seed=4)
    per_frame = frame_hausdorff(original, level, samples=2000, seed=4)
    assert np.all(full.hausdorff > 0.0) and len(np.unique(full.hausdorff)) == 4
    np.testing.assert_array_equal(per_frame.hausdorff, full.hausdorff)
    np.testing.assert_array_equal(per_frame.diagonal, full.diagonal)
    np.testing.assert_array_equal(per_frame.relative_hausdorff, full.relative_hausdorff)
    itself = surface_error(original, original, samples=500).hausdorff  # rounding: the samples lie between vertices
    np.testing.assert_array_equal(frame_hausdorff(original, original, samples=500).hausdorff, itself)
    with pytest.raises(ValueError, match="simplified: 2 frames, the original has 3"):
        frame_hausdorff(flat_square(np.zeros(3)), flat_square(np.zeros(2)))


def test_vertices_no_face_uses_are_not_measured():
    # OBJ files often keep vertices no face uses (left over from a deleted part): no surface.
    original = ellipsoid(frames=3)
    level = simplify_animated(original, (0.1,)).levels[0].mesh
    far = np.full((original.frame_count, 5, 3), 50.0, np.float32)
    extended = AnimatedMesh(original.faces, np.concatenate([original.frames, far], axis=1))
    expected, got = surface_error(original, level, samples=2000), surface_error(extended, level, samples=2000)
    for name in ("hausdorff", "rms", "diagonal"):
        np.testing.assert_array_equal(getattr(got, name), getattr(expected, name))
    assert hausdorff_distance(extended, level, samples=2000) == hausdorff_distance(original, level, samples=2000)


def test_point_mesh_distance_matches_libigl_on_a_deformed_surface():
    igl = pytest.importorskip("igl")  # the reference the metrics used before the core's
    mesh = ellipsoid(frames=3)
    vertices = mesh.frames[2].astype(np.float64)
    faces = np.concatenate([mesh.faces, [[0, 0, 1], [2, 2, 2]]])  # a segment and a point
    rng = np.random.default_rng(5)
    points = np.concatenate([vertices * (1.0 + 0.1 * rng.normal(size=(len(vertices), 1))), rng.normal(size=(500, 3))])
    expected = igl.point_mesh_squared_distance(points, vertices, faces.astype(np.int64))[0]
    for threads in (1, 2):
        np.testing.assert_allclose(
            _core.point_mesh_squared_distance(points, vertices, faces, threads=threads), expected, rtol=1e-9, atol=1e-14
        )
    # Every frame at once: frames 1 and 2 refit frame 0's tree.
    frames = mesh.frames.astype(np.float64)
    moved = points[None] * np.array([1.0, 1.5, 0.5])[:, None, None]
    each = [igl.point_mesh_squared_distance(moved[t], frames[t], faces.astype(np.int64))[0] for t in range(3)]
    np.testing.assert_allclose(_core.point_mesh_squared_distance(moved, frames, faces), each, rtol=1e-9, atol=1e-14)


def test_point_mesh_distance_of_no_frame_is_empty():
    triangle = np.array([[0, 1, 2]])
    assert _core.point_mesh_squared_distance(np.zeros((0, 5, 3)), np.zeros((0, 3, 3)), triangle).shape == (0, 5)
    assert _core.point_mesh_max_squared_distance(np.zeros((0, 5, 3)), np.zeros((0, 3, 3)), triangle, floor=0.5) == 0.5


def test_point_mesh_distance_names_bad_input():
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0]], np.float64)
    with pytest.raises(ValueError, match=r"faces\[0\]: vertex index 3 is outside \[0, 3\)"):
        _core.point_mesh_squared_distance(np.zeros((1, 3)), square, np.array([[0, 1, 3]]))
    with pytest.raises(ValueError, match="no triangle"):
        _core.point_mesh_squared_distance(np.zeros((1, 3)), square, np.zeros((0, 3), np.int32))
    with pytest.raises(ValueError, match=r"points\[1\]: not a finite position"):
        _core.point_mesh_squared_distance([[0, 0, 0], [np.nan, 0, 0]], square, np.array([[0, 1, 2]]))
    with pytest.raises(ValueError, match=r"points\[1\]: not a finite position"):
        _core.point_mesh_max_squared_distance([[0, 0, 0], [np.nan, 0, 0]], square, np.array([[0, 1, 2]]))
    with pytest.raises(ValueError, match=r"vertices: expected"):
        _core.point_mesh_max_squared_distance(np.zeros((2, 1, 3)), square, np.array([[0, 1, 2]]))
    points, triangle = np.zeros((3, 3)), np.array([[0, 1, 2]])
    for ends, floors, message in (
        ([1, 2], [0.0, 0.0], "the last end is not the point count, 3"),
        ([2, 1, 3], [0.0] * 3, r"segment_ends\[1\]: 1 is not within the points \(3\) and increasing"),
        ([-1, 3], [0.0, 0.0], r"segment_ends\[0\]: negative"),
        ([1, 3], [0.0], r"floors: expected shape \(S,\) like segment_ends"),
        ([1, 3], [0.0, np.nan], r"floors\[1\]: not a number"),
    ):
        with pytest.raises(ValueError, match=message):
            _core.point_mesh_max_squared_distances(points, square, triangle, np.array(ends), np.array(floors))


def test_sample_counts_and_seeds_are_checked_by_name():
    from animlod import synth

    mesh = synth.bending_cylinder(frames=2, rings=6, segments=6)
    with pytest.raises(ValueError, match="samples: expected a whole number >= 0, got -5"):
        surface_error(mesh, mesh, samples=-5)  # numpy's "negative dimensions are not allowed" before
    with pytest.raises(ValueError, match="samples: expected a whole number >= 0, got 1.5"):
        sample_surface(mesh, 1.5)
    with pytest.raises(ValueError, match="seed: expected a whole number >= 0, got -1"):
        surface_error(mesh, mesh, seed=-1)
