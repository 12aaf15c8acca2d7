"""What a motion level's GLB of its own (`animlod motion`) carries of a glTF input besides the
level's skeleton, its clips and the skin, and what it leaves out, in words for the run's notes.

A level file is a new document (:func:`animlod.io.gltf.write_glb`): the input's nodes are not in
it, so its skinned mesh takes the names of the input's (:func:`level_mesh_names`), and what hangs
from the joints is copied onto the level's skeleton (:mod:`.attachments`)
with the channels that animate it, and of the input's extensions only those that name no node
go along. `animlod character` keeps the whole document instead.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, NamedTuple

from ..io.glb_builder import GlbBuilder
from ..io.gltf_document import POINTER_EXTENSION, GltfDocument
from ..io.gltf_references import LIGHTS_EXTENSION
from ..io.gltf_skin import SkinRig
from ..io.gltf_write import STANDALONE_NODE_EXTENSIONS, STANDALONE_ROOT_EXTENSIONS, HungNodes, MeshNames
from ..model import Motion
from ..motion_lod.chain import MotionLevel
from .attachments import (
    Attachment,
    add_level_attachments,
    carry_other_channels,
    hung_nodes,
    posed_by_level_clips,
    posing_nodes,
    standalone_pointer,
)

if TYPE_CHECKING:
    from .motion import PlayedClip


class LevelContent(NamedTuple):
    """What a glTF input's motion level files carry besides the skeleton, its clips and the skin:
    what hangs from ``rig``'s joints (:func:`~.attachments.find_attachments`) with the channels
    that animate it, the pointer channels at materials, textures, cameras and lights, and the
    names of the skinned mesh's node and mesh (:func:`level_mesh_names`)."""

    document: GltfDocument
    rig: SkinRig
    attachments: list[Attachment]
    mesh_names: MeshNames

    def on_level(self, original: Motion, level: MotionLevel, played: list[PlayedClip]) -> HungNodes:
        """The attachments' copies on ``level`` of ``original``, for its GLB, with the channels that
        animate them in each of the ``played`` clips that is one of the document's animations."""

        def add(builder: GlbBuilder, joint_nodes: list[int], animations: list[int]) -> None:
            document, rig = self.document, self.rig
            copies = add_level_attachments(builder, document, rig, self.attachments, original, level, joint_nodes)
            posing = posed_by_level_clips(document, rig, self.attachments)
            for clip, animation in zip(played, animations):
                if clip.animation is not None:
                    carry_other_channels(builder, document, posing, clip.animation, animation, copies, standalone=True)
            _keep_used_cameras_and_lights(builder.json, joint_nodes[0])

        return HungNodes(self.document, add)


_CAMERA_POINTER = re.compile(r"(/cameras/)(\d+)(/.*)?", re.DOTALL)
_LIGHT_POINTER = re.compile(rf"(/extensions/{LIGHTS_EXTENSION}/lights/)(\d+)(/.*)?", re.DOTALL)


def _keep_used_cameras_and_lights(js: dict, first: int) -> None:
    """Of the cameras and KHR_lights_punctual lights that ``js`` holds at the input's indices (for
    the copies of what hangs from the joints), only those that its nodes from ``first`` on (the
    level's own, the copies) or its animations' pointers use, renumbered: the input's elsewhere,
    which the run's note says the levels leave out, were left in the file unused."""
    nodes = js.get("nodes", [])[first:]
    targets = [channel["target"] for animation in js.get("animations", []) for channel in animation["channels"]]
    pointers = [target["extensions"][POINTER_EXTENSION] for target in targets
                if POINTER_EXTENSION in (target.get("extensions") or {})]  # fmt: skip
    if "cameras" in js:
        used = {node["camera"] for node in nodes if "camera" in node}
        new = _renumbered(js["cameras"], used, pointers, _CAMERA_POINTER)
        for node in nodes:
            if "camera" in node:
                node["camera"] = new[node["camera"]]
        js["cameras"] = [js["cameras"][old] for old in new]
        if not js["cameras"]:
            del js["cameras"]
    lights = (js.get("extensions") or {}).get(LIGHTS_EXTENSION)
    if lights is not None:
        holders = [
            node["extensions"][LIGHTS_EXTENSION] for node in nodes if LIGHTS_EXTENSION in (node.get("extensions") or {})
        ]
        new = _renumbered(lights.get("lights", []), {holder["light"] for holder in holders}, pointers, _LIGHT_POINTER)
        for holder in holders:
            holder["light"] = new[holder["light"]]
        lights["lights"] = [lights["lights"][old] for old in new]
        if not lights["lights"]:
            del js["extensions"][LIGHTS_EXTENSION]


def _renumbered(items: list, used: set[int], pointers: list[dict], pattern: re.Pattern) -> dict[int, int]:
    """The new index of each of ``items`` kept (those ``used`` or that a pointer of ``pattern``
    names), old to new in order; the ``pointers`` at them renumbered."""
    named = [(pointer, pattern.fullmatch(str(pointer.get("pointer", "")))) for pointer in pointers]
    used = used | {int(match[2]) for _, match in named if match}
    new = {old: index for index, old in enumerate(sorted(old for old in used if 0 <= old < len(items)))}
    for pointer, match in named:
        if match and int(match[2]) in new:
            pointer["pointer"] = f"{match[1]}{new[int(match[2])]}{match[3] or ''}"
    return new


def level_mesh_names(doc: GltfDocument, part_nodes: list[int]) -> MeshNames:
    """The names of the level files' skinned mesh node and mesh, joined from the meshes of
    ``part_nodes`` (the body's first): the input's own for one (unnamed where it is), else the
    parts' names joined by " + " (``node <n>`` or ``mesh <m>`` for an unnamed one)."""
    nodes = [doc.json["nodes"][node] for node in part_nodes]
    meshes = [doc.json["meshes"][node["mesh"]] for node in nodes]
    if len(nodes) == 1:
        return MeshNames(nodes[0].get("name"), meshes[0].get("name"))
    node_names = [node.get("name") or f"node {index}" for node, index in zip(nodes, part_nodes)]
    mesh_names = [mesh.get("name") or f"mesh {node['mesh']}" for mesh, node in zip(meshes, nodes)]
    return MeshNames(" + ".join(node_names), " + ".join(mesh_names))


def left_out_of_level_files(doc: GltfDocument, rig: SkinRig, joined: set[int], attachments: list[Attachment]) -> str:
    """What of ``doc`` the motion levels' GLBs (a skinned mesh with its materials and the morph
    weight channels of the ``joined`` nodes' meshes, ``rig``'s skeleton and its joint channels,
    copies of the ``attachments`` with their channels) do not carry, as words for a note; empty
    where that is nothing."""
    hung = hung_nodes(doc, attachments)
    elsewhere = [node for n, node in enumerate(doc.gltf.nodes or []) if n not in hung]
    parts = []
    meshes = sum(node.mesh is not None and node.skin is None for node in elsewhere)
    if meshes:
        parts.append(f"{meshes} mesh{'es' if meshes > 1 else ''} without a skin elsewhere (static parts, scenery)")
    channels = [(node, path) for targets in doc.channel_targets for node, path in targets]
    if any(path == "weights" and node not in joined | hung for node, path in channels):
        parts.append("the morph weight channels of other meshes")
    posing = posing_nodes(doc, rig)
    moving = {node for node, path in channels if node is not None and path != "weights"} - posing - hung
    if moving and rig.skin is not None:  # a skeleton of an animated node tree: the others are named apart
        parts.append(
            f"the animation of {len(moving)} node{'s that hang' if len(moving) > 1 else ' that hangs'} from no joint"
        )
    raw = [channel["target"] for animation in doc.json.get("animations", []) for channel in animation["channels"]]
    resolved = [path for targets in doc.channel_targets for _, path in targets]  # pointers at nodes: node channels
    if any(path == "pointer" and not standalone_pointer(target) for target, path in zip(raw, resolved)):
        parts.append("KHR_animation_pointer channels at meshes or other objects")
    if any(node.camera is not None or "KHR_lights_punctual" in (node.extensions or {}) for node in elsewhere):
        parts.append("its cameras and lights elsewhere")
    dropped = sorted({name for name in doc.json.get("extensions") or {} if name not in STANDALONE_ROOT_EXTENSIONS}
                     | {name for n in hung for name in doc.json["nodes"][n].get("extensions") or {}
                        if name not in STANDALONE_NODE_EXTENSIONS})  # fmt: skip
    if dropped:
        parts.append(f"the extensions {', '.join(dropped)} (they may name nodes of the input)")
    return ", ".join(parts[:-1]) + (" or " if len(parts) > 1 else "") + (parts[-1] if parts else "")


def poses_nothing(doc: GltfDocument, rig: SkinRig) -> bool:
    """Whether an animation of ``doc`` has a channel that poses no joint of ``rig`` (morph
    weights, a prop's own motion, a KHR_animation_pointer channel at anything but a node)."""
    posing = posing_nodes(doc, rig)
    return any(node not in posing or path == "weights" for targets in doc.channel_targets for node, path in targets)
