"""Which joint to freeze first: the orders motion analysis can give the elimination priority.

Every ranking gives each joint a score; joints are frozen lowest score first (ties by index), and
a joint frozen at one level stays frozen at every coarser one.

- ``importance`` (default): joint importance eps_j (Eq. 3) with zero-length bones measured
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

Every ranking but ``paper`` freezes at the key frames of the looked-through Eqs. 1-2.
"""

from __future__ import annotations

import numpy as np

from .. import rotations
from ..model import Motion

RANKINGS = ("importance", "paper", "depth", "variance")
DEFAULT_RANKING = "importance"
PAPER_RANKING = "paper"


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


def rank_scores(
    ranking: str, motion: Motion, importance: np.ndarray, key_frames: np.ndarray, frames: np.ndarray
) -> np.ndarray:
    """Scores ``(J,)`` of ``ranking`` (lowest frozen first).

    Parameters
    ----------
    ranking : one of RANKINGS.
    motion : the clip.
    importance : (J,) eps_j of Eq. 3 (looked through or printed, see the module notes).
    key_frames : (J,) key frames of Eq. 2 (no ranking here uses them yet).
    frames : (n,) frames the analysis uses.
    """
    del key_frames
    if ranking in ("importance", PAPER_RANKING):
        return importance
    if ranking == "depth":
        return -joint_depths(motion.skeleton.parents).astype(np.float64)
    if ranking == "variance":
        return rotation_variance(motion, frames)
    raise ValueError(f"ranking: expected one of {', '.join(RANKINGS)}, got {ranking!r}")
