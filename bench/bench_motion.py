"""Motion LoD: levels on every dev clip, the core's SLSQP against the Python reference, the
speed goals, and the joint-choice comparison.

Run: ``.venv/bin/python bench/bench_motion.py [--quick]`` (part of ``make bench``). Tables:

1. Per clip (the BVH files of ../shared/data/bvh, the longest clip of every skinned glTF of
   ../shared/data/gltf, the procedural walk), 8 levels (or as many as the skeleton allows) with
   the default: SLSQP in the C++ core with hard bone lengths. Per level: joints, joint position
   error mean and max against the original (asset units and relative to the figure size),
   Fig. 7's bone-length variation (the worst re-fitted bone's standard deviation over frames
   relative to its key length), FK residual, SLSQP evaluations per frame, frames whose first
   solve failed and frames that fell back to the frozen key motion, seconds.
2. Speed: 8 levels of 131_01.bvh, of the procedural humanoid with fingers (594 frames), of
   Xbot.glb's clips end to end (captured fingers, 67 joints, 268 frames) and of two figures with
   long chains (:func:`hanging_chains`: 10 of 7 joints on the head, one of 40), with the default
   ranking, its greedy form (one choice carried from level to level) and Eq. 3 alone (whose
   chain has no trial re-fits), best of 3 interleaved
   rounds: wall and CPU seconds (goal: 131_01 under 10 s), the cost per joint-frame and its
   ratio to 131_01's with the same ranking (goal: 1).
3. Both solvers on the same frames: the Python reference (PyPI nlopt, Python callbacks) and the
   core (nlopt's C library), plain (the reference's variables) and preconditioned (the default),
   on one thread, per level of 131_01 and the Bandai run: ms per frame, evaluations, and how many
   frames reach the reference's E within 1e-6 relative.
4. The re-fit's reductions, rigid bodies and bone directions (MotionRefitOptions.rigid_bodies,
   .bone_directions), each on and off, per clip and long-chain figure, Eq. 3 ranking (no trial
   re-fits), one thread: CPU seconds of the 8 levels (best of 3 rounds taking turns), the
   largest relative differences of a level's mean E, and at how many levels mean and max error
   agree to 5 digits.
5. Joint choice: mean (and max) joint position error over every original joint and frame after
   the same re-fit, per level, for every ranking: the default (trial re-fits, two choices carried
   from level to level), Eq. 3 with zero-length bones looked through, the paper's Eq. 3 as
   printed, leaf-first by depth, least rotation variance, cumulative, spread, and the default with
   one choice carried (each level's lowest trial error); on every clip of table 1 and on figures with long
   chains (the speed table's two, and :func:`animlod.synth.tail_clips`: a tail of 40 joints with
   a clip that moves all of it and one that moves its first half).

Wall times depend on what else runs on the machine; the load average is printed first and CPU
seconds (all threads of this process) are given beside wall seconds.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from functools import partial
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table, wall_and_cpu

from animlod import rotations
from animlod.io.bvh import read_bvh
from animlod.model import Motion, Skeleton
from animlod.motion_lod import RANKINGS, analyze_motion, build_motion_chain, joint_floor, level_joint_counts
from animlod.motion_lod.chain import _cold_starts
from animlod.motion_lod.clips import merge_split_clips
from animlod.motion_lod.core_refit import refit_core
from animlod.motion_lod.frozen import freeze, frozen_motion
from animlod.motion_lod.objective import build_problem
from animlod.motion_lod.refit import refit_slsqp
from animlod.motion_lod.refit_choice import NEGLIGIBLE_ERROR, SEARCH_PATHS
from animlod.options import MotionRefitOptions
from animlod.synth import humanoid, humanoid_motion, tail_clips

# The default ranking's greedy form in the tables: one choice carried from level to level.
GREEDY = "refit, 1 path"

# The core's SLSQP in the Python reference's variables (no preconditioner, every point a variable).
PLAIN = MotionRefitOptions(precondition=False, eliminate_points=False)


def subsample(motion: Motion, stride: int) -> Motion:
    """Every ``stride``-th frame."""
    if stride <= 1:
        return motion
    return dataclasses.replace(motion.take_frames(slice(None, None, stride)), fps=motion.fps / stride)


def clips(quick: bool) -> list[tuple[str, Motion]]:
    """(label, motion) of every dev clip: BVH files, the longest clip of each skinned glTF, the walk."""
    result = []
    for path in sorted((DATA_DIR / "bvh").glob("*.bvh")):
        result.append((path.name, read_bvh(path)))
    from animlod.io.gltf import read_skinned

    for path in sorted((DATA_DIR / "gltf").glob("*.gl*")):
        try:
            _, motions = read_skinned(path)
        except ValueError:
            continue  # no skinned mesh
        merged = merge_split_clips(motions)
        if merged is not None:  # one motion stored as one animation per joint node (Monster.glb)
            result.append((f"{path.name} (its {len(motions)} animations as one)", merged))
            continue
        usable = [m for m in motions if m.frame_count >= 2 and np.abs(m.skeleton.offsets[1:]).max() > 0.0]
        if usable:
            longest = max(usable, key=lambda m: m.frame_count)
            result.append((f"{path.name} {longest.name or 'clip ' + str(motions.index(longest))}", longest))
    walk = humanoid_motion(humanoid().skeleton, "walk", cycles=2 if quick else 4)
    result.append(("procedural walk", walk))
    return result[:3] if quick else result


def clips_end_to_end(path: Path) -> Motion:
    """The clips of a skinned glTF on the first one's skeleton and frame rate, one after the other
    (Xbot: 7 clips, 268 frames)."""
    from animlod.io.gltf import read_skinned

    _, motions = read_skinned(path)
    first = motions[0]
    same = [m for m in motions if m.skeleton.names == first.skeleton.names and m.fps == first.fps]
    return Motion.concatenate(same, f"{path.stem} clips")


def chain_figures(frames: int) -> list[tuple[str, Motion]]:
    """Figures with long chains of joints, which the dev clips lack: hair and a tail on a body."""
    return [
        ("hair: 10 chains of 7 on the head", hanging_chains(10, 7, frames)),
        ("tail: one chain of 40", hanging_chains(1, 40, frames)),
    ]


def hanging_chains(strands: int, length: int, frames: int = 300) -> Motion:
    """A figure whose head carries ``strands`` chains of ``length`` joints (hair, or one long
    tail or rope), each with an end site, swinging out of phase above a body of 11 joints that
    sways and steps; 30 fps, centimetres. Long chains are what captures of animals, hair and
    cloth rigs bring and the dev clips lack: a frozen run of a chain is one cluster of free
    points for the re-fit's Newton method."""
    names, parents, offsets = [], [], []

    def add(name: str, parent: int, offset: tuple[float, float, float]) -> int:
        names.append(name)
        parents.append(parent)
        offsets.append(offset)
        return len(names) - 1

    hips = add("Hips", -1, (0.0, 90.0, 0.0))
    for side, x in (("Left", 1.0), ("Right", -1.0)):
        knee = add(f"{side}Leg", add(f"{side}UpLeg", hips, (10.0 * x, 0.0, 0.0)), (0.0, -40.0, 0.0))
        add(f"{side}Foot end", add(f"{side}Foot", knee, (0.0, -40.0, 0.0)), (0.0, -5.0, 10.0))
    head = add("Head", add("Neck", add("Chest", add("Spine", hips, (0.0, 10.0, 0.0)), (0.0, 20.0, 0.0)),
                           (0.0, 20.0, 0.0)), (0.0, 10.0, 0.0))  # fmt: skip
    swings = []  # (joint, strand, place along it)
    for strand in range(strands):
        angle = 2.0 * np.pi * strand / strands
        joint = head
        for place in range(length):
            offset = (5.0 * np.cos(angle), 8.0, 5.0 * np.sin(angle)) if place == 0 else (
                0.5 * np.cos(angle), -3.0, 0.5 * np.sin(angle))  # fmt: skip
            joint = add(f"strand{strand}_{place}", joint, offset)
            swings.append((joint, strand, place))
        add(f"strand{strand} end", joint, (0.0, -3.0, 0.0))
    end_sites = np.array([name.endswith(" end") for name in names])
    skeleton = Skeleton(names, np.array(parents), np.array(offsets, np.float64), end_sites=end_sites)
    t = np.arange(frames) / 30.0
    euler = np.zeros((frames, len(names), 3))  # radians about x, y, z
    euler[:, hips] = np.stack([np.zeros(frames), 0.17 * np.sin(t), 0.09 * np.sin(2.0 * t)], axis=1)
    for side, phase in (("Left", 0.0), ("Right", np.pi)):
        euler[:, names.index(f"{side}UpLeg"), 0] = 0.5 * np.sin(4.0 * t + phase)
        euler[:, names.index(f"{side}Leg"), 0] = 0.4 * (1.0 + np.sin(4.0 * t + phase + 1.0))
    for joint, strand, place in swings:
        euler[:, joint, 0] = 0.26 * np.sin(3.0 * t + 0.3 * strand + 0.5 * place)
        euler[:, joint, 2] = 0.17 * np.cos(2.0 * t + 0.2 * strand)
    roots = np.stack([20.0 * np.sin(t), 90.0 + 2.0 * np.sin(4.0 * t), 30.0 * t], axis=1)
    return Motion(skeleton, roots, rotations.from_euler(euler, "xyz"), 30.0, f"{strands} chains of {length}")


def joints_of(motion: Motion) -> int:
    return int(np.count_nonzero(~motion.skeleton.end_sites))


def float32_keys_error(motion: Motion, size: float) -> tuple[float, float]:
    """Mean and max distance, over ``size``, that storing the clip's keys and offsets as float32
    moves its joints: the resolution below which refit_choice.NEGLIGIBLE_ERROR ties trial errors."""

    def rounded(values: np.ndarray | None) -> np.ndarray | None:
        return None if values is None else values.astype(np.float32).astype(np.float64)

    stored = dataclasses.replace(
        motion,
        skeleton=dataclasses.replace(motion.skeleton, offsets=rounded(motion.skeleton.offsets)),
        root_positions=rounded(motion.root_positions),
        local_rotations=rounded(motion.local_rotations),
        joint_translations=rounded(motion.joint_translations),
    )
    moved = np.linalg.norm(stored.world_positions() - motion.world_positions(), axis=-1) / size
    return float(moved.mean()), float(moved.max())


def level_table(label: str, motion: Motion) -> tuple[float, float]:
    """Table 1 for one clip; returns wall and CPU seconds of the whole chain."""
    analysis = analyze_motion(motion)
    floor = joint_floor(motion, analysis)
    levels = min(8, floor.possible_levels)
    chain, wall, cpu = wall_and_cpu(lambda: build_motion_chain(motion, levels, analysis=analysis))
    size = chain.figure_size
    rows = []
    for k, level in enumerate(chain.levels):
        r = level.report
        fell_back = sum(f.outcome == "fallback" for f in r.failures)
        rows.append(
            (k, r.joint_count, f"{r.mean_error:.4g}", f"{r.max_error:.4g}", f"{100 * r.max_error / size:.2f}%",
             f"{100 * r.bone_variation:.2e}%", f"{r.fk_residual:.2g}", f"{r.evaluations:.1f}", len(r.failures),
             fell_back, f"{r.seconds:.2f}")
        )  # fmt: skip
    floor_note = "" if floor.fewest <= floor.paper_fewest else f"; floor {floor.fewest} ({floor.explain()})"
    rounding = float32_keys_error(motion, size)
    print_table(
        f"{label}: {joints_of(motion)} joints, {motion.frame_count} frames, figure size {size:.4g}{floor_note}; "
        f"{wall:.1f} s wall, {cpu:.1f} s CPU; float32 keys move the joints by {rounding[0]:.1e} of the size "
        f"(at most {rounding[1]:.1e})",
        ("level", "joints", "mean error", "max error", "max/size", "bone variation", "FK residual",
         "evaluations per frame", "failed", "fell back", "seconds"),
        rows,
    )  # fmt: skip
    return wall, cpu


def speed_table(quick: bool) -> None:
    """Issue 8, item 4: 8 levels of 131_01 under 10 s, and a clip with fingers at 131_01's CPU per
    joint-frame. Every row runs ROUNDS times, the rows taking turns (load bursts hit all alike),
    and keeps its lowest CPU time; the walk's rows are compared with 131_01's of the same ranking
    and threads."""
    cases = []
    path = DATA_DIR / "bvh" / "131_01.bvh"
    if path.exists():
        cases.append(("131_01.bvh", read_bvh(path)))
    # 18 cycles: 594 frames, the length of the 43-joint clip with fingers (592).
    cases.append(("procedural humanoid, walk", humanoid_motion(humanoid().skeleton, "walk", cycles=2 if quick else 18)))
    xbot = DATA_DIR / "gltf" / "Xbot.glb"
    if xbot.exists() and not quick:  # captured fingers: 67 joints, 30 of them in the hands
        cases.append(("Xbot.glb, its clips end to end", clips_end_to_end(xbot)))
    frames = 30 if quick else 150
    cases += chain_figures(frames)
    # (row name, ranking, refit_paths): the default, its greedy form (one choice carried from level
    # to level) and Eq. 3 alone.
    rankings = (("refit", "refit", SEARCH_PATHS), (GREEDY, "refit", 1), ("importance", "importance", SEARCH_PATHS))
    runs = [(label, motion, 0, ranking) for label, motion in cases for ranking in rankings]
    if cases[0][0] == "131_01.bvh":
        runs.insert(0, (cases[0][0], cases[0][1], 1, rankings[0]))
    rounds = 1 if quick else 3
    best: dict[int, tuple[float, float, float, int]] = {}
    for _ in range(rounds):
        for index, (_, motion, threads, (_, ranking, paths)) in enumerate(runs):
            build = partial(build_motion_chain, motion, 8, workers=threads, ranking=ranking, refit_paths=paths)
            chain, wall, cpu = wall_and_cpu(build)
            solved = sum(level.report.joint_count * motion.frame_count for level in chain.levels[1:])
            failed = sum(len(level.report.failures) for level in chain.levels)
            if index not in best or cpu < best[index][1]:
                best[index] = (wall, cpu, 1e6 * cpu / solved, failed)
    reference = {(threads, ranking): best[i][2] for i, (label, _, threads, ranking) in enumerate(runs)
                 if label == "131_01.bvh"}  # fmt: skip
    rows = []
    for index, (label, motion, threads, ranking) in enumerate(runs):
        wall, cpu, per_joint_frame, failed = best[index]
        peer = reference.get((threads, ranking)) if label != "131_01.bvh" else None
        rows.append(
            (label, ranking[0], joints_of(motion), motion.frame_count, threads or os.cpu_count(), f"{wall:.1f}",
             f"{cpu:.1f}", f"{per_joint_frame:.2f}", f"{per_joint_frame / peer:.2f}" if peer else "", failed)
        )  # fmt: skip
    print_table(
        f"8 levels with the core's SLSQP (hard bone lengths), analysis included, best of {rounds} rounds "
        "(goals: 131_01 under 10 s; a clip with fingers at 1.00x 131_01's CPU per joint-frame)",
        (
            "clip",
            "ranking",
            "joints",
            "frames",
            "threads",
            "wall s",
            "CPU s",
            "CPU us per joint-frame",
            "/ 131_01 (same ranking)",
            "failed frames",
        ),
        rows,
    )


def solver_table(label: str, motion: Motion, frame_count: int) -> None:
    analysis = analyze_motion(motion)
    total = joints_of(motion)
    middle = motion.frame_count // 2
    frames = np.arange(max(0, middle - frame_count // 2), min(motion.frame_count, middle + frame_count // 2))
    original_all = motion.world_positions()
    rows = []
    for count in level_joint_counts(motion, analysis, 8)[1:]:
        level = freeze(motion, analysis, analysis.priority[: total - count])
        problem = build_problem(level)
        fallback_all = frozen_motion(level, motion).world_positions()
        cold = _cold_starts(level, problem, motion, original_all, fallback_all)[frames]
        original, fallback = original_all[frames], fallback_all[frames]
        chunk = frames.size
        runs = {
            "python": (refit_slsqp, {"chunk_frames": chunk}),
            "plain": (refit_core, {"options": PLAIN, "threads": 1, "chunk_frames": chunk}),
            "core": (refit_core, {"threads": 1, "chunk_frames": chunk}),
        }
        results = {}
        for name, (solve, settings) in runs.items():
            start = time.process_time()
            result = solve(problem, original, fallback, cold_starts=cold, **settings)
            results[name] = (result, 1e3 * (time.process_time() - start) / frames.size)
        reference = results["python"][0].objective
        cells = [count]
        for name in ("python", "plain", "core"):
            result, ms = results[name]
            cells += [f"{ms:.2f}", f"{result.evaluations.mean():.1f}"]
            if name != "python":
                relative = (result.objective - reference) / np.maximum(reference, 1e-300)
                same = int(np.count_nonzero(np.abs(relative) <= 1e-6))
                cells += [f"{same}/{frames.size}", f"{relative.min():+.1e}", f"{relative.max():+.1e}"]
        cells.append(sum(len(r.failures) for r, _ in results.values()))
        rows.append(tuple(cells))
    print_table(
        f"{label}: Python reference vs the core, {frames.size} consecutive frames, one thread, hard bone lengths "
        "(CPU ms per frame; E relative to the reference)",
        ("joints", "Python ms", "Python evals", "core plain ms", "plain evals", "plain within 1e-6", "plain min",
         "plain max", "core ms", "core evals", "core within 1e-6", "core min", "core max", "failed"),
        rows,
    )  # fmt: skip


def reduction_table(all_clips: list[tuple[str, Motion]], option: str, title: str, rounds: int = 3) -> None:
    """One of the re-fit's reductions (a boolean field of MotionRefitOptions) off and on, taking
    turns ``rounds`` times: the best CPU seconds of each (single runs move by 10-20% here)."""
    rows = []
    for label, motion in all_clips:
        cpu_seconds = {False: np.inf, True: np.inf}
        reports = {}
        for _ in range(rounds):
            for enabled in (False, True):
                cpu = time.process_time()
                chain = build_motion_chain(
                    motion, 8, workers=1, ranking="importance", slsqp_options=MotionRefitOptions(**{option: enabled})
                )
                cpu_seconds[enabled] = min(cpu_seconds[enabled], time.process_time() - cpu)
                reports[enabled] = [level.report for level in chain.levels[1:]]
        off_cpu, on_cpu = cpu_seconds[False], cpu_seconds[True]
        off, on = reports[False], reports[True]
        change = [(b.energy - a.energy) / max(a.energy, 1e-300) for a, b in zip(off, on)]
        agree = sum(f"{a.mean_error:.5g} {a.max_error:.5g}" == f"{b.mean_error:.5g} {b.max_error:.5g}"
                    for a, b in zip(off, on))  # fmt: skip
        rows.append((label, f"{off_cpu:.2f}", f"{on_cpu:.2f}", f"{on_cpu / off_cpu:.2f}", f"{min(change):+.1e}",
                     f"{max(change):+.1e}", f"{agree}/{len(on)}"))  # fmt: skip
    print_table(
        f"{title} off and on ({option}; Eq. 3 ranking, one thread, best CPU of {rounds} rounds taking turns; "
        "E: a level's mean E with them relative to without)",
        ("clip", "CPU s off", "CPU s on", "on / off", "E change min", "E change max",
         "levels with equal errors (5 digits)"),
        rows,
    )  # fmt: skip


def ranking_table(label: str, motion: Motion) -> None:
    base = analyze_motion(motion)
    floor = joint_floor(motion, base)
    counts = level_joint_counts(motion, base, min(8, floor.possible_levels))
    chains = {ranking: build_motion_chain(motion, counts, ranking=ranking).levels[1:] for ranking in RANKINGS}
    # The default's search against its greedy form, each level's lowest trial error alone.
    chains[GREEDY] = build_motion_chain(motion, counts, refit_paths=1).levels[1:]
    # The rankings choose by the mean (refit's trials too); the level's max error is what the
    # runtime chooser switches on, so it is shown as well.
    for statistic in ("mean", "max"):
        rows = []
        for k, count in enumerate(counts[1:]):
            values = [getattr(chains[r][k].report, f"{statistic}_error") for r in chains]
            best = min(values)
            # Below the float32 keys' resolution (refit_choice.NEGLIGIBLE_ERROR) errors are ties.
            tolerance = max(1e-6 * best, NEGLIGIBLE_ERROR * chains["refit"][k].frozen.length_scale())
            winners = [r for r, v in zip(chains, values) if v <= best + tolerance]
            rows.append((count, *[f"{v:.4g}" for v in values], ", ".join(winners)))
        print_table(
            f"{label} ({motion.frame_count} frames): {statistic} joint position error per ranking, same re-fit",
            ("joints", *chains, "lowest"),
            rows,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer clips and frames")
    args = parser.parse_args()
    load = os.getloadavg()
    print(f"load average {load[0]:.1f} {load[1]:.1f} {load[2]:.1f} on {os.cpu_count()} cores")
    all_clips = clips(args.quick)
    for label, motion in all_clips:
        level_table(label, motion)
    speed_table(args.quick)
    by_label = dict(all_clips)
    for label in ("131_01.bvh", "dataset-1_run_proud_001.bvh"):
        if label in by_label:
            solver_table(label, by_label[label], 16 if args.quick else 48)
    figures = chain_figures(30 if args.quick else 150)
    for option, title in (("rigid_bodies", "Rigid bodies"), ("bone_directions", "Bone directions")):
        reduction_table(all_clips + figures, option, title)
    for label, motion in all_clips:
        # At most ~250 frames: the comparison needs the joints' motion, not every frame of it.
        ranking_table(label, subsample(motion, max(1, motion.frame_count // 250)))
    two_clips = ("tail of 40 joints: a wave, then a curl of its first half", tail_clips(40, 120, 24.0)[0])
    for label, motion in figures + [two_clips]:
        ranking_table(label, motion)


if __name__ == "__main__":
    main()
