"""A character in parts: a skinned mesh whose skin lists some of another skin's joints (Soldier's
visor on the head and neck, VRoid's hair on the head and its own hair bones) moved onto that
skin's skeleton, so that both play one skeleton: one reduced skeleton per motion level, one set of
clips.

Where both skins were bound in one pose, a part's inverse binds differ from the first skin's by
one transform ``T`` for every joint its weights use (its mesh node's,
:func:`animlod.io.gltf_read.skinned_mesh_of_node`); ``T`` moves into its vertices. Bones of the
part's own that hold their bind pose fold into the joint above them (:func:`placement_on`);
bones that move join the first skin's skeleton (:func:`joined_rig`), bound as the part binds them.
A skin that lists none of the other's joints but hangs from one in the node tree (a cape or hair
skin over its own bones alone, Khronos' RecursiveSkeletons) takes that joint first
(:func:`hanging_rig`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from ..io.gltf_document import GltfDocument
from ..io.gltf_skin import SkinRig
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


def placement_on(
    first: SkinnedMesh, part: SkinnedMesh, keys: JointKeys, motion: Motion | None = None
) -> Placement | None:
    """How ``part`` lies on ``first``'s skeleton and binds, or None: where its weights reach a joint
    with no ancestor ``first`` lists, reach none, or it was bound in another pose. ``keys`` tell
    which joints of the two skeletons are one.

    A joint ``first`` lacks (VRoid hair and skirt bones under the head and hips) moves its
    vertices with its nearest ancestor that ``first`` lists. That is exact only where it holds
    its bind pose on that ancestor in every frame of ``motion``, the part's clips (checked on
    its skin matrices); without ``motion``, such a part has no placement (:func:`joined_rig`
    adds such bones to ``first``'s skeleton instead).
    """
    lying = _lying_on(first, part, keys)
    if lying is None:
        return None
    folded = lying.used[~lying.listed[lying.used]]
    if folded.size:
        if motion is None:
            return None
        matrices = motion.skin_matrices(part.inverse_bind)
        if not _alike(matrices[:, folded], matrices[:, lying.anchor[folded]]):
            return None
    return Placement(lying.joint_map, lying.transform)


def hanging_rig(doc: GltfDocument, rig: SkinRig, joints: set[int]) -> SkinRig | None:
    """``rig`` with the node of ``joints`` that its bones hang from in the node tree (another
    skin's joint, the nearest above each tree of its joints: two locks of hair under the head) as
    an extra joint, so that :func:`placement_on` and :func:`joined_rig` see where it meets that
    skin; None where a tree of its joints lies under none of ``joints``, its trees hang from
    different ones or were bound apart, or it already lists one. That joint is bound where the
    node tree's rest pose puts it relative to a tree's root joint's bind: ``IBM_anchor = L @
    IBM_root``, ``L`` the rest transforms of the nodes from the anchor down to that root.
    Exporters bind at the rest pose; a part bound with its roots elsewhere relative to that joint
    is placed off by as much."""
    listed = set(doc.gltf.skins[rig.skin].joints)
    if joints & listed or rig.extra_joints:
        return None
    anchor, binds = None, []
    for root in (node for node in rig.joint_nodes if node in listed and listed.isdisjoint(doc.ancestors(node))):
        above = doc.ancestors(root)
        depth = next((i for i, node in enumerate(above) if node in joints), None)
        if depth is None or anchor not in (None, above[depth]):
            return None
        anchor, down = above[depth], np.eye(4)
        for node in reversed([root, *above[:depth]]):  # the anchor's child first
            down = down @ doc.rest_matrix(node)
        binds.append(down @ rig.inverse_bind[rig.joint_nodes.index(root)])
    if anchor is None or not all(_same_bind(bind, binds[0]) for bind in binds[1:]):
        return None
    return SkinRig(doc, rig.skin, [anchor], binds[0][None])


def _same_bind(first: np.ndarray, second: np.ndarray) -> bool:
    """Whether two inverse binds (4, 4) of one joint agree to the float32 rounding of stored ones."""
    scale = 1.0 + np.abs(first[:3, 3]).max()
    return bool(np.allclose(first[:3], second[:3], rtol=0.0, atol=1e-5 * scale))


def joined_rig(
    doc: GltfDocument, first_rig: SkinRig, first: SkinnedMesh, part_rig: SkinRig, part: SkinnedMesh
) -> SkinRig | None:
    """``first``'s rig with the joints of ``part`` it lacks (a cape's or hair's own bones, below
    joints it lists), bound as ``part`` binds them, so that a part whose own bones move in its
    clips plays one skeleton with ``first``; None where ``part`` has no such joint, or has no
    placement but for them (:func:`placement_on`: its weights reach a joint with no ancestor
    ``first`` lists, or it was bound in another pose). Joints are one where they are one node."""
    lying = _lying_on(first, part, JointKeys(first_rig.joint_nodes, part_rig.joint_nodes))
    if lying is None:
        return None
    extra = np.flatnonzero(~lying.listed & (lying.anchor >= 0))
    if not extra.size:
        return None
    # In the stored binds (SkinRig.inverse_bind), IBM_part = IBM_first @ T at every joint both
    # list, T a rigid change of bind space (the same T as Placement's, before each mesh's node).
    shared = part_rig.joint_nodes[int(lying.anchor[lying.used[0]])]
    to_part = (
        np.linalg.inv(first_rig.inverse_bind[first_rig.joint_nodes.index(shared)])
        @ part_rig.inverse_bind[part_rig.joint_nodes.index(shared)]
    )
    nodes = first_rig.extra_joints + [part_rig.joint_nodes[j] for j in extra]
    binds = np.concatenate([first_rig.extra_binds, part_rig.inverse_bind[extra] @ np.linalg.inv(to_part)])
    return SkinRig(doc, first_rig.skin, nodes, binds)


class JointKeys(NamedTuple):
    """The node of each joint of two skeletons of one document, in skeleton order: what tells which
    joints are one (names may repeat: two bones named "Hair")."""

    first: Sequence[int]
    part: Sequence[int]


class _Lying(NamedTuple):
    """Where a part's joints (its skeleton's) meet another skin's (:func:`_lying_on`)."""

    listed: np.ndarray  # (J,) bool: the other skin lists the joint
    anchor: np.ndarray  # (J,) the nearest listed joint at or above each, -1 for none
    used: np.ndarray  # the joints the part's weights use
    joint_map: np.ndarray  # (J,) the other skin's joint for each anchor, -1 for none
    transform: np.ndarray  # (4, 4) T of Placement


def _lying_on(first: SkinnedMesh, part: SkinnedMesh, keys: JointKeys) -> _Lying | None:
    """How ``part``'s joints meet ``first``'s; None where a joint its weights use has no ancestor
    ``first`` lists, it uses none, or it was bound in another pose."""
    index = {key: joint for joint, key in enumerate(keys.first)}
    parents = part.skeleton.parents
    listed = np.array([key in index for key in keys.part])
    anchor = np.full(part.skeleton.joint_count, -1)
    for joint in range(part.skeleton.joint_count):  # parents before children
        anchor[joint] = joint if listed[joint] else (anchor[parents[joint]] if parents[joint] >= 0 else -1)
    used = np.unique(part.joints[part.weights > 0.0])
    if not used.size or (anchor[used] < 0).any():
        return None
    joint_map = np.array([index[keys.part[a]] if a >= 0 else -1 for a in anchor])
    anchors = np.unique(anchor[used])
    transforms = np.linalg.inv(first.inverse_bind[joint_map[anchors]]) @ part.inverse_bind[anchors]
    if not _alike(transforms, transforms[0]):
        return None
    return _Lying(listed, anchor, used, joint_map, transforms[0])


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
        default_morph_weights=part.default_morph_weights,
    )
