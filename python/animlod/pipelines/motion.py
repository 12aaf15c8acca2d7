"""The motion LoD pipeline: a BVH or a skinned glTF clip in, one BVH (and GLB) per level out.

Joint elimination and re-fit (the motion LoD paper, Sections 4-6) through
:func:`animlod.build_motion_chain`; ``animlod motion`` and the batch runner's ``motion`` job
call :func:`build_motion_levels`.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from ..io.detect import input_kind, input_stem
from ..io.errors import FormatError
from ..model import Motion
from ..motion_lod.chain import SOLVERS, MotionLodChain
from .result import AssetResult, LevelRow, Progress


@dataclass
class MotionReport:
    """What :func:`build_motion_levels` did.

    chain : the analysis and the levels, finest first (level 0 keeps every joint).
    files : per level, the files written (relative to the output folder): a BVH, and a GLB for a
        skinned glTF input.
    manifest : the level chooser's manifest (``<stem>_motion_lod.json``).
    faces : triangles of the skinned mesh (None for a BVH).
    motion : the input clip.
    """

    chain: MotionLodChain
    files: list[list[Path]]
    manifest: Path
    faces: int | None
    motion: Motion


def build_motion_levels(
    source: str | os.PathLike,
    output: str | os.PathLike,
    levels: int = 8,
    *,
    joints: Sequence[int] | None = None,
    lock: Sequence[str] = (),
    solver: str = SOLVERS[0],
    hard: bool = False,
    weights: Sequence[float] = (0.2, 0.4, 0.4),
    max_frames: int = 600,
    clip: int = 0,
    workers: int = 1,
    on_level: Callable[[int, int, int], Callable[[float], None] | None] | None = None,
) -> MotionReport:
    """Motion levels of ``source`` (a .bvh, or a .glb/.gltf with a skinned mesh and animations)
    written into the folder ``output`` as ``<stem>_lod<i>.bvh`` (and ``.glb`` with the skin moved
    onto the kept joints), plus ``<stem>_motion_lod.json``, each file atomically.

    Parameters
    ----------
    levels : number of levels at the paper's fractions of the joints (100 .. 8 %).
    joints : joint counts of the levels instead of ``levels``.
    lock : names of joints never to freeze.
    solver, hard : the re-fit, ``"slsqp"`` (with bone lengths as equality constraints when
        ``hard``) or ``"newton"``.
    weights : (alpha, beta, gamma) of the distance, string and angle errors (Eq. 5).
    max_frames : frames the motion analysis looks at, at most.
    clip : which animation of a glTF input.
    workers : processes solving chunks of frames side by side.
    on_level : called with (level index, joint count, frame count) as each level starts; may
        return a callback taking the frames done.

    Raises FormatError for unreadable input or a glTF without a skinned, animated mesh;
    ValueError naming the option for bad options.
    """
    from ..motion_lod.analysis import analyze_motion
    from ..motion_lod.chain import build_motion_chain, level_joint_counts
    from ..motion_lod.objective import Weights
    from ..motion_lod.refit import SlsqpOptions

    if hard and solver != "slsqp":
        raise ValueError("hard: bone-length equality constraints need solver 'slsqp'")
    if workers < 1:
        raise ValueError(f"workers: must be at least 1, got {workers}")
    if len(weights) != 3:
        raise ValueError(f"weights: expected (alpha, beta, gamma), got {len(weights)} values")
    path = os.fspath(source)
    kind = input_kind(source)
    skin = None
    if kind == "bvh":
        from ..io.bvh import read_bvh

        motion = read_bvh(source)
    elif kind == "gltf":
        from ..io.gltf import read_skinned

        skin, motions = read_skinned(source)
        if not motions:
            raise FormatError(path, "animations", "the skinned mesh has no animation to simplify")
        if not 0 <= clip < len(motions):
            raise FormatError(path, "animations", f"has {len(motions)} animations, clip {clip} was asked for")
        motion = motions[clip]
    else:
        raise FormatError(path, "file", f"a {kind} input has no skeleton; motion LoD needs a .bvh or a skinned glTF")

    analysis = analyze_motion(motion, locked=lock, max_frames=max_frames)
    counts = level_joint_counts(motion, analysis, list(joints) if joints else levels)
    chain = build_motion_chain(
        motion,
        counts,
        weights=Weights(*weights),
        solver=solver,
        slsqp_options=SlsqpOptions(hard_constraints=hard),
        workers=workers,
        skin=skin,
        on_level=(lambda index, count: on_level(index, count, motion.frame_count)) if on_level else None,
        analysis=analysis,
    )

    from ..io.bvh import write_bvh
    from ..io.manifest import write_lod_manifest

    folder = Path(output)
    folder.mkdir(parents=True, exist_ok=True)
    stem = input_stem(source)
    files, rows = [], []
    for index, level in enumerate(chain.levels):
        names = [Path(f"{stem}_lod{index}.bvh")]
        write_bvh(folder / names[0], level.motion)
        if level.skin is not None:
            from ..io.gltf import write_glb

            names.append(Path(f"{stem}_lod{index}.glb"))
            write_glb(folder / names[1], level.skin, [level.motion])
        files.append(names)
        rows.append({"files": [name.as_posix() for name in names], "joints": level.report.joint_count,
                     "error": level.report.max_error})  # fmt: skip
    # The runtime's level chooser: each level's largest joint position error in asset units.
    manifest = Path(f"{stem}_motion_lod.json")
    write_lod_manifest(folder / manifest, "motion", rows)
    return MotionReport(chain, files, manifest, None if skin is None else int(skin.faces.shape[0]), motion)


def motion_asset(
    source: str | os.PathLike,
    output: str | os.PathLike,
    *,
    progress: Progress | None = None,
    **options: object,
) -> AssetResult:
    """The batch job of :func:`build_motion_levels`: its files in the folder ``output`` and one
    row per level (joints, max joint position error in asset units and over the figure size,
    the level's re-fit seconds). ``options`` are the keyword arguments of :func:`build_motion_levels`.
    """
    started = time.perf_counter()

    def on_level(index: int, count: int, frames: int) -> None:
        if progress is not None:
            progress(None, f"level {index}: {count} joints, {frames} frames")

    report = build_motion_levels(source, output, on_level=on_level, **options)  # type: ignore[arg-type]
    folder = Path(output)
    size = report.chain.figure_size
    rows = [
        LevelRow(index, "", report.faces, level.report.joint_count, level.report.max_error,
                 level.report.max_error / size if size > 0 else None, level.report.seconds)
        for index, level in enumerate(report.chain.levels)
    ]  # fmt: skip
    outputs = [folder / name for names in report.files for name in names] + [folder / report.manifest]
    failures = sum(len(level.report.failures) for level in report.chain.levels)
    notes = [f"{failures} frames needed a second solve"] if failures else []
    return AssetResult("motion", os.fspath(source), outputs, rows, time.perf_counter() - started, notes)
