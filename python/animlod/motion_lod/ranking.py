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
- ``refit`` (default): each level's next joints chosen by the error they leave after the re-fit
  (refit_choice.py), among what the orders above propose.

Every ranking but ``paper`` freezes at the key frames of the looked-through Eqs. 1-2.
"""

from __future__ import annotations

import numpy as np

from .. import rotations
from ..model import Motion, spread_frames

RANKINGS = ("refit", "importance", "paper", "depth", "variance", "cumulative")
DEFAULT_RANKING = "refit"
PAPER_RANKING = "paper"
# Orders refit_choice.py tries at every level (the printed Eq. 3 measures zero-length bones
# differently and never won a level of the dev clips: bench/bench_motion.py).
PROPOSING_RANKINGS = ("importance", "cumulative", "depth", "variance")
# Frames the cumulative ranking measures at most (evenly spaced among the analysis frames).
CUMULATIVE_FRAMES = 150


def joint_depths(parents: np.ndarray) -> np.ndarray:
    """Number of ancestors of every joint, ``(J,) int64`` (parents in topological order)."""
    depth = np.zeros(parents.size, dtype=np.int64)
    for joint in range(1, parents.size):  # O(J): parents come first
        depth[joint] = depth[parents[joint]] + 1
    return depth


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


def descendants(parents: np.ndarray) -> np.ndarray:
    """``(J, J) bool``: ``[j, d]`` is True when ``d`` is below ``j`` (not ``j`` itself)."""
    count = parents.size
    below = np.zeros((count, count), bool)
    for joint in range(count - 1, 0, -1):  # children before parents: O(J^2) booleans
        parent = parents[joint]
        below[parent, joint] = True
        below[parent] |= below[joint]
    return below


def _rigid_inverse(transforms: np.ndarray) -> np.ndarray:
    """Inverses of rigid 4x4 transforms ``(..., 4, 4)``."""
    rotation = np.swapaxes(transforms[..., :3, :3], -1, -2)
    inverse = np.zeros_like(transforms)
    inverse[..., :3, :3] = rotation
    inverse[..., :3, 3] = -np.einsum("...ij,...j->...i", rotation, transforms[..., :3, 3])
    inverse[..., 3, 3] = 1.0
    return inverse


def cumulative_scores(
    motion: Motion, key_frames: np.ndarray, frames: np.ndarray, candidates: np.ndarray
) -> np.ndarray:
    """Step at which the ``cumulative`` ranking freezes each candidate, ``(J,)`` (inf for others).

    Freezing joint j at its key frame's local transform moves j and every point below it by one
    rigid transform, so each candidate's cost is O(points below it) per frame, with no forward
    kinematics per candidate; after a freeze only the costs of the frozen joint's ancestors and
    descendants change, and only those are measured again. At most ``CUMULATIVE_FRAMES`` of the
    analysis frames (evenly spaced) are used: the cost is a mean over frames.
    """
    skeleton = motion.skeleton
    count = skeleton.joint_count
    joints = np.arange(count)
    if frames.size > CUMULATIVE_FRAMES:
        frames = frames[spread_frames(frames.size, CUMULATIVE_FRAMES)]
    key_local = rotations.compose_transform(
        motion.local_translations()[key_frames, joints], motion.local_rotations[key_frames, joints]
    )  # (J, 4, 4)
    world = motion.world_transforms()[frames]  # (n, J, 4, 4): the current (partly frozen) figure
    positions = world[..., :3, 3]  # a view: follows every update of world
    original = positions.copy()
    subtree = descendants(skeleton.parents) | np.eye(count, dtype=bool)  # [j, d]: d is j or below it
    pair_joint, pair_point = np.nonzero(subtree & candidates[:, None])
    parents = np.maximum(skeleton.parents, 0)  # the root is never a candidate
    error = np.zeros((frames.size, count))  # every point's distance from its original position
    cost = np.full(count, np.inf)  # mean growth of the summed error if the joint froze next
    stale = candidates.copy()
    scores = np.full(count, np.inf)

    def moves(joints: np.ndarray) -> np.ndarray:
        """(n, len(joints), 4, 4): how each joint's subtree moves if it froze now (its frozen world
        transform times the inverse of its current one)."""
        return world[:, parents[joints]] @ key_local[joints] @ _rigid_inverse(world[:, joints])

    for step in range(int(np.count_nonzero(candidates))):  # O(J) steps, vectorised over frames
        measured = np.flatnonzero(stale)
        move = moves(measured)
        rows = stale[pair_joint]
        joint, point = pair_joint[rows], pair_point[rows]
        slot = np.searchsorted(measured, joint)
        moved = np.einsum("npij,npj->npi", move[:, slot, :3, :3], positions[:, point]) + move[..., :3, 3][:, slot]
        growth = np.linalg.norm(moved - original[:, point], axis=-1) - error[:, point]
        cost[measured] = np.bincount(slot, weights=growth.sum(axis=0), minlength=measured.size)
        chosen = int(np.argmin(cost))  # ties: the lowest index
        scores[chosen] = step
        cost[chosen] = np.inf
        below = subtree[chosen]
        world[:, below] = moves(np.array([chosen]))[:, :1] @ world[:, below]
        error[:, below] = np.linalg.norm(positions[:, below] - original[:, below], axis=-1)
        stale = (below | subtree[:, chosen]) & candidates & np.isfinite(cost)
    return scores


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
    raise ValueError(f"ranking: expected one of {', '.join(RANKINGS)}, got {ranking!r}")
