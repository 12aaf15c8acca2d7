"""The skin of a level (Section 5.1): frozen joints' weights go to their nearest kept ancestor,
and the rest pose takes the key posture on the frozen part.

"The rest pose of a VH's mesh is modified by the key posture, including skinning weights
re-arrangement on the frozen area. If a vertex is related to a frozen joint, the skinning
weights move to its parent joint." Here the bind pose is re-posed with every frozen joint at its
key rotation (translations unchanged), the mesh is skinned into that pose with the original
weights (linear blend skinning in the C++ core), and that becomes the new rest mesh and bind
pose. With the level's motion the new skin then deforms like the original skin under the
original skeleton with frozen joints held at their key rotations: exactly for a vertex whose
influences all end on one kept joint, otherwise up to the non-linearity of blending twice
(about 1e-4 of the figure's height on the procedural walk's coarsest level).
"""

from __future__ import annotations

import numpy as np

from .. import rotations
from .._core import bake_lbs
from ..model import SkinnedMesh, merge_repeated_influences
from .frozen import FrozenLevel
from .ranking import joint_depths
from .skeleton_reduce import reduce_skeleton


def key_bind_pose(skin: SkinnedMesh, level: FrozenLevel) -> np.ndarray:
    """World transforms ``(J, 4, 4)`` of the bind pose with frozen joints at their key posture
    (rotation and translation), as the level's motion holds them. A frozen joint's translation is
    not read from the bind pose: without inverseBindMatrices every bind is the identity, and the
    joint lost its bone."""
    bind = np.linalg.inv(skin.inverse_bind)
    parents = skin.skeleton.parents
    local = bind.copy()
    local[1:] = np.linalg.inv(bind[parents[1:]]) @ bind[1:]
    frozen = np.flatnonzero(level.frozen)
    local[frozen, :3, :3] = rotations.to_matrix(level.key_rotations[frozen])
    local[frozen, :3, 3] = level.key_translations[frozen]
    world = local.copy()
    depths = joint_depths(parents)
    for depth in range(1, int(depths.max(initial=0)) + 1):  # forward kinematics, one layer of joints at a time
        layer = np.flatnonzero(depths == depth)
        world[layer] = world[parents[layer]] @ local[layer]
    return world


def transfer_skin(skin: SkinnedMesh, level: FrozenLevel) -> SkinnedMesh:
    """``skin`` bound to the level's skeleton (:func:`reduce_skeleton`).

    Weights of a frozen joint move to its nearest kept ancestor and merge with the weight that
    ancestor already has on the vertex, so every vertex keeps K influences summing to one that
    reference kept joints only (those beyond the level's joint count weigh 0). Normals follow
    the re-posing; morph targets are kept as they are (their deltas stay in the original rest
    frame).
    """
    skeleton = skin.skeleton
    if skeleton.names != level.skeleton.names:
        raise ValueError("skin: its skeleton's joint names differ from the motion's")
    posed = key_bind_pose(skin, level)
    matrices = posed @ skin.inverse_bind
    rest = bake_lbs(skin.rest_positions, skin.joints, skin.weights, matrices[None].astype(np.float32))[0]
    normals = None
    if skin.normals is not None:
        blended = np.einsum("vk,vkij->vij", skin.weights, matrices[skin.joints][..., :3, :3])
        normals = np.einsum("vij,vj->vi", blended, skin.normals)
        normals /= np.maximum(np.linalg.norm(normals, axis=-1, keepdims=True), 1e-30)

    # Nearest kept ancestor-or-self of every joint, then its index in the level's skeleton.
    target = np.arange(skeleton.joint_count)
    for joint in range(1, skeleton.joint_count):
        if not level.kept[joint]:
            target[joint] = target[skeleton.parents[joint]]
    new_index = np.full(skeleton.joint_count, -1, dtype=np.int64)
    new_index[level.kept_indices] = np.arange(level.kept_indices.size)
    joints = new_index[target[skin.joints]]
    weights = merge_repeated_influences(joints, skin.weights)
    # Heaviest first, equal weights by joint index: the order of the vertex's row in a table of
    # merged weights by kept joint, built in the slots alone (a (V, kept joints) table is 94 MB
    # for a 175k-vertex mesh of 67 joints).
    order = np.lexsort((joints, -weights), axis=1)
    joints, weights = np.take_along_axis(joints, order, axis=1), np.take_along_axis(weights, order, axis=1)
    return SkinnedMesh(
        rest_positions=rest,
        faces=skin.faces,
        joints=joints,
        weights=weights,
        inverse_bind=np.linalg.inv(posed[level.kept_indices]),
        skeleton=reduce_skeleton(level),
        uvs=skin.uvs,
        normals=normals,
        morph_targets=skin.morph_targets,
        morph_target_names=skin.morph_target_names,
        default_morph_weights=skin.default_morph_weights,
    )
