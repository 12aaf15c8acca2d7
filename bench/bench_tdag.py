"""TDAG (Shamir and Pascucci 2001): Figure 6, build time and size, and the cost of each level.

Run: ``.venv/bin/python bench/bench_tdag.py [--quick]``. Tables:

1. Figure 6 on the dev sequences (../shared/data: crane, face-poses, the Flamingo, Parrot,
   Stork and MorphStressTest morph-target animations baked to frames) and a procedural bending
   cylinder: for each governing choice (first mesh, average mesh, an arbitrary frame at 2/3 of
   the sequence, AQEM over all frames, online with lambda = 1) and the per-frame optimal
   decimation (online, lambda = 0): decimations per frame and in total, and the average and
   median of the per-edge maximum quadric cost over time (Section 4's measure; costs divided by
   the squared bounding-box diagonal, times 1e6).
2. Build time (total and per frame) and .tdag size against the raw float32 frames, governed by
   the first mesh and online.
3. A long clip (crane's 12 frames, or the cylinder's without the dev data, repeated to 1,200):
   build and load seconds and each process's peak memory against the raw frames.
4. Per-frame cost of each temporal approximation level (Section 5) at a tolerance of 2% of the
   bounding-box diagonal against a fresh query from the roots (median over frames, best of three
   walks, so that other processes on the machine do not count), the largest vertex error of
   each, and the level-3 walk on one thread and double-buffered.
5. How tight the error bound is: at tolerances of 0.5% to 5% of the diagonal, the faces of a
   query's cut at the middle frame and its measured two-sided Hausdorff distance to the input
   frame (``animlod.metrics.hausdorff_distance``), against the coarsest cut the same TDAG has
   whose measured distance is within the tolerance (bisecting face counts with
   ``tolerance_for_faces``): what a query would give if its bound were the measured distance.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from functools import partial
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table

from animlod import AnimatedMesh, TemporalDag, synth
from animlod.metrics import hausdorff_distance

TOLERANCE = 0.02  # of the bounding-box diagonal
BOUND_TOLERANCES = (0.005, 0.01, 0.02, 0.05)  # of the bounding-box diagonal
LONG_CLIP_FRAMES = 1200

# Run in a process of its own, so that its peak memory is the step's: build (and save) or load.
_LONG_CLIP_STEP = """
import json, resource, sys, time
import numpy as np
from animlod import AnimatedMesh, TemporalDag
step, source, target, frames = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
start = time.perf_counter()
if step == "build":
    with np.load(source) as base:
        repeats = -(-frames // len(base["frames"]))
        mesh = AnimatedMesh(base["faces"], np.tile(base["frames"], (repeats, 1, 1))[:frames])
    start = time.perf_counter()
    TemporalDag.build(mesh).save(target)
else:
    TemporalDag.load(target)
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"seconds": time.perf_counter() - start, "peak": peak}))
"""


def sequences(quick: bool) -> list[tuple[str, AnimatedMesh]]:
    """(name, mesh): the dev sequences that exist, then the procedural cylinder."""
    from animlod.io.gltf import read_gltf
    from animlod.io.meshseq import read_sequence

    found = []
    if (DATA_DIR / "meshseq").is_dir():
        found.append(("crane", read_sequence(DATA_DIR / "meshseq" / "crane")))
        if not quick:
            found.append(("face-poses", read_sequence(DATA_DIR / "meshseq" / "face-poses")))
        gltf = [("Flamingo", DATA_DIR / "meshseq" / "Flamingo-morph-glTF" / "Flamingo.glb")]
        gltf += [(name, DATA_DIR / "morph" / f"{name}.glb") for name in ("Parrot", "Stork")]
        gltf += [("MorphStressTest", DATA_DIR / "morph" / "MorphStressTest.gltf")]
        for name, path in gltf:
            if path.exists():
                found.append((name, read_gltf(path).morph_animations[0]))
    rings, segments = (40, 36) if quick else (96, 90)
    found.append(("bending cylinder", synth.bending_cylinder(frames=24, rings=rings, segments=segments)))
    return found


def diagonal(mesh: AnimatedMesh) -> float:
    return float(np.linalg.norm(mesh.frames[0].max(axis=0) - mesh.frames[0].min(axis=0)))


def figure6_table(inputs: list[tuple[str, AnimatedMesh]]) -> None:
    rows = []
    for name, mesh in inputs:
        arbitrary = (2 * (mesh.frame_count - 1)) // 3
        choices = [
            ("first", "first", 1.0),
            ("average", "average", 1.0),
            (f"arbitrary (frame {arbitrary})", arbitrary, 1.0),
            ("AQEM", "aqem", 1.0),
            ("online, lambda 1", "online", 1.0),
            ("optimal (per frame)", "online", 0.0),
        ]
        scale = 1e6 / diagonal(mesh) ** 2
        results = []
        for label, governing, weight in choices:
            dag = TemporalDag.build(mesh, governing, history_weight=weight)
            average, median = dag.report.quality_measure()
            counts = dag.report.collapse_counts
            results.append((label, counts.mean(), int(counts.sum()), average * scale, median * scale))
        optimal = results[-1][3]
        for label, per_frame, total, average, median in results:
            ratio = average / optimal if optimal > 0 else float("nan")
            rows.append((name, mesh.frame_count, label, f"{per_frame:.0f}", total, average, median, f"{ratio:.2f}"))
    print_table(
        "Figure 6: governing the decimation (costs / diagonal^2 x 1e6)",
        ["sequence", "frames", "governing", "decimations per frame", "total", "average", "median", "average / optimal"],
        rows,
    )


def build_table(inputs: list[tuple[str, AnimatedMesh]]) -> None:
    rows = []
    for name, mesh in inputs:
        for governing in ("first", "online"):
            start = time.perf_counter()
            dag = TemporalDag.build(mesh, governing)
            seconds = time.perf_counter() - start
            size = len(dag.to_bytes())
            raw = mesh.frames.size * 4
            rows.append(
                (name, governing, mesh.frame_count, mesh.face_count, seconds, seconds / mesh.frame_count * 1e3,
                 size, raw, f"{size / raw:.2f}")
            )  # fmt: skip
    print_table(
        "Build time and file size (.tdag: TDAG and affine maps; raw: float32 frames)",
        ["sequence", "governing", "frames", "faces", "build s", "ms per frame", "tdag bytes", "raw bytes", "ratio"],
        rows,
    )


def long_clip_table(inputs: list[tuple[str, AnimatedMesh]]) -> None:
    name, mesh = next((item for item in inputs if item[0] == "crane"), inputs[-1])
    with tempfile.TemporaryDirectory() as folder:
        source, target = Path(folder) / "base.npz", Path(folder) / "long.tdag"
        np.savez(source, faces=mesh.faces, frames=mesh.frames)
        steps = {}
        for step in ("build", "load"):
            command = [sys.executable, "-c", _LONG_CLIP_STEP, step, str(source), str(target), str(LONG_CLIP_FRAMES)]
            steps[step] = json.loads(subprocess.run(command, check=True, capture_output=True, text=True).stdout)
        size = target.stat().st_size
    raw = LONG_CLIP_FRAMES * mesh.vertex_count * 3 * 4
    mb = 1 << 20
    print_table(
        f"A long clip: {name}'s {mesh.frame_count} frames repeated to {LONG_CLIP_FRAMES} (governed by frame 0; "
        "peak: the process's, Python and numpy included)",
        ["sequence", "raw MB", "build s", "build peak MB", ".tdag MB", "load s", "load peak MB"],
        [(name, raw / mb, steps["build"]["seconds"], steps["build"]["peak"] / mb, size / mb,
          steps["load"]["seconds"], steps["load"]["peak"] / mb)],
    )  # fmt: skip


def query_table(inputs: list[tuple[str, AnimatedMesh]]) -> None:
    rows = []
    for name, mesh in inputs:
        dag = TemporalDag.build(mesh)
        tolerance = TOLERANCE * diagonal(mesh)
        walks = [dag.play(tolerance) for _ in range(3)]
        best = {key: min((walk.levels[i] if i < 3 else walk.full_query).median_seconds for walk in walks)
                for i, key in enumerate(("1", "2", "3", "fresh"))}  # fmt: skip
        update = min(walk.median_update_seconds for walk in walks)
        fresh_cut = min(walk.median_fresh_cut_seconds for walk in walks)
        report = walks[0]
        errors = [stats.max_error / tolerance for stats in [*report.levels, report.full_query]]
        sequential = min(walk.sequential_seconds_per_frame for walk in walks)
        buffered = min(walk.double_buffered_seconds_per_frame for walk in walks)
        rows.append(
            (
                name,
                mesh.face_count,
                f"{report.levels[2].mean_faces:.0f}",
                best["1"] * 1e3,
                best["2"] * 1e3,
                best["3"] * 1e3,
                best["fresh"] * 1e3,
                f"{best['3'] / best['fresh']:.3f}",
                f"{update * 1e3:.3f} / {fresh_cut * 1e3:.3f} = {update / fresh_cut:.3f}",
                " / ".join(f"{e:.2f}" for e in errors),
                f"{report.mean_splits:.0f} / {report.mean_collapses:.0f}",
                f"{sequential * 1e3:.3f} / {buffered * 1e3:.3f}",
            )
        )
    print_table(
        f"Per-frame cost of the approximation levels at tolerance {TOLERANCE:g} x diagonal (governed by frame 0; "
        "ms, median over frames, best of 3 walks)",
        ["sequence", "faces", "cut faces", "level 1", "level 2", "level 3", "fresh query", "level 3 / fresh",
         "cut update / fresh cut (ms)", "max error / tolerance (1 / 2 / 3 / fresh)", "splits / collapses",
         "level-3 walk ms: 1 thread / 2"],
        rows,
    )  # fmt: skip


def _measured(original: AnimatedMesh, size: float, cut) -> float:
    """The two-sided Hausdorff distance from a one-frame input to a query's cut, over ``size``."""
    return hausdorff_distance(original, AnimatedMesh(cut.faces, cut.positions[None])) / size


def bound_table(inputs: list[tuple[str, AnimatedMesh]]) -> None:
    rows = []
    for name, mesh in inputs:
        dag, frame = TemporalDag.build(mesh), mesh.frame_count // 2
        size = diagonal(mesh)
        measured = partial(_measured, AnimatedMesh(mesh.faces, mesh.frames[frame : frame + 1]), size)
        for tolerance in BOUND_TOLERANCES:
            cut = dag.query(frame, tolerance * size)
            # The coarsest face budget whose cut measures within the tolerance (bisection: the
            # measured distance falls with the faces nearly, not strictly, monotonically).
            low, high = 1, len(cut.faces)
            while low < high:
                middle = (low + high) // 2
                if measured(dag.query(frame, dag.tolerance_for_faces(frame, middle))) <= tolerance:
                    high = middle
                else:
                    low = middle + 1
            coarsest = dag.query(frame, dag.tolerance_for_faces(frame, low))
            error = measured(cut)
            ratio = f"{tolerance / error:.1f}" if error > 1e-6 else "- (rounding)"  # the input's own faces
            rows.append((name, f"{tolerance:.1%}", len(cut.faces), f"{error:.3%}", ratio,
                         len(coarsest.faces), f"{measured(coarsest):.3%}",
                         f"{len(cut.faces) / len(coarsest.faces):.1f}"))  # fmt: skip
    print_table(
        "How tight the error bound is: a query's cut at the middle frame against the coarsest cut measuring within "
        "the tolerance (governed by frame 0; Hausdorff: two-sided, 20,000 samples, % of the diagonal)",
        ["sequence", "tolerance", "cut faces", "measured Hausdorff", "tolerance / measured",
         "coarsest cut within it: faces", "its Hausdorff", "faces / coarsest"],
        rows,
    )  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="smaller inputs, for a smoke test")
    args = parser.parse_args()
    inputs = sequences(args.quick)
    if not (DATA_DIR / "meshseq").is_dir():
        print(f"development data not found at {DATA_DIR}: procedural input only")
    figure6_table(inputs)
    build_table(inputs)
    long_clip_table(inputs)
    query_table(inputs)
    bound_table(inputs)


if __name__ == "__main__":
    main()
