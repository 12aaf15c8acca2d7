"""A faster solver of the same objective: damped Newton, vectorised over frames.

E (Eqs. 5-8) has cheap exact second derivatives (objective.half_hessian), so each step solves
``(H + mu I) delta = -grad / 2`` for all active frames at once with batched dense solves
(3 unknowns per point of each independent group, objective.split_problem). mu follows Nielsen's rule for
Levenberg-Marquardt: shrink it by
the ratio of actual to promised decrease when a step succeeds, double its growth factor when
one fails. It has no hard constraints (use SLSQP for those). Frames converge independently and
leave the active set. SLSQP (refit.py) stays the reference; bench/bench_motion.py compares their
optima.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .grouped_solve import FrameFailure, RefitResult, solve_grouped
from .objective import RefitProblem, half_hessian, objective

# E is unit-free and E >= alpha |x - x^o|^2 / L^2 (Eq. 6), so below this no point can move by
# more than ~1e-12 L: a frame there is solved (a group with no Es or Ea error starts at ~1e-32,
# rounding error, where no step can gain and the damping would only climb to its limit).
_NEGLIGIBLE_OBJECTIVE = 1e-24


def refit_newton(
    problem: RefitProblem,
    original: np.ndarray,
    start: np.ndarray | None = None,
    ftol_rel: float = 1e-8,
    xtol: float = 1e-6,
    max_iterations: int = 100,
    chunk_frames: int = 256,
    workers: int = 1,
    progress: Callable[[float], None] | None = None,
) -> RefitResult:
    """Minimise E per frame, starting from the original positions.

    Parameters
    ----------
    problem : the level's problem.
    original : (T, P, 3) original positions (Ed's targets).
    start : (T, P, 3) starting positions, ``original`` when None.
    ftol_rel : a frame is done when the next step promises less than this fraction of E,
    xtol : or when an accepted step moves no point by more than ``xtol * L`` (E is quartic, so
        flat, where a frozen chain is straight in the key posture: cos theta_r(0) = -1).
    max_iterations : steps per frame; a frame still moving then is reported as a failure
        (its best point is kept), as is a frame whose damping passes 1e12 times Ed's curvature
        before it converges (reason "damping limit").
    chunk_frames : frames solved together (bounds the (chunk, N, N) matrices in memory).
    workers : processes solving chunks side by side; 1 solves in this process.
    progress : called with the (fractional) number of frames finished after each chunk.

    Returns
    -------
    RefitResult; ``evaluations`` counts objective evaluations per frame, summed over groups.
    """
    begin = original if start is None else start
    return solve_grouped(
        problem, _solve_chunk, (original, begin), (ftol_rel, xtol, max_iterations), chunk_frames, workers, progress
    )


def _solve_chunk(
    problem: RefitProblem,
    first_frame: int,
    original: np.ndarray,
    start: np.ndarray,
    ftol_rel: float,
    xtol: float,
    max_iterations: int,
) -> RefitResult:
    frames, n = original.shape[0], problem.variable_count
    x = start.copy()
    value, gradient = objective(problem, x, original)
    evaluations = np.ones(frames, dtype=np.int64)
    stiffness = problem.weights.distance / problem.length_scale**2  # Ed's curvature, H's floor
    growth = np.full(frames, 2.0)
    active = np.flatnonzero(value > _NEGLIGIBLE_OBJECTIVE)
    diagonal = np.arange(n)
    damping = np.full(frames, 1e-3 * stiffness)
    failed_frames: list[int] = []  # frames stopped by the damping limit
    for iteration in range(max_iterations):
        if active.size == 0:
            break
        xa = x[active]
        g = -0.5 * gradient[active, 1:].reshape(active.size, n)
        matrix = half_hessian(problem, xa)
        if iteration == 0:
            # Far from the optimum H can be strongly indefinite (a frozen joint bends a chain
            # hard); start mu just past its most negative eigenvalue instead of growing into it.
            lowest = np.linalg.eigvalsh(matrix)[:, 0]
            damping[active] += np.maximum(-1.5 * lowest, 0.0)
        matrix[:, diagonal, diagonal] += damping[active, None]
        step = np.linalg.solve(matrix, g[..., None])[..., 0]
        # E(x + d) ~ E - 2 g.d + d^T H d with (H + mu) d = g: the model promises g.d + mu |d|^2.
        promised = np.sum(g * step, axis=1) + damping[active] * np.sum(step**2, axis=1)
        trial = xa.copy()
        trial[:, 1:] += step.reshape(active.size, -1, 3)
        trial_value, trial_gradient = objective(problem, trial, original[active])
        evaluations[active] += 1
        gain = value[active] - trial_value
        # An indefinite H + mu I can promise a rise: reject that step and damp harder.
        better = np.isfinite(trial_value) & (gain > 0.0) & (promised > 0.0)
        accepted = active[better]
        x[accepted] = trial[better]
        gradient[accepted] = trial_gradient[better]
        value[accepted] = trial_value[better]
        ratio = np.where(promised > 0.0, gain / np.maximum(promised, 1e-300), 0.0)
        damping[active] = np.where(
            better,
            damping[active] * np.maximum(1.0 / 3.0, 1.0 - (2.0 * ratio - 1.0) ** 3),
            damping[active] * growth[active],
        )
        growth[active] = np.where(better, 2.0, growth[active] * 2.0)
        small_step = better & (np.abs(step).max(axis=1) <= xtol * problem.length_scale)
        flat = (promised >= 0.0) & (promised <= ftol_rel * value[active])
        converged = flat | small_step
        # Damping this large means no step is found at all: the frame stops unconverged.
        stalled = ~converged & (damping[active] > 1e12 * stiffness)
        failed_frames.extend(int(i) for i in active[stalled])
        active = active[~(converged | stalled)]
    failures = [FrameFailure(first_frame + i, "damping limit", "kept best point") for i in failed_frames] + [
        FrameFailure(first_frame + int(i), f"not converged in {max_iterations} steps", "kept best point")
        for i in active
    ]
    return RefitResult(x, value, evaluations, sorted(failures, key=lambda f: f.frame))
