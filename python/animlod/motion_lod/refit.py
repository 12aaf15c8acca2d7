"""Per-frame re-fit with nlopt's SLSQP (Section 5.2: "SQP is applied to solve this problem").

E (Eq. 5) does not couple frames, so every frame is one small problem in 3(P - 1) unknowns,
never one big one (SLSQP's cost grows with the cube of the size); within a frame it splits
further into independent groups of points (objective.split_problem), each solved on its own. The unknowns are the
points'
displacements from the original positions in units of the length scale L, so a frame starts
at z = 0 (the paper's "initial values: the original positions") and the next frame is
warm-started from the previous frame's correction z*(t-1), since neighbouring frames need
nearly the same correction. Frames are split into chunks (warm starts run inside a chunk);
chunks can run in worker processes (threads would not help: the callbacks are Python).

Every solve is checked: the result must be finite, not worse than its start, and, with hard
bone-length constraints, feasible within ``feasibility_tolerance`` (SLSQP can report success
with violated constraints). Hard constraints hold every length Es holds, bones and siblings,
and keep rigid groups of three children from flipping into their mirror image, so that
forward kinematics of the recovered skeleton reproduces the result. A frame that fails is solved again from z = 0,
and if that fails too
it takes the fallback positions (the original motion with frozen joints at their key rotations,
which satisfies every constraint); every such frame is reported in ``RefitResult.failures``.
With hard constraints, cold starts begin at the fallback rather than the original positions:
it is feasible, and on the key posture's side of every mirror image.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import nlopt
import numpy as np

from .grouped_solve import FrameFailure, RefitResult, solve_grouped
from .objective import RefitProblem, handedness_constraints, objective, rigidity_constraints


@dataclass(frozen=True)
class SlsqpOptions:
    """Stopping rules and checks of the SLSQP re-fit."""

    hard_constraints: bool = False
    ftol_rel: float = 1e-8
    max_evaluations: int = 400
    feasibility_tolerance: float = 1e-6  # max |b - b0| / L accepted with hard constraints
    warm_start: bool = True


def _positions(problem: RefitProblem, original: np.ndarray, z: np.ndarray) -> np.ndarray:
    x = original.copy()
    x[1:] += problem.length_scale * z.reshape(-1, 3)
    return x


def _solve_frame(
    problem: RefitProblem, original: np.ndarray, z0: np.ndarray, options: SlsqpOptions
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
            return z, value, evaluations, f"a held length is off by {violation:.3g} L"
        if problem.handed_quads.size:
            result = np.empty(problem.handed_quads.shape[0])
            handedness(result, z, np.empty(0))
            if result.max() > 0.0:
                return z, value, evaluations, "a rigid group turned into its mirror image"
    elif value > start_value:
        return z, value, evaluations, "objective rose above its start"
    return z, value, evaluations, ""


def _solve_chunk(
    problem: RefitProblem, first_frame: int, original: np.ndarray, fallback: np.ndarray, options: SlsqpOptions
) -> RefitResult:
    """Solve consecutive frames ``original (C, P, 3)``, warm-starting each from the previous."""
    frames = original.shape[0]
    positions = np.empty_like(original)
    values = np.empty(frames)
    evaluations = np.zeros(frames, dtype=np.int64)
    failures = []
    # Cold starts: the original positions (the paper), or with hard constraints the fallback,
    # which is feasible and on the right side of every mirror image.
    cold = (fallback - original)[:, 1:].reshape(frames, -1) / problem.length_scale
    if not options.hard_constraints:
        cold[:] = 0.0
    z = cold[0]
    for i in range(frames):  # sequential by nature: each frame starts from the previous optimum
        start = z if options.warm_start else cold[i]
        z, value, count, reason = _solve_frame(problem, original[i], start, options)
        evaluations[i] = count
        if reason:
            z, value, count, second = _solve_frame(problem, original[i], cold[i], options)
            evaluations[i] += count
            failures.append(FrameFailure(first_frame + i, reason, "fallback" if second else "cold restart"))
            if second:
                positions[i] = fallback[i]
                values[i] = float(objective(problem, fallback[i : i + 1], original[i : i + 1])[0][0])
                z = (fallback[i, 1:] - original[i, 1:]).ravel() / problem.length_scale
                continue
        positions[i] = _positions(problem, original[i], z)
        values[i] = value
    return RefitResult(positions, values, evaluations, failures)


def refit_slsqp(
    problem: RefitProblem,
    original: np.ndarray,
    fallback: np.ndarray,
    options: SlsqpOptions | None = None,
    chunk_frames: int = 64,
    workers: int = 1,
    progress: Callable[[float], None] | None = None,
) -> RefitResult:
    """Re-fit every frame with SLSQP, one solve per frame and independent group of points.

    Parameters
    ----------
    problem : the level's problem (objective.build_problem).
    original : (T, P, 3) original positions x^o.
    fallback : (T, P, 3) positions kept for a frame whose solves fail (feasible by construction).
    options : stopping rules, hard constraints, checks.
    chunk_frames : frames per warm-started chunk (and per task with ``workers > 1``).
    workers : processes; 1 solves in this process.
    progress : called with the (fractional) number of frames finished after each chunk.
    """
    options = options or SlsqpOptions()
    return solve_grouped(problem, _solve_chunk, (original, fallback), (options,), chunk_frames, workers, progress)
