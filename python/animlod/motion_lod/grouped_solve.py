"""Running a per-frame re-fit solver over independent groups of points and chunks of frames.

E (Eq. 5) couples neither frames nor the groups of points objective.split_problem finds, so
both solvers (refit.py, newton.py) cut the work the same way: one task per group and chunk of
consecutive frames, run in this process or in worker processes (threads would not help: the
solvers are Python), and put back together into one result for the whole problem.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from contextlib import nullcontext
from dataclasses import dataclass, field, replace

import numpy as np

from .objective import RefitProblem, split_problem


@dataclass(frozen=True)
class FrameFailure:
    """A frame whose first solve was not kept, and what was kept instead."""

    frame: int
    reason: str
    outcome: str  # "cold restart", "fallback" (SLSQP) or "kept best point" (Newton)


@dataclass
class RefitResult:
    """Positions ``(T, P, 3)`` after the re-fit, with per-frame statistics ``(T,)``."""

    positions: np.ndarray
    objective: np.ndarray
    evaluations: np.ndarray
    failures: list[FrameFailure] = field(default_factory=list)


# solve_chunk(sub_problem, first_frame, *frame_arrays (C, Pg, 3), *settings) -> RefitResult
ChunkSolver = Callable[..., RefitResult]


def solve_grouped(
    problem: RefitProblem,
    solve_chunk: ChunkSolver,
    frame_arrays: tuple[np.ndarray, ...],
    settings: tuple,
    chunk_frames: int,
    workers: int,
    progress: Callable[[float], None] | None,
) -> RefitResult:
    """Solve every independent group of points, chunk by chunk, and combine the results.

    Parameters
    ----------
    problem : the level's whole problem; split here with objective.split_problem.
    solve_chunk : a module-level function (worker processes pickle it by name), called as
        ``solve_chunk(sub_problem, first_frame, *chunks, *settings)``, where ``chunks`` are the
        ``frame_arrays`` cut to the chunk's frames and the group's points, ``(C, Pg, 3)``.
    frame_arrays : (T, P, 3) arrays, the original positions (Ed's targets) first.
    settings : further arguments passed to every call unchanged.
    chunk_frames : consecutive frames per task.
    workers : processes solving tasks side by side; 1 solves in this process.
    progress : called with the (fractional) number of frames finished after each task.
    """
    original = frame_arrays[0]
    groups, _ = split_problem(problem)
    tasks = [
        (solve_chunk, sub, first, *(a[first : first + chunk_frames, points] for a in frame_arrays), *settings)
        for points, sub in groups
        for first in range(0, original.shape[0], chunk_frames)
    ]
    results = []
    with ProcessPoolExecutor(max_workers=workers) if workers > 1 else nullcontext() as pool:
        for result in pool.map(_run, tasks) if pool else map(_run, tasks):
            results.append(result)
            if progress:
                progress(result.positions.shape[0] / len(groups))
    per_group = len(tasks) // max(len(groups), 1)
    return combine_groups(
        original,
        [(points, _concatenate(results[k * per_group : (k + 1) * per_group])) for k, (points, _) in enumerate(groups)],
    )


def _run(task: tuple) -> RefitResult:
    solve_chunk, *arguments = task
    return solve_chunk(*arguments)


def _concatenate(results: list[RefitResult]) -> RefitResult:
    """Consecutive chunks of frames as one result."""
    return RefitResult(
        np.concatenate([r.positions for r in results]),
        np.concatenate([r.objective for r in results]),
        np.concatenate([r.evaluations for r in results]),
        [f for r in results for f in r.failures],
    )


def combine_groups(original: np.ndarray, solved: list[tuple[np.ndarray, RefitResult]]) -> RefitResult:
    """The whole problem's result from its groups': points in no group keep their original
    positions, their exact optimum; E and evaluations add up; a frame is reported once, with its
    first group failure."""
    positions = original.copy()
    value = np.zeros(original.shape[0])
    evaluations = np.zeros(original.shape[0], dtype=np.int64)
    failures: dict[int, FrameFailure] = {}
    for points, result in solved:
        positions[:, points[1:]] = result.positions[:, 1:]
        value += result.objective
        evaluations += result.evaluations
        for failure in result.failures:
            failures.setdefault(failure.frame, failure)
    return RefitResult(positions, value, evaluations, [failures[f] for f in sorted(failures)])


def combine_frames(frame_count: int, parts: list[tuple[np.ndarray, RefitResult]]) -> RefitResult:
    """The result over ``frame_count`` frames from results over disjoint sets of them
    (``(frames, result)``, each result's frames in the order of its indices), which cover all."""
    first = parts[0][1]
    positions = np.empty((frame_count,) + first.positions.shape[1:])
    value = np.empty(frame_count)
    evaluations = np.empty(frame_count, dtype=first.evaluations.dtype)
    failures = []
    for frames, result in parts:
        positions[frames] = result.positions
        value[frames] = result.objective
        evaluations[frames] = result.evaluations
        failures += [replace(f, frame=int(frames[f.frame])) for f in result.failures]
    return RefitResult(positions, value, evaluations, sorted(failures, key=lambda f: f.frame))
