"""Level-by-level motion LoD (Sections 4-6): analyse once, then freeze, re-fit and rebuild.

Level k freezes the first ``J - n_k`` joints of the priority list (so a joint frozen at one
level stays frozen at every coarser one), re-fits every frame (refit.py or newton.py), recovers
the level's skeleton and motion (skeleton_reduce.py) and, for a skinned character, its skin
(skin_transfer.py). Each level records its error in the asset's units, for a runtime chooser.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..model import Motion, SkinnedMesh
from ..options import MotionRefitOptions, resolve_options
from .analysis import MotionAnalysis, analyze_motion
from .core_refit import core_energy, refit_core
from .frozen import FrozenLevel, freeze, frozen_motion
from .grouped_solve import FrameFailure, RefitResult, combine_frames
from .neighbour_restarts import RESTART_EVALUATIONS, restart_from_neighbours
from .newton import refit_newton
from .objective import RefitProblem, Weights, build_problem
from .ranking import DEFAULT_RANKING
from .refit import refit_slsqp
from .refit_choice import SEARCH_PATHS, choose_by_refit
from .skeleton_reduce import expand_motion, recover_motion
from .skin_transfer import transfer_skin

# "slsqp": nlopt's SLSQP per frame in the C++ core (default); "slsqp-python": the same solve in
# Python with the PyPI nlopt (the reference); "newton": damped Newton on the penalty objective.
SOLVERS = ("slsqp", "slsqp-python", "newton")
# Joint counts of the paper's 8 levels as fractions of the full skeleton (Fig. 1).
_PAPER_FRACTIONS = np.array([1.0, 0.82, 0.70, 0.58, 0.45, 0.33, 0.20, 0.08])
# Scores a trial re-fit of the "refit" ranking: (frozen level, re-fitted motion, trial frames) -> error.
TrialMeasure = Callable[[FrozenLevel, Motion, np.ndarray], float]


@dataclass
class LevelReport:
    """Errors and cost of one level, lengths in the asset's units.

    mean_error / max_error: joint position error of the level (frozen parts placed by their key
    posture) against the original, over every original point (but MotionAnalysis.hidden's) and
    frame. bone_error: Fig. 7's
    mean over frames of the summed |b(t) - b(0)| of the re-fitted bones; bone_variation: the
    largest standard deviation over frames of a re-fitted bone's length, relative to its key
    length. fk_residual: largest distance between the output's forward kinematics and the
    re-fitted positions (0 up to round-off with hard constraints). energy: mean E per frame.
    frame_errors: (T,) each frame's largest joint position error (a clip's share of max_error).
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
    frame_errors: np.ndarray = field(default_factory=lambda: np.zeros(0))


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


@dataclass(frozen=True)
class JointFloor:
    """The fewest joints a level can keep, and why: the root, locked and translating joints
    stay (names in skeleton order; a locked joint that also translates is listed once, as locked),
    and every joint of a skeleton whose bones all have zero length (``zero_length``)."""

    total: int
    fewest: int
    locked: list[str]
    translating: list[str]
    zero_length: bool = False

    @property
    def possible_levels(self) -> int:
        """Distinct joint counts from ``total`` down to ``fewest``."""
        return self.total - self.fewest + 1

    @property
    def paper_fewest(self) -> int:
        """The paper's coarsest level, 8 % of the joints (at least 1)."""
        return max(1, int(round(_PAPER_FRACTIONS[-1] * self.total)))

    def explain(self) -> str:
        """Why joints stay, e.g. ``root, 2 locked (A, B), 1 translating (Hips)``."""
        parts = ["root"]
        for label, names in (("locked", self.locked), ("translating", self.translating)):
            if names:
                shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
                parts.append(f"{len(names)} {label} ({shown})")
        if self.zero_length:
            parts.append("every bone of zero length (joint positions show no rotation)")
        return ", ".join(parts)


def joint_floor(motion: Motion, analysis: MotionAnalysis) -> JointFloor:
    """Joints of the skeleton (end sites not counted) and the fewest a level keeps."""
    names = motion.skeleton.names
    total = int(np.count_nonzero(~motion.skeleton.end_sites))
    locked = [j for j in analysis.locked if j != 0]
    translating = [j for j in analysis.translating if j != 0 and j not in locked and j not in analysis.hidden]
    return JointFloor(
        total=total,
        fewest=total - len(analysis.priority),
        locked=[names[j] for j in locked],
        translating=[names[j] for j in translating],
        zero_length=analysis.r_max == 0.0,
    )


def check_level_request(levels: int | Sequence[int]) -> None:
    """ValueError naming ``levels`` unless it is a number of levels of at least 1 or a non-empty
    list of whole joint counts; whether the skeleton allows them is :func:`level_joint_counts`'s."""
    if isinstance(levels, int | np.integer):
        if levels < 1:
            raise ValueError(f"levels: must be at least 1, got {levels}")
        return
    given = np.asarray(levels)
    if given.ndim != 1 or given.dtype.kind not in "iuf" or np.any(given != np.round(given)):
        raise ValueError(f"levels: expected a whole number of levels or a list of joint counts, got {levels!r}")
    if given.size == 0:
        raise ValueError("levels: empty list of joint counts")


def level_joint_counts(motion: Motion, analysis: MotionAnalysis, levels: int | Sequence[int]) -> list[int]:
    """Joint counts per level, strictly decreasing, first = every joint (end sites not counted).

    An int asks for that many levels spread from every joint down to the fewest possible
    (joint_floor): at the paper's fractions (8 levels: 100, 82, 70, 58, 45, 33, 20, 8 % of the
    joints, interpolated for other counts) where they stay above the floor; where they do not,
    the same fractions mapped onto the range from the floor to every joint, so that the last
    level reaches the floor. A list gives the counts.
    """
    check_level_request(levels)
    floor = joint_floor(motion, analysis)
    total, fewest = floor.total, floor.fewest
    if isinstance(levels, int | np.integer):
        if levels > floor.possible_levels:
            raise ValueError(
                f"levels: {levels} levels need {levels} distinct joint counts, but the skeleton allows "
                f"{floor.possible_levels} ({total} joints, at least {fewest} kept: {floor.explain()})"
            )
        if levels == 1:
            return [total]
        fractions = np.interp(np.linspace(0, 1, levels), np.linspace(0, 1, _PAPER_FRACTIONS.size), _PAPER_FRACTIONS)
        paper = fractions * total
        mapped = fewest + (total - fewest) * (fractions - fractions[-1]) / (1.0 - fractions[-1])
        counts = np.round(np.maximum(paper, mapped)).astype(int)
        counts[0] = total
        # Distinct and within reach of the floor: level k keeps room for the levels after it.
        room = fewest + np.arange(levels - 1, -1, -1)
        counts = np.clip(counts, room, total - np.arange(levels))
        for k in range(1, levels):
            counts[k] = min(counts[k], counts[k - 1] - 1)
        return [int(c) for c in counts]
    counts = sorted({int(c) for c in levels}, reverse=True)
    if counts[0] > total or counts[-1] < fewest:
        raise ValueError(
            f"levels: joint counts must lie in {fewest}..{total} (at least {fewest} kept: {floor.explain()}), "
            f"got {counts}"
        )
    return counts if counts[0] == total else [total] + counts


def _cold_starts(
    level: FrozenLevel, problem: RefitProblem, motion: Motion, original: np.ndarray, fallback: np.ndarray
) -> np.ndarray:
    """Feasible starts for the hard-constrained solve, ``(T, P, 3)``: per frame, of the frozen key
    motion and the original projected onto the level's rigid skeleton (its joints turned to aim
    at the original positions, frozen joints at their key rotations), the one with the lower E."""
    projected = expand_motion(level, recover_motion(level, original, motion), motion).world_positions()
    lower = core_energy(problem, projected, original) < core_energy(problem, fallback, original)
    return np.where(lower[:, None, None], projected, fallback)


def _refit(
    problem: RefitProblem,
    original: np.ndarray,
    fallback: np.ndarray,
    cold_starts: np.ndarray | None,
    solver: str,
    slsqp_options: MotionRefitOptions,
    workers: int,
    progress: Callable[[float], None] | None,
) -> RefitResult:
    if solver == "slsqp":
        return refit_core(
            problem, original, fallback, slsqp_options, threads=workers, progress=progress, cold_starts=cold_starts
        )
    processes = max(workers, 1)
    if solver == "slsqp-python":
        return refit_slsqp(
            problem, original, fallback, slsqp_options, workers=processes, progress=progress, cold_starts=cold_starts
        )
    # E has several minima at coarse levels; Newton is cheap enough to try the paper's start
    # (the original positions) and the frozen motion, and keep the lower E per frame.
    half = (lambda frames: progress(frames / 2)) if progress else None
    from_original = refit_newton(problem, original, workers=processes, progress=half)
    from_frozen = refit_newton(problem, original, start=fallback, workers=processes, progress=half)
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


def resolve_solver(solver: str, slsqp_options: MotionRefitOptions | None) -> MotionRefitOptions:
    """The SLSQP options a solver runs with (hard bone lengths for SLSQP, penalties for Newton)."""
    if solver not in SOLVERS:
        raise ValueError(f"solver: expected one of {SOLVERS}, got {solver!r}")
    slsqp_options = slsqp_options or MotionRefitOptions(hard_constraints=solver != "newton")
    if slsqp_options.hard_constraints and solver == "newton":
        raise ValueError("solver: hard constraints need an SLSQP solver (the Newton solver only minimises E)")
    return slsqp_options


@dataclass
class _KnownFrames:
    """A level's re-fit on some frames of the clip (the refit ranking's trial of the chosen joints)."""

    frames: np.ndarray
    result: RefitResult


def _trial_key(level: FrozenLevel) -> bytes:
    """What identifies a level among the refit ranking's trials: its frozen joints."""
    return level.frozen.tobytes()


@dataclass
class _Solved:
    """A level re-fitted on a motion's frames: the problem, the solve (each frame's positions with
    its root at the origin), the level's output motion, every original point placed by it
    (frozen parts by their key posture), the original, and which points the errors count
    (FrozenLevel.measured)."""

    problem: RefitProblem
    result: RefitResult
    output: Motion
    placed: np.ndarray
    original: np.ndarray
    measured: np.ndarray

    def errors(self) -> np.ndarray:
        """(T, M) distance of every measured original point from its original position."""
        return np.linalg.norm(self.placed[:, self.measured] - self.original[:, self.measured], axis=-1)


def _solve_level(
    level: FrozenLevel,
    motion: Motion,
    weights: Weights | None,
    solver: str,
    slsqp_options: MotionRefitOptions,
    workers: int,
    progress: Callable[[float], None] | None,
    known: _KnownFrames | None = None,
    clip_of: np.ndarray | None = None,
) -> _Solved:
    """Re-fits ``level`` on every frame of ``motion`` (but ``known``'s, whose re-fit is given) and
    places every original point. With ``clip_of``, the clip of each frame (consecutive frames
    of one clip are neighbours), frames whose E stands above their neighbours' are solved again
    from the neighbours' solutions; None: no restarts (a trial's frames are not neighbours)."""
    problem = build_problem(level, weights)
    # E (Eq. 5) is the same for a frame moved as a whole, and a clip 1e9 units from the origin
    # had its held lengths rounded away (fallbacks, 20% errors): every frame is solved with its
    # root at the origin, and the root's path is put back on the level's motion.
    at_origin = replace(motion, root_positions=np.zeros_like(motion.root_positions))
    original = at_origin.world_positions()
    if level.frozen.any():
        fallback = frozen_motion(level, at_origin).world_positions()
        hard = slsqp_options.hard_constraints
        cold_starts = _cold_starts(level, problem, at_origin, original, fallback) if hard else None
        rest = np.arange(motion.frame_count)
        parts = []
        if known is not None:
            rest = np.setdiff1d(rest, known.frames)
            parts.append((known.frames, known.result))
            if progress:
                progress(known.frames.size)
        if rest.size:
            starts = None if cold_starts is None else cold_starts[rest]
            solved = _refit(problem, original[rest], fallback[rest], starts, solver, slsqp_options, workers, progress)
            parts.append((rest, solved))

        evaluations = min(slsqp_options.max_evaluations, RESTART_EVALUATIONS)
        restart_options = resolve_options(MotionRefitOptions, slsqp_options, {"max_evaluations": evaluations})

        def solve_from(frames: np.ndarray, starts: np.ndarray) -> RefitResult:
            if solver == "newton":
                return refit_newton(problem, original[frames], start=starts, workers=max(workers, 1))
            return _refit(problem, original[frames], fallback[frames], starts, solver, restart_options, workers, None)

        result = combine_frames(motion.frame_count, parts)
        if clip_of is not None:
            result = restart_from_neighbours(result, solve_from, clip_of)
    else:  # E = 0 at the original positions, its global minimum: nothing to solve
        result = RefitResult(original, np.zeros(motion.frame_count), np.zeros(motion.frame_count, dtype=np.int64))
        if progress:
            progress(motion.frame_count)
    output = recover_motion(level, result.positions, at_origin)
    output = replace(output, root_positions=output.root_positions + motion.root_positions)
    placed = expand_motion(level, output, motion).world_positions()
    return _Solved(problem, result, output, placed, motion.world_positions(), level.measured)


def build_level(
    motion: Motion,
    analysis: MotionAnalysis,
    joint_count: int,
    weights: Weights | None = None,
    solver: str = SOLVERS[0],
    slsqp_options: MotionRefitOptions | None = None,
    workers: int = 0,
    skin: SkinnedMesh | None = None,
    progress: Callable[[float], None] | None = None,
    trials: Mapping[bytes, _KnownFrames] | None = None,
) -> MotionLevel:
    """One level with ``joint_count`` joints (see :func:`build_motion_chain` for the options);
    ``trials``: re-fits on some frames already done, by :func:`_trial_key`; the level's is reused."""
    slsqp_options = resolve_solver(solver, slsqp_options)
    start = time.perf_counter()
    total = int(np.count_nonzero(~motion.skeleton.end_sites))
    frozen_joints = analysis.priority[: total - joint_count]
    level = freeze(motion, analysis, frozen_joints)
    known = trials.get(_trial_key(level)) if trials else None
    clip_of = analysis.clip_of_frames(motion.frame_count)
    solved = _solve_level(level, motion, weights, solver, slsqp_options, workers, progress, known, clip_of)
    result = replace(solved.result, positions=solved.result.positions + motion.root_positions[:, None, :])
    fk = solved.output.world_positions()
    error = solved.errors()
    bone_error, bone_variation = _bone_statistics(solved.problem, result.positions)
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
        frame_errors=error.max(axis=1),
    )
    level_skin = transfer_skin(skin, level) if skin is not None else None
    return MotionLevel(level, result.positions, solved.output, report, level_skin)


def build_motion_chain(
    motion: Motion,
    levels: int | Sequence[int] = 8,
    locked: Sequence[str] = (),
    weights: Weights | None = None,
    solver: str = SOLVERS[0],
    slsqp_options: MotionRefitOptions | None = None,
    workers: int = 0,
    skin: SkinnedMesh | None = None,
    max_frames: int = 600,
    on_level: Callable[[int, int], Callable[[float], None] | None] | None = None,
    analysis: MotionAnalysis | None = None,
    ranking: str = DEFAULT_RANKING,
    on_choice: Callable[[int, int], None] | None = None,
    trial_measure: TrialMeasure | None = None,
    refit_paths: int = SEARCH_PATHS,
) -> MotionLodChain:
    """Analyse ``motion`` and build its levels.

    Parameters
    ----------
    motion : the clip (one frame, a pose, freezes exactly).
    levels : number of levels, or the joint counts (end sites not counted) of each level.
    locked : joint names never frozen.
    weights : alpha, beta, gamma of Eq. 5.
    solver : ``"slsqp"`` (nlopt's SLSQP per frame in the C++ core, the paper's SQP; default),
        ``"slsqp-python"`` (the same in Python, the reference) or ``"newton"`` (damped Newton on
        the penalty objective, vectorised over frames; no hard constraints).
    slsqp_options : SLSQP stopping rules and the hard-constraint option (default: hard bone
        lengths for the SLSQP solvers, penalties for Newton).
    workers : threads of the core's solve and of the motion analysis (0: every core), or
        processes of the Python solvers (0 or 1: this process).
    skin : the character's skin on ``motion.skeleton`` (same joint names), or None.
    max_frames : frames motion analysis uses at most (analysis.py).
    on_level : called with (level index, joint count) before each level; may return a progress
        callback taking the number of frames finished.
    analysis : a finished :func:`analyze_motion` of ``motion`` (then ``locked``,
        ``max_frames`` and ``ranking`` are not used).
    ranking : the joint elimination order (ranking.RANKINGS; by default "refit": each level's next
        joints chosen by their error after a trial re-fit, refit_choice.py).
    on_choice : with the "refit" ranking, called with (levels chosen, levels to choose) as its
        trial re-fits, which run before the first level, finish each level.
    trial_measure : with the "refit" ranking, how a trial re-fit is scored (lower is better): called
        with the frozen level, its re-fitted motion on the trial frames and those frames. None: the
        mean distance of every measured point from its original position; a skinned rig's chain
        measures its skin (skin_measure.skin_trial_measure).
    refit_paths : with the "refit" ranking, the choices of joints (at least 1) its search carries
        from each level to the next (refit_choice.SEARCH_PATHS; 1: each level takes its lowest
        trial error).

    Returns
    -------
    MotionLodChain
    """
    if skin is not None and skin.skeleton.names != motion.skeleton.names:
        raise ValueError("skin: its skeleton's joint names differ from the motion's")
    if refit_paths < 1:
        raise ValueError(f"refit_paths: must be at least 1, got {refit_paths}")
    analysis = analysis or analyze_motion(
        motion, locked=locked, max_frames=max_frames, ranking=ranking, workers=workers
    )
    counts = level_joint_counts(motion, analysis, levels)
    # Each trial's re-fit by its frozen joints: a level reuses its chosen trial's frames (every
    # frame's solve is its own, so those frames' results are the level's; not with warm starts,
    # which carry a frame's result into the next).
    trials: dict[bytes, _KnownFrames] = {}
    if analysis.ranking == "refit":
        slsqp_options = resolve_solver(solver, slsqp_options)

        def trial_error(level: FrozenLevel, frames: np.ndarray) -> float:
            trial_motion = motion.take_frames(frames)  # frames spread over the clip: not neighbours
            solved = _solve_level(level, trial_motion, weights, solver, slsqp_options, workers, None)
            if not slsqp_options.warm_start:
                trials[_trial_key(level)] = _KnownFrames(frames, solved.result)
            if trial_measure is not None:
                return trial_measure(level, solved.output, frames)
            return float(solved.errors().mean())

        analysis = choose_by_refit(motion, analysis, counts, trial_error, on_choice, refit_paths)
    result = []
    for index, count in enumerate(counts):
        progress = on_level(index, count) if on_level else None
        result.append(
            build_level(motion, analysis, count, weights, solver, slsqp_options, workers, skin, progress, trials)
        )
    return MotionLodChain(analysis, result)
