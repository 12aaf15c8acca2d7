"""A character in parts: a skinned mesh whose skin lists some of another skin's joints (Soldier's
visor on the head and neck, eyes or hair on the head) moved onto that skin's skeleton, so that
both play one skeleton: one reduced skeleton per motion level, one set of clips.

Where both skins were bound in one pose, a part's inverse binds differ from the first skin's by
one transform ``T`` for every joint its weights use (its mesh node's,
:func:`animlod.io.gltf_read.skinned_mesh_of_node`); ``T`` moves into its vertices.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..model import SkinnedMesh

# Inverse binds stored as float32 agree to about 1e-7 of their largest entry where two skins were
# bound in one pose; a part whose binds differ by more than this was bound in another.
SAME_BIND_TOLERANCE = 1e-5


@dataclasses.dataclass(frozen=True)
class Placement:
    """How a part lies on another skin's skeleton: the skeleton's joint for each of the part's
    joints, and ``T`` (4, 4) with ``IBM_part = IBM_first @ T`` for every joint its weights use."""

    joint_map: np.ndarray
    transform: np.ndarray


def placement_on(first: SkinnedMesh, part: SkinnedMesh) -> Placement | None:
    """How ``part`` lies on ``first``'s skeleton and binds, or None where its joints (by name) are
    not all ``first``'s, its weights use none, or it was bound in another pose."""
    index = {name: joint for joint, name in enumerate(first.skeleton.names)}
    if part.skeleton is first.skeleton:
        joint_map = np.arange(first.skeleton.joint_count)
    elif all(name in index for name in part.skeleton.names):
        joint_map = np.array([index[name] for name in part.skeleton.names])
    else:
        return None
    used = np.unique(part.joints[part.weights > 0.0])
    if not used.size:
        return None
    transforms = np.linalg.inv(first.inverse_bind[joint_map[used]]) @ part.inverse_bind[used]
    scale = max(1.0, float(np.abs(transforms).max()))
    if not np.allclose(transforms, transforms[0], rtol=0.0, atol=SAME_BIND_TOLERANCE * scale):
        return None
    return Placement(joint_map, transforms[0])


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
        joints=placement.joint_map[part.joints],
        weights=part.weights,
        inverse_bind=first.inverse_bind,
        skeleton=first.skeleton,
        uvs=part.uvs,
        normals=normals,
        morph_targets=targets,
        morph_target_names=part.morph_target_names,
    )
