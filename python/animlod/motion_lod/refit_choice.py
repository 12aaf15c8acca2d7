"""The default ranking, "refit": each level's next joints chosen by the error they leave after
the re-fit, among what the other rankings propose.

Every other ranking guesses a freeze's cost before the re-fit (Section 6), and the re-fit
changes which freezes are cheap: it repairs a nearly still joint between two kept ones almost
exactly (the procedural walk's Spine and Spine1 cost 0.013 units before it and 2e-6 after), but
not a finger or a chain of several frozen joints. Eq. 3 alone loses levels of the dev clips to
leaf-first or least-variance (bench/bench_motion.py's joint-choice table), each for a reason
the others do not share. So at every level, going from fine to coarse, each ranking of
ranking.PROPOSING_RANKINGS proposes its next joints after those already frozen; each distinct
proposal is frozen and re-fitted on TRIAL_FRAMES evenly spaced frames of the clip and scored by
its mean joint position error over every original point (a skinned rig: its skin's mean
distance, skin_measure.skin_trial_measure). A joint frozen at one level stays frozen at every
coarser one, so a level's lowest error can bind the coarser ones to worse: the search carries
the SEARCH_PATHS best choices from level to level, scored by the sum of the log errors of their
levels, and the chain takes the best at the coarsest level (ties: the earlier path and ranking,
importance first). The kept trials are the levels' own re-fits of those frames (chain.py reuses
them). Hidden joints (MotionAnalysis.hidden: they move nothing measured) freeze first, without
a trial.

Proposals are tried in ranking order, and one whose error is at the resolution of the float32 keys
the levels are written with (NEGLIGIBLE_ERROR) is kept without trying the rest: below it the
proposals cannot be told apart (the dev clips' finest levels differ by 1e-16 of the figure, and
trying them all was most of the choice's cost on short clips with fingers).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence

import numpy as np

from ..model import Motion, spread_frames
from .analysis import MotionAnalysis
from .frozen import FrozenLevel, freeze
from .ranking import PROPOSING_RANKINGS, elimination_order, rank_scores, spread_steps

# Frames each proposal is re-fitted on: the error is a mean over frames, and the proposals of one
# level differ by whole joints, so a few frames tell them apart (the chain re-fits every frame).
TRIAL_FRAMES = 16
# A trial error at most this fraction of the figure's size (the level's length scale) is float32
# round-off: storing a dev clip's own keys as float32 moves its joints by 1.3e-8 to 3.7e-8 of the
# figure on average and 1.2e-7 at most (bench/bench_motion.py's level tables).
NEGLIGIBLE_ERROR = 1e-7
# Choices of joints carried from each level to the next. The levels are nested, so a level's
# lowest trial error can bind the coarser levels to worse ones; a runner-up carried along wins
# where its coarser levels make up for it (the sum of the log errors over the levels is lower):
# 131_01's 10-joint level 0.330 -> 0.239 for 0.092 -> 0.100 at 14 joints (README, "Joint choice").
SEARCH_PATHS = 2
# A runner-up whose errors so far (their product over the levels) pass the best path's by more
# than this factor is dropped: the two that won in the speed table's clips stood 1.08x (131_01) and
# 1.13x (the walk) behind when carried.
SEARCH_MARGIN = 1.25


def proposers(motion: Motion, analysis: MotionAnalysis) -> list[Callable[[list[int]], list[int]]]:
    """For every ranking of PROPOSING_RANKINGS, a function giving its elimination order of the
    analysis's candidates left after the given frozen joints. ``spread`` is asked again from what
    is frozen (its costs are runs of frozen joints); the others' orders do not change with it."""
    candidates = np.zeros(motion.skeleton.joint_count, bool)
    candidates[analysis.priority] = True

    def after(order: list[int]) -> Callable[[list[int]], list[int]]:
        return lambda frozen: [j for j in order if j not in frozen]

    def spread(frozen: list[int]) -> list[int]:
        steps = spread_steps(analysis.importance, motion.skeleton.parents, candidates, frozen)
        return elimination_order(steps, np.isfinite(steps))

    return [
        spread
        if name == "spread"
        else after(
            elimination_order(
                rank_scores(name, motion, analysis.importance, analysis.key_frames, analysis.frames, candidates),
                candidates,
            )
        )
        for name in PROPOSING_RANKINGS
    ]


def choose_by_refit(
    motion: Motion,
    analysis: MotionAnalysis,
    counts: Sequence[int],
    trial_error: Callable[[FrozenLevel, np.ndarray], float],
    progress: Callable[[int, int], None] | None = None,
    paths: int = SEARCH_PATHS,
) -> MotionAnalysis:
    """``analysis`` with its priority chosen level by level by the re-fit's error.

    Parameters
    ----------
    motion : the clip.
    analysis : its analysis (key frames, importance, candidates in ``priority``).
    counts : joint counts of the levels, strictly decreasing, the first every joint.
    trial_error : the error (mean joint position error, or the skin's mean distance) of a frozen
        level re-fitted on the given frames of ``motion`` (TRIAL_FRAMES evenly spaced ones, the
        same for every call).
    progress : called with (levels chosen, levels to choose) after each level.
    paths : choices of joints kept from each level to the next, at least 1 (SEARCH_PATHS; 1:
        each level takes its lowest trial error, whatever it leaves the coarser levels).

    Returns
    -------
    MotionAnalysis whose ``priority`` freezes, for each count, the chosen joints first.
    """
    proposing = proposers(motion, analysis)
    frames = spread_frames(motion.frame_count, TRIAL_FRAMES)
    hidden = [j for j in analysis.hidden if not motion.skeleton.end_sites[j]]
    kept = [_Path([], 0.0)]
    for chosen, count in enumerate(counts[1:], start=1):
        need = counts[0] - count
        extended: list[tuple[_Path, list[list[int]]]] = []
        for path in kept:
            # Hidden joints move nothing measured: they go first, without a trial.
            frozen = path.frozen + [j for j in hidden if j not in path.frozen][: need - len(path.frozen)]
            extended.append((_Path(frozen, path.score), _proposals(proposing, frozen, need - len(frozen))))
        kept = _best_paths(extended, motion, analysis, frames, trial_error, paths)
        if progress:
            progress(chosen, len(counts) - 1)
    frozen = kept[0].frozen
    return dataclasses.replace(analysis, priority=frozen + [j for j in analysis.priority if j not in frozen])


@dataclasses.dataclass
class _Path:
    """Joints frozen so far, in order, and the sum over the levels of the log of their trial error."""

    frozen: list[int]
    score: float


def _proposals(proposing: list[Callable[[list[int]], list[int]]], frozen: list[int], need: int) -> list[list[int]]:
    """The distinct next ``need`` joints the rankings propose after ``frozen``, in ranking order."""
    proposals: list[list[int]] = []
    for propose in proposing:
        proposal = propose(frozen)[:need]
        if proposal and sorted(proposal) not in [sorted(p) for p in proposals]:
            proposals.append(proposal)
    return proposals or [[]]


def _best_paths(
    extended: list[tuple[_Path, list[list[int]]]],
    motion: Motion,
    analysis: MotionAnalysis,
    frames: np.ndarray,
    trial_error: Callable[[FrozenLevel, np.ndarray], float],
    paths: int,
) -> list[_Path]:
    """Up to ``paths`` of the paths extended by their proposals, the lowest score first (ties:
    the earlier path and ranking), none whose score passes the lowest by SEARCH_MARGIN. A path's
    proposals are tried in order until one's error is negligible; a level with one proposal in
    all is taken without a trial (it adds the same to every score)."""
    if len(extended) == 1 and len(extended[0][1]) == 1:
        path, (proposal,) = extended[0]
        return [_Path(path.frozen + proposal, path.score)]
    candidates: list[_Path] = []
    seen: set[tuple[int, ...]] = set()
    for path, proposals in extended:
        for proposal in proposals:
            frozen = path.frozen + proposal
            key = tuple(sorted(frozen))
            if key in seen:  # reached by a better path first
                continue
            seen.add(key)
            level = freeze(motion, analysis, frozen)
            negligible = NEGLIGIBLE_ERROR * level.length_scale()
            error = trial_error(level, frames)
            candidates.append(_Path(frozen, path.score + float(np.log(max(error, negligible)))))
            if error <= negligible:
                break
    candidates.sort(key=lambda c: c.score)  # stable: ties keep the earlier path and ranking
    return [c for c in candidates[:paths] if c.score <= candidates[0].score + np.log(SEARCH_MARGIN)]
