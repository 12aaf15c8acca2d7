"""Per-frame re-fit with nlopt's SLSQP (Section 5.2: "SQP is applied to solve this problem"),
in Python with the PyPI nlopt: the reference of the core's solve (core_refit.py,
cpp/src/motion_refit_solve.cpp), which runs the same loop in C++ on several threads.

E (Eq. 5) does not couple frames, so every frame is one small problem in 3(P - 1) unknowns,
never one big one (SLSQP's cost grows with the cube of the size); within a frame it splits
further into independent groups of points (objective.split_problem), each solved on its own.
The unknowns are the points' displacements from the original positions in units of the length
scale L. Every frame starts cold: at the original positions (the paper's "initial values"), or
with hard constraints at the fallback (the original motion with frozen joints at their key
rotations: feasible, and on the key posture's side of every mirror image). With ``warm_start``
(off by default, as in the core) every next frame of a chunk starts from the previous result
where E is lower there: without hard constraints the previous correction x* - x^o added to this
frame's original; with them the previous result moved by the root's displacement, which is
feasible because lengths and volumes do not change under translation. A group whose
original positions or cold start have negligible E (no frozen joint touches it) is solved there. Frames are split into
chunks; chunks can run in worker processes (threads would not help: the callbacks are Python).

Every solve is checked: the result must be finite, not worse than its start, and, with hard
constraints, feasible within ``feasibility_tolerance`` (SLSQP can report success with violated
constraints) and on the right side of every mirror image. Hard constraints hold every length Es
holds, bones and siblings, and the height of every flat group's child over its base plane
(objective.RefitProblem.flat_quads), so that forward kinematics of the recovered skeleton
reproduces the result. A frame that fails is solved again from its cold start, and if that fails too it takes
the fallback positions; every such frame is reported in ``RefitResult.failures``.
"""

from __future__ import annotations

from collections.abc import Callable

import nlopt
import numpy as np

from ..options import MotionRefitOptions, resolve_options
from .grouped_solve import FrameFailure, RefitResult, solve_grouped
from .objective import RefitProblem, handedness_constraints, objective, rigidity_constraints

# E >= alpha |x - x^o|^2 / L^2 (Eq. 6): original positions or a cold start with E below this are
# the optimum to ~1e-12 L (a group no frozen joint touches), solved without a call to SLSQP.
_NEGLIGIBLE_OBJECTIVE = 1e-24
# SLSQP also stops when E changes by less than this (~1e-11 L in the positions): on a level that
# reproduces the clip almost exactly, E's own rounding is above ftol_rel. The core's
# kObjectiveResolution (cpp/src/motion_refit_solve.cpp), where the reason is measured.
_OBJECTIVE_RESOLUTION = 1e-22


def _positions(problem: RefitProblem, original: np.ndarray, z: np.ndarray) -> np.ndarray:
    x = original.copy()
    x[1:] += problem.length_scale * z.reshape(-1, 3)
    return x


def _energy(problem: RefitProblem, original: np.ndarray, z: np.ndarray) -> float:
    """E of one frame at the scaled displacements ``z``."""
    x = _positions(problem, original, z)
    return float(objective(problem, x[None], original[None])[0][0])


def _solve_frame(
    problem: RefitProblem, original: np.ndarray, z0: np.ndarray, options: MotionRefitOptions
) -> tuple[np.ndarray, float, int, str]:
    """One SLSQP solve; returns ``z``, E, evaluations and "" or the reason it is not acceptable."""
    n = problem.variable_count
    scale = problem.length_scale

    def energy(z: np.ndarray, grad: np.ndarray) -> float:
        value, gradient = objective(problem, _positions(problem, original, z)[None], original[None])
        if grad.size:
            grad[:] = scale * gradient[0, 1:].ravel()
        return float(value[0])

    def constraints(result: np.ndarray, z: np.ndarray, grad: np.ndarray) -> None:
        values, jacobian = rigidity_constraints(problem, _positions(problem, original, z)[None])
        result[:] = values[0]
        if grad.size:
            grad[:] = scale * jacobian[0, :, 1:].reshape(values.shape[1], n)

    def handedness(result: np.ndarray, z: np.ndarray, grad: np.ndarray) -> None:
        values, jacobian = handedness_constraints(problem, _positions(problem, original, z)[None])
        result[:] = values[0]
        if grad.size:
            grad[:] = scale * jacobian[0, :, 1:].reshape(values.shape[1], n)

    opt = nlopt.opt(nlopt.LD_SLSQP, n)
    opt.set_exceptions_enabled(False)  # keep the last point and read the code instead
    opt.set_min_objective(energy)
    if options.hard_constraints and problem.constraint_count:
        opt.add_equality_mconstraint(
            constraints, np.full(problem.constraint_count, 0.1 * options.feasibility_tolerance)
        )
        if problem.handed_quads.size:
            opt.add_inequality_mconstraint(handedness, np.zeros(problem.handed_quads.shape[0]))
    opt.set_ftol_rel(options.ftol_rel)
    opt.set_ftol_abs(_OBJECTIVE_RESOLUTION)
    opt.set_maxeval(options.max_evaluations)
    start_value = energy(z0, np.empty(0))
    z = np.asarray(opt.optimize(z0.copy()), dtype=np.float64)
    code = opt.last_optimize_result()
    evaluations = opt.get_numevals()
    value = energy(z, np.empty(0)) if np.all(np.isfinite(z)) else np.inf
    if not np.isfinite(value):
        return z, value, evaluations, "non-finite result"
    # NLopt documents ROUNDOFF_LIMITED as usually still returning a useful result: it is kept
    # when it passes the same checks as a success.
    if code < 0 and code != nlopt.ROUNDOFF_LIMITED:
        return z, value, evaluations, f"nlopt result {code}"
    if options.hard_constraints and problem.constraint_count:
        result = np.empty(problem.constraint_count)
        constraints(result, z, np.empty(0))
        violation = float(np.abs(result).max())
        if violation > options.feasibility_tolerance:
            return z, value, evaluations, f"a held length or flat group's height is off by {violation:.3g} L"
        if problem.handed_quads.size:
            result = np.empty(problem.handed_quads.shape[0])
            handedness(result, z, np.empty(0))
            if result.max() > 0.0:
                return z, value, evaluations, "a rigid group turned into its mirror image"
    # Every start is feasible (see _solve_chunk), so a result above it is never progress.
    if value > start_value:
        return z, value, evaluations, "objective rose above its start"
    return z, value, evaluations, ""


def _solve_chunk(
    problem: RefitProblem,
    first_frame: int,
    original: np.ndarray,
    fallback: np.ndarray,
    cold_starts: np.ndarray,
    options: MotionRefitOptions,
    explicit_cold_starts: bool,
) -> RefitResult:
    """Solve consecutive frames ``original (C, P, 3)``, each from its cold start or, with
    ``options.warm_start``, from the previous result where E is lower there."""
    frames = original.shape[0]
    positions = np.empty_like(original)
    values = np.empty(frames)
    evaluations = np.zeros(frames, dtype=np.int64)
    failures = []
    hard = options.hard_constraints and problem.constraint_count > 0
    # Cold starts: the caller's, or the original positions (the paper), or with hard constraints
    # the fallback (cold_starts then holds it), feasible and on the key side of every mirror image.
    cold_positions = cold_starts if explicit_cold_starts or hard else original
    cold = (cold_positions - original)[:, 1:].reshape(frames, -1) / problem.length_scale
    cold_values = objective(problem, cold_positions, original)[0]
    original_values = objective(problem, original, original)[0]
    for i in range(frames):  # sequential: with warm_start a frame starts from the previous optimum
        if min(cold_values[i], original_values[i]) <= _NEGLIGIBLE_OBJECTIVE:
            at_original = original_values[i] <= cold_values[i]
            positions[i] = original[i] if at_original else cold_positions[i]
            values[i] = min(cold_values[i], original_values[i])
            evaluations[i] = 1
            continue
        if i == 0 or not options.warm_start:
            start = cold[i]
        elif hard:  # the previous result moved with the root: feasible (lengths ignore translation)
            start = (positions[i - 1, 1:] + (original[i, 0] - original[i - 1, 0]) - original[i, 1:]).ravel()
            start /= problem.length_scale
        else:  # the previous correction x* - x^o on this frame's original
            start = (positions[i - 1, 1:] - original[i - 1, 1:]).ravel() / problem.length_scale
        # Of the warm and the cold start the lower E (both feasible with hard constraints).
        if _energy(problem, original[i], start) > cold_values[i]:
            start = cold[i]
        z, value, count, reason = _solve_frame(problem, original[i], start, options)
        evaluations[i] = count
        if reason:
            z, value, count, second = _solve_frame(problem, original[i], cold[i], options)
            evaluations[i] += count
            failures.append(FrameFailure(first_frame + i, reason, "fallback" if second else "cold restart"))
            if second:
                positions[i] = fallback[i]
                values[i] = float(objective(problem, fallback[i : i + 1], original[i : i + 1])[0][0])
                continue
        positions[i] = _positions(problem, original[i], z)
        values[i] = value
    return RefitResult(positions, values, evaluations, failures)


def refit_slsqp(
    problem: RefitProblem,
    original: np.ndarray,
    fallback: np.ndarray,
    options: MotionRefitOptions | None = None,
    workers: int = 1,
    progress: Callable[[float], None] | None = None,
    cold_starts: np.ndarray | None = None,
    **option_fields: object,
) -> RefitResult:
    """Re-fit every frame with SLSQP, one solve per frame and independent group of points.

    Parameters
    ----------
    problem : the level's problem (objective.build_problem).
    original : (T, P, 3) original positions x^o.
    fallback : (T, P, 3) positions kept for a frame whose solves fail (feasible by construction).
    options, **option_fields : a :class:`~animlod.options.MotionRefitOptions` and/or its fields
        by name: stopping rules, hard constraints, checks, ``warm_start``, ``chunk_frames``
        (frames per warm-started chunk, and per task with ``workers > 1``). ``precondition``,
        ``eliminate_points``, ``rigid_bodies``, ``bone_directions`` and ``threads`` belong to the
        core's solve and are ignored here.
    cold_starts : (T, P, 3) where frames start and failed frames restart (feasible with hard
        constraints), or None: the original positions, or the fallback with hard constraints.
    workers : processes; 1 solves in this process.
    progress : called with the (fractional) number of frames finished after each chunk.
    """
    options = resolve_options(MotionRefitOptions, options, option_fields)
    explicit = cold_starts is not None
    return solve_grouped(
        problem,
        _solve_chunk,
        (original, fallback, cold_starts if explicit else fallback),
        (options, explicit),
        options.chunk_frames,
        workers,
        progress,
    )
