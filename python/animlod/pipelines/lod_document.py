"""A whole glTF document in, one LoD GLB out (or one GLB per level with ``separate``).

Every (mesh, skin) pair a node draws is simplified once with AQEM over frames that cover all
its animations (skinning and morph weights), its primitives together so that material borders
do not crack and the triangle budget goes where the error is. Each level is measured after
re-skinning over every clip (max-over-frames Hausdorff distance, asset units), and the error
sets the level's MSFT_screencoverage. The chain ends at the last level coarser than the one before
(a max error or the topology can stop the collapses short of a target). Everything the simplifier
does not touch stays as it was.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ..aqem import Preparation
from ..io.detect import glb_name
from ..io.errors import FormatError
from ..io.glb_builder import GlbBuilder
from ..io.gltf_document import GltfDocument
from ..io.gltf_drawable import Drawable, mesh_label, points_and_lines_meshes, read_drawables
from ..io.gltf_lod import (
    ANIMLOD_EXTRA,
    LevelInfo,
    add_level_mesh,
    add_level_node,
    attach_chain,
    hidden_level_notes,
    node_extras,
    screen_coverages,
    unchained,
)
from ..io.stored_weights import normalise_stored_weights
from ..model import AnimatedMesh
from .clip_import import document_with_clips
from .drawable_levels import DrawableLevels, DrawableSettings, simplify_drawable, split_empty
from .level_chain import chain_notes, coarser_level_count

DEFAULT_RATIOS = (0.5, 0.25, 0.1)


@dataclass
class LevelReport:
    """One level of one drawable: faces, whether the target was reached, measured error."""

    level: int
    faces: int
    target_faces: int
    reached: bool
    error: float  # asset units: max over measured frames of the Hausdorff distance
    relative_error: float  # error / bounding-box diagonal of the rest pose
    coverage: float  # MSFT_screencoverage threshold where this level ends


@dataclass
class DrawableReport:
    """What happened to one (mesh, skin) pair."""

    label: str
    nodes: list[int]
    faces: int
    clips: int
    preparation: Preparation
    renormalised_weights: int
    levels: list[LevelReport] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    rest_meshes: list[AnimatedMesh] = field(default_factory=list)  # level 0, 1, ... at rest, world less the placement


@dataclass
class DocumentReport:
    """The result of :func:`simplify_document`."""

    source: Path
    outputs: list[Path]
    drawables: list[DrawableReport]
    seconds: float
    notes: list[str] = field(default_factory=list)  # about the document (clips added from other files)


def simplify_document(
    source: str | os.PathLike,
    output: str | os.PathLike,
    ratios: Sequence[float] = DEFAULT_RATIOS,
    *,
    separate: bool = False,
    clips: Sequence[str] = (),
    joint_map: str | os.PathLike | None = None,
    settings: DrawableSettings | None = None,
    progress: Callable[[str], None] | None = None,
    **keywords: object,
) -> DocumentReport:
    """Simplify every drawable of the glTF file ``source`` and write the LoD GLB ``output``.

    Parameters
    ----------
    source : a .glb, .gltf or .vrm file.
    output : the LoD GLB to write (atomically); with ``separate``, a folder that receives one
        ``<stem>_lod<i>.glb`` per level written instead, each the whole document at that level.
    ratios : face ratios of the levels below level 0, in (0, 1].
    clips : glTF files of clips on the same rig, added to the document's own by node name
        (:mod:`.clip_import`): they drive the skinned meshes' levels, and the output plays them.
    joint_map : a JSON table of the character's node each BVH clip's joint drives, where the
        skeletons' shape, body parts and names do not tell (:func:`.joint_matching.read_joint_map`).
    settings, **keywords : a :class:`~animlod.pipelines.DrawableSettings` and/or its fields by
        name (``fps``, ``frame_budget``, ``measured_frames``, ``pixel_error``, ``viewport_px``)
        and AQEM options (``use_motion_features``, ``max_error``, ``placement`` ..., see
        :class:`~animlod.AqemOptions`).
    progress : called with a line of text as each drawable, its collapses and its measurement start.

    Raises
    ------
    FormatError naming the file and element for input it cannot read; ValueError for bad options.
    """
    started = time.perf_counter()
    if not ratios or any(not 0.0 < ratio <= 1.0 for ratio in ratios):
        raise ValueError(f"ratios: each must be in (0, 1], got {list(ratios)}")
    settings = DrawableSettings.resolve(settings, keywords)
    notes: list[str] = []
    doc = document_with_clips(source, clips, notes.append, joint_map)
    drawables = read_drawables(doc, settings.fps)
    lines = [f"{mesh_label(doc, mesh)} (nodes {nodes})" for mesh, nodes in points_and_lines_meshes(doc).items()]
    if lines:
        notes.append(f"kept as they are, without levels (points or lines only): {', '.join(lines)}")
    chained = [drawable for drawable in drawables if not unchained(doc, drawable.nodes)]
    drawables = [drawable for drawable in drawables if unchained(doc, drawable.nodes)]
    if chained:
        notes.append("kept with the MSFT_lod chains they have: "
                     + ", ".join(f"{drawable.label} (nodes {drawable.nodes})" for drawable in chained))  # fmt: skip
    # Degenerate triangles are valid glTF: a placeholder collapsed to a point stays as it is.
    drawables, empty = split_empty(drawables, settings.measured_frames)
    if empty:
        notes.append(empty_drawables_note(empty))
    if not drawables:
        reason = "no node draws a triangle mesh, nothing to simplify"
        if empty:
            reason = "no mesh has a triangle with three distinct corners, nothing to simplify"
        elif chained:
            reason = "every node that draws a mesh has an MSFT_lod chain already, nothing to simplify"
        elif doc.gltf.animations:  # an animation library: its clips are motion LoD's input
            reason += " (its animations are `animlod motion`'s input)"
        raise FormatError(doc.path, "meshes", reason)
    simplified = []
    for drawable in drawables:
        if progress:
            progress(f"{drawable.label}: {drawable.geometry.faces.shape[0]} triangles, {len(drawable.clips)} clips")
        simplified.append(simplify_drawable(drawable, ratios, settings, progress=progress))
    reports = [drawable_report(d, s, ratios, settings) for d, s in zip(drawables, simplified)]
    if separate:
        outputs = _write_separate(doc, drawables, simplified, reports, Path(output), source)
        if not outputs:
            notes.append("no file written: no drawable has a level coarser than its input (see its notes)")
    else:
        outputs = [Path(output)]
        _write_chain(doc, drawables, simplified, reports).save(output)
    return DocumentReport(Path(source), outputs, reports, time.perf_counter() - started, notes)


def empty_drawables_note(empty: list[Drawable]) -> str:
    """The note on drawables left without levels because they draw nothing (:func:`split_empty`)."""
    labels = ", ".join(drawable.label for drawable in empty)
    return f"kept as they are, without levels (no triangle with three distinct corners): {labels}"


def drawable_report(
    drawable: Drawable, levels: DrawableLevels, ratios: Sequence[float], settings: DrawableSettings
) -> DrawableReport:
    """The drawable's report, whose ``levels`` (made for face ``ratios``) are those written
    (:func:`coarser_level_count`)."""
    simplified = [level.simplified for level in levels.levels]
    written = levels.levels[: coarser_level_count(simplified, ratios)]
    errors = [0.0] + [level.error for level in written]
    coverages = screen_coverages(errors, levels.size, settings.pixel_error, settings.viewport_px)
    report = DrawableReport(
        label=drawable.label,
        nodes=drawable.nodes,
        faces=int(drawable.geometry.faces.shape[0]),
        clips=len(drawable.clips),
        preparation=levels.preparation,
        renormalised_weights=drawable.weight_breaks.vertices,
        notes=list(levels.notes),
        rest_meshes=[AnimatedMesh(drawable.geometry.faces, drawable.rest_positions()[None])]
        + [AnimatedMesh(level.simplified.mesh.faces, level.rest_positions()[None]) for level in written],
    )
    max_error = float(settings.aqem.get("max_error", math.inf))
    for index, (level, coverage) in enumerate(zip(written, coverages[1:]), start=1):
        report.levels.append(
            LevelReport(
                level=index,
                faces=level.simplified.mesh.face_count,
                target_faces=level.simplified.target_face_count,
                reached=level.simplified.reached,
                error=level.error,
                relative_error=level.error / levels.size if levels.size > 0 else 0.0,
                coverage=coverage,
            )
        )
    report.notes.extend(chain_notes(simplified, len(written), max_error))
    report.levels.insert(0, LevelReport(0, report.faces, report.faces, True, 0.0, 0.0, coverages[0]))
    report.notes.extend(hidden_level_notes([level.relative_error for level in report.levels], coverages))
    return report


def _write_chain(
    doc: GltfDocument, drawables: list[Drawable], simplified: list[DrawableLevels], reports: list[DrawableReport]
) -> GlbBuilder:
    """The input document with every drawable's levels attached to its nodes by MSFT_lod."""
    builder = GlbBuilder.from_document(doc)
    for drawable, levels, report in zip(drawables, simplified, reports):
        add_drawable_chain(builder, doc, drawable, levels, report)
    return builder


def add_drawable_chain(
    builder: GlbBuilder, doc: GltfDocument, drawable: Drawable, levels: DrawableLevels, report: DrawableReport
) -> None:
    """The drawable's written levels (``report.levels``, :func:`drawable_report`) as an MSFT_lod
    chain on each of its nodes without one; its stored skin weights normalised (a note on it goes
    to ``report.notes``)."""
    note = normalise_stored_weights(builder, doc, drawable)
    if note:
        report.notes.append(note)
    written = levels.levels[: len(report.levels) - 1]
    if not written:
        return  # no level coarser than the input: its nodes stay as they are
    meshes = [
        add_level_mesh(builder, drawable.mesh_index, level.primitives, drawable.geometry.other_primitives, name)
        for level, name in zip(written, _level_names(doc, drawable, len(written)))
    ]
    coverages = [level.coverage for level in report.levels]
    joints = len(doc.gltf.skins[drawable.skin_index].joints) if drawable.skin_index is not None else 0
    infos = [LevelInfo(level.level, level.error, level.faces, level.level, 0, joints) for level in report.levels]
    for base in unchained(doc, drawable.nodes):
        nodes = [
            add_level_node(builder, base, mesh, drawable.skin_index, info) for mesh, info in zip(meshes, infos[1:])
        ]
        attach_chain(builder, base, nodes, coverages, infos[0])


def _write_separate(
    doc: GltfDocument,
    drawables: list[Drawable],
    simplified: list[DrawableLevels],
    reports: list[DrawableReport],
    folder: Path,
    source: str | os.PathLike,
) -> list[Path]:
    """One whole document per written level, every drawable's nodes drawing that level's mesh; a
    drawable whose chain ends sooner draws its coarsest level (its input when it has none)."""
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"{folder}: --separate writes a folder of levels, and this is a file")
    outputs = []
    files = max(len(report.levels) for report in reports) - 1
    for report in reports:
        last = len(report.levels) - 1
        if last < files:
            names = ", ".join(glb_name(source, f"_lod{index}") for index in range(last + 1, files + 1))
            drawn = f"level {last}" if last else "the input"
            report.notes.append(f"{names} {'draws' if last + 1 == files else 'draw'} {drawn}")
    for file_index in range(files):
        builder = GlbBuilder.from_document(doc)
        for drawable, levels, report in zip(drawables, simplified, reports):
            index = min(file_index, len(report.levels) - 2)
            if index < 0:
                continue  # no level written: the input's mesh
            name = _level_names(doc, drawable, index + 1)[index]
            mesh = add_level_mesh(
                builder, drawable.mesh_index, levels.levels[index].primitives, drawable.geometry.other_primitives, name
            )
            info = LevelInfo(index + 1, report.levels[index + 1].error, report.levels[index + 1].faces, index + 1)
            for base in unchained(doc, drawable.nodes):
                node = builder.json["nodes"][base]
                node["mesh"] = mesh
                node["extras"] = {**node_extras(node), ANIMLOD_EXTRA: info.extras()}
        builder.prune()
        path = folder / glb_name(source, f"_lod{file_index + 1}")
        builder.save(path)
        outputs.append(path)
    return outputs


def _level_names(doc: GltfDocument, drawable: Drawable, count: int) -> list[str]:
    name = doc.gltf.meshes[drawable.mesh_index].name or f"mesh{drawable.mesh_index}"
    return [f"{name}_LOD{level}" for level in range(1, count + 1)]
