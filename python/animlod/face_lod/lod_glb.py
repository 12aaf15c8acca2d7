"""Blendshape face levels as one LoD GLB (the format of ``animlod.io.gltf_lod``).

Two cases:

- a glTF input (:func:`gltf_face_levels`, :func:`write_gltf_face_lod`): the face is the first
  drawable of the document with morph targets. Its levels come from the whole-document
  pipeline (:func:`animlod.pipelines.drawable_levels.simplify_drawable`: every primitive,
  attribute, normal and morph target carried) with the region importance grown from the
  targets' motion, then the targets each level does not need are pruned
  (:func:`~animlod.face_lod.blendshape.prune_levels`). The input document is written whole,
  level 0 untouched, the levels attached to the face's nodes by MSFT_lod;
- a face without a document (a pose folder, the procedural head) (:func:`write_new_face_lod`):
  a new document with the face as a mesh with morph targets, its animation as a morph-weight
  clip, and the levels attached the same way.

A pruned target stays in its level's mesh with zero deltas, so that every level has as many
targets as the base mesh and the base node's morph-weight animation applies to any level
(glTF requires one weight per target); ``extras.animlod.targets`` on each level node lists the
targets it keeps, so a runtime can skip the others.

Shapes: ``V`` vertices, ``N`` targets, ``T`` animation frames.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..io.glb_builder import GlbBuilder
from ..io.gltf_document import GltfDocument
from ..io.gltf_drawable import Drawable, read_drawables
from ..io.gltf_lod import ANIMLOD_EXTRA, LevelInfo, PrimitiveArrays, add_level_mesh, add_level_node, attach_chain
from ..io.stored_weights import normalise_stored_weights
from ..normals import vertex_normals
from .blendshape import (
    BlendshapeFace,
    BlendshapeLevel,
    BlendshapeLodOptions,
    check_fractions,
    checked_face_counts,
    one_at_a_time,
    prune_levels,
    target_regions,
)


@dataclass
class GltfFace:
    """A glTF document and its face drawable, as a blendshape face.

    Attributes
    ----------
    doc : the parsed document.
    drawable : the drawable with morph targets and the most triangles (a head exported as face,
        eyes and teeth meshes: the face).
    face : its world-space neutral mesh, targets and the morph weights of every clip that drives
        them, played one after the other (each target in turn when no clip does).
    others : labels of the other drawables with morph targets, written unchanged.
    """

    doc: GltfDocument
    drawable: Drawable
    face: BlendshapeFace
    others: list[str]


def read_gltf_face(path: str | os.PathLike, fps: float | None = None, frames_each: int = 15) -> GltfFace:
    """The face of a .glb/.gltf file: its drawable with morph targets and the most triangles, its
    clips sampled at ``fps`` (None: at the rate of their keys, as :func:`animlod.io.read_gltf`).
    Raises FormatError naming the file when none has morph targets, and the reader's errors for
    malformed files."""
    doc = GltfDocument(path)
    fps = doc.sample_rate(fps)
    morphed = [drawable for drawable in read_drawables(doc, fps) if drawable.geometry.targets is not None]
    morphed = [drawable for drawable in morphed if len(drawable.geometry.targets)]
    if not morphed:
        raise doc.fail("meshes", "no mesh has morph targets, so there is no blendshape face to simplify")
    drawable = max(morphed, key=lambda item: len(item.geometry.faces))  # the first of the largest
    targets = drawable.morph_targets
    tracks = [clip.morph_weights for clip in drawable.clips if clip.morph_weights is not None]
    weights = np.concatenate(tracks) if tracks else one_at_a_time(len(targets), frames_each)
    names = drawable.geometry.target_names or [f"target_{index}" for index in range(len(targets))]
    try:
        face = BlendshapeFace(
            neutral=drawable.bind_positions(), faces=drawable.geometry.faces, targets=targets, names=names,
            weights=weights, fps=fps, uvs=drawable.geometry.uvs,
        )  # fmt: skip
    except ValueError as error:
        raise doc.fail(drawable.label, str(error)) from None
    return GltfFace(doc, drawable, face, [other.label for other in morphed if other is not drawable])


@dataclass
class GltfFaceLevels:
    """Levels of a glTF face: for measuring (``levels``, the input first) and for writing
    (``primitives``, one list per simplified level, pruned targets zeroed)."""

    levels: list[BlendshapeLevel]
    primitives: list[list[PrimitiveArrays]]
    notes: list[str]


def gltf_face_levels(source: GltfFace, options: BlendshapeLodOptions | None = None) -> GltfFaceLevels:
    """Simplify the face drawable with the whole-document pipeline and prune its targets per level."""
    from ..pipelines.drawable_levels import simplify_drawable

    options = options or BlendshapeLodOptions()
    face = source.face
    ratios = (
        [count / len(face.faces) for count in checked_face_counts(options.face_counts, len(face.faces))]
        if options.face_counts is not None
        else list(options.ratios)
    )
    check_fractions(options.target_fractions, len(ratios) + 1)
    importance = None
    if options.grow is not None and np.any(face.targets):
        importance = target_regions(face, options.grow).vertex_importance()
    # The levels are measured as blendshape levels (prune_levels and the caller), not here.
    drawn = simplify_drawable(source.drawable, ratios, importance=importance, measure=False)
    everything = np.arange(face.target_count)
    identity = np.arange(face.vertex_count, dtype=np.int32)
    levels = [BlendshapeLevel(face.faces, face.neutral, face.targets, everything, identity, face.uvs, 0.0, 0.0)]
    for level in drawn.levels:
        levels.append(
            BlendshapeLevel(
                faces=level.simplified.mesh.faces, neutral=level.bind, targets=np.asarray(level.morph_targets),
                kept_targets=everything, kept_vertices=level.simplified.kept_vertices, uvs=None,
                aqem_error=level.simplified.error,
            )
        )  # fmt: skip
    prune_levels(face, levels, options, _shading_only(source.drawable, face))
    primitives = []
    for level, drawn_level in zip(levels[1:], drawn.levels):
        pruned = np.setdiff1d(everything, level.kept_targets)
        for primitive in drawn_level.primitives:
            for index in pruned:
                primitive.targets[index] = {name: np.zeros_like(d) for name, d in primitive.targets[index].items()}
        primitives.append(drawn_level.primitives)
    notes = list(drawn.notes)
    if source.others:
        notes.append(
            f"the face is {source.drawable.label} ({len(face.faces)} triangles, the largest mesh with morph targets); "
            f"written unchanged: {', '.join(source.others)}"
        )
    return GltfFaceLevels(levels, primitives, notes)


def _shading_only(drawable: Drawable, face: BlendshapeFace) -> np.ndarray:
    """(N,) the targets that move no vertex but carry NORMAL or TANGENT deltas."""
    turns = np.zeros(face.target_count, bool)
    for primitive in drawable.geometry.primitives:
        for index, target in enumerate(primitive.targets):
            turns[index] |= any(np.any(target[name]) for name in ("NORMAL", "TANGENT") if name in target)
    return turns & ~np.any(face.targets, axis=(1, 2))


def write_gltf_face_lod(
    path: str | os.PathLike, source: GltfFace, levels: GltfFaceLevels, errors: Sequence[float],
    coverages: Sequence[float],
) -> str | None:  # fmt: skip
    """The input document whole with the face's levels attached to each node that draws it.
    Returns a note when level 0's skin weights were rewritten (:mod:`animlod.io.stored_weights`)."""
    builder = GlbBuilder.from_document(source.doc)
    drawable = source.drawable
    weights_note = normalise_stored_weights(builder, source.doc, drawable)
    name = source.doc.gltf.meshes[drawable.mesh_index].name or f"mesh{drawable.mesh_index}"
    meshes = [
        add_level_mesh(builder, drawable.mesh_index, primitives, drawable.geometry.other_primitives, f"{name}_LOD{i}")
        for i, primitives in enumerate(levels.primitives, start=1)
    ]
    for base in drawable.nodes:
        _attach(builder, base, meshes, drawable.skin_index, levels.levels, errors, coverages)
    builder.save(path)
    return weights_note


def write_new_face_lod(
    path: str | os.PathLike,
    levels: Sequence[BlendshapeLevel],
    names: Sequence[str],
    weights: np.ndarray,
    fps: float,
    errors: Sequence[float],
    coverages: Sequence[float],
    clip_name: str = "animation",
) -> None:
    """A new LoD GLB: level 0 as a mesh with one morph target per name and smooth normals, a
    node drawing it, the morph weights ``(T, N)`` as a LINEAR clip of that node; the other levels
    attached by MSFT_lod. Pruned targets are written as zero deltas."""
    builder = GlbBuilder()
    target_count = len(names)
    base_mesh = builder.append("meshes", {
        "name": "face", "weights": [0.0] * target_count, "extras": {"targetNames": list(names)},
        "primitives": [{"attributes": {}, "mode": 4}],
    })  # fmt: skip
    # Level 0 goes through add_level_mesh like the others, then becomes the base mesh itself.
    first = add_level_mesh(builder, base_mesh, [_primitive(levels[0], target_count)], [], "face")
    builder.json["meshes"][base_mesh] = builder.json["meshes"].pop(first)
    base = builder.append("nodes", {"name": "face", "mesh": base_mesh})
    builder.json["scenes"] = [{"nodes": [base]}]
    builder.json["scene"] = 0
    if target_count:
        times = builder.add((np.arange(len(weights)) / fps).astype(np.float32)[:, None], bounds=True)
        values = builder.add(np.asarray(weights, np.float32).reshape(-1, 1))
        builder.append("animations", {
            "name": clip_name,
            "samplers": [{"input": times, "output": values, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": base, "path": "weights"}}],
        })  # fmt: skip
    meshes = [
        add_level_mesh(builder, base_mesh, [_primitive(level, target_count)], [], f"face_LOD{i}")
        for i, level in enumerate(levels[1:], start=1)
    ]
    _attach(builder, base, meshes, None, levels, errors, coverages)
    builder.save(path)


def _attach(builder: GlbBuilder, base: int, meshes: list[int], skin: int | None, levels: Sequence[BlendshapeLevel],
            errors: Sequence[float], coverages: Sequence[float]) -> None:  # fmt: skip
    infos = [LevelInfo(i, float(errors[i]), level.triangle_count, i) for i, level in enumerate(levels)]
    nodes = [add_level_node(builder, base, mesh, skin, info) for mesh, info in zip(meshes, infos[1:])]
    attach_chain(builder, base, nodes, list(coverages), infos[0])
    for node, level in zip([base, *nodes], levels):
        builder.json["nodes"][node]["extras"][ANIMLOD_EXTRA]["targets"] = [int(t) for t in level.kept_targets]


def _primitive(level: BlendshapeLevel, target_count: int) -> PrimitiveArrays:
    """One primitive of a level: positions, smooth normals, UVs, every target (zeros when pruned)."""
    attributes = {"POSITION": level.neutral.astype(np.float32), "NORMAL": vertex_normals(level.neutral, level.faces)}
    if level.uvs is not None:
        attributes["TEXCOORD_0"] = level.uvs.astype(np.float32)
    deltas = np.zeros((target_count,) + level.neutral.shape, np.float32)
    deltas[level.kept_targets] = level.targets
    return PrimitiveArrays(0, attributes, level.faces, [{"POSITION": delta} for delta in deltas])
