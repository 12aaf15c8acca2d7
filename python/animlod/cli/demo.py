"""``animlod demo``: the main job on the embedded procedural character."""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from ..io.atomic import atomic_write


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "demo",
        help="build the procedural character, bake its motions and write a GLB and a summary",
        description="Build the default procedural humanoid, animate it (walk, run, jump), bake the walk with "
        "linear blend skinning in the C++ core, and write character.glb and summary.txt into the output folder.",
    )
    parser.add_argument("-o", "--output", default="out/demo", help="output folder (default: out/demo)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the procedural assets (default: 0)")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from .. import synth
    from ..io.gltf import write_glb

    output = Path(args.output)
    lines: list[str] = []

    start = time.perf_counter()
    character = synth.humanoid(seed=args.seed)
    motions = [synth.humanoid_motion(character.skeleton, kind, seed=args.seed) for kind in ("walk", "run", "jump")]
    skeleton = character.skeleton
    lines.append(
        f"character: {skeleton.joint_count} joints ({int(np.count_nonzero(skeleton.end_sites))} end sites), "
        f"{character.vertex_count} vertices, {character.face_count} triangles "
        f"({time.perf_counter() - start:.2f} s)"
    )

    start = time.perf_counter()
    baked = character.bake(motions[0])
    extent = baked.frames.max(axis=(0, 1)) - baked.frames.min(axis=(0, 1))
    lines.append(
        f"baked walk: {baked.frame_count} frames at {baked.fps:g} fps, extent "
        f"{' x '.join(f'{value:.2f}' for value in extent)} m "
        f"({time.perf_counter() - start:.3f} s)"
    )

    glb_path = output / "character.glb"
    write_glb(glb_path, character, motions)
    lines.append(f"wrote {glb_path} with animations {[m.name for m in motions]}")

    summary_path = output / "summary.txt"
    with atomic_write(summary_path, "w", encoding="utf-8") as handle:
        handle.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"wrote {summary_path}")
    return 0
