"""Which joint to freeze first: the orders motion analysis can give the elimination priority.

Every ranking gives each joint a score; joints are frozen lowest score first (ties by index), and
a joint frozen at one level stays frozen at every coarser one.

- ``importance``: joint importance eps_j (Eq. 3) with zero-length bones measured
  through the points below them (analysis.child_bones). Eq. 1 as printed measures a joint by its
  direct children only, so a joint whose children all sit at its own position (CMU's Chest2 under
  the neck and both collars, a wrist above a zero-length hand) gets importance 0 and is frozen
  first, though its rotation turns the whole upper body or hand; bench/bench_motion.py shows the
  printed form losing to both simple rankings below on 131_01.bvh for that reason.
- ``paper``: Eq. 3 exactly as printed (key frames, Eq. 2, from the same printed Eq. 1).
- ``depth``: leaf-first by hierarchy depth, deepest joints first (what bone-list and bone-depth
  LoD tools amount to); ties by index.
- ``variance``: least angular motion first, each joint's rotation variance over the clip (mean
  squared angle between its local rotation and their mean), blind to how long its bones are.
- ``cumulative``: Eq. 3's question asked of the whole figure and re-asked after each freeze: the
  next joint is the one whose freeze, with every joint before it frozen, moves the points of the
  figure least from their original positions (mean over points and frames). Eq. 3 measures each
  joint alone and only its own bones, so it freezes several nearly still joints along one chain
  (the procedural walk's spine, neck and shoulders) whose small turns add up at the head and
  hands; this order sees that sum.
- ``spread``: Eq. 3's importance summed over the run of connected frozen joints a freeze would
  make: the next joint is the one whose freeze, with its frozen parent and children and the
  joints frozen beside them, adds up to the least importance. The re-fit repairs a lone frozen
  joint through its kept neighbours but not a run of them (the frozen run bends as one rigid
  piece), and Eq. 3, measuring each joint alone, freezes whole runs where the importances of a
  chain differ a little: a tail whose first half a second clip also moves had its other half
  frozen at once (tests/python/test_motion_ranking.py's 20-joint tail at 8 joints: mean error
  0.081 with Eq. 3, 0.0039 spread).
- ``refit`` (default): each level's next joints chosen by the error they leave after the re-fit
  (refit_choice.py), among what the orders above propose, two choices carried from level to level.

Every ranking but ``paper`` freezes at the key frames of the looked-through Eqs. 1-2.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import _core, rotations
from ..model import Motion, joint_depths, spread_frames

RANKINGS = ("refit", "importance", "paper", "depth", "variance", "cumulative", "spread")
DEFAULT_RANKING = "refit"
PAPER_RANKING = "paper"
# Orders refit_choice.py tries at every level (the printed Eq. 3 measures zero-length bones
# differently and never won a level of the dev clips: bench/bench_motion.py).
PROPOSING_RANKINGS = ("importance", "cumulative", "depth", "variance", "spread")
# Frames the cumulative ranking measures at most (evenly spaced among the analysis frames).
CUMULATIVE_FRAMES = 150


def rotation_variance(motion: Motion, frames: np.ndarray) -> np.ndarray:
    """Mean squared angle (radians^2) between each joint's local rotation and its mean, ``(J,)``.

    The mean is the normalised sum of the quaternions, each turned to the hemisphere of the
    joint's first sampled rotation (q and -q are the same rotation).
    """
    q = motion.local_rotations[frames]  # (n, J, 4)
    q = q * np.where(np.sum(q * q[:1], axis=-1, keepdims=True) < 0.0, -1.0, 1.0)
    mean = rotations.normalize(q.mean(axis=0))
    cosine = np.clip(np.abs(np.sum(q * mean, axis=-1)), 0.0, 1.0)
    return np.mean((2.0 * np.arccos(cosine)) ** 2, axis=0)


def cumulative_scores(motion: Motion, key_frames: np.ndarray, frames: np.ndarray, candidates: np.ndarray) -> np.ndarray:
    """Step at which the ``cumulative`` ranking freezes each candidate, ``(J,)`` (inf for others).

    Freezing joint j at its key frame's local transform moves j and every point below it by one
    rigid transform per frame, so no candidate needs forward kinematics, and after a freeze only
    the frozen joint's ancestors and descendants are measured again (the core's
    ``cumulative_freeze_steps``). At most ``CUMULATIVE_FRAMES`` of the analysis frames (evenly
    spaced) are used: the cost is a mean over frames.
    """
    joints = np.arange(motion.skeleton.joint_count)
    if frames.size > CUMULATIVE_FRAMES:
        frames = frames[spread_frames(frames.size, CUMULATIVE_FRAMES)]
    key_local = rotations.compose_transform(
        motion.local_translations()[key_frames, joints], motion.local_rotations[key_frames, joints]
    )  # (J, 4, 4)
    world = motion.world_transforms()[frames]  # (n, J, 4, 4)
    return _core.cumulative_freeze_steps(world, key_local, motion.skeleton.parents, candidates)


def spread_steps(
    importance: np.ndarray, parents: np.ndarray, candidates: np.ndarray, frozen: Sequence[int] = ()
) -> np.ndarray:
    """Step at which the ``spread`` ranking freezes each candidate after ``frozen``, ``(J,)`` (inf
    for the others and for ``frozen``).

    A run is a set of frozen joints connected through parent links; its cost is the sum of its
    joints' ``importance``. Each step freezes the remaining candidate whose freeze makes the run of
    least cost (ties: lower index). A joint's parent and children lie in different runs (the
    hierarchy is a tree), so that cost is its importance plus its frozen neighbours' runs' costs.
    """
    count = parents.size
    is_frozen = np.zeros(count, bool)
    is_frozen[list(frozen)] = True
    run = np.arange(count)  # a frozen joint's run: its topmost frozen ancestor in the run
    for joint in np.nonzero(is_frozen[1:] & is_frozen[parents[1:]])[0] + 1:  # parents come first
        run[joint] = run[parents[joint]]
    steps = np.full(count, np.inf)
    left = candidates & ~is_frozen
    child = np.arange(1, count)
    for step in range(int(left.sum())):
        run_cost = np.bincount(run[is_frozen], weights=importance[is_frozen], minlength=count)
        frozen_child = child[is_frozen[child]]
        cost = importance + np.bincount(parents[frozen_child], weights=run_cost[run[frozen_child]], minlength=count)
        cost[child] += np.where(is_frozen[parents[child]], run_cost[run[parents[child]]], 0.0)
        joint = int(np.flatnonzero(left)[np.argmin(cost[left])])
        steps[joint] = step
        left[joint] = False
        label = run[parents[joint]] if joint and is_frozen[parents[joint]] else joint
        below = run[frozen_child[parents[frozen_child] == joint]]
        is_frozen[joint] = True
        run[is_frozen & np.isin(run, below)] = label
        run[joint] = label
    return steps


def elimination_order(scores: np.ndarray, candidates: np.ndarray) -> list[int]:
    """The candidates (``(J,) bool``) by ascending ``scores (J,)``, ties by index."""
    return [int(j) for j in np.lexsort((np.arange(scores.size), scores)) if candidates[j]]


def rank_scores(
    ranking: str,
    motion: Motion,
    importance: np.ndarray,
    key_frames: np.ndarray,
    frames: np.ndarray,
    candidates: np.ndarray,
) -> np.ndarray:
    """Scores ``(J,)`` of ``ranking`` (lowest frozen first).

    Parameters
    ----------
    ranking : one of RANKINGS ("refit" scores by importance here: refit_choice.py revises the
        order once the levels' joint counts are known).
    motion : the clip.
    importance : (J,) eps_j of Eq. 3 (looked through or printed, see the module notes).
    key_frames : (J,) key frames of Eq. 2.
    frames : (n,) frames the analysis uses.
    candidates : (J,) bool joints that may freeze.
    """
    if ranking in ("refit", "importance", PAPER_RANKING):
        return importance
    if ranking == "depth":
        return -joint_depths(motion.skeleton.parents).astype(np.float64)
    if ranking == "variance":
        return rotation_variance(motion, frames)
    if ranking == "cumulative":
        return cumulative_scores(motion, key_frames, frames, candidates)
    if ranking == "spread":
        return spread_steps(importance, motion.skeleton.parents, candidates)
    raise ValueError(f"ranking: expected one of {', '.join(RANKINGS)}, got {ranking!r}")
