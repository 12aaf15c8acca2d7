"""The rational FFD of the core (animlod._core.ffd_*) against independent numpy formulas."""

from __future__ import annotations

from math import comb

import numpy as np
import pytest

from animlod import _core
from animlod.face_lod.lattice import bounding_box, region_lattice


def bezier_ffd(local: np.ndarray, control: np.ndarray) -> np.ndarray:
    """Plain tensor-product Bezier volume, written out from the Bernstein formula."""
    result = np.zeros((len(local), 3))
    sizes = control.shape[:3]
    bases = [
        np.stack([comb(n - 1, i) * local[:, axis] ** i * (1 - local[:, axis]) ** (n - 1 - i) for i in range(n)], 1)
        for axis, n in enumerate(sizes)
    ]
    for i in range(sizes[0]):
        for j in range(sizes[1]):
            for k in range(sizes[2]):
                result += (bases[0][:, i] * bases[1][:, j] * bases[2][:, k])[:, None] * control[i, j, k]
    return result


@pytest.fixture
def local() -> np.ndarray:
    return np.random.default_rng(3).random((200, 3)).astype(np.float32)


@pytest.mark.parametrize("size", [(3, 3, 3), (2, 2, 2), (4, 3, 2)])
def test_rational_ffd_with_unit_weights_is_the_plain_bezier_ffd(local, size):
    control = np.random.default_rng(4).normal(size=size + (3,))
    expected = bezier_ffd(local.astype(np.float64), control)
    np.testing.assert_allclose(_core.ffd_evaluate(local, control), expected, atol=1e-5)
    np.testing.assert_allclose(_core.ffd_evaluate(local, control, np.ones(size)), expected, atol=1e-5)
    # Control: other weights give another volume, so the comparison above can fail.
    weights = np.random.default_rng(5).uniform(0.5, 3.0, size)
    assert np.abs(_core.ffd_evaluate(local, control, weights) - expected).max() > 1e-2


def test_rational_ffd_matches_its_formula(local):
    control = np.random.default_rng(6).normal(size=(3, 3, 3, 3))
    weights = np.random.default_rng(7).uniform(0.5, 3.0, (3, 3, 3))
    numerator = bezier_ffd(local.astype(np.float64), control * weights[..., None])
    denominator = bezier_ffd(local.astype(np.float64), np.broadcast_to(weights[..., None], (3, 3, 3, 3)))[:, :1]
    np.testing.assert_allclose(_core.ffd_evaluate(local, control, weights), numerator / denominator, atol=1e-5)


def test_local_coordinates_of_a_box():
    box = np.array([[1.0, 2.0, 3.0], [2.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 0.5]])
    points = np.array([[1.0, 2.0, 3.0], [3.0, 6.0, 3.5], [2.0, 3.0, 3.25]], np.float32)
    np.testing.assert_allclose(_core.ffd_local_coordinates(points, box), [[0, 0, 0], [1, 1, 1], [0.5, 0.25, 0.5]])


def test_zero_displacement_leaves_points_whatever_the_weights(local):
    rest = np.random.default_rng(8).normal(size=(len(local), 3)).astype(np.float32)
    lattice = np.zeros(len(local), np.int32)
    weights = np.random.default_rng(9).uniform(0.5, 3.0, 27)
    out = _core.ffd_displace(rest, local, lattice, np.array([[3, 3, 3]]), np.zeros((27, 3)), weights)
    assert out.tobytes() == rest.tobytes()


def test_displace_with_unit_weights_is_the_ffd_of_the_displaced_regular_lattice(local):
    box = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 3.0]])
    rest = (local.astype(np.float64) * [2.0, 1.0, 3.0]).astype(np.float32)
    delta = np.random.default_rng(10).normal(scale=0.1, size=(3, 3, 3, 3))
    local_in_box = _core.ffd_local_coordinates(rest, box)
    # The regular lattice of the box: its plain FFD is the identity (linear precision).
    regular = box[0] + np.stack(np.meshgrid(*[np.linspace(0, 1, 3)] * 3, indexing="ij"), -1) @ box[1:]
    expected = _core.ffd_evaluate(local_in_box, regular + delta)
    moved = _core.ffd_displace(rest, local_in_box, np.zeros(len(rest), np.int32), np.array([[3, 3, 3]]),
                               delta.reshape(-1, 3))  # fmt: skip
    np.testing.assert_allclose(moved, expected, atol=1e-5)
    assert np.abs(moved - rest).max() > 1e-2  # the displacement did move the points


def test_a_2x2x2_fit_reproduces_a_trilinear_displacement_exactly(local):
    corners = np.random.default_rng(11).normal(size=(2, 2, 2, 3))
    trilinear = bezier_ffd(local.astype(np.float64), corners)  # degree 1 Bernstein = trilinear
    fitted = _core.ffd_fit(
        local, trilinear.astype(np.float32), [2, 2, 2], options=_core.FfdFitOptions(smoothness=0.0, ridge=0.0)
    )
    np.testing.assert_allclose(fitted, corners, atol=1e-4)
    np.testing.assert_allclose(_core.ffd_evaluate(local, fitted), trilinear, atol=1e-5)
    # Control: a quadratic field is not trilinear; the 2x2x2 fit leaves a residual there.
    quadratic = trilinear + np.stack([local[:, 0] ** 2, 0 * local[:, 0], 0 * local[:, 0]], 1)
    fitted = _core.ffd_fit(local, quadratic.astype(np.float32), [2, 2, 2])
    assert np.abs(_core.ffd_evaluate(local, fitted) - quadratic).max() > 1e-2


def test_a_region_whose_mpa_is_trilinear_keeps_it_exactly_on_a_2x2x2_lattice():
    from animlod.face_lod import FaceRegions, FaceRig, Mpa
    from animlod.synth import icosphere

    positions, faces = icosphere(2, 1.0)
    rig = FaceRig(positions, faces, FaceRegions(["ball"], np.zeros(len(positions), np.int32)))
    corners = np.random.default_rng(12).normal(scale=0.1, size=(2, 2, 2, 3))
    # The same trilinear field on 3x3x3 control points (degree elevation: the field at i/2, j/2, k/2).
    grid = np.stack(np.meshgrid(*[np.linspace(0, 1, 3)] * 3, indexing="ij"), -1).reshape(-1, 3).astype(np.float32)
    rig.add_mpa(Mpa("warp", {"ball": bezier_ffd(grid, corners).reshape(3, 3, 3, 3)}))
    np.testing.assert_allclose(rig.reduced_displacements(0, "ball"), corners, atol=1e-6)
    full = rig.animator().frame(np.ones(1))
    reduced = rig.animator(reduced=["ball"]).frame(np.ones(1))
    np.testing.assert_allclose(reduced, full, atol=1e-6)
    assert np.abs(full - positions).max() > 1e-2


def test_degenerate_boxes_and_bad_arguments_are_named():
    flat = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match="axis U is degenerate"):
        _core.ffd_local_coordinates(np.zeros((1, 3), np.float32), flat)
    with pytest.raises(ValueError, match="region 'dot'.*degenerate"):
        region_lattice("dot", np.ones((4, 3), np.float32))
    with pytest.raises(ValueError, match="no vertex"):
        region_lattice("empty", np.zeros((0, 3), np.float32))
    with pytest.raises(ValueError, match=r"control_points: expected shape \(l, m, n, 3\)"):
        _core.ffd_evaluate(np.zeros((1, 3), np.float32), np.zeros((27, 3)))
    with pytest.raises(ValueError, match="weight of control point 4"):
        weights = np.ones((2, 2, 2))
        weights.flat[4] = -1.0
        _core.ffd_evaluate(np.zeros((1, 3), np.float32), np.zeros((2, 2, 2, 3)), weights)
    with pytest.raises(ValueError, match="vertex 1 names lattice 3"):
        _core.ffd_displace(np.zeros((2, 3), np.float32), np.zeros((2, 3), np.float32), np.array([0, 3], np.int32),
                           np.array([[2, 2, 2]]), np.zeros((8, 3)))  # fmt: skip
    with pytest.raises(ValueError, match="8 control points, the lattice sizes give 27"):
        _core.ffd_displace(np.zeros((1, 3), np.float32), np.zeros((1, 3), np.float32), np.zeros(1, np.int32),
                           np.array([[3, 3, 3]]), np.zeros((8, 3)))  # fmt: skip
    with pytest.raises(ValueError, match="no points"):
        _core.ffd_fit(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.float32), [2, 2, 2])


def test_bounding_box_gives_a_flat_region_depth():
    box = bounding_box(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]]))
    assert box[3, 2] > 0.0  # the region is flat in z, its box is not
    np.testing.assert_allclose(box[0], [-0.1, -0.1, -0.1])
