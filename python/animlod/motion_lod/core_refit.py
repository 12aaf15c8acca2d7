"""The re-fit in the C++ core: E (Eq. 5), its gradient and the constraint Jacobians, and the
per-frame SLSQP solve (nlopt's C library) on several threads (cpp/include/animlod/motion_refit.hpp).

This module only hands a level's problem to the core, one independent group of points
(objective.split_problem) at a time, and puts the groups back together. refit.py is the same
solve in Python with the PyPI nlopt, kept as the reference the tests compare against.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .. import _core
from ..options import MotionRefitOptions, resolve_options
from .grouped_solve import FrameFailure, RefitResult, combine_frames, combine_groups
from .objective import RefitProblem, split_problem


def core_problem(problem: RefitProblem) -> _core.MotionRefitProblem:
    """The core's copy of a level's problem (index arrays as int32, values as float64)."""
    w = problem.weights
    return _core.MotionRefitProblem(
        problem.point_count,
        problem.length_pairs,
        problem.key_lengths,
        problem.coincident_pairs,
        problem.handed_quads,
        problem.key_volumes,
        problem.angle_triples,
        problem.key_cosines,
        w.distance,
        w.string,
        w.angle,
        problem.length_scale,
        problem.flat_quads,
        problem.flat_volumes,
        problem.flat_areas,
    )


def core_energy(problem: RefitProblem, x: np.ndarray, original: np.ndarray) -> np.ndarray:
    """E (Eq. 5) per frame of positions ``x`` against ``original`` (both (T, P, 3)), in the core."""
    return _core.motion_refit_objective(core_problem(problem), x, original)[0]


def refit_core(
    problem: RefitProblem,
    original: np.ndarray,
    fallback: np.ndarray,
    options: MotionRefitOptions | None = None,
    progress: Callable[[float], None] | None = None,
    cold_starts: np.ndarray | None = None,
    **option_fields: object,
) -> RefitResult:
    """Re-fit every frame with SLSQP in the core, group of points by group.

    Parameters
    ----------
    problem : the level's problem (objective.build_problem).
    original : (T, P, 3) original positions x^o.
    fallback : (T, P, 3) positions kept where a frame's solves fail (feasible by construction).
    options, **option_fields : a :class:`~animlod.options.MotionRefitOptions` and/or its fields
        by name: stopping rules, hard constraints, preconditioning, ``threads`` (0: every
        hardware thread; the result does not depend on it) and ``chunk_frames`` (with
        ``warm_start``, consecutive frames per task, the warm starts running inside a chunk;
        without, each frame is a task).
    progress : called with the (fractional) number of frames finished after each group.
    cold_starts : (T, P, 3) where frames start and failed frames restart (feasible with hard
        constraints), or None: the original positions, or the fallback with hard constraints.

    Returns
    -------
    RefitResult over all frames; ``evaluations`` sums the groups' objective evaluations.
    """
    settings = resolve_options(MotionRefitOptions, options, option_fields)
    groups, _ = split_problem(problem)
    original = np.ascontiguousarray(original, dtype=np.float64)
    fallback = np.ascontiguousarray(fallback, dtype=np.float64)
    frame_count = original.shape[0]
    step = _slice_frames(frame_count, settings)
    solved = []
    for points, sub in groups:
        core = core_problem(sub)
        parts = []
        for first in range(0, frame_count, step):
            frames = np.arange(first, min(first + step, frame_count))
            cold = None if cold_starts is None else cold_starts[frames][:, points]
            out = _core.motion_refit_solve(
                core, original[frames][:, points], fallback[frames][:, points], settings, cold_starts=cold
            )
            failures = [
                FrameFailure(int(frame), reason, "fallback" if fell_back else "cold restart")
                for frame, reason, fell_back in out["failures"]
            ]
            parts.append((frames, RefitResult(out["positions"], out["values"], out["evaluations"], failures)))
            if progress:
                progress(len(frames) / len(groups))
        solved.append((points, combine_frames(frame_count, parts)))
    if not groups and progress:
        progress(frame_count)
    return combine_groups(original, solved)


# A long clip is solved a slice of frames at a time, so that progress moves as the frames are
# done: in one call per group, a level of a 1,200-frame clip of a wide rig sat at 0 for 10-19 s.
_PROGRESS_STEPS = 50
_SLICE_FRAMES = 64  # at least: fewer frames per call would leave a thread idle at each slice's end


def _slice_frames(frame_count: int, settings: MotionRefitOptions) -> int:
    """Frames per call of the core: a slice boundary is a chunk boundary with warm starts (they
    run inside a chunk), so the result is the same as in one call."""
    step = max(_SLICE_FRAMES, -(-frame_count // _PROGRESS_STEPS))
    if settings.warm_start:
        step = -(-step // settings.chunk_frames) * settings.chunk_frames
    return step
