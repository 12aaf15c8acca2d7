"""Procedural assets: determinism, sizes, closed outward surfaces, skins, cyclic motions, faces."""

from __future__ import annotations

import numpy as np
import pytest

from animlod import rotations, synth
from animlod.model import AnimatedMesh


def edge_use_counts(faces: np.ndarray) -> np.ndarray:
    """How many faces use each undirected edge."""
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    return np.unique(edges, axis=0, return_counts=True)[1]


def assert_closed_manifold(faces: np.ndarray) -> None:
    """Every edge in exactly two faces, each direction once (so orientations agree)."""
    assert np.all(edge_use_counts(faces) == 2)
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    assert len(np.unique(directed, axis=0)) == len(directed)


def signed_volume(positions: np.ndarray, faces: np.ndarray) -> float:
    """Divergence theorem: positive for a closed surface whose faces wind counter-clockwise outside."""
    corners = np.asarray(positions, dtype=np.float64)[faces]
    return float(np.einsum("ij,ij->", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])) / 6.0)


@pytest.fixture(scope="module")
def body():
    return synth.humanoid()


@pytest.fixture(scope="module")
def head():
    return synth.face()


# --- geometry -------------------------------------------------------------------------------


@pytest.mark.parametrize("subdivisions", [0, 1, 2, 3])
def test_icosphere_counts_and_closure(subdivisions):
    positions, faces = synth.icosphere(subdivisions)
    assert positions.shape == (10 * 4**subdivisions + 2, 3) and positions.dtype == np.float32
    assert faces.shape == (20 * 4**subdivisions, 3) and faces.dtype == np.int32
    np.testing.assert_allclose(np.linalg.norm(positions, axis=1), 1.0, rtol=1e-6)
    assert_closed_manifold(faces)
    # Inscribed polyhedra approach the unit ball's volume from below.
    assert 0.6 * 4 / 3 * np.pi < signed_volume(positions, faces) < 4 / 3 * np.pi


# --- humanoid -------------------------------------------------------------------------------


def test_humanoid_is_deterministic():
    a, b = synth.humanoid(seed=3), synth.humanoid(seed=3)
    for name in ("rest_positions", "faces", "joints", "weights", "inverse_bind", "uvs", "normals"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes()
    assert synth.humanoid(seed=4).rest_positions.tobytes() != a.rest_positions.tobytes()


def test_humanoid_skeleton(body):
    skeleton = body.skeleton
    assert 38 <= skeleton.joint_count <= 45
    assert skeleton.names[0] == "Hips" and skeleton.parents[0] == -1
    assert np.all(skeleton.parents[1:] < np.arange(1, skeleton.joint_count))
    for name in ("Spine2", "Neck", "Head", "LeftHand", "RightHandIndex2", "LeftToeBase", "RightUpLeg"):
        skeleton.index(name)
    assert tuple(skeleton.names[j] for j in np.nonzero(skeleton.end_sites)[0]) == synth.END_SITES
    np.testing.assert_array_equal(skeleton.rest_rotations, rotations.identity((skeleton.joint_count,)))
    # T-pose: arms straight out along +-X, left side at +X.
    world = skeleton.rest_world_transforms()[:, :3, 3]
    hand, arm = world[skeleton.index("LeftHand")], world[skeleton.index("LeftArm")]
    assert hand[0] > arm[0] + 0.4 and abs(hand[1] - arm[1]) < 1e-12
    np.testing.assert_allclose(world[skeleton.index("RightHand")], hand * [-1, 1, 1])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_humanoid_body_size_and_surface(seed):
    body = synth.humanoid(seed=seed)
    assert 1300 <= body.face_count <= 5000
    height = body.rest_positions[:, 1].max() - body.rest_positions[:, 1].min()
    assert 1.68 < height < 1.82
    assert abs(body.rest_positions[:, 1].min()) < 0.01  # standing on y = 0
    assert_closed_manifold(body.faces)
    assert 0.04 < signed_volume(body.rest_positions, body.faces) < 0.1  # a person is about 0.07 m^3


def test_humanoid_skin(body):
    assert body.joints.shape == (body.vertex_count, 4) and body.weights.shape == (body.vertex_count, 4)
    np.testing.assert_allclose(body.weights.sum(axis=1), 1.0, atol=1e-6)
    assert np.all(np.diff(body.weights, axis=1) <= 0.0)  # sorted by decreasing weight
    assert np.all(body.weights[:, 1] > 0.0)  # smooth: every vertex blends at least two bones
    influenced = np.unique(body.joints[body.weights > 0.0])
    assert not np.any(body.skeleton.end_sites[influenced])
    world = body.skeleton.rest_world_transforms()
    np.testing.assert_allclose(world @ body.inverse_bind, np.broadcast_to(np.eye(4), world.shape), atol=1e-12)
    assert body.uvs.min() >= 0.0 and body.uvs.max() <= 1.0
    np.testing.assert_allclose(np.linalg.norm(body.normals, axis=1), 1.0, rtol=1e-5)


def test_humanoid_influence_count():
    eight = synth.humanoid(influences=8)
    assert eight.joints.shape[1] == 8
    with pytest.raises(ValueError, match="influences"):
        synth.humanoid(influences=5)


def test_finger_vertices_follow_their_finger(body):
    """The tip of each finger is skinned mostly to that finger's last joint."""
    skeleton = body.skeleton
    world = skeleton.rest_world_transforms()[:, :3, 3]
    for name in ("LeftHandIndex2", "RightHandThumb2", "LeftHandRing2"):
        joint = skeleton.index(name)
        tip = world[joint] + 0.8 * (world[joint] - world[skeleton.parents[joint]])
        nearest = np.argmin(np.linalg.norm(body.rest_positions - tip, axis=1))
        assert body.joints[nearest, 0] == joint and body.weights[nearest, 0] > 0.9


# --- motions --------------------------------------------------------------------------------


@pytest.mark.parametrize("kind, period", [("walk", 1.1), ("run", 0.7), ("jump", 1.2)])
def test_motion_is_cyclic(body, kind, period):
    motion = synth.humanoid_motion(body.skeleton, kind, cycles=2, fps=30.0)
    per_cycle = round(period * 30.0)
    assert motion.frame_count == 2 * per_cycle and motion.fps == 30.0 and motion.name == kind
    positions = motion.world_positions()
    # The second cycle repeats the first, and the step from the last frame back to frame 0 is an
    # ordinary step, no jump.
    np.testing.assert_allclose(positions[per_cycle:], positions[:per_cycle], atol=1e-9)
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=-1).max(axis=1)
    wrap = np.linalg.norm(positions[0] - positions[-1], axis=-1).max()
    assert 0.0 < wrap <= 1.05 * steps.max()


def test_motion_frame_count_follows_fps(body):
    motion = synth.humanoid_motion(body.skeleton, "walk", cycles=3, fps=24.0)
    assert motion.frame_count == 3 * round(1.1 * 24.0) and motion.fps == 24.0


def test_motion_is_deterministic(body):
    a = synth.humanoid_motion(body.skeleton, "walk", seed=7)
    b = synth.humanoid_motion(body.skeleton, "walk", seed=7)
    assert a.local_rotations.tobytes() == b.local_rotations.tobytes()
    assert a.root_positions.tobytes() == b.root_positions.tobytes()
    assert synth.humanoid_motion(body.skeleton, "walk", seed=8).local_rotations.tobytes() != a.local_rotations.tobytes()


def test_walk_looks_like_a_walk(body):
    skeleton = body.skeleton
    motion = synth.humanoid_motion(skeleton, "walk", cycles=1)
    positions = motion.world_positions()
    left, right = skeleton.index("LeftFoot"), skeleton.index("RightFoot")
    # Feet alternate: when one is furthest forward the other is behind.
    lead = np.argmax(positions[:, left, 2])
    assert positions[lead, right, 2] < positions[lead, left, 2] - 0.3
    # Arms counter-swing: the left hand is behind when the left foot leads.
    hand = skeleton.index("LeftHand")
    assert positions[lead, hand, 2] < positions[:, hand, 2].mean()
    # Hips bob and sway a little; the head stays level.
    root = motion.root_positions
    assert 0.01 < np.ptp(root[:, 1]) < 0.08 and 0.01 < np.ptp(root[:, 0]) < 0.1
    world = motion.world_transforms()
    head_up = world[:, skeleton.index("Head"), :3, 1]
    assert np.degrees(np.arccos(head_up[:, 1].min())) < 8.0
    # The chest twists against the pelvis (yaw of each joint's +Z axis about +Y).
    forward = world[:, :, :3, 2]
    yaw = np.arctan2(forward[..., 0], forward[..., 2])
    pelvis, chest = yaw[:, skeleton.index("Hips")], yaw[:, skeleton.index("Spine2")]
    assert np.corrcoef(pelvis, chest)[0, 1] < -0.9 and np.ptp(pelvis) > 0.05
    # Knees bend forward only, by up to about 60 degrees in the swing.
    knee = motion.local_rotations[:, skeleton.index("LeftLeg")]
    angle = 2.0 * np.arctan2(knee[:, 0], knee[:, 3])  # rotation about +X
    assert angle.min() >= 0.0 and 0.7 < angle.max() < 1.4


def test_jump_leaves_the_ground(body):
    motion = synth.humanoid_motion(body.skeleton, "jump", cycles=1)
    skin = body.bake(motion)
    lowest = skin.frames[:, :, 1].min(axis=1)
    standing = motion.root_positions[0, 1]
    assert motion.root_positions[:, 1].min() < standing - 0.1  # crouch
    assert lowest.max() > 0.2  # flight: the soles are well above the floor
    assert abs(lowest[0]) < 0.02  # starts standing on the floor


def test_still_finger_chain_is_still_and_other_fingers_move(body):
    skeleton = body.skeleton
    motion = synth.humanoid_motion(skeleton, "walk")
    for name in synth.STILL_FINGER_CHAIN:
        joint = skeleton.index(name)
        np.testing.assert_array_equal(
            motion.local_rotations[:, joint], np.broadcast_to(skeleton.rest_rotations[joint], (motion.frame_count, 4))
        )
    for name in ("LeftHandIndex1", "RightHandRing1", "LeftHandThumb2"):
        angle = 2.0 * np.arccos(np.clip(np.abs(motion.local_rotations[:, skeleton.index(name), 3]), 0.0, 1.0))
        assert 0.005 < np.ptp(angle) < 0.3  # small but real


def test_end_sites_keep_rest_rotation(body):
    motion = synth.humanoid_motion(body.skeleton, "run")
    ends = body.skeleton.end_sites
    np.testing.assert_array_equal(
        motion.local_rotations[:, ends], rotations.identity((motion.frame_count, int(ends.sum())))
    )


def test_bake_keeps_the_body_together(body):
    baked = body.bake(synth.humanoid_motion(body.skeleton, "run", cycles=1))
    assert isinstance(baked, AnimatedMesh) and baked.frames.shape[1:] == body.rest_positions.shape
    # Edge lengths stretch moderately at most: weights are smooth and bones rigid.
    edges = body.faces[:, [0, 1]]
    rest = np.linalg.norm(np.diff(body.rest_positions[edges], axis=1)[:, 0], axis=-1)
    posed = np.linalg.norm(np.diff(baked.frames[:, edges], axis=2)[:, :, 0], axis=-1)
    assert np.max(posed / rest) < 3.0


def test_motion_rejects_bad_input(body):
    with pytest.raises(ValueError, match="kind"):
        synth.humanoid_motion(body.skeleton, "dance")
    with pytest.raises(ValueError, match="cycles"):
        synth.humanoid_motion(body.skeleton, cycles=0)
    skeleton = synth.bending_cylinder_skinned()[0].skeleton
    with pytest.raises(ValueError, match="no joint named"):
        synth.humanoid_motion(skeleton)


# --- simple deforming meshes ----------------------------------------------------------------


def test_bending_cylinder_equals_its_skin_and_motion():
    skin, motion = synth.bending_cylinder_skinned(frames=6)
    baked = synth.bending_cylinder(frames=6)
    np.testing.assert_array_equal(baked.frames, skin.bake(motion).frames)
    assert baked.fps == 30.0 and baked.frames.shape == (6, 24 * 16 + 2, 3)
    np.testing.assert_allclose(baked.frames[0], skin.rest_positions, atol=1e-6)  # frame 0 straight
    assert_closed_manifold(baked.faces)
    assert signed_volume(baked.frames[0], baked.faces) == pytest.approx(np.pi * 0.25**2 * 2.0, rel=0.03)
    # The top bends by max_angle: the top cap centre ends at (-1, 1, 0) after pi/2 about +Z.
    np.testing.assert_allclose(baked.frames[-1, -1], [-1.0, 1.0, 0.0], atol=1e-5)
    np.testing.assert_allclose(baked.frames[:, -2], 0.0, atol=1e-7)  # the base does not move


def test_twisting_bar():
    bar = synth.twisting_bar(frames=5, max_angle=np.pi / 2)
    assert_closed_manifold(bar.faces)
    assert signed_volume(bar.frames[0], bar.faces) == pytest.approx(0.2 * 0.2 * 2.0, rel=1e-6)
    assert signed_volume(bar.frames[-1], bar.faces) > 0.0
    top = np.isclose(bar.frames[0, :, 1], 2.0)
    # At the top a quarter turn about +Y maps (x, z) to (z, -x).
    np.testing.assert_allclose(bar.frames[-1, top][:, [0, 2]], bar.frames[0, top][:, [2, 0]] * [1, -1], atol=1e-6)
    np.testing.assert_array_equal(bar.frames[:, :, 1], np.broadcast_to(bar.frames[0, :, 1], bar.frames.shape[:2]))


def test_translating_mesh():
    mesh = synth.translating_mesh(frames=4, subdivisions=2, step=(0.1, 0.0, -0.2))
    assert mesh.face_count == 320
    assert_closed_manifold(mesh.faces)
    np.testing.assert_allclose(mesh.frames[3] - mesh.frames[0], np.broadcast_to([0.3, 0.0, -0.6], (162, 3)), atol=1e-6)
    with pytest.raises(ValueError, match="frames"):
        synth.translating_mesh(frames=0)


# --- face -----------------------------------------------------------------------------------


def test_face_mesh(head):
    assert len(head.faces) == 2 * 40 * 24 + 2 * 80 + 2 * 112  # head rings x segments, eyeballs, teeth
    assert head.positions.dtype == np.float32 and head.faces.dtype == np.int32
    assert_closed_manifold(head.faces)
    assert signed_volume(head.positions, head.faces) > 0.0
    assert synth.face(seed=1).positions.tobytes() == synth.face(seed=1).positions.tobytes()


def test_face_regions(head):
    for family in ("eyebrow", "eyelid", "eyeball", "nose", "cheek", "zygomatic", "mouth", "lip", "jaw", "ear", "teeth"):
        assert any(name.startswith(family) for name in head.region_names), family
    counts = np.bincount(head.vertex_regions, minlength=len(head.region_names))
    assert np.all(counts > 0), dict(zip(head.region_names, counts))
    # Left regions are at +X, right ones at -X.
    for name in ("ear", "eyeball", "cheek"):
        assert head.positions[head.region_mask(f"{name}_left"), 0].min() > 0.0
        assert head.positions[head.region_mask(f"{name}_right"), 0].max() < 0.0
    with pytest.raises(ValueError, match="no region named"):
        head.region_mask("antenna")


def test_face_animation_moves_the_jaw_not_the_ears(head):
    animation = synth.face_animation(head, seconds=2.0, fps=30.0)
    assert animation.frames.shape == (60, len(head.positions), 3) and animation.fps == 30.0
    movement = np.linalg.norm(animation.frames - head.positions, axis=-1).max(axis=0)  # (V,)
    for name in synth.STILL_REGIONS:
        assert movement[head.region_mask(name)].max() == 0.0, name
    for name, at_least in (("jaw", 0.01), ("teeth_lower", 0.005), ("lip_lower", 0.003), ("eyelid_upper_left", 0.002),
                           ("eyebrow_right", 0.002), ("eyeball_left", 0.001)):  # fmt: skip
        assert movement[head.region_mask(name)].max() > at_least, name
    # The jaw opens downwards.
    jaw = head.region_mask("jaw")
    assert animation.frames[:, jaw, 1].mean(axis=1).min() < head.positions[jaw, 1].mean() - 0.003
    again = synth.face_animation(head, seconds=2.0, fps=30.0)
    assert again.frames.tobytes() == animation.frames.tobytes()
    assert synth.face_animation(head, seconds=2.0, fps=30.0, seed=1).frames.tobytes() != animation.frames.tobytes()


def test_face_animation_blinks_and_rejects_bad_input(head):
    animation = synth.face_animation(head, seconds=2.0, fps=30.0)
    eyelid = head.region_mask("eyelid_upper_left")
    height = animation.frames[:, eyelid, 1].mean(axis=1)
    assert height.min() < height[0] - 0.001  # the upper lid comes down at least once
    with pytest.raises(ValueError, match="seconds"):
        synth.face_animation(head, seconds=0.0)
