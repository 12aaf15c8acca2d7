"""A character in parts: a skinned mesh whose skin lists some of another skin's joints (Soldier's
visor on the head and neck, VRoid's hair on the head and its own hair bones) moved onto that
skin's skeleton, so that both play one skeleton: one reduced skeleton per motion level, one set of
clips.

Where both skins were bound in one pose, a part's inverse binds differ from the first skin's by
one transform ``T`` for every joint its weights use (its mesh node's,
:func:`animlod.io.gltf_read.skinned_mesh_of_node`); ``T`` moves into its vertices.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..model import Motion, SkinnedMesh

# Inverse binds stored as float32 agree to about 1e-7 of their largest entry where two skins were
# bound in one pose; a part whose binds differ by more than this was bound in another.
SAME_BIND_TOLERANCE = 1e-5


@dataclasses.dataclass(frozen=True)
class Placement:
    """How a part lies on another skin's skeleton: the skeleton's joint for each of the part's
    joints (for a joint it lacks, a hair or skirt bone, its nearest ancestor's), and ``T`` (4, 4)
    with ``IBM_part = IBM_first @ T`` for every joint both list that the part's weights reach."""

    joint_map: np.ndarray
    transform: np.ndarray


def placement_on(first: SkinnedMesh, part: SkinnedMesh, motion: Motion | None = None) -> Placement | None:
    """How ``part`` lies on ``first``'s skeleton and binds, or None: where its weights reach a joint
    with no ancestor ``first`` lists (by name), reach none, or it was bound in another pose.

    A joint ``first`` lacks (VRoid hair and skirt bones under the head and hips) moves its
    vertices with its nearest ancestor that ``first`` lists. That is exact only where it holds
    its bind pose on that ancestor in every frame of ``motion``, the part's clips (checked on
    its skin matrices); without ``motion``, such a part has no placement.
    """
    index = {name: joint for joint, name in enumerate(first.skeleton.names)}
    parents = part.skeleton.parents
    listed = np.array([name in index for name in part.skeleton.names])
    anchor = np.full(part.skeleton.joint_count, -1)  # the nearest listed joint at or above each joint
    for joint in range(part.skeleton.joint_count):  # parents before children
        anchor[joint] = joint if listed[joint] else (anchor[parents[joint]] if parents[joint] >= 0 else -1)
    used = np.unique(part.joints[part.weights > 0.0])
    if not used.size or (anchor[used] < 0).any():
        return None
    joint_map = np.array([index[part.skeleton.names[a]] if a >= 0 else -1 for a in anchor])
    folded = used[~listed[used]]
    if folded.size:
        if motion is None:
            return None
        matrices = motion.skin_matrices(part.inverse_bind)
        if not _alike(matrices[:, folded], matrices[:, anchor[folded]]):
            return None
    anchors = np.unique(anchor[used])
    transforms = np.linalg.inv(first.inverse_bind[joint_map[anchors]]) @ part.inverse_bind[anchors]
    return Placement(joint_map, transforms[0]) if _alike(transforms, transforms[0]) else None


def _alike(matrices: np.ndarray, reference: np.ndarray) -> bool:
    """Whether ``matrices`` agree with ``reference`` to SAME_BIND_TOLERANCE of their largest entry."""
    scale = max(1.0, float(np.abs(matrices).max()))
    return bool(np.allclose(matrices, reference, rtol=0.0, atol=SAME_BIND_TOLERANCE * scale))


def moved_onto(part: SkinnedMesh, first: SkinnedMesh, placement: Placement) -> SkinnedMesh:
    """``part`` on ``first``'s skeleton and inverse binds (:func:`placement_on`): its joints mapped,
    ``T`` moved into its positions, normals and morph targets; it deforms as before."""
    to_first = placement.transform
    normals = None
    if part.normals is not None:
        normals = part.normals @ np.linalg.inv(to_first[:3, :3])  # the inverse transpose, row vectors
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
    targets = None if part.morph_targets is None else part.morph_targets @ to_first[:3, :3].T
    return SkinnedMesh(
        rest_positions=(part.rest_positions @ to_first[:3, :3].T + to_first[:3, 3]).astype(np.float32),
        faces=part.faces,
        joints=np.where(part.weights > 0.0, placement.joint_map[part.joints], 0),  # unused slots: joint 0
        weights=part.weights,
        inverse_bind=first.inverse_bind,
        skeleton=first.skeleton,
        uvs=part.uvs,
        normals=normals,
        morph_targets=targets,
        morph_target_names=part.morph_target_names,
    )
