"""Clips from other glTF or BVH files of the same rig, added to a character's document by node name.

Animation libraries come apart from their characters: Mixamo's "without skin" downloads, one
file per clip, hold the rig's nodes and a clip each, no mesh. Each translation, rotation or
scale channel of such a file moves the character's node of the same name, its keys copied as
they are (times, values, interpolation); the result is the character's document with more
animations, which the pipelines then treat as its own (every level plays them).

Only the same rig in the same proportions is taken as it is: a node whose translation a clip
animates must rest where the character's node of that name rests (within ``REST_TOLERANCE`` of
the rig's size), or the clip would stretch the character's bones to another figure's
(retargeting is not done here). Rotations and scales move any node of the name. Channels on
nodes the character lacks, or whose name it uses twice, are left out and counted in a note.
A BVH file of the same skeleton or of another humanoid is carried over relative to the rest
poses, its joints matched by shape or body part (:mod:`.bvh_clips`).
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from ..io.glb_builder import GlbBuilder
from ..io.gltf_document import GltfDocument
from .bvh_clips import add_bvh_clip
from .joint_matching import named_nodes, read_joint_map

# A node whose translation a clip animates rests within this fraction of the rig's size (the
# largest rest translation among the character's nodes the clip names) of the character's node.
REST_TOLERANCE = 0.01
_NODE_PATHS = {"translation": 3, "rotation": 4, "scale": 3}


def document_with_clips(
    source: str | os.PathLike,
    clip_files: Sequence[str | os.PathLike],
    note: Callable[[str], None],
    joint_map: str | os.PathLike | None = None,
) -> GltfDocument:
    """The glTF at ``source`` with the clips of ``clip_files`` added (:func:`with_clips`), and a
    note naming its morph weight channels that change nothing
    (:meth:`~animlod.io.gltf_document.GltfDocument.idle_weight_channels_note`)."""
    doc = with_clips(GltfDocument(source), clip_files, note, joint_map)
    if idle := doc.idle_weight_channels_note():
        note(idle)
    return doc


def with_clips(
    doc: GltfDocument,
    clip_files: Sequence[str | os.PathLike],
    note: Callable[[str], None],
    joint_map: str | os.PathLike | None = None,
) -> GltfDocument:
    """``doc`` with every animation of each of ``clip_files`` added (see the module notes), the
    joints of BVH files matched by the JSON table ``joint_map`` where given
    (:func:`.joint_matching.read_joint_map`); FormatError naming the clip file for one that
    cannot be read, has no animation moving a node of the character's by name, or moves the
    translation of a node of the same name resting elsewhere (a ``.bvh`` file:
    :func:`.bvh_clips.add_bvh_clip`); ValueError for a joint map without a BVH file. ``doc``
    itself where there is nothing to add."""
    if not clip_files and joint_map is None:
        return doc
    builder = GlbBuilder.from_document(doc)
    targets = named_nodes(doc)
    bvh_files = [clip_file for clip_file in clip_files if Path(clip_file).suffix.lower() == ".bvh"]
    if joint_map is not None and not bvh_files:
        raise ValueError(f"joint map {os.fspath(joint_map)}: maps the joints of BVH clips, and no BVH clip is given")
    table = read_joint_map(joint_map) if joint_map is not None else None
    for clip_file in clip_files:
        first_added = len(builder.json.get("animations", []))
        if clip_file in bvh_files:
            note(add_bvh_clip(builder, doc, clip_file, table) + _named_apart(builder, first_added, clip_file))
            continue
        source = GltfDocument(clip_file)
        if not source.gltf.animations:
            raise source.fail("animations", f"no animation to add to {Path(doc.path).name}")
        mapping = {node: targets[name] for name, node in named_nodes(source).items() if name in targets}
        _check_rests(source, doc, mapping)
        left_out = added = 0
        for index, animation in enumerate(source.gltf.animations):
            samplers: list[dict] = []
            placed: dict[int, int] = {}  # the clip's sampler -> the added animation's
            channels = []
            for (node, path), channel in zip(source.channel_targets[index], animation.channels or []):
                if path not in _NODE_PATHS or node not in mapping:
                    left_out += 1
                    continue
                if channel.sampler not in placed:
                    placed[channel.sampler] = len(samplers)
                    samplers.append(_copied_sampler(builder, source, index, channel.sampler, _NODE_PATHS[path]))
                channels.append({"sampler": placed[channel.sampler], "target": {"node": mapping[node], "path": path}})
            if channels:
                name = animation.name or f"{Path(clip_file).stem} {index}"
                builder.append("animations", {"name": name, "samplers": samplers, "channels": channels})
                added += 1
        into = Path(doc.path).name
        if not added:
            raise source.fail("animations", f"none moves a node of {into}'s by name (another rig?)")
        dropped = f"; {left_out} channel(s) on nodes {into} lacks, or on morph weights, left out" if left_out else ""
        total = len(source.gltf.animations)
        renamed = _named_apart(builder, first_added, clip_file)
        note(f"{os.fspath(clip_file)}: {added} of its {total} clip(s) added to {into}{dropped}{renamed}")
    return GltfDocument(doc.path, doc.max_animation_frames, data=builder.to_bytes())


def _named_apart(builder: GlbBuilder, first_added: int, clip_file: str | os.PathLike) -> str:
    """Rename the animations added from ``clip_file`` (from index ``first_added`` on) whose name
    an animation before them has: every Mixamo export names its clip "mixamo.com", and engines
    find clips by name. The file's stem tells them apart ("mixamo.com (Walking)"), then a count.
    Returns the note's part that says so ("" when none is renamed)."""
    animations = builder.json["animations"]
    taken = {animation.get("name") for animation in animations[:first_added]}
    renamed = []
    for animation in animations[first_added:]:
        name = animation.get("name")
        if name in taken:
            candidates = (
                f"{name} ({Path(clip_file).stem})" + (f" {count}" if count > 1 else "") for count in itertools.count(1)
            )
            animation["name"] = next(candidate for candidate in candidates if candidate not in taken)
            renamed.append(f"{name!r} -> {animation['name']!r}")
        taken.add(animation["name"])
    return f"; renamed where another clip has the name: {', '.join(renamed)}" if renamed else ""


def _check_rests(source: GltfDocument, doc: GltfDocument, mapping: dict[int, int]) -> None:
    """FormatError for a node whose translation the clips animate, resting away from the
    character's node of its name (another figure's proportions)."""
    moved = sorted({node for targets in source.channel_targets for node, path in targets if path == "translation"})
    moved = [node for node in moved if node in mapping]
    if not moved:
        return
    rests = {node: (source.rest_trs(node)[0], doc.rest_trs(mapping[node])[0]) for node in moved}
    size = max(float(np.linalg.norm(doc.rest_trs(node)[0])) for node in mapping.values())
    for node, (theirs, own) in rests.items():
        if np.linalg.norm(theirs - own) > REST_TOLERANCE * max(size, 1e-12):
            reason = (
                f"its translation is animated and it rests at {np.round(theirs, 4).tolist()}, the character's "
                f"{source.gltf.nodes[node].name!r} at {np.round(own, 4).tolist()}: another figure's proportions "
                "(retarget the clip to this character first)"
            )
            raise source.fail(source.node_label(node), reason)


def _copied_sampler(builder: GlbBuilder, source: GltfDocument, animation: int, sampler: int, width: int) -> dict:
    """Sampler ``sampler`` of the clip file's animation ``animation``, its keys added to ``builder``."""
    times, values, interpolation = source.sampler_keys(
        animation, sampler, width, f"animation {animation} sampler {sampler}"
    )
    return {
        "input": builder.add(times.astype(np.float32)[:, None], bounds=True),
        "output": builder.add(np.ascontiguousarray(values.reshape(-1, width), dtype=np.float32)),
        "interpolation": interpolation,
    }
