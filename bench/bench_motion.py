"""Motion LoD: preprocessing time (Table 1), bone length stability (Fig. 7), position error per
level, the 8-level time goal, and SLSQP against the damped-Newton solver.

Run: ``.venv/bin/python bench/bench_motion.py [--quick]``. Tables:

1. Table 1 of the paper: SLSQP re-fit of one level (about 70 % of the joints, like the paper's
   24 of 33) with the key posture from motion analysis (ASQP) against the first frame as key
   posture (SQP): mean objective evaluations per frame and seconds, measured on an evenly spaced
   frame sample and scaled to the whole clip, on the dev clips and the procedural ones.
2. All 8 levels of 131_01.bvh (31 joints, 994 frames, 120 fps), once with SLSQP (the default)
   and once with damped Newton: time per level and in total (goal: under 30 s on this 2-core
   machine), also with 2 worker processes; joint position error mean and max (asset units and
   relative to the figure size); Fig. 7's mean summed bone length error and the worst bone's
   length standard deviation relative to its key length (goal: under 0.5 %); FK residual and
   frames whose solve did not converge.
3. SLSQP (the paper's SQP) against damped Newton on the same objective, per level of 131_01,
   on a frame sample: mean E, worst and best per-frame difference of E relative to the mean,
   time per frame;
   and SLSQP with hard length constraints: E, time, Fig. 7's bone length variation.
4. SLSQP with 1 and 2 worker processes on the same frames (does the pool pay?).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table, stopwatch

from animlod.io.bvh import read_bvh
from animlod.motion_lod import analyze_motion
from animlod.motion_lod.chain import SOLVERS, build_motion_chain, level_joint_counts
from animlod.motion_lod.frozen import freeze, frozen_motion
from animlod.motion_lod.newton import refit_newton
from animlod.motion_lod.objective import build_problem
from animlod.motion_lod.refit import SlsqpOptions, refit_slsqp
from animlod.synth import humanoid, humanoid_motion

DATA = DATA_DIR / "bvh"


def clips(quick: bool) -> list[tuple[str, object]]:
    skeleton = humanoid().skeleton
    result = [(f"procedural {kind}", humanoid_motion(skeleton, kind)) for kind in ("walk", "run", "jump")]
    for name in ("131_01.bvh", "dataset-1_run_proud_001.bvh"):
        if (DATA / name).exists():
            result.append((name, read_bvh(DATA / name)))
    return result[:2] if quick else result


def sample(frame_count: int, count: int) -> np.ndarray:
    return np.unique(np.linspace(0, frame_count - 1, min(count, frame_count)).round().astype(int))


def table1(quick: bool) -> None:
    rows = []
    for name, motion in clips(quick):
        analysis = analyze_motion(motion)
        joints = int((~motion.skeleton.end_sites).sum())
        count = max(joints - len(analysis.priority), round(0.7 * joints))
        frames = sample(motion.frame_count, 12 if quick else 40)
        original = motion.world_positions()
        first_frame = dataclasses.replace(analysis, key_frames=np.zeros_like(analysis.key_frames))
        for label, chosen in (("ASQP (key posture)", analysis), ("SQP (first frame)", first_frame)):
            level = freeze(motion, chosen, chosen.priority[: joints - count])
            problem = build_problem(level)
            fallback = frozen_motion(level, motion).world_positions()
            with stopwatch() as elapsed:
                result = refit_slsqp(problem, original[frames], fallback[frames])
            whole_clip = elapsed[0] * motion.frame_count / frames.size
            rows.append(
                (name, label, count, motion.frame_count, f"{result.evaluations.mean():.1f}", whole_clip,
                 whole_clip / 60.0, f"{result.objective.mean():.3g}", len(result.failures))
            )  # fmt: skip
    print_table(
        "Table 1: SLSQP preprocessing of one level, key posture from analysis (ASQP) vs first frame (SQP)",
        ("clip", "method", "joints", "frames", "evaluations/frame", "seconds", "minutes", "mean E", "failed"),
        rows,
    )


def level_table(motion, quick: bool, solver: str) -> None:
    levels = 4 if quick else 8
    with stopwatch() as pooled:
        build_motion_chain(motion, levels, solver=solver, workers=2)
    with stopwatch() as elapsed:
        chain = build_motion_chain(motion, levels, solver=solver)
    size = chain.figure_size
    rows = [
        (k, level.report.joint_count, level.report.seconds, level.report.mean_error, level.report.max_error,
         f"{100 * level.report.max_error / size:.2f}%", level.report.bone_error,
         f"{100 * level.report.bone_variation:.3f}%", level.report.fk_residual, len(level.report.failures))
        for k, level in enumerate(chain.levels)
    ]  # fmt: skip
    print_table(
        f"{levels} levels of {motion.name or '131_01'} ({motion.frame_count} frames), solver {solver}: total "
        f"{elapsed[0]:.1f} s including analysis ({pooled[0]:.1f} s with 2 worker processes); figure size {size:.4g}",
        ("level", "joints", "seconds", "mean error", "max error", "max/size", "Fig.7 bone error", "bone std/len",
         "FK residual", "not converged"),
        rows,
    )  # fmt: skip


def solver_table(motion, quick: bool) -> None:
    analysis = analyze_motion(motion)
    frames = sample(motion.frame_count, 10 if quick else 30)
    original = motion.world_positions()[frames]
    rows = []
    for count in level_joint_counts(motion, analysis, 8)[1:]:
        level = freeze(motion, analysis, analysis.priority[: int((~motion.skeleton.end_sites).sum()) - count])
        problem = build_problem(level)
        fallback = frozen_motion(level, motion).world_positions()[frames]
        with stopwatch() as slsqp_time:
            slsqp = refit_slsqp(problem, original, fallback)
        with stopwatch() as newton_time:
            newton = refit_newton(problem, original)
        with stopwatch() as hard_time:
            hard = refit_slsqp(problem, original, fallback, SlsqpOptions(hard_constraints=True))
        bones = problem.length_pairs[problem.bone_pair]
        lengths = np.linalg.norm(hard.positions[:, bones[:, 0]] - hard.positions[:, bones[:, 1]], axis=-1)
        hard_variation = (lengths.std(axis=0) / problem.key_lengths[problem.bone_pair]).max() if bones.size else 0.0
        # Relative to the level's mean E: some frames have E ~ 1e-32, where ratios mean nothing.
        difference = (newton.objective - slsqp.objective) / slsqp.objective.mean()
        rows.append(
            (count, f"{slsqp.objective.mean():.4g}", f"{newton.objective.mean():.4g}", f"{difference.max():+.2e}",
             f"{difference.min():+.2e}", 1e3 * slsqp_time[0] / frames.size, 1e3 * newton_time[0] / frames.size,
             f"{slsqp.evaluations.mean():.0f}", f"{newton.evaluations.mean():.0f}", f"{hard.objective.mean():.4g}",
             1e3 * hard_time[0] / frames.size, f"{100 * hard_variation:.2e}%", len(hard.failures))
        )  # fmt: skip
    print_table(
        f"SLSQP vs damped Newton (same objective, same start: the original positions), {frames.size} frames",
        ("joints", "E SLSQP", "E Newton", "worst (N-S)/mean S", "best (N-S)/mean S", "ms/frame SLSQP",
         "ms/frame Newton", "evals SLSQP", "evals Newton", "E SLSQP hard", "ms/frame hard", "bone std/len hard",
         "hard failed"),
        rows,
    )  # fmt: skip


def workers_table(motion, quick: bool) -> None:
    """Does a process pool pay for SLSQP? Same level and frames with 1 and 2 workers."""
    analysis = analyze_motion(motion)
    count = level_joint_counts(motion, analysis, 8)[2]
    level = freeze(motion, analysis, analysis.priority[: int((~motion.skeleton.end_sites).sum()) - count])
    problem = build_problem(level)
    frames = sample(motion.frame_count, 32 if quick else 128)
    original = motion.world_positions()[frames]
    fallback = frozen_motion(level, motion).world_positions()[frames]
    rows = []
    for workers in (1, 2):
        with stopwatch() as elapsed:
            refit_slsqp(problem, original, fallback, chunk_frames=16, workers=workers)
        rows.append((count, frames.size, workers, elapsed[0], 1e3 * elapsed[0] / frames.size))
    print_table(
        "SLSQP over worker processes (chunks of 16 frames, warm starts inside a chunk)",
        ("joints", "frames", "workers", "seconds", "ms/frame"),
        rows,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer clips, frames and levels")
    args = parser.parse_args()
    table1(args.quick)
    path = DATA / "131_01.bvh"
    motion = read_bvh(path) if path.exists() else humanoid_motion(humanoid().skeleton, "walk", cycles=8)
    for solver in SOLVERS:
        level_table(motion, args.quick, solver)
    solver_table(motion, args.quick)
    workers_table(motion, args.quick)


if __name__ == "__main__":
    main()
