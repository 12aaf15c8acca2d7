"""``animlod demo``: the main job on the embedded procedural character.

The procedural humanoid walks, runs and jumps; it is written as a GLB, and
:func:`animlod.pipelines.character.build_character` turns that file into one LoD GLB: AQEM
geometry levels over the poses of all three clips times motion levels of its skeleton. The
chain is read back as a :class:`~animlod.model.LodChain` and the summary shows which level a
runtime picks at a few distances.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from . import non_negative_int

MESH_RATIOS = (0.5, 0.25, 0.1)
# The damped Newton solver reaches SLSQP's optimum on this objective over ten times faster
# (bench/bench_motion.py compares them); SLSQP stays the library's and the CLI's default.
MOTION_SOLVER = "newton"
# Where the summary shows which levels a runtime would pick: a 1080p camera with a 60 degree
# vertical field of view (focal length 935 px) and a one-pixel error budget.
FOCAL_LENGTH_PX = 935.0
PIXEL_BUDGET = 1.0
SAMPLE_DISTANCES = (2.0, 10.0, 40.0)


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "demo",
        help="procedural character -> one LoD GLB of geometry x motion levels, with a summary",
        description="Build the default procedural humanoid and its walk, run and jump, write it as character.glb, "
        "and turn that into character_lod.glb: AQEM geometry levels (50%%, 25%%, 10%% of the faces) over the poses "
        "of every clip, times motion levels of the skeleton (frozen joints, re-fitted clips, moved skin weights), "
        "attached with MSFT_lod. summary.txt lists the levels and the level a runtime picks by distance.",
    )
    parser.add_argument("-o", "--output", default="out/demo", help="output folder (default: out/demo)")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the procedural assets (default: 0)")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from .. import synth
    from ..io import read_lod_chains, write_glb
    from ..io.atomic import staged_files
    from ..pipelines.character import build_character

    output = Path(args.output)
    lines: list[str] = []

    def report(line: str) -> None:
        lines.append(line)
        print(line, flush=True)

    start = time.perf_counter()
    # The three files replace an earlier run's together: an interrupted build left its
    # character.glb beside the earlier seed's character_lod.glb and summary.txt.
    with staged_files(output) as staged:
        character, motions = synth.humanoid_with_clips(args.seed)
        skeleton = character.skeleton
        write_glb(staged / "character.glb", character, motions)
        report(
            f"character.glb: {skeleton.joint_count} joints ({int(np.count_nonzero(skeleton.end_sites))} end sites), "
            f"{character.vertex_count} vertices, {character.face_count} triangles, clips "
            f"{', '.join(f'{m.name} ({m.frame_count} frames)' for m in motions)} ({time.perf_counter() - start:.2f} s)"
        )
        result = build_character(
            staged / "character.glb", staged / "character_lod.glb", MESH_RATIOS, solver=MOTION_SOLVER
        )
        report(
            f"character_lod.glb: motion levels ({MOTION_SOLVER} re-fit) {result.motion_seconds:.2f} s, "
            f"geometry levels (AQEM) {result.geometry_seconds:.2f} s"
        )
        for levels in result.chains.values():
            for level in levels:
                report(
                    f"  level {level.level}: {level.faces} triangles, {level.joints} joints, error "
                    f"{level.error:.4f} m (max Hausdorff distance over every clip), used while covering >= "
                    f"{level.coverage:.3f} of the screen"
                )
        (chain,) = read_lod_chains(staged / "character_lod.glb")
        for distance in SAMPLE_DISTANCES:
            chosen = chain.level_for(PIXEL_BUDGET, distance, FOCAL_LENGTH_PX)
            report(f"at {distance:g} m ({PIXEL_BUDGET:g} px budget, focal {FOCAL_LENGTH_PX:g} px): level {chosen}")
        (staged / "summary.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"wrote {output}/: character.glb, character_lod.glb and summary.txt")
    return 0
