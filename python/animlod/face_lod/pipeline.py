"""The face LoD pipeline: a face in, its levels as one LoD GLB, a measured table and pictures out.

Inputs: nothing (the procedural head, animated by MPAs and lattices), a glTF with morph targets,
or a folder of OBJ/PLY poses (neutral + expressions). The output is one LoD GLB
(:mod:`animlod.face_lod.lod_glb`): for a glTF, the input document whole with the face's levels
attached by MSFT_lod; otherwise a new document whose face mesh has one morph target per
expression or MPA (the procedural face's MPAs become targets exactly: the FFD is linear in the
MPA intensities) and whose animation plays them. Beside it, a JSON manifest holds each level's
size, measured error (asset units), screen-coverage threshold and kept targets, and, for the
procedural face, its active regions, lattice sizes and the active tree's own thresholds.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..aqem import check_aqem_options
from ..io.atomic import staged_files
from .blendshape import (
    BlendshapeLevel,
    BlendshapeLodOptions,
    build_blendshape_lod,
    check_fractions,
    measure_blendshape_lod,
    target_regions,
)
from .chain import FaceLodOptions, build_face_lod
from .lod_glb import gltf_face_levels, read_gltf_face, write_gltf_face_lod, write_new_face_lod
from .measure import animation_errors, every_nth, measure_chain
from .mpa import expression_intensities, expression_sequence
from .procedural import procedural_face
from .selection import Camera, coverage_thresholds

# The head of the procedural face is about 0.24 m tall; a face of that size fills the viewport
# height at about 0.2 m with the default camera.
PIXEL_TOLERANCE = 1.0


@dataclass
class FaceRun:
    """What :func:`run_face_lod` did.

    Attributes
    ----------
    kind : "procedural" or "blendshape".
    columns, rows : the measured table (one row per level).
    files : every file written.
    notes : lines worth printing (what was read, what was pruned).
    """

    kind: str
    columns: list[str]
    rows: list[list[object]]
    files: list[Path] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def run_face_lod(
    source: str | os.PathLike | None,
    output: str | os.PathLike,
    *,
    ratios: Sequence[float] | None = None,
    face_counts: Sequence[int] | None = None,
    target_fractions: Sequence[float] | None = None,
    neutral: str | None = None,
    plot: bool = False,
    expression: str | None = None,
    repeats: int = 3,
    error_frames: int = 24,
    progress: Callable[[str], None] | None = None,
) -> FaceRun:
    """Build, measure and write the levels of a face.

    Parameters
    ----------
    source : None for the procedural face, a .glb/.gltf with morph targets, or a pose folder.
    output : folder for the files (created when they are written, together at the end: a run
        that fails writes none of them).
    ratios, face_counts : triangle fractions or counts of the levels after the full face.
    target_fractions : blendshape faces: fraction of targets kept per level (the full face included).
    neutral : pose folders: the file name of the neutral face.
    plot : also write a PNG with every level showing one expression.
    expression : the expression (procedural face) or target (blendshape face) to plot.
    repeats : timing runs per frame (the fastest is kept).
    error_frames : evenly spaced animation frames the surface error is measured on, besides
        each target's (or MPA's) peak-weight frame (:func:`animlod.face_lod.measure.measured_frames`).
    progress : a face read from a file: called with a line of text as the levels' building and
        their measurement start.
    """
    check_face_options(ratios=ratios, face_counts=face_counts, target_fractions=target_fractions, repeats=repeats,
                       error_frames=error_frames)  # fmt: skip
    output = Path(output)  # created only by the writing (io.atomic.staged_files), so a refused run leaves nothing
    if source is None:
        return _run_procedural(output, ratios, face_counts, plot, expression, repeats, error_frames)
    return _run_blendshape(Path(source), output, ratios, face_counts, target_fractions, neutral, plot, expression,
                           repeats, error_frames, progress or (lambda _line: None))  # fmt: skip


def check_face_options(
    *,
    ratios: Sequence[float] | None,
    face_counts: Sequence[int] | None,
    target_fractions: Sequence[float] | None,
    repeats: int,
    error_frames: int,
) -> None:
    """Refuse, naming the option, values of :func:`run_face_lod`'s options it cannot take whatever
    the face: both ``ratios`` and ``face_counts``, a ratio outside (0, 1] or a count of 0 (the
    core's check of AQEM's level targets), a fraction outside [0, 1], fewer than one repeat or
    error frame. A batch checks its manifest with it before anything runs."""
    if ratios is not None and face_counts is not None:
        raise ValueError("ratios and face_counts: give one of them, not both")
    if face_counts is not None:
        check_aqem_options(target_face_counts=list(face_counts))
    elif ratios is not None:
        check_aqem_options(list(ratios))
    check_fractions(target_fractions)
    for name, value in (("repeats", repeats), ("error_frames", error_frames)):
        if value < 1:
            raise ValueError(f"{name}: must be at least 1, got {value}")


def _run_procedural(output, ratios, face_counts, plot, expression, repeats, error_frames) -> FaceRun:
    from ..io.manifest import write_lod_manifest

    face = procedural_face()
    rig = face.rig
    chosen = None
    if plot:  # a mistake in the name stops the run before the work
        name = expression or "smile"
        chosen = next((e for e in face.expressions if e.name == name), None)
        if chosen is None:
            raise ValueError(f"--expression: no expression {name!r}; the face has "
                             f"{', '.join(e.name for e in face.expressions)}")  # fmt: skip
    animation = expression_sequence(face.expressions, rig.mpa_names)
    options = FaceLodOptions(face_counts=face_counts, **({"ratios": tuple(ratios)} if ratios else {}))
    chain = build_face_lod(rig, face.tree, animation, options)
    measured = measure_chain(chain, animation, repeats=repeats, samples=10000, error_frames=error_frames)
    timed = [row.max_frame_seconds for row in measured]
    radius = _radius(rig.positions)
    thresholds = coverage_thresholds([row.hausdorff_units for row in measured], radius, Camera(), PIXEL_TOLERANCE)
    run = FaceRun(
        "procedural",
        ["level", "triangles", "vertices", "animated regions", "lattices", "MPAs", "MAT (us)", "MAT / level 0",
         "Hausdorff (% of diagonal)", "coverage >="],
        [],
    )  # fmt: skip
    manifest, as_blendshapes = [], []
    glb = Path("face_lod.glb")
    for row, threshold in zip(measured, thresholds):
        g = row.geometry_level
        level = chain.geometry[g]
        animator = chain.animator(g)
        kept = animator.active_mpas
        as_blendshapes.append(BlendshapeLevel(level.faces, level.rest, animator.targets()[kept], kept,
                                              level.kept_vertices, None, level.aqem_error))  # fmt: skip
        run.rows.append([g, row.triangles, row.vertices, row.animated_regions, row.lattices, row.active_mpas,
                         1e6 * row.max_frame_seconds, row.max_frame_seconds / timed[0] if timed[0] else 0.0,
                         100 * row.hausdorff, threshold])  # fmt: skip
        manifest.append({
            "files": [glb.name], "triangles": row.triangles, "vertices": row.vertices, "error": row.hausdorff_units,
            "screen_coverage": threshold, "animation_floor": level.animation_floor,
            "active_regions": sorted(chain.tree.active(row.animation_level)),
            "lattices": {name: "2x2x2" if name in level.reduced else "3x3x3" for name in animator.regions},
        })  # fmt: skip
    # The active tree's levels with their own errors and thresholds: a runtime picks the animation
    # level from the coverage too, then lowers it to the geometry level's floor (Figure 6).
    errors = animation_errors(chain, every_nth(animation, error_frames))
    animation_thresholds = coverage_thresholds(errors, radius, Camera(), PIXEL_TOLERANCE)
    run.notes.append(
        "active tree levels (regions animated, largest vertex error in asset units): "
        + "; ".join(f"{k}: {len(chain.tree.active(k))}, {e:.3g}" for k, e in enumerate(errors))
    )
    written = [glb, Path("face_lod.json"), Path("face_lod_animation.json")]
    with staged_files(output) as staged:  # every file lands together, or none
        write_new_face_lod(staged / glb, as_blendshapes, rig.mpa_names, animation.intensities, animation.fps,
                           [row.hausdorff_units for row in measured], thresholds, "expressions")  # fmt: skip
        write_lod_manifest(staged / written[1], "face", manifest)
        write_lod_manifest(staged / written[2], "face_animation", [
            {"regions": sorted(chain.tree.active(k)), "error": error, "screen_coverage": threshold}
            for k, (error, threshold) in enumerate(zip(errors, animation_thresholds))
        ])  # fmt: skip
        if chosen is not None:
            weights = expression_intensities(chosen, rig.mpa_names)
            panels = [
                (chain.animator(g).frame(weights), chain.geometry[g].faces, chain.geometry[g].face_regions,
                 f"level {g}: {chain.geometry[g].triangle_count} triangles, {run.rows[g][3]} regions")
                for g in range(len(chain.geometry))
            ]  # fmt: skip
            written.append(Path("face_lod.png"))
            _plot(staged / written[-1], panels, f"procedural face, {chosen.name}")
    run.files += [output / name for name in written]
    return run


def _run_blendshape(source, output, ratios, face_counts, target_fractions, neutral, plot, expression, repeats,
                    error_frames, say) -> FaceRun:  # fmt: skip
    from ..io.detect import glb_name, input_kind, input_stem
    from ..io.manifest import write_lod_manifest
    from .sources import pose_files, read_pose_face

    kind = input_kind(source)
    gltf, read_notes = None, []
    if kind == "gltf":
        gltf = read_gltf_face(source)
        face = gltf.face
    elif kind == "sequence" and source.is_dir():
        face = read_pose_face(source, neutral)
        chosen = pose_files(source, neutral)[0].name
        read_notes.append(f"{source}: neutral face {chosen}, every other file an expression (--neutral names another)")
    else:
        raise ValueError(f"{source}: face LoD reads a .glb/.gltf with morph targets or a folder of OBJ/PLY poses")
    plot_weights = _plot_weights(face, expression) if plot else None
    options = BlendshapeLodOptions(face_counts=face_counts, target_fractions=target_fractions,
                                   **({"ratios": tuple(ratios)} if ratios else {}))  # fmt: skip
    say(f"{source}: building the levels")
    try:
        if gltf is not None:
            gltf_levels = gltf_face_levels(gltf, options)
            levels = gltf_levels.levels
        else:
            levels = build_blendshape_lod(face, options)
    except ValueError as error:
        raise ValueError(f"{source}: {error}") from None
    say(f"{source}: measuring {len(levels)} levels over {len(face.weights)} animation frames")
    measured = measure_blendshape_lod(face, levels, repeats=repeats, max_frames=error_frames, samples=10000)
    errors = [row.hausdorff_units for row in measured]
    thresholds = coverage_thresholds(errors, _radius(face.neutral), Camera(), PIXEL_TOLERANCE)
    stem = input_stem(source)
    run = FaceRun(
        "blendshape",
        ["level", "triangles", "vertices", "targets", "blend max (us)", "blend median (us)", "median / level 0",
         "Hausdorff (% of diagonal)", "coverage >="],
        [],
        notes=[f"{source}: {face.vertex_count} vertices, {len(face.faces)} triangles, {face.target_count} targets, "
               f"{len(face.weights)} animation frames", *read_notes, *_repeated_sizes_note(source, levels)],
    )  # fmt: skip
    glb = Path(glb_name(source, "_lod"))
    manifest = []
    base = measured[0].median_frame_seconds
    for level, row, threshold in zip(levels, measured, thresholds):
        names = [face.names[i] for i in level.kept_targets]
        run.rows.append([row.level, row.triangles, row.vertices, row.targets, 1e6 * row.max_frame_seconds,
                         1e6 * row.median_frame_seconds, row.median_frame_seconds / base if base else 0.0,
                         100 * row.hausdorff, threshold])  # fmt: skip
        manifest.append({"files": [glb.name], "triangles": row.triangles, "vertices": row.vertices,
                         "targets": names, "error": row.hausdorff_units, "screen_coverage": threshold})  # fmt: skip
    written = [glb, Path(f"{stem}_face_lod.json")]
    with staged_files(output) as staged:  # every file lands together, or none
        if gltf is not None:
            weights_note = write_gltf_face_lod(staged / glb, gltf, gltf_levels, errors, thresholds)
            run.notes += gltf_levels.notes + ([weights_note] if weights_note else [])
        else:
            write_new_face_lod(staged / glb, levels, face.names, face.weights, face.fps, errors, thresholds,
                               "expressions")  # fmt: skip
        write_lod_manifest(staged / written[1], "blendshape_face", manifest)
        if plot_weights is not None:
            # Coloured by the regions grown from the targets' motion (the importance AQEM used).
            regions = target_regions(face, options.grow) if options.grow and np.any(face.targets) else None
            panels = [
                (level.frame(plot_weights), level.faces,
                 None if regions is None else regions.subset(level.kept_vertices).face_regions(level.faces),
                 f"level {i}: {level.triangle_count} triangles, {len(level.kept_targets)} targets")
                for i, level in enumerate(levels)
            ]  # fmt: skip
            written.append(Path(f"{stem}_face_lod.png"))
            _plot(staged / written[-1], panels, f"{stem}")
    run.files += [output / name for name in written]
    return run


def _repeated_sizes_note(source: Path, levels: Sequence[BlendshapeLevel]) -> list[str]:
    """A note naming the levels no smaller than the one before (a tiny face's), or none."""
    counts = [level.triangle_count for level in levels]
    repeated = (np.flatnonzero(np.diff(counts) >= 0) + 1).tolist()
    if not repeated:
        return []
    return [f"{source}: level{'s' if len(repeated) > 1 else ''} {', '.join(map(str, repeated))}: no fewer triangles "
            f"than the level before ({' / '.join(map(str, counts))}): the face is too small for the sizes asked (a "
            "level keeps one triangle at least) or has no legal collapse left"]  # fmt: skip


def _plot_weights(face, expression: str | None) -> np.ndarray:
    """The target named ``expression`` at weight 1, or the animation frame that moves the face most."""
    if expression is not None:
        if expression not in face.names:
            raise ValueError(f"--expression: no target {expression!r}; the face has {', '.join(face.names)}")
        weights = np.zeros(face.target_count)
        weights[face.names.index(expression)] = 1.0
        return weights
    motion = np.abs(face.weights) @ np.linalg.norm(face.targets, axis=2).max(axis=1, initial=0.0)
    return face.weights[int(np.argmax(motion))]


def _plot(path: Path, panels, title: str) -> None:
    from .plots import Panel, plot_panels

    dense = max(len(faces) for _, faces, _, _ in panels) > 20000  # a wireframe would hide the surface
    plot_panels(path, [[Panel(positions, faces, text, colours) for positions, faces, colours, text in panels]],
                title=title, wireframe=not dense)  # fmt: skip


def _radius(positions: np.ndarray) -> float:
    """Radius of the bounding sphere around the bounding-box centre."""
    points = np.asarray(positions, dtype=np.float64)
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    return float(np.linalg.norm(points - centre, axis=1).max(initial=0.0)) or 1.0
