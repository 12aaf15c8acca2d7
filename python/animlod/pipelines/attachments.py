"""Nodes hung from a character's joints (props, sockets, eyes), carried to every motion level.

A motion level is a skeleton of its own (see :mod:`animlod.pipelines.character`): a level's
animation moves its joint nodes, not the input's. A node hung from a joint of the input (a sword
in a hand, a hat on the head, an empty socket node an engine attaches things to) follows the
input's skeleton only, so wherever a level plays it would stand still in its rest pose. Each
such attachment is copied for every motion level: under the level's node of its joint, or, where
that joint is frozen, under its nearest kept ancestor with the frozen joints' key posture in
between (seeds/000, Section 5.1: a frozen joint keeps the local transformation of its key
frame), so that it moves as the level's skin moves the vertices bound to its joint. The copies
share the input's meshes, cameras and lights.
"""

from __future__ import annotations

from copy import deepcopy
from dataclasses import dataclass

import numpy as np

from ..io.glb_builder import GlbBuilder
from ..io.gltf_document import GltfDocument
from ..io.gltf_skin import SkinRig
from ..model import Motion
from ..motion_lod.chain import MotionLevel
from ..motion_lod.skeleton_reduce import expand_motion


@dataclass(frozen=True)
class Attachment:
    """A node (with its subtree) hung from joint ``joint`` (skeleton order) of a rig."""

    joint: int
    node: int


def find_attachments(doc: GltfDocument, rig: SkinRig) -> tuple[list[Attachment], list[str]]:
    """The rig's attachments, and notes on the nodes hung from its joints that cannot follow a
    motion level: an animated node (the level's clips animate joints only)."""
    joint_of = {node: j for j, node in enumerate(rig.joint_nodes)}
    # Nodes that are part of a skeleton or skinned: posed by their own rules, never attachments.
    skeletal = {node for skin in doc.gltf.skins for node in skin.joints}
    skeletal |= {n for n, node in enumerate(doc.gltf.nodes) if node.skin is not None}
    animated = {channel.target.node for animation in doc.gltf.animations for channel in animation.channels}
    attachments, notes = [], []
    for node, joint in joint_of.items():
        for child in doc.gltf.nodes[node].children or []:
            subtree = _subtree(doc, child)
            if child in joint_of or not skeletal.isdisjoint(subtree):
                continue  # a joint, a node between joints, or a skinned mesh (LoD'd on its own)
            if not animated.isdisjoint(subtree):
                notes.append(
                    f"{doc.node_label(child)} hangs from joint {rig.skeleton.names[joint]!r} and is animated: "
                    "the motion levels do not carry it"
                )
                continue
            attachments.append(Attachment(joint, child))
    return attachments, notes


def add_level_attachments(
    builder: GlbBuilder,
    doc: GltfDocument,
    rig: SkinRig,
    attachments: list[Attachment],
    original: Motion,
    level: MotionLevel,
    level_index: int,
    joint_nodes: list[int],
) -> None:
    """Copies of ``attachments`` on motion level ``level_index``'s skeleton, whose joint nodes
    (level joint order) are ``joint_nodes``. ``original`` is the motion the level reduces."""
    frozen = level.frozen
    level_joint = np.full(frozen.frozen.size, -1, dtype=np.int64)
    level_joint[frozen.kept_indices] = np.arange(frozen.kept_indices.size)
    # Frozen joints sit at their key posture under their kept ancestor: the same offset at every
    # frame of the level put back on the input's skeleton (expand_motion), so frame 0 gives it.
    first = np.array([0])
    world = expand_motion(frozen, level.motion.take_frames(first), original.take_frames(first)).world_transforms()[0]
    parents = frozen.skeleton.parents
    for attachment in attachments:
        ancestor = attachment.joint
        while level_joint[ancestor] < 0:
            ancestor = int(parents[ancestor])
        relative = np.linalg.inv(world[ancestor]) @ world[attachment.joint]  # identity where kept
        # The document's joint node carries its accumulated uniform scale, the rigid level joint
        # does not (gltf_skin.py: W = W_rigid S(c)).
        scale = np.diag([*[rig.scales[attachment.joint]] * 3, 1.0])
        local = relative @ scale @ doc.rest_matrix(attachment.node)
        copy = _copy_subtree(builder, attachment.node, f"@motion{level_index}")
        node = builder.json["nodes"][copy]
        for key in ("translation", "rotation", "scale"):
            node.pop(key, None)
        node["matrix"] = local.T.reshape(16).tolist()  # column-major
        builder.json["nodes"][joint_nodes[level_joint[ancestor]]].setdefault("children", []).append(copy)


def _subtree(doc: GltfDocument, node: int) -> set[int]:
    """``node`` and its descendants."""
    found, stack = set(), [node]
    while stack:
        current = stack.pop()
        found.add(current)
        stack.extend(doc.gltf.nodes[current].children or [])
    return found


def _copy_subtree(builder: GlbBuilder, node: int, suffix: str) -> int:
    """A copy of node ``node`` and its descendants (names suffixed, same meshes, cameras and
    extensions); the copy's index. It is in no scene and no children list yet."""
    source = builder.json["nodes"][node]
    copy = {key: deepcopy(value) for key, value in source.items() if key not in ("children", "name")}
    copy["name"] = f"{source.get('name') or f'node{node}'}{suffix}"
    children = [_copy_subtree(builder, child, suffix) for child in source.get("children", [])]
    if children:
        copy["children"] = children
    return builder.append("nodes", copy)
