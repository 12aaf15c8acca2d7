import numpy as np
import pytest

from animlod import rotations

ORDERS = ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"]


def _random_unit_quaternions(count: int, seed: int = 0) -> np.ndarray:
    q = np.random.default_rng(seed).normal(size=(count, 4))
    return rotations.normalize(q) * np.sign(q[:, 3:4])


def test_matrix_round_trip():
    q = _random_unit_quaternions(200)
    back = rotations.from_matrix(rotations.to_matrix(q))
    np.testing.assert_allclose(back, q, atol=1e-12)


def test_to_matrix_is_a_rotation():
    m = rotations.to_matrix(_random_unit_quaternions(50))
    np.testing.assert_allclose(m @ np.swapaxes(m, -1, -2), np.broadcast_to(np.eye(3), m.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(m), 1.0, atol=1e-12)


def test_rotate_matches_matrix():
    q = _random_unit_quaternions(30)
    v = np.random.default_rng(1).normal(size=(30, 3))
    np.testing.assert_allclose(rotations.rotate(q, v), np.einsum("nij,nj->ni", rotations.to_matrix(q), v), atol=1e-12)


def test_multiply_composes_like_matrices():
    a, b = _random_unit_quaternions(20, 2), _random_unit_quaternions(20, 3)
    np.testing.assert_allclose(
        rotations.to_matrix(rotations.multiply(a, b)), rotations.to_matrix(a) @ rotations.to_matrix(b), atol=1e-12
    )


@pytest.mark.parametrize("order", ORDERS)
def test_euler_is_intrinsic_product_in_channel_order(order):
    angles = np.array([0.3, -0.7, 1.1])
    expected = np.eye(3)
    for axis_name, angle in zip(order, angles):
        axis = np.zeros(3)
        axis["XYZ".index(axis_name)] = 1.0
        expected = expected @ rotations.to_matrix(rotations.from_axis_angle(axis, angle))
    np.testing.assert_allclose(rotations.to_matrix(rotations.from_euler(angles, order)), expected, atol=1e-12)


@pytest.mark.parametrize("order", ORDERS)
def test_euler_round_trip(order):
    angles = np.random.default_rng(4).uniform(-1.4, 1.4, size=(100, 3))
    back = rotations.to_euler(rotations.from_euler(angles, order), order)
    np.testing.assert_allclose(back, angles, atol=1e-9)


def test_euler_gimbal_lock_still_reproduces_rotation():
    angles = np.array([0.4, np.pi / 2, 0.0])
    q = rotations.from_euler(angles, "ZXY")
    back = rotations.from_euler(rotations.to_euler(q, "ZXY"), "ZXY")
    np.testing.assert_allclose(rotations.to_matrix(back), rotations.to_matrix(q), atol=1e-9)


def test_slerp_endpoints_and_midpoint():
    a = rotations.identity()
    b = rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.pi / 2)
    np.testing.assert_allclose(rotations.slerp(a, b, 0.0), a, atol=1e-12)
    np.testing.assert_allclose(rotations.slerp(a, b, 1.0), b, atol=1e-12)
    mid = rotations.slerp(a, b, 0.5)
    np.testing.assert_allclose(mid, rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.pi / 4), atol=1e-12)


def test_zero_quaternion_is_rejected():
    with pytest.raises(ValueError, match="zero"):
        rotations.normalize(np.zeros(4))


def test_euler_refuses_an_order_or_a_count_of_angles_it_cannot_use():
    q = rotations.identity((5,))
    with pytest.raises(ValueError, match="Euler order: only Tait-Bryan orders .* got 'XYQ'"):
        rotations.to_euler(q, "XYQ")  # a KeyError before
    with pytest.raises(ValueError, match=r"angles: expected \(\.\.\., 3\) for order 'ZXY', got shape \(5, 2\)"):
        rotations.from_euler(np.zeros((5, 2)), "ZXY")  # an IndexError before


UNIT = np.array([0.0, 0.0, 0.0, 1.0])


@pytest.mark.parametrize(
    "call, message",
    [
        # A last axis of 5 was read in part (a silent answer), one of 3 or 2 an IndexError or unpacking error.
        (lambda: rotations.multiply(np.zeros(5), UNIT), r"^a: expected shape \(\.\.\., 4\), got \(5,\)$"),
        (lambda: rotations.multiply(UNIT, np.zeros((2, 3))), r"^b: expected shape \(\.\.\., 4\), got \(2, 3\)$"),
        (lambda: rotations.rotate(np.zeros(5), np.zeros(3)), r"^q: expected shape \(\.\.\., 4\), got \(5,\)$"),
        (lambda: rotations.rotate(UNIT, np.zeros(4)), r"^v: expected shape \(\.\.\., 3\), got \(4,\)$"),
        (lambda: rotations.rotate(UNIT, 1.0), r"^v: expected shape \(\.\.\., 3\), got \(\)$"),
        (lambda: rotations.to_matrix(np.zeros((2, 5))), r"^q: expected shape \(\.\.\., 4\), got \(2, 5\)$"),
    ],
)
def test_hot_helpers_name_the_argument_whose_last_axis_is_wrong(call, message):
    with pytest.raises(ValueError, match=message):
        call()
