"""A procedural humanoid: a 41-joint mocap-style skeleton and a skinned capsule body.

The character stands in a T-pose with identity rest rotations, Y up, facing +Z, in metres
(about 1.75 m tall); its left side is +X. The body is 15 closed tubes (torso with neck and head,
two arms with palms, eight fingers, two legs, two feet), so the whole mesh is a closed 2-manifold
made of several components.
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from ..model import Skeleton, SkinnedMesh
from ..normals import vertex_normals
from .geometry import Tube, capsule, merge

_JointRow = tuple[str, Optional[str], tuple[float, float, float]]

# Mocap-style joint table for the left side and the centre line: (name, parent, offset in
# metres). Right-side joints mirror the left ones in x. Fingers: thumb, index, middle and ring
# with two joints each.
_SPINE: list[_JointRow] = [
    ("Hips", None, (0.0, 0.95, 0.0)),
    ("Spine", "Hips", (0.0, 0.10, 0.0)),
    ("Spine1", "Spine", (0.0, 0.12, 0.0)),
    ("Spine2", "Spine1", (0.0, 0.12, 0.0)),
    ("Neck", "Spine2", (0.0, 0.18, 0.0)),
    ("Head", "Neck", (0.0, 0.10, 0.0)),
    ("HeadTop_End", "Head", (0.0, 0.18, 0.0)),
]
_LEFT_ARM: list[_JointRow] = [
    ("LeftShoulder", "Spine2", (0.05, 0.12, 0.0)),
    ("LeftArm", "LeftShoulder", (0.13, 0.0, 0.0)),
    ("LeftForeArm", "LeftArm", (0.28, 0.0, 0.0)),
    ("LeftHand", "LeftForeArm", (0.25, 0.0, 0.0)),
    ("LeftHandThumb1", "LeftHand", (0.025, -0.01, 0.035)),
    ("LeftHandThumb2", "LeftHandThumb1", (0.03, -0.005, 0.025)),
    ("LeftHandIndex1", "LeftHand", (0.085, 0.0, 0.025)),
    ("LeftHandIndex2", "LeftHandIndex1", (0.045, 0.0, 0.0)),
    ("LeftHandMiddle1", "LeftHand", (0.09, 0.0, 0.0)),
    ("LeftHandMiddle2", "LeftHandMiddle1", (0.05, 0.0, 0.0)),
    ("LeftHandRing1", "LeftHand", (0.085, 0.0, -0.025)),
    ("LeftHandRing2", "LeftHandRing1", (0.04, 0.0, 0.0)),
]
_LEFT_LEG: list[_JointRow] = [
    ("LeftUpLeg", "Hips", (0.09, -0.05, 0.0)),
    ("LeftLeg", "LeftUpLeg", (0.0, -0.42, 0.0)),
    ("LeftFoot", "LeftLeg", (0.0, -0.40, 0.0)),
    ("LeftToeBase", "LeftFoot", (0.0, -0.05, 0.12)),
    ("LeftToe_End", "LeftToeBase", (0.0, 0.0, 0.07)),
]
END_SITES = ("HeadTop_End", "LeftToe_End", "RightToe_End")
FINGERS = ("Thumb", "Index", "Middle", "Ring")


def _mirrored(rows: list[_JointRow]) -> list[_JointRow]:
    """The right-side twin of left-side rows: names renamed, x negated."""

    def right(name: str) -> str:
        return "Right" + name[len("Left") :] if name.startswith("Left") else name

    return [(right(name), parent and right(parent), (-x, y, z)) for name, parent, (x, y, z) in rows]


def _joint_table() -> list[_JointRow]:
    return _SPINE + _LEFT_ARM + _mirrored(_LEFT_ARM) + _LEFT_LEG + _mirrored(_LEFT_LEG)


def _proportions(seed: int) -> tuple[float, float]:
    """Height and girth scale factors of ``seed``: within +-3 % and +-6 %."""
    height, girth = np.clip(np.random.default_rng(seed).standard_normal(2), -1.0, 1.0)
    return 1.0 + 0.03 * height, 1.0 + 0.06 * girth


def humanoid_skeleton(seed: int = 0) -> Skeleton:
    """The 41-joint skeleton, its proportions varied by ``seed`` (height within about +-3 %)."""
    table = _joint_table()
    names = [name for name, _, _ in table]
    parents = np.array([-1 if parent is None else names.index(parent) for _, parent, _ in table], dtype=np.int32)
    offsets = np.array([offset for _, _, offset in table], dtype=np.float64) * _proportions(seed)[0]
    end_sites = np.isin(names, END_SITES)
    return Skeleton(names, parents, offsets, end_sites=end_sites)


def _body_parts(joints: dict[str, np.ndarray], girth: float) -> list[tuple[Tube, list[str]]]:
    """The closed tubes of the body and the joints each may be skinned to.

    Stations are ``(distance along the tube, half-width, half-depth, shift)`` in metres, laid
    out on the rest joint positions so that the body follows the seed's proportions.
    """
    up, forward = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    hips, head_top = joints["Hips"], joints["HeadTop_End"]
    neck, head = joints["Neck"][1] - hips[1], joints["Head"][1] - hips[1]
    torso_start = hips - np.array([0.0, 0.17, 0.0])
    torso_stations = np.array(
        [
            [0.00, 0.12, 0.10, 0.00],  # crotch
            [0.12, 0.17, 0.11, 0.00],  # hips
            [0.22, 0.155, 0.10, 0.01],  # waist
            [0.32, 0.145, 0.095, 0.01],
            [0.44, 0.16, 0.10, 0.00],  # chest
            [0.17 + neck - 0.10, 0.18, 0.10, -0.01],  # shoulders
            [0.17 + neck - 0.04, 0.12, 0.08, -0.01],
            [0.17 + neck, 0.055, 0.055, 0.00],  # neck
            [0.17 + head - 0.05, 0.055, 0.06, 0.01],
            [0.17 + head, 0.08, 0.09, 0.02],  # jaw
            [0.17 + head + 0.08, 0.09, 0.10, 0.02],
            [head_top[1] - torso_start[1], 0.085, 0.095, 0.02],  # top of the head
        ]
    )
    torso_stations[:, 1:3] *= girth
    parts = [
        (
            capsule(torso_start, up, [1.0, 0.0, 0.0], torso_stations, 16, 0.045, shift_direction=forward),
            ["Hips", "Spine", "Spine1", "Spine2", "Neck", "Head", "LeftShoulder", "RightShoulder",
             "LeftUpLeg", "RightUpLeg"],
        )
    ]  # fmt: skip
    for side, sign in (("Left", 1.0), ("Right", -1.0)):
        parts += _limb_parts(joints, side, sign, girth)
    return parts


def _limb_parts(joints: dict[str, np.ndarray], side: str, sign: float, girth: float) -> list[tuple[Tube, list[str]]]:
    """Arm with palm, four fingers, leg and foot of one side (``sign`` +1 left, -1 right)."""
    outward, up, forward = np.array([sign, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    named = {key[len(side) :]: value for key, value in joints.items() if key.startswith(side)}
    shoulder, arm, fore, hand = (named[k] for k in ("Shoulder", "Arm", "ForeArm", "Hand"))
    arm_start = shoulder + 0.05 * outward
    knuckle_row = np.mean([named["Hand" + finger + "1"] for finger in FINGERS[1:]], axis=0)
    along = [float((p - arm_start) @ outward) for p in (arm, fore, hand, knuckle_row)]
    arm_stations = np.array(
        [
            [0.0, 0.055, 0.055, 0.0],
            [along[0], 0.05, 0.05, 0.0],  # upper arm
            [0.5 * (along[0] + along[1]), 0.045, 0.045, 0.0],
            [along[1], 0.035, 0.037, 0.0],  # elbow
            [0.5 * (along[1] + along[2]), 0.033, 0.035, 0.0],
            [along[2], 0.022, 0.03, 0.0],  # wrist
            [along[2] + 0.04, 0.018, 0.045, 0.0],  # palm
            [along[3], 0.016, 0.042, 0.0],  # knuckles
        ]
    )
    arm_stations[:, 1:3] *= girth
    parts = [
        (
            capsule(arm_start, outward, up, arm_stations, 12, 0.055, cap_rings=2),
            ["Spine2", side + "Shoulder", side + "Arm", side + "ForeArm", side + "Hand"],
        )
    ]
    for finger in FINGERS:
        base, middle = named["Hand" + finger + "1"], named["Hand" + finger + "2"]
        tip = middle + 0.8 * (middle - base)
        start = base - 0.35 * (middle - base)
        length = float(np.linalg.norm(tip - start))
        radius = (0.0105 if finger == "Thumb" else 0.0085) * girth
        stations = np.array([[0.0, radius, radius, 0.0], [length, 0.85 * radius, 0.8 * radius, 0.0]])
        parts.append(
            (
                capsule(start, tip - start, up, stations, 6, 0.03, cap_rings=2),
                [side + "Hand", side + "Hand" + finger + "1", side + "Hand" + finger + "2"],
            )
        )

    up_leg, leg, foot, toe = (named[k] for k in ("UpLeg", "Leg", "Foot", "ToeBase"))
    leg_start = up_leg + np.array([0.0, 0.08, 0.0])
    down = [float(leg_start[1] - p[1]) for p in (up_leg, leg, foot)]
    leg_stations = np.array(
        [
            [0.0, 0.085, 0.085, 0.0],
            [down[0], 0.08, 0.085, 0.0],  # thigh
            [0.5 * (down[0] + down[1]), 0.065, 0.07, 0.0],
            [down[1], 0.05, 0.055, 0.0],  # knee
            [down[1] + 0.15, 0.05, 0.055, -0.01],  # calf
            [down[2] - 0.07, 0.035, 0.04, 0.0],
            [down[2] + 0.03, 0.032, 0.035, 0.0],  # ankle, rounded into the foot
        ]
    )
    leg_stations[:, 1:3] *= girth
    heel = np.array([foot[0], 0.0, foot[2] - 0.07])
    toe_length = float(toe[2] - heel[2])
    foot_stations = np.array(
        [
            [0.0, 0.035, 0.04, 0.045],  # heel
            [0.07, 0.04, 0.045, 0.05],  # ankle
            [toe_length - 0.03, 0.045, 0.032, 0.032],
            [toe_length, 0.045, 0.025, 0.026],  # toe base
            [toe_length + 0.07, 0.035, 0.02, 0.022],  # toe tip
        ]
    )
    foot_stations[:, 1:3] *= girth
    parts += [
        (
            capsule(leg_start, -up, [1.0, 0.0, 0.0], leg_stations, 12, 0.06, shift_direction=forward),
            ["Hips", side + "UpLeg", side + "Leg", side + "Foot"],
        ),
        (
            capsule(heel, forward, [1.0, 0.0, 0.0], foot_stations, 10, 0.04, cap_rings=2, shift_direction=up),
            [side + "Foot", side + "ToeBase"],
        ),
    ]
    return parts


def _bone_segments(skeleton: Skeleton, world: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Segment ``(start, end)`` of every joint's bone, each ``(J, 3)``.

    A bone runs from its joint to the mean of its children; a leaf that is not an end site
    (a finger tip) continues its parent's direction for 0.8 of its own bone length.
    """
    joint_count = skeleton.joint_count
    child_sum = np.zeros((joint_count, 3))
    child_count = np.zeros(joint_count)
    np.add.at(child_sum, skeleton.parents[1:], world[1:])
    np.add.at(child_count, skeleton.parents[1:], 1.0)
    leaf_end = world + 0.8 * (world - world[np.maximum(skeleton.parents, 0)])
    end = np.where(child_count[:, None] > 0, child_sum / np.maximum(child_count, 1.0)[:, None], leaf_end)
    return world, end


def _skin_weights(
    positions: np.ndarray, allowed: np.ndarray, start: np.ndarray, end: np.ndarray, influences: int
) -> tuple[np.ndarray, np.ndarray]:
    """Inverse-distance weights to bone segments, top ``influences`` kept.

    ``w_j = (d_j + eps)^-4`` with ``d_j`` the distance to bone j; the fourth power blends over
    about one limb radius around a joint. ``allowed (V, J)`` masks the bones of a vertex's part.
    """
    direction = end - start  # (J, 3)
    length_sq = np.maximum(np.einsum("jk,jk->j", direction, direction), 1e-12)
    relative = positions[:, None, :] - start[None]  # (V, J, 3)
    along = np.clip(np.einsum("vjk,jk->vj", relative, direction) / length_sq, 0.0, 1.0)
    distance = np.linalg.norm(relative - along[..., None] * direction, axis=-1)
    weights = np.where(allowed, (distance + 0.005) ** -4.0, 0.0)
    order = np.argsort(-weights, axis=1, kind="stable")[:, :influences]
    top = np.take_along_axis(weights, order, axis=1)
    return order.astype(np.int32), top / top.sum(axis=1, keepdims=True)


def humanoid(seed: int = 0, influences: int = 4) -> SkinnedMesh:
    """A skinned humanoid in T-pose: 41 joints, about 3,700 triangles, 15 closed tubes.

    Parameters
    ----------
    seed : varies height (about +-3 %) and girth (about +-6 %); same seed, same bytes.
    influences : K, skin influences per vertex (1-4 or 8).

    Returns
    -------
    SkinnedMesh with ``rest_positions (V, 3)``, ``faces (M, 3)`` counter-clockwise outward,
    ``joints``/``weights (V, K)``, ``inverse_bind (41, 4, 4)`` (inverse rest world transforms),
    cylindrical ``uvs (V, 2)`` packed one part per atlas tile, and vertex ``normals (V, 3)``.
    End sites carry no skin weight.
    """
    if influences not in (1, 2, 3, 4, 8):
        raise ValueError(f"influences: K must be 1-4 or 8, got {influences}")
    skeleton = humanoid_skeleton(seed)
    girth = _proportions(seed)[1]
    rest = skeleton.rest_world_transforms()
    world = rest[:, :3, 3]
    parts = _body_parts(dict(zip(skeleton.names, world)), girth)
    positions, faces, part_of_vertex = merge([(tube.positions, tube.faces) for tube, _ in parts])

    allowed_by_part = np.array([np.isin(skeleton.names, names) for _, names in parts])  # (P, J)
    start, end = _bone_segments(skeleton, world)
    joints, weights = _skin_weights(positions, allowed_by_part[part_of_vertex], start, end, influences)

    # Cylindrical UVs, one tile per part in a square atlas.
    tiles = int(np.ceil(np.sqrt(len(parts))))
    around = np.concatenate([tube.around for tube, _ in parts])
    along = np.concatenate([tube.along for tube, _ in parts])
    tile = np.stack([part_of_vertex % tiles, part_of_vertex // tiles], axis=-1)
    uvs = (tile + np.stack([around, along], axis=-1)) / tiles

    return SkinnedMesh(
        rest_positions=positions,
        faces=faces,
        joints=joints,
        weights=weights,
        inverse_bind=np.linalg.inv(rest),
        skeleton=skeleton,
        uvs=uvs,
        normals=vertex_normals(positions, faces),
    )
