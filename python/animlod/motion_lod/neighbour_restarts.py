"""Frames whose re-fit stopped in a worse minimum of E (Eq. 5) than their neighbours', solved
again from the neighbours' solutions.

Every frame starts cold (a warm start carries one frame's minimum into the next, and that
raised E on the dev clips), and at coarse levels E has several minima: now and then one frame
lands in another than the frames around it, and a kept joint jumps for that frame alone (an
elbow of a 61-joint figure at its 5-joint level: 3.3%, 6.8%, 2.9% of its height off in three
frames in a row, with E 40% above its neighbours'). A frame whose
E stands above both neighbours' is solved again from each neighbour's solution (feasible for
it: bone lengths and frozen angles do not change between frames), and the solve with the
lowest E is kept; E only goes down. A frame next to one that changed is looked at again where
its E stands above that neighbour's, so a run of poor frames is mended from its ends inward.
Frames of two clips played one after another are not neighbours: a clip's first and last frames
have one neighbour each.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .grouped_solve import RefitResult

# A frame is looked at again where its E exceeds both neighbours' by this factor and by this
# share of the clip's median E: the small peaks of a smooth motion's E, and rounding noise at
# fine levels whose E is nearly 0, cost no second solve.
_PEAK_RATIO = 1.1
_PEAK_SHARE_OF_MEDIAN = 0.25
# Differences of E below this are not looked at, nor kept: one point 0.3% of L from its place
# (E is over lengths divided by L, Eq. 5 with weight 1), far below a visible jump.
_NOTICEABLE = 1e-5
# Rounds of restarts at most; each looks only at neighbours of frames the round before changed
# (a run of poor frames mends from its ends inward, a frame or two per round), and each change
# lowers E.
_ROUNDS = 16
# The frames whose solutions a frame is started from, by offset: the next frame's solution can
# lie in the same poor basin (a fast swing of the arm), the one after it often not.
_SIDES = (-1, 1, -2, 2)

# SLSQP evaluations a restart may take: from a neighbour's solution SLSQP took 5-6x a cold
# solve's ~10 evaluations to converge, and up to 400 at Soldier's coarsest level, whose skinned
# chain took 17 s of CPU instead of 3.3. A restart that starts in the better basin mostly gets
# below the frame's E within this many: the dev clips' chains are the same capped or not, and
# Soldier's coarsest level keeps 6 of its 8 mends.
RESTART_EVALUATIONS = 40

# solve(frames, starts (F, P, 3)) -> RefitResult of those frames, each started from its start.
FrameSolver = Callable[[np.ndarray, np.ndarray], RefitResult]


def restart_from_neighbours(result: RefitResult, solve: FrameSolver, clip_of: np.ndarray) -> RefitResult:
    """``result`` with each frame whose E stands above its neighbours' replaced by the solve from
    a neighbour's solution (``_SIDES``) with the lowest E, where that is lower (by
    ``_NOTICEABLE``) and the solve did not fail (the frame's failure, if any, then dropped);
    ``evaluations`` counts the extra solves. ``solve(frames, starts)`` solves the motion's
    ``frames`` (repeats allowed) from ``starts``; ``clip_of`` ``(T,)``: each frame's clip (a
    neighbour is a frame of the same clip)."""
    frame_count = result.objective.size
    if frame_count < 2:
        return result
    positions, objective = result.positions.copy(), result.objective.copy()
    evaluations = result.evaluations.copy()
    failures = {failure.frame: failure for failure in result.failures}
    candidates = _peaks(objective, clip_of, np.arange(frame_count), both=True)
    for _ in range(_ROUNDS):
        # Every (frame, neighbour) pair in one solve: a solve has a fixed cost per call.
        neighbours = (candidates[None] + np.array(_SIDES)[:, None]).ravel()
        frames = np.tile(candidates, len(_SIDES))
        inside = _in_clip(neighbours, frames, clip_of)
        frames, neighbours = frames[inside], neighbours[inside]
        if not frames.size:
            break
        trial = solve(frames, positions[neighbours])
        np.add.at(evaluations, frames, trial.evaluations)
        value = trial.objective.copy()
        value[np.array([failure.frame for failure in trial.failures], dtype=np.int64)] = np.inf
        best = np.lexsort((value, frames))  # by frame, the lowest E first
        first = best[np.r_[True, frames[best][1:] != frames[best][:-1]]]
        better = first[value[first] < objective[frames[first]] - _NOTICEABLE]
        changed = frames[better]
        positions[changed], objective[changed] = trial.positions[better], trial.objective[better]
        for frame in changed:
            failures.pop(int(frame), None)
        # Beside a mended frame, a frame above that one alone is the next of a run of poor frames.
        beside = np.concatenate([changed - 1, changed + 1])
        beside = np.unique(beside[_in_clip(beside, np.concatenate([changed, changed]), clip_of)])
        candidates = _peaks(objective, clip_of, beside, both=False)
    return RefitResult(positions, objective, evaluations, sorted(failures.values(), key=lambda f: f.frame))


def _in_clip(frames: np.ndarray, of: np.ndarray, clip_of: np.ndarray) -> np.ndarray:
    """Which of ``frames`` lie in the motion and in the clip of the frame ``of`` beside them."""
    inside = (frames >= 0) & (frames < clip_of.size)
    inside[inside] = clip_of[frames[inside]] == clip_of[of[inside]]
    return inside


def _peaks(objective: np.ndarray, clip_of: np.ndarray, frames: np.ndarray, both: bool) -> np.ndarray:
    """The frames among ``frames`` whose E stands above (``_PEAK_RATIO``,
    ``_PEAK_SHARE_OF_MEDIAN``) both neighbours' E in their clip, or with ``both`` False the
    lower one's."""
    end = -np.inf if both else np.inf  # a clip's first and last frames have one neighbour
    sides = []
    for side in (frames - 1, frames + 1):
        inside = _in_clip(side, frames, clip_of)
        sides.append(np.where(inside, objective[np.clip(side, 0, objective.size - 1)], end))
    neighbours = (np.maximum if both else np.minimum)(*sides)
    above = objective[frames] - _PEAK_RATIO * neighbours
    return frames[above > max(_PEAK_SHARE_OF_MEDIAN * np.median(objective), _NOTICEABLE)]
