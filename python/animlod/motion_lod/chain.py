"""Level-by-level motion LoD (Sections 4-6): analyse once, then freeze, re-fit and rebuild.

Level k freezes the first ``J - n_k`` joints of the priority list (so a joint frozen at one
level stays frozen at every coarser one), re-fits every frame (refit.py or newton.py), recovers
the level's skeleton and motion (skeleton_reduce.py) and, for a skinned character, its skin
(skin_transfer.py). Each level records its error in the asset's units, for a runtime chooser.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..model import Motion, SkinnedMesh
from .analysis import MotionAnalysis, analyze_motion
from .frozen import FrozenLevel, freeze, frozen_motion
from .grouped_solve import FrameFailure, RefitResult
from .newton import refit_newton
from .objective import RefitProblem, Weights, build_problem
from .refit import SlsqpOptions, refit_slsqp
from .skeleton_reduce import expand_motion, recover_motion
from .skin_transfer import transfer_skin

SOLVERS = ("slsqp", "newton")  # the first is the default
# Joint counts of the paper's 8 levels as fractions of the full skeleton (Fig. 1).
_PAPER_FRACTIONS = np.array([1.0, 0.82, 0.70, 0.58, 0.45, 0.33, 0.20, 0.08])


@dataclass
class LevelReport:
    """Errors and cost of one level, lengths in the asset's units.

    mean_error / max_error: joint position error of the level (frozen parts placed by their key
    posture) against the original, over every original point and frame. bone_error: Fig. 7's
    mean over frames of the summed |b(t) - b(0)| of the re-fitted bones; bone_variation: the
    largest standard deviation over frames of a re-fitted bone's length, relative to its key
    length. fk_residual: largest distance between the output's forward kinematics and the
    re-fitted positions (0 up to round-off with hard constraints). energy: mean E per frame.
    """

    joint_count: int
    frozen: list[str]
    mean_error: float
    max_error: float
    bone_error: float
    bone_variation: float
    fk_residual: float
    energy: float
    evaluations: float
    seconds: float
    failures: list[FrameFailure] = field(default_factory=list)


@dataclass
class MotionLevel:
    """One level: the frozen split, the re-fitted positions ``(T, J, 3)``, the output motion on
    the level's skeleton and, for a skinned input, the level's skin."""

    frozen: FrozenLevel
    positions: np.ndarray
    motion: Motion
    report: LevelReport
    skin: SkinnedMesh | None = None


@dataclass
class MotionLodChain:
    """The analysis and the levels, finest first (level 0 keeps every joint)."""

    analysis: MotionAnalysis
    levels: list[MotionLevel]

    @property
    def figure_size(self) -> float:
        """Largest extent of the key posture's bounding box (the height of a standing figure)."""
        return float(np.ptp(self.levels[0].frozen.key_positions, axis=0).max())


def level_joint_counts(motion: Motion, analysis: MotionAnalysis, levels: int | Sequence[int]) -> list[int]:
    """Joint counts per level, strictly decreasing, first = every joint (end sites not counted).

    An int asks for that many levels at the paper's fractions (8 levels: 100, 82, 70, 58, 45,
    33, 20, 8 % of the joints), spread evenly for other counts; a list gives the counts.
    """
    total = int(np.count_nonzero(~motion.skeleton.end_sites))
    fewest = total - len(analysis.priority)  # root, locked and translating joints stay
    if isinstance(levels, int | np.integer):
        if levels < 1:
            raise ValueError(f"levels: must be at least 1, got {levels}")
        if levels > total - fewest + 1:
            raise ValueError(
                f"levels: {levels} levels need {levels} joint counts, but only {fewest}..{total} are possible"
            )
        fractions = np.interp(np.linspace(0, 1, levels), np.linspace(0, 1, _PAPER_FRACTIONS.size), _PAPER_FRACTIONS)
        counts = np.maximum(np.round(fractions * total).astype(int), fewest)
        counts[0] = total
        # Keep them distinct: push collisions down, never below the fewest possible.
        for k in range(1, counts.size):
            counts[k] = min(counts[k], counts[k - 1] - 1)
        if counts[-1] < fewest:
            counts = np.arange(total, total - levels, -1)
        return [int(c) for c in counts]
    counts = sorted({int(c) for c in levels}, reverse=True)
    if not counts:
        raise ValueError("levels: empty list of joint counts")
    if counts[0] > total or counts[-1] < fewest:
        raise ValueError(f"levels: joint counts must lie in {fewest}..{total}, got {counts}")
    return counts if counts[0] == total else [total] + counts


def _refit(
    problem: RefitProblem,
    original: np.ndarray,
    fallback: np.ndarray,
    solver: str,
    slsqp_options: SlsqpOptions,
    workers: int,
    progress: Callable[[float], None] | None,
) -> RefitResult:
    if solver == "slsqp":
        return refit_slsqp(problem, original, fallback, slsqp_options, workers=workers, progress=progress)
    # E has several minima at coarse levels; Newton is cheap enough to try the paper's start
    # (the original positions) and the frozen motion, and keep the lower E per frame.
    half = (lambda frames: progress(frames / 2)) if progress else None
    from_original = refit_newton(problem, original, workers=workers, progress=half)
    from_frozen = refit_newton(problem, original, start=fallback, workers=workers, progress=half)
    better = from_frozen.objective < from_original.objective
    keep = [f for f in from_original.failures if not better[f.frame]] + [
        f for f in from_frozen.failures if better[f.frame]
    ]
    return RefitResult(
        np.where(better[:, None, None], from_frozen.positions, from_original.positions),
        np.where(better, from_frozen.objective, from_original.objective),
        from_original.evaluations + from_frozen.evaluations,
        sorted(keep, key=lambda f: f.frame),
    )


def _bone_statistics(problem: RefitProblem, positions: np.ndarray) -> tuple[float, float]:
    """Fig. 7 on the re-fitted positions: mean summed bone error, worst relative length std."""
    bones = problem.length_pairs[problem.bone_pair]
    if bones.size == 0:
        return 0.0, 0.0
    lengths = np.linalg.norm(positions[:, bones[:, 0]] - positions[:, bones[:, 1]], axis=-1)
    key = problem.key_lengths[problem.bone_pair]
    error = float(np.abs(lengths - key).sum(axis=1).mean())
    variation = float((lengths.std(axis=0) / key).max())
    return error, variation


def build_level(
    motion: Motion,
    analysis: MotionAnalysis,
    joint_count: int,
    weights: Weights | None = None,
    solver: str = SOLVERS[0],
    slsqp_options: SlsqpOptions | None = None,
    workers: int = 1,
    skin: SkinnedMesh | None = None,
    progress: Callable[[float], None] | None = None,
) -> MotionLevel:
    """One level with ``joint_count`` joints (see :func:`build_motion_chain` for the options)."""
    if solver not in SOLVERS:
        raise ValueError(f"solver: expected one of {SOLVERS}, got {solver!r}")
    slsqp_options = slsqp_options or SlsqpOptions()
    if slsqp_options.hard_constraints and solver != "slsqp":
        raise ValueError("hard constraints need solver='slsqp' (the Newton solver only minimises E)")
    start = time.perf_counter()
    total = int(np.count_nonzero(~motion.skeleton.end_sites))
    frozen_joints = analysis.priority[: total - joint_count]
    level = freeze(motion, analysis, frozen_joints)
    problem = build_problem(level, weights)
    original = motion.world_positions()
    if frozen_joints:
        fallback = frozen_motion(level, motion).world_positions()
        result = _refit(problem, original, fallback, solver, slsqp_options, workers, progress)
    else:  # E = 0 at the original positions, its global minimum: nothing to solve
        result = RefitResult(original, np.zeros(motion.frame_count), np.zeros(motion.frame_count, dtype=np.int64))
        if progress:
            progress(motion.frame_count)
    output = recover_motion(level, result.positions, motion)
    fk = output.world_positions()
    placed = expand_motion(level, output, motion).world_positions()
    error = np.linalg.norm(placed - original, axis=-1)
    bone_error, bone_variation = _bone_statistics(problem, result.positions)
    report = LevelReport(
        joint_count=level.joint_count,
        frozen=[motion.skeleton.names[j] for j in frozen_joints],
        mean_error=float(error.mean()),
        max_error=float(error.max()),
        bone_error=bone_error,
        bone_variation=bone_variation,
        fk_residual=float(np.linalg.norm(fk - result.positions[:, level.kept_indices], axis=-1).max()),
        energy=float(result.objective.mean()),
        evaluations=float(result.evaluations.mean()),
        seconds=time.perf_counter() - start,
        failures=result.failures,
    )
    level_skin = transfer_skin(skin, level) if skin is not None else None
    return MotionLevel(level, result.positions, output, report, level_skin)


def build_motion_chain(
    motion: Motion,
    levels: int | Sequence[int] = 8,
    locked: Sequence[str] = (),
    weights: Weights | None = None,
    solver: str = SOLVERS[0],
    slsqp_options: SlsqpOptions | None = None,
    workers: int = 1,
    skin: SkinnedMesh | None = None,
    max_frames: int = 600,
    on_level: Callable[[int, int], Callable[[float], None] | None] | None = None,
    analysis: MotionAnalysis | None = None,
) -> MotionLodChain:
    """Analyse ``motion`` and build its levels.

    Parameters
    ----------
    motion : the clip (at least 2 frames).
    levels : number of levels, or the joint counts (end sites not counted) of each level.
    locked : joint names never frozen.
    weights : alpha, beta, gamma of Eq. 5.
    solver : ``"slsqp"`` (nlopt's SLSQP per frame, the paper's SQP and the reference; needed
        for hard constraints; default) or ``"newton"`` (damped Newton on the same objective,
        vectorised over frames, over ten times faster per frame where both converge; see bench/bench_motion.py).
    slsqp_options : SLSQP stopping rules and the hard-constraint option.
    workers : processes solving chunks of frames side by side (both solvers).
    skin : the character's skin on ``motion.skeleton`` (same joint names), or None.
    max_frames : frames motion analysis uses at most (analysis.py).
    on_level : called with (level index, joint count) before each level; may return a progress
        callback taking the number of frames finished.
    analysis : a finished :func:`analyze_motion` of ``motion`` (then ``locked`` and
        ``max_frames`` are not used).

    Returns
    -------
    MotionLodChain
    """
    if skin is not None and skin.skeleton.names != motion.skeleton.names:
        raise ValueError("skin: its skeleton's joint names differ from the motion's")
    analysis = analysis or analyze_motion(motion, locked=locked, max_frames=max_frames)
    result = []
    for index, count in enumerate(level_joint_counts(motion, analysis, levels)):
        progress = on_level(index, count) if on_level else None
        result.append(build_level(motion, analysis, count, weights, solver, slsqp_options, workers, skin, progress))
    return MotionLodChain(analysis, result)
