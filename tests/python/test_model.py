import numpy as np
import pytest

from animlod import AnimatedMesh, Motion, Skeleton, SkinnedMesh, rotations
from animlod._core import bake_lbs, skin_distance_maxima

Z = np.array([0.0, 0.0, 1.0])


def _chain() -> Skeleton:
    """Three joints along +X, one unit apart."""
    return Skeleton(["root", "mid", "tip"], [-1, 0, 1], [[0, 0, 0], [1, 0, 0], [1, 0, 0]])


def _bend(angles_mid: np.ndarray) -> Motion:
    frames = len(angles_mid)
    local = rotations.identity((frames, 3))
    local[:, 1] = rotations.from_axis_angle(Z, angles_mid)
    return Motion(_chain(), np.zeros((frames, 3)), local, fps=30.0)


def test_forward_kinematics_of_a_bent_chain():
    positions = _bend(np.array([0.0, np.pi / 2])).world_positions()
    np.testing.assert_allclose(positions[0], [[0, 0, 0], [1, 0, 0], [2, 0, 0]], atol=1e-12)
    # Rotating the middle joint by 90 degrees about Z swings the tip to +Y.
    np.testing.assert_allclose(positions[1], [[0, 0, 0], [1, 0, 0], [1, 1, 0]], atol=1e-12)


def test_root_translation_moves_everything():
    motion = _bend(np.zeros(2))
    motion.root_positions[1] = [0, 5, 0]
    positions = motion.world_positions()
    np.testing.assert_allclose(positions[1] - positions[0], np.tile([0, 5, 0], (3, 1)), atol=1e-12)


def test_world_transforms_are_rigid():
    motion = _bend(np.linspace(0, 1, 5))
    rot = motion.world_transforms()[..., :3, :3]
    np.testing.assert_allclose(rot @ np.swapaxes(rot, -1, -2), np.broadcast_to(np.eye(3), rot.shape), atol=1e-12)


def test_world_transforms_match_numpy_products():
    motion = _bend(np.linspace(0, 1, 5))
    local = rotations.compose_transform(motion.local_translations(), motion.local_rotations)
    expected = local.copy()
    for joint in range(1, motion.skeleton.joint_count):
        expected[:, joint] = expected[:, motion.skeleton.parents[joint]] @ local[:, joint]
    np.testing.assert_allclose(motion.world_transforms(), expected, rtol=0, atol=1e-14)


def _numpy_lbs(rest, joints, weights, matrices):
    homogeneous = np.concatenate([rest, np.ones((len(rest), 1))], axis=1)
    per_influence = np.einsum("tvkij,vj->tvki", matrices[:, joints], homogeneous)
    return np.einsum("tvki,vk->tvi", per_influence, weights)[..., :3]


def test_bake_lbs_matches_numpy_reference():
    rng = np.random.default_rng(7)
    rest = rng.normal(size=(50, 3)).astype(np.float32)
    joints = rng.integers(0, 6, size=(50, 4)).astype(np.int32)
    weights = rng.random((50, 4)).astype(np.float32)
    weights /= weights.sum(axis=1, keepdims=True)
    q = rotations.normalize(rng.normal(size=(3, 6, 4)))
    matrices = rotations.compose_transform(rng.normal(size=(3, 6, 3)), q).astype(np.float32)
    got = bake_lbs(rest, joints, weights, matrices)
    assert got.shape == (3, 50, 3) and got.dtype == np.float32
    np.testing.assert_allclose(got, _numpy_lbs(rest, joints, weights, matrices), atol=1e-5)


def _skinned_tube(vertices: int) -> SkinnedMesh:
    """``vertices`` points along the chain, each on two of its joints."""
    rng = np.random.default_rng(3)
    skeleton = _chain()
    rest = np.column_stack([np.linspace(0.0, 2.0, vertices), rng.normal(0.0, 0.1, (vertices, 2))])
    joints = rng.integers(0, 3, (vertices, 2))
    return SkinnedMesh(
        rest, np.array([[0, 1, 2]]), joints, rng.random((vertices, 2)) + 0.1,
        np.linalg.inv(skeleton.rest_world_transforms()), skeleton,
    )  # fmt: skip


def test_a_long_bake_on_every_core_equals_its_frames_baked_one_by_one():
    # 3,000 vertices x 60 frames: contiguous ranges of vertex-frames on each core, split
    # inside a frame; one frame alone is too little work for a second thread.
    skin, motion = _skinned_tube(3000), _bend(np.linspace(0.0, 2.0, 60))
    whole = skin.bake(motion).frames
    for t in range(motion.frame_count):
        np.testing.assert_array_equal(whole[t], skin.bake(motion.take_frames([t])).frames[0])


def test_distance_maxima_are_the_maxima_of_the_distances_between_two_bakes_bit_for_bit():
    skin, motion = _skinned_tube(3000), _bend(np.linspace(0.0, 2.0, 60))
    rigid = SkinnedMesh(skin.rest_positions, skin.faces, np.zeros((3000, 1), int), np.ones((3000, 1)),
                        skin.inverse_bind, skin.skeleton)  # fmt: skip
    other_motion = _bend(np.linspace(0.5, 0.0, 60))
    maxima = skin.distance_maxima(motion, [(rigid, motion), (skin, other_motion), (skin, motion)])
    baked = skin.bake(motion).frames
    for row, (other, played) in zip(maxima, [(rigid, motion), (skin, other_motion), (skin, motion)]):
        expected = np.linalg.norm(other.bake(played).frames - baked, axis=-1).max(axis=1)
        np.testing.assert_array_equal(row, expected)
    assert maxima.shape == (3, 60) and maxima[0, -1] > 0.1 and not maxima[2].any()


def test_distance_maxima_name_the_skin_that_does_not_match_and_keep_a_nan():
    skin, motion = _skinned_tube(10), _bend(np.zeros(2))
    with pytest.raises(ValueError, match=r"skin 1: 20 vertices and 2 frames, expected 10 and 2"):
        skin.distance_maxima(motion, [(skin, motion), (_skinned_tube(20), motion)])
    with pytest.raises(ValueError, match=r"skin 0: 10 vertices and 1 frames, expected 10 and 2"):
        skin.distance_maxima(motion, [(skin, motion.take_frames([0]))])
    arrays = skin._lbs_inputs(motion)
    matrices = arrays[3].copy()
    matrices[1, 2, 0, 3] = np.nan  # frame 1, joint 2
    maxima = skin_distance_maxima(arrays, [(*arrays[:3], matrices)])
    assert maxima[0, 0] == 0.0 and np.isnan(maxima[0, 1])


def _skinned_bar() -> SkinnedMesh:
    """Two vertices at x = 0.5 and 1.5, the first on the root, the second on 'mid'."""
    skeleton = _chain()
    inverse_bind = np.linalg.inv(skeleton.rest_world_transforms())
    return SkinnedMesh(
        rest_positions=[[0.5, 0, 0], [1.5, 0, 0], [2.0, 0, 0]],
        faces=[[0, 1, 2]],
        joints=[[0, 1], [1, 0], [1, 2]],
        weights=[[1, 0], [3, 1], [1, 1]],
        inverse_bind=inverse_bind,
        skeleton=skeleton,
    )


def test_skinned_mesh_normalises_and_sorts_weights():
    skinned = _skinned_bar()
    np.testing.assert_allclose(skinned.weights, [[1, 0], [0.75, 0.25], [0.5, 0.5]])
    assert skinned.joints[0].tolist() == [0, 0]  # unused influence points at joint 0


def test_bake_follows_the_skeleton():
    skinned = _skinned_bar()
    mesh = skinned.bake(_bend(np.array([0.0, np.pi / 2])))
    assert isinstance(mesh, AnimatedMesh) and mesh.frames.shape == (2, 3, 3)
    np.testing.assert_allclose(mesh.frames[0], skinned.rest_positions, atol=1e-6)
    # The vertex fully on 'mid' (half a unit beyond it along the bone) swings to +Y.
    expected_mid = 0.75 * np.array([1.0, 0.5, 0.0]) + 0.25 * np.array([1.5, 0.0, 0.0])
    np.testing.assert_allclose(mesh.frames[1, 1], expected_mid, atol=1e-6)


def test_joint_deformations_act_in_the_joints_frame_and_travel_with_the_frames():
    skinned = _skinned_bar()
    bend = _bend(np.array([0.0, np.pi / 2]))
    stretch = np.broadcast_to(np.eye(3), (2, 3, 3, 3)).copy()
    stretch[1, 1] = np.diag([2.0, 1.0, 1.0])  # 'mid' doubles along its bone in frame 1
    stretched = Motion(bend.skeleton, bend.root_positions, bend.local_rotations, bend.fps, "s", None, stretch)
    frames = skinned.bake(stretched).frames
    np.testing.assert_allclose(frames[0], skinned.bake(bend).frames[0], atol=1e-6)
    # Half a unit beyond 'mid' along its bone becomes a whole unit, turned to +Y with the bone.
    expected_mid = 0.75 * np.array([1.0, 1.0, 0.0]) + 0.25 * np.array([1.5, 0.0, 0.0])
    np.testing.assert_allclose(frames[1, 1], expected_mid, atol=1e-6)
    np.testing.assert_allclose(stretched.world_positions(), bend.world_positions())  # joints stay rigid
    np.testing.assert_array_equal(stretched.take_frames([1]).joint_deformations[0], stretch[1])
    joined = Motion.concatenate([bend, stretched], "both")
    np.testing.assert_array_equal(
        joined.joint_deformations, np.concatenate([np.broadcast_to(np.eye(3), (2, 3, 3, 3)), stretch])
    )
    assert bend.deforming_joint() is None and stretched.deforming_joint() == "mid"
    with pytest.raises(ValueError, match="motion 's': joint 'mid' scales; motion LoD takes rigid motions only"):
        stretched.require_rigid("motion LoD")


def test_bake_rejects_a_motion_for_another_skeleton():
    other = Skeleton(["a", "b"], [-1, 0], np.zeros((2, 3)))
    motion = Motion(other, np.zeros((1, 3)), rotations.identity((1, 2)), fps=30.0)
    with pytest.raises(ValueError, match="2 joints"):
        _skinned_bar().bake(motion)


def _nan_at(shape: tuple, index: tuple, base: np.ndarray | None = None) -> np.ndarray:
    values = np.zeros(shape) if base is None else base.copy()
    values[index] = np.nan
    return values


@pytest.mark.parametrize(
    "inverse_bind, message",
    [
        (np.eye(4), r"inverse_bind: expected shape \(3, 4, 4\), got \(4, 4\)"),  # broadcast to every joint before
        (np.zeros((1, 4, 4)), r"inverse_bind: expected shape \(3, 4, 4\), got \(1, 4, 4\)"),  # broadcast too
        (np.zeros((2, 4, 4)), r"inverse_bind: expected shape \(3, 4, 4\), got \(2, 4, 4\)"),  # numpy's error
        (np.zeros((3, 3, 3)), r"inverse_bind: expected shape \(3, 4, 4\), got \(3, 3, 3\)"),
        (_nan_at((3, 4, 4), (1, 0, 0), np.eye(4)[None].repeat(3, 0)), r"inverse_bind: .* index \(1, 0, 0\)"),
    ],
)
def test_skin_matrices_rejects_inverse_binds_of_another_shape_or_not_finite(inverse_bind, message):
    with pytest.raises(ValueError, match=message):
        _bend(np.zeros(2)).skin_matrices(inverse_bind)


@pytest.mark.parametrize(
    "targets, morph_weights, message",
    [
        (2, np.zeros((2, 5)), r"morph_weights: expected shape \(2, 2\), got \(2, 5\)"),
        (2, np.zeros(2), r"morph_weights: expected shape \(2, 2\), got \(2,\)"),
        (2, _nan_at((2, 2), (1, 0)), r"morph_weights: non-finite value at index \(1, 0\)"),  # "frames" before
        (None, np.ones((2, 5)), r"morph_weights: expected shape \(2, 0\), got \(2, 5\)"),  # ignored before
    ],
)
def test_bake_rejects_morph_weights_of_another_shape_or_not_finite(targets, morph_weights, message):
    skinned = _skinned_bar()
    if targets is not None:
        skinned.morph_targets = np.ones((targets, skinned.vertex_count, 3), np.float32)
    with pytest.raises(ValueError, match=message):
        skinned.bake(_bend(np.zeros(2)), morph_weights)


def test_bake_blends_morph_weights_of_the_right_shape():
    skinned = _skinned_bar()
    skinned.morph_targets = np.stack([np.tile([0.0, 1.0, 0.0], (3, 1)), np.tile([0.0, 0.0, 1.0], (3, 1))])
    frames = skinned.bake(_bend(np.zeros(2)), [[0.0, 0.0], [0.5, 2.0]]).frames
    np.testing.assert_allclose(frames[0], skinned.rest_positions, atol=1e-6)
    np.testing.assert_allclose(frames[1] - skinned.rest_positions, np.tile([0.0, 0.5, 2.0], (3, 1)), atol=1e-6)
    plain = _skinned_bar()
    unmorphed = plain.bake(_bend(np.zeros(2)), np.zeros((2, 0))).frames  # N = 0: no targets, no weights
    np.testing.assert_allclose(unmorphed, np.broadcast_to(plain.rest_positions, (2, 3, 3)), atol=1e-6)


@pytest.mark.parametrize(
    "parents, message",
    [
        ([0, 0, 1], "joint 0 must be the root"),
        ([-1, 2, 0], "does not come before"),
        ([-1, 0, -1], "only joint 0"),
        ([-1, 0, 2**32 + 1], r"joint 2 4294967297 has an index outside \[-1, 3\)"),  # wrapped to 1 before
        ([-1, 0, 0.5], "joint 2 0.5 has an index that is not a whole number"),  # truncated to 0 before
    ],
)
def test_skeleton_rejects_bad_hierarchies(parents, message):
    with pytest.raises(ValueError, match=message):
        Skeleton(["a", "b", "c"], parents, np.zeros((3, 3)))


def test_end_site_must_be_a_leaf():
    with pytest.raises(ValueError, match="leaf"):
        Skeleton(["a", "b", "c"], [-1, 0, 1], np.zeros((3, 3)), end_sites=[False, True, False])


def test_animated_mesh_validation_names_the_problem():
    frames = np.zeros((2, 3, 3), np.float32)
    with pytest.raises(ValueError, match=r"face 0 \[0, 1, 3\]"):
        AnimatedMesh([[0, 1, 3]], frames)
    frames[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"non-finite value at index \(1, 2, 0\)"):
        AnimatedMesh([[0, 1, 2]], frames)


def test_motion_rejects_nan_rotation():
    local = rotations.identity((2, 3))
    local[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match="local_rotations"):
        Motion(_chain(), np.zeros((2, 3)), local, fps=30.0)


def test_skinned_mesh_and_animated_mesh_refuse_what_a_writer_could_not_write_back():
    def skinned(**changes) -> SkinnedMesh:
        arguments = {"rest_positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "faces": [[0, 1, 2]],
                     "joints": [[0], [1], [2]], "weights": [[1], [1], [1]],
                     "inverse_bind": np.tile(np.eye(4), (3, 1, 1)), "skeleton": _chain()}  # fmt: skip
        return SkinnedMesh(**{**arguments, **changes})

    with pytest.raises(ValueError, match="joints: vertex 2 4294967297 has an index outside"):
        skinned(joints=[[0], [1], [2**32 + 1]])
    with pytest.raises(ValueError, match="uvs: non-finite value"):
        skinned(uvs=[[0, 0], [1, 0], [np.nan, 1]])
    with pytest.raises(ValueError, match="normals: non-finite value"):
        skinned(normals=[[0, 0, 1], [0, 0, 1], [0, 0, np.inf]])
    with pytest.raises(ValueError, match="morph_targets: non-finite value"):
        skinned(morph_targets=np.full((1, 3, 3), np.nan))
    for fps in (-30.0, np.nan):
        with pytest.raises(ValueError, match="fps: expected > 0"):
            AnimatedMesh([[0, 1, 2]], np.zeros((1, 3, 3)), fps=fps)


def test_skinned_mesh_rejects_vertex_without_weight():
    with pytest.raises(ValueError, match="vertex 1 has no positive skin weight"):
        SkinnedMesh(
            [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
            [[0, 1, 2]],
            [[0], [0], [0]],
            [[1], [0], [1]],
            np.tile(np.eye(4), (3, 1, 1)),
            _chain(),
        )


def test_lod_chain_picks_the_coarsest_level_within_the_pixel_budget():
    from animlod import LodChain, LodLevel

    chain = LodChain([LodLevel(None, None, [], error) for error in (0.0, 0.01, 0.05, 0.2)])
    # At 10 units with a 1000 px focal length, errors project to 0, 1, 5 and 20 pixels.
    assert chain.level_for(1.0, 10.0, 1000.0) == 1
    assert chain.level_for(5.0, 10.0, 1000.0) == 2
    assert chain.level_for(0.5, 10.0, 1000.0) == 0
    assert chain.level_for(1.0, 1000.0, 1000.0) == 3
    with pytest.raises(ValueError, match="distance"):
        chain.level_for(1.0, 0.0, 1000.0)
    # NaN compares false and a negative focal length makes every error fit: both picked a level.
    for arguments, name in (((1.0, np.nan, 1000.0), "distance"), ((1.0, 10.0, -1.0), "focal_length_px"),
                            ((np.nan, 10.0, 1000.0), "screen_error_budget")):  # fmt: skip
        with pytest.raises(ValueError, match=name):
            chain.level_for(*arguments)


def test_rotations_name_the_argument_and_the_quaternion_that_has_no_norm():
    local = rotations.identity((4, 3))
    local[2, 1] = 0.0
    with pytest.raises(ValueError, match=r"local_rotations: index \(2, 1\) has a zero or non-finite norm"):
        Motion(_chain(), np.zeros((4, 3)), local, fps=30.0)
    with pytest.raises(ValueError, match=r"rest_rotations: expected shape \(3, 4\), got \(3, 3\)"):
        Skeleton(["a", "b", "c"], [-1, 0, 1], np.zeros((3, 3)), rest_rotations=np.zeros((3, 3)))
