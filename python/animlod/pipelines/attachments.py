"""What moves with a character besides its skeleton, carried to every motion level: the nodes
hung from its joints (props, sockets, eyes), what its joint nodes draw, and its clips' other
channels (morph weights, those nodes' own animation, anything else the clip moves).

A motion level is a skeleton of its own (see :mod:`animlod.pipelines.character`) with a clip of
its own per input clip: playing a level's clip moves the level's joint nodes, not the input's. A
node hung from a joint of the input (a sword in a hand, a hat on the head, an empty socket node
an engine attaches things to) would stand still in its rest pose there, and whatever else the
input clip animates (a face's morph weights) would not move. Each attachment (such a node with
its subtree, or what a joint's own node draws: an unskinned mesh, a camera, a light) is copied
for every motion level: under the level's node of its joint, or, where that joint is frozen,
under its nearest kept ancestor with the frozen joints' key posture in between (seeds/000,
Section 5.1: a frozen joint keeps the local transformation of its key frame), so that it moves
as the level's skin moves the vertices bound to its joint. What hangs from a node between joints
(an exporter's helper node), or what such a node draws, hangs from its nearest joint through
copies of the nodes between, which play their own channels. The copies share the input's meshes,
cameras and lights. Each level clip then takes the input clip's channels that pose no skeleton,
retargeted to the copies where they animate an attachment. A copy of a node with an MSFT_lod
chain (a prop with levels of its own) gets level nodes of its own, drawing the same level meshes
(:func:`copy_level_chains`).
"""

from __future__ import annotations

from copy import deepcopy
from dataclasses import dataclass

import numpy as np

from ..io.glb_builder import GlbBuilder
from ..io.gltf_document import LOD_EXTENSION, POINTER_EXTENSION, GltfDocument
from ..io.gltf_lod import ANIMLOD_EXTRA, COVERAGE_EXTRA, drive_level_nodes, has_lod_chain, lod_ids, node_extras
from ..io.gltf_skin import SkinRig
from ..model import Motion
from ..motion_lod.chain import MotionLevel
from ..motion_lod.skeleton_reduce import expand_motion

# What a joint node draws or holds besides its transform and children (lights are an extension).
_CONTENT = ("mesh", "camera", "weights", "extensions")
_TRANSFORM = ("translation", "rotation", "scale", "matrix")
# What KHR_animation_pointer channels of a standalone level file may point at.
_STANDALONE_POINTERS = ("/materials/", "/textures/", "/cameras/", "/extensions/KHR_lights_punctual/")


@dataclass(frozen=True)
class Attachment:
    """A node (with its subtree) hung from joint ``joint`` (skeleton order) of a rig, or, with
    ``content_only``, a node for what it draws (a mesh, camera or light on it): the joint's own,
    or a node between joints. ``via``: the nodes between the joint and ``node`` (``node``
    itself for its content), copied with it (an exporter's helper node such as assimp's
    ``RightHand_$AssimpFbx$_PostRotation``, a sword holding tassel bones)."""

    joint: int
    node: int
    content_only: bool = False
    via: tuple[int, ...] = ()


def find_attachments(doc: GltfDocument, rig: SkinRig) -> list[Attachment]:
    """The subtrees hung from the rig's joint nodes that hold no joint and no skinned mesh, and
    the nodes that draw an unskinned mesh or hold a camera or a light: the joint nodes, and the
    nodes between joints (each with what hangs from it, through it, from its nearest joint)."""
    joint_of = {node: j for j, node in enumerate(rig.joint_nodes)}
    skeletal = posing_nodes(doc, rig) | {n for n, node in enumerate(doc.gltf.nodes) if node.skin is not None}
    attachments = []
    for node, joint in joint_of.items():
        if _draws(doc, node):
            attachments.append(Attachment(joint, node, content_only=True))
        below = [(child, ()) for child in doc.gltf.nodes[node].children or []]
        while below:
            child, via = below.pop()
            if child in joint_of:
                continue
            if skeletal.isdisjoint(_subtree(doc, child)):
                attachments.append(Attachment(joint, child, via=via))
                continue
            # A node between joints or a skinned mesh's (LoD'd on its own): what it draws, and
            # what hangs from it, hang from the joint through it.
            if _draws(doc, child):
                attachments.append(Attachment(joint, child, content_only=True, via=(*via, child)))
            below += [(grandchild, (*via, child)) for grandchild in doc.gltf.nodes[child].children or []]
    return attachments


def _draws(doc: GltfDocument, node: int) -> bool:
    """Whether ``node`` draws an unskinned mesh or holds a camera or a light."""
    own = doc.gltf.nodes[node]
    light = "KHR_lights_punctual" in (own.extensions or {})
    return (own.mesh is not None and own.skin is None) or own.camera is not None or light


def hung_nodes(doc: GltfDocument, attachments: list[Attachment]) -> set[int]:
    """The nodes whose content the copies of ``attachments`` carry."""
    found = set()
    for attachment in attachments:
        found |= {attachment.node} if attachment.content_only else _subtree(doc, attachment.node)
    return found


def posing_nodes(doc: GltfDocument, rig: SkinRig) -> set[int]:
    """Nodes that pose a skeleton: every skin's joints, ``rig``'s (a skin's, or an animated node
    tree's) and their ancestors (a level's clip poses its own skeleton in their place)."""
    joints = {node for skin in doc.gltf.skins for node in skin.joints} | set(rig.joint_nodes)
    found = set(joints)
    for joint in joints:
        found.update(doc.ancestors(joint))
    return found


def posed_by_level_clips(doc: GltfDocument, rig: SkinRig, attachments: list[Attachment]) -> set[int]:
    """The nodes whose channels a level's clip leaves out (its own joints take their place): those
    that pose a skeleton (:func:`posing_nodes`) but the nodes between joints that ``attachments``
    hang through, whose copies take their channels."""
    return posing_nodes(doc, rig) - {node for attachment in attachments for node in attachment.via}


def add_level_attachments(
    builder: GlbBuilder,
    doc: GltfDocument,
    rig: SkinRig,
    attachments: list[Attachment],
    original: Motion,
    level: MotionLevel,
    joint_nodes: list[int],
    suffix: str = "",
) -> dict[int, int]:
    """Copies of ``attachments`` on ``level``'s skeleton, whose joint nodes (level joint order) are
    ``joint_nodes``, their names ending in ``suffix``; ``original`` is the motion the level
    reduces. The nodes between a joint and what hangs through them are copied once each, with
    their own transforms and content, so that their channels can move the copies. Returns the
    copy of each node of the copied subtrees and of the nodes between."""
    frozen = level.frozen
    level_joint = np.full(frozen.frozen.size, -1, dtype=np.int64)
    level_joint[frozen.kept_indices] = np.arange(frozen.kept_indices.size)
    # Frozen joints sit at their key posture under their kept ancestor: the same offset at every
    # frame of the level put back on the input's skeleton (expand_motion), so frame 0 gives it.
    first = np.array([0])
    world = expand_motion(frozen, level.motion.take_frames(first), original.take_frames(first)).world_transforms()[0]
    parents = frozen.skeleton.parents
    copies: dict[int, int] = {}
    places: dict[int, int] = {}  # the node a joint's attachments hang from in the level
    for attachment in attachments:
        joint = attachment.joint
        if joint not in places:
            ancestor = joint
            while level_joint[ancestor] < 0:
                ancestor = int(parents[ancestor])
            # The document's joint node carries its rest scale, the rigid level joint does not.
            rest_linear = np.eye(4)
            rest_linear[:3, :3] = rig.rest_linear[joint]
            frame = np.linalg.inv(world[ancestor]) @ world[joint] @ rest_linear
            places[joint] = joint_nodes[level_joint[ancestor]]
            if not np.allclose(frame, np.eye(4), rtol=0.0, atol=1e-12):  # a static node for the joint's frame
                name = f"{_name(builder, rig.joint_nodes[joint])} frame{suffix}"
                places[joint] = _child(builder, places[joint], {"name": name, "matrix": frame.T.reshape(16).tolist()})
        parent = places[joint]
        for between in attachment.via:  # each copied once, with its content: it holds its own channels
            if between not in copies:
                source = builder.json["nodes"][between]
                own = {key: deepcopy(source[key]) for key in (*_TRANSFORM, *_CONTENT) if key in source}
                copies[between] = _child(builder, parent, {"name": f"{_name(builder, between)}{suffix}", **own})
            parent = copies[between]
        if attachment.content_only and attachment.via:
            continue  # a node between joints: its copy above draws what it draws
        if attachment.content_only:
            source = builder.json["nodes"][attachment.node]
            content = {key: deepcopy(source[key]) for key in _CONTENT if key in source}
            # A joint's own content is named apart from the level's joint node where no suffix does.
            name = f"{_name(builder, attachment.node)}{suffix or ' content'}"
            copies[attachment.node] = _child(builder, parent, {"name": name, **content})
        else:
            builder.json["nodes"][parent].setdefault("children", []).append(
                _copy_subtree(builder, attachment.node, suffix, copies)
            )
    return copies


def copy_level_chains(
    builder: GlbBuilder, doc: GltfDocument, copies: dict[int, int], suffix: str, motion_level: int
) -> None:
    """Level nodes of its own for each copy (:func:`add_level_attachments`) on ``motion_level``'s
    skeleton of an MSFT_lod chain's base in ``builder``, named with ``suffix``: copies of the
    base's level nodes where the copy is (its transform), drawing the same meshes, with the base's
    coverages, their ``extras.animlod`` at that motion level; the copy's channels in the level
    clips, added before, drive them. A level node listed by several bases would be one node in
    several places, and the copies kept the input's ids (and, what a node between or a joint's
    own node draws, no coverages)."""
    nodes = builder.json["nodes"]
    for source, copy in copies.items():
        if not has_lod_chain(nodes[source]):
            continue
        ids = lod_ids(doc, source) or nodes[source]["extensions"][LOD_EXTENSION]["ids"]  # checked if the input's
        levels = []
        for level in ids:
            levels.append(_copy_subtree(builder, level, suffix, {}))
            for key in _TRANSFORM:
                nodes[levels[-1]].pop(key, None)
                if key in nodes[copy]:
                    nodes[levels[-1]][key] = deepcopy(nodes[copy][key])
        nodes[copy].setdefault("extensions", {})[LOD_EXTENSION] = {"ids": levels}
        chain_extras = {key: deepcopy(value) for key, value in node_extras(nodes[source]).items()
                        if key in (COVERAGE_EXTRA, ANIMLOD_EXTRA)}  # fmt: skip
        nodes[copy]["extras"] = {**node_extras(nodes[copy]), **chain_extras}
        for node in (copy, *levels):
            info = nodes[node].get("extras", {}).get(ANIMLOD_EXTRA)
            if isinstance(info, dict):  # animlod's chains; another tool's have none
                info["motion_level"] = motion_level
        drive_level_nodes(builder, copy, levels)


def _child(builder: GlbBuilder, parent: int, node: dict) -> int:
    """``node`` appended as the last child of ``parent``; its index."""
    index = builder.append("nodes", node)
    builder.json["nodes"][parent].setdefault("children", []).append(index)
    return index


def carry_other_channels(
    builder: GlbBuilder,
    doc: GltfDocument,
    posing: set[int],
    animation: int,
    level_animation: int,
    copies: dict[int, int],
    standalone: bool = False,
) -> None:
    """Adds to ``level_animation`` of ``builder`` (which holds the accessors of ``doc``'s at their
    indices) the channels of the document's ``animation`` that pose no skeleton (not on a node
    of ``posing``, :func:`posed_by_level_clips`; a joint's morph weights do not pose it), on the
    attachments' copies where they have one; KHR_animation_pointer channels of anything but a
    node (a material's colour) as they are. ``standalone``: for a file of its own, which holds
    of the document only the copies and its materials, textures, cameras and lights (at their
    indices): the channels of the copies and the pointers at those. The samplers reuse the
    input's accessors: the level clip keeps the input clip's times (add_animation's ``start``)."""
    source = doc.json["animations"][animation]
    target = builder.json["animations"][level_animation]
    for channel, (node, path) in zip(source.get("channels", []), doc.channel_targets[animation]):
        if standalone and node not in copies and not standalone_pointer(channel["target"]):
            continue
        if path == "pointer":
            carried = deepcopy(channel["target"])
        elif node is None or (node in posing and path != "weights"):
            continue
        else:  # a node's channel, or a pointer at a node's property written as one
            kept = {} if channel["target"].get("path") == "pointer" else channel["target"]
            carried = {**kept, "node": copies.get(node, node), "path": path}
        target["samplers"].append(deepcopy(source["samplers"][channel["sampler"]]))
        target["channels"].append({"sampler": len(target["samplers"]) - 1, "target": carried})


def standalone_pointer(target: dict) -> bool:
    """Whether a channel's ``target`` is a KHR_animation_pointer at what a standalone level file
    keeps at the document's indices (:func:`carry_other_channels`)."""
    pointer = (target.get("extensions") or {}).get(POINTER_EXTENSION) or {}
    return str(pointer.get("pointer", "")).startswith(_STANDALONE_POINTERS)


def _subtree(doc: GltfDocument, node: int) -> set[int]:
    """``node`` and its descendants."""
    found, stack = set(), [node]
    while stack:
        current = stack.pop()
        found.add(current)
        stack.extend(doc.gltf.nodes[current].children or [])
    return found


def _copy_subtree(builder: GlbBuilder, node: int, suffix: str, copies: dict[int, int]) -> int:
    """A copy of node ``node`` and its descendants (names suffixed; same transforms, meshes,
    cameras and extensions), recorded in ``copies``; the copy's index, in no children list yet."""
    source = builder.json["nodes"][node]
    copy = {key: deepcopy(value) for key, value in source.items() if key not in ("children", "name")}
    copy["name"] = f"{_name(builder, node)}{suffix}"
    children = [_copy_subtree(builder, child, suffix, copies) for child in source.get("children", [])]
    if children:
        copy["children"] = children
    copies[node] = builder.append("nodes", copy)
    return copies[node]


def _name(builder: GlbBuilder, node: int) -> str:
    """A node's name, ``node<i>`` when it has none (as animlod names unnamed joints)."""
    return builder.json["nodes"][node].get("name") or f"node{node}"
