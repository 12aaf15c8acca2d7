"""The default ranking, "refit": each level's next joints chosen by the error they leave after
the re-fit, among what the other rankings propose.

Every other ranking guesses a freeze's cost before the re-fit (Section 6), and the re-fit
changes which freezes are cheap: it repairs a nearly still joint between two kept ones almost
exactly (the procedural walk's Spine and Spine1 cost 0.013 units before it and 2e-6 after), but
not a finger or a chain of several frozen joints. Eq. 3 alone loses levels of the dev clips to
leaf-first or least-variance (bench/bench_motion.py's joint-choice table), each for a reason
the others do not share. So at every level, going from fine to coarse, each ranking of
ranking.PROPOSING_RANKINGS proposes its next joints after those already frozen; each distinct
proposal is frozen and re-fitted on TRIAL_FRAMES evenly spaced frames of the clip, and the one
with the lowest mean joint position error over every original point is kept (ties: the earlier
ranking, importance first); a skinned rig scores the trials by its skin's mean distance instead
(skin_measure.skin_trial_measure). A joint frozen at one level stays frozen at every coarser one.
The kept proposal's trial is the level's own re-fit of those frames (chain.py reuses it). Hidden
joints (MotionAnalysis.hidden: they move nothing measured) freeze first, without a trial.

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

    Returns
    -------
    MotionAnalysis whose ``priority`` freezes, for each count, the chosen joints first.
    """
    proposing = proposers(motion, analysis)
    frames = spread_frames(motion.frame_count, TRIAL_FRAMES)
    frozen: list[int] = []
    hidden = [j for j in analysis.hidden if not motion.skeleton.end_sites[j]]
    for chosen, count in enumerate(counts[1:], start=1):
        # Hidden joints move nothing measured: they go first, without a trial.
        frozen += [j for j in hidden if j not in frozen][: counts[0] - count - len(frozen)]
        need = counts[0] - count - len(frozen)
        proposals: list[list[int]] = []
        for propose in proposing:
            proposal = propose(frozen)[:need]
            if proposal and sorted(proposal) not in [sorted(p) for p in proposals]:
                proposals.append(proposal)
        if len(proposals) > 1:
            levels = [freeze(motion, analysis, frozen + p) for p in proposals]
            proposals = [proposals[_lowest_error(levels, frames, trial_error)]]
        frozen += proposals[0] if proposals else []
        if progress:
            progress(chosen, len(counts) - 1)
    return dataclasses.replace(analysis, priority=frozen + [j for j in analysis.priority if j not in frozen])


def _lowest_error(
    levels: list[FrozenLevel], frames: np.ndarray, trial_error: Callable[[FrozenLevel, np.ndarray], float]
) -> int:
    """Index of the first level with the lowest trial error, or of the first whose error is negligible."""
    best, best_error = 0, np.inf
    for index, level in enumerate(levels):
        error = trial_error(level, frames)
        if error < best_error:
            best, best_error = index, error
        if best_error <= NEGLIGIBLE_ERROR * level.length_scale():
            break
    return best
