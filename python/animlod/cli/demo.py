"""``animlod demo``: the main job on the embedded procedural character.

The procedural humanoid walks, runs and jumps; its mesh is simplified with AQEM over the
poses of all three clips, its walk gets a motion LoD chain, and every level is written with a
manifest of its error, so that a runtime can pick levels by distance.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write

MESH_RATIOS = (0.5, 0.25, 0.1)
MOTION_LEVELS = 4
# The damped Newton solver reaches SLSQP's optimum on this objective over ten times faster
# (bench/bench_motion.py compares them); SLSQP stays the library's and the CLI's default.
MOTION_SOLVER = "newton"
# Where the summary shows which levels a runtime would pick: a 1080p camera with a 60 degree
# vertical field of view (focal length 935 px) and a one-pixel error budget.
FOCAL_LENGTH_PX = 935.0
PIXEL_BUDGET = 1.0
SAMPLE_DISTANCES = (2.0, 10.0, 40.0)
# Mesh levels are measured on every third frame of every clip, to keep the demo quick.
MEASURED_FRAME_STRIDE = 3


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "demo",
        help="procedural character -> mesh and motion LoD chains, written as GLB/BVH with a summary",
        description="Build the default procedural humanoid and its walk, run and jump; bake them with linear blend "
        "skinning in the C++ core; simplify the mesh with AQEM over all their poses (50%%, 25%%, 10%% of the faces) "
        "and the walk with motion LoD (4 levels); write every level, a JSON manifest per chain and summary.txt "
        "into the output folder.",
    )
    parser.add_argument("-o", "--output", default="out/demo", help="output folder (default: out/demo)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the procedural assets (default: 0)")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from .. import synth
    from ..aqem import simplify_skinned
    from ..io.bvh import write_bvh
    from ..io.gltf import write_glb
    from ..io.manifest import write_lod_manifest
    from ..metrics import surface_error
    from ..model import AnimatedMesh, LodChain, LodLevel
    from ..motion_lod import build_motion_chain

    output = Path(args.output)
    lines: list[str] = []

    def report(line: str) -> None:
        lines.append(line)
        print(line, flush=True)

    start = time.perf_counter()
    character = synth.humanoid(seed=args.seed)
    motions = [synth.humanoid_motion(character.skeleton, kind, seed=args.seed) for kind in synth.KINDS]
    skeleton = character.skeleton
    report(
        f"character: {skeleton.joint_count} joints ({int(np.count_nonzero(skeleton.end_sites))} end sites), "
        f"{character.vertex_count} vertices, {character.face_count} triangles, clips "
        f"{', '.join(f'{m.name} ({m.frame_count} frames)' for m in motions)} ({time.perf_counter() - start:.2f} s)"
    )
    start = time.perf_counter()
    baked = [character.bake(motion) for motion in motions]
    seconds = time.perf_counter() - start
    report(f"baked {sum(b.frame_count for b in baked)} frames with LBS in the core ({seconds:.3f} s)")
    write_glb(output / "character.glb", character, motions)

    start = time.perf_counter()
    mesh_levels = simplify_skinned(character, motions, MESH_RATIOS)
    report(f"mesh LoD (AQEM over {1 + sum(b.frame_count for b in baked)} poses): {time.perf_counter() - start:.2f} s")

    # A level's error for the runtime is measured: the largest Hausdorff distance between the
    # original and the level re-skinned with its merged weights. AQEM's own error is an RMS
    # distance to the merged planes, which does not bound the largest deviation.
    def measured_frames(mesh: AnimatedMesh) -> AnimatedMesh:
        return AnimatedMesh(mesh.faces, mesh.frames[::MEASURED_FRAME_STRIDE], mesh.fps)

    mesh_rows = [{"file": "character.glb", "faces": character.face_count, "error": 0.0}]
    for index, level in enumerate(mesh_levels, start=1):
        name = f"character_mesh_lod{index}.glb"
        write_glb(output / name, level.mesh, motions)
        hausdorff = max(
            float(
                surface_error(
                    measured_frames(original), measured_frames(level.mesh.bake(motion)), samples=2000
                ).hausdorff.max()
            )
            for original, motion in zip(baked, motions)
        )
        mesh_rows.append({"file": name, "faces": level.mesh.face_count, "error": hausdorff, "aqem_error": level.error})
        report(
            f"  level {index}: {level.mesh.face_count} triangles, Hausdorff error max {hausdorff:.4f} m after "
            f"re-skinning, every {MEASURED_FRAME_STRIDE}rd frame of every clip "
            f"(AQEM RMS plane distance {level.error:.4f} m)"
        )
    write_lod_manifest(output / "character_mesh_lod.json", "skinned mesh", mesh_rows)

    start = time.perf_counter()
    walk = motions[0]
    chain = build_motion_chain(walk, MOTION_LEVELS, solver=MOTION_SOLVER, skin=character)
    seconds = time.perf_counter() - start
    report(f"motion LoD of the walk ({MOTION_LEVELS} levels, {MOTION_SOLVER} re-fit): {seconds:.2f} s")
    motion_rows = []
    for index, level in enumerate(chain.levels):
        stem = f"walk_lod{index}"
        write_bvh(output / f"{stem}.bvh", level.motion)
        write_glb(output / f"{stem}.glb", level.skin, [level.motion])
        kept = level.report.joint_count
        motion_rows.append({"files": [f"{stem}.bvh", f"{stem}.glb"], "joints": kept, "error": level.report.max_error})
        report(
            f"  level {index}: {kept} joints, joint error mean {level.report.mean_error:.4f} m, "
            f"max {level.report.max_error:.4f} m, bone length variation {100 * level.report.bone_variation:.2f}%"
        )
    write_lod_manifest(output / "walk_motion_lod.json", "motion", motion_rows)

    mesh_chain = LodChain([LodLevel(None, None, [], row["error"]) for row in mesh_rows])
    motion_chain = LodChain([LodLevel(None, None, [], row["error"]) for row in motion_rows])
    for distance in SAMPLE_DISTANCES:
        report(
            f"at {distance:g} m ({PIXEL_BUDGET:g} px budget, focal {FOCAL_LENGTH_PX:g} px): mesh level "
            f"{mesh_chain.level_for(PIXEL_BUDGET, distance, FOCAL_LENGTH_PX)}, motion level "
            f"{motion_chain.level_for(PIXEL_BUDGET, distance, FOCAL_LENGTH_PX)}"
        )

    with atomic_write(output / "summary.txt", "w", encoding="utf-8") as handle:
        handle.write("\n".join(lines) + "\n")
    print(f"wrote {output}/: character.glb, mesh and motion levels, their manifests and summary.txt")
    return 0
