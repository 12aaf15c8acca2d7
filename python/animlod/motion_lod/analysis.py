"""Motion analysis: posture error, key frames, joint importance and the elimination order.

Implements Section 4 of the motion LoD paper (seeds/000): the posture error E_j(t_ref, t) of
Eq. 1, the key frame of each joint (Eq. 2), the key posture assembled from them and the joint
importance eps_j (Eq. 3), which orders the joints for elimination (lowest first).

Conventions this implementation fixes where the paper is silent:

- ``c`` runs over the *direct* children of ``j`` (end sites included), as in the paper's
  Fig. 3. The bone ``j -> c`` is measured in the frame of ``j``'s parent, i.e. as
  ``R_j(t) @ offset_c``: only ``j``'s own rotation changes it, so a joint whose local rotation
  never changes has importance exactly zero, however its ancestors move. (Freezing ``j`` fixes
  exactly that local rotation, so this is the error the freeze introduces.)
- Eq. 1 takes, as the paper's text says, the average of the two radii: the arc length
  ``(r(t_ref) + r(t)) / 2 * theta`` over the circumference ``2 pi r_max``; ``r_max`` is the summed
  length of the root's child bones (mean over frames), or the longest bone when those are all
  zero. (The printed bracket omits the 1/2; constant factors change neither key frames nor order.)
- Joints whose local translation moves (BVH position channels below the root that carry
  motion) are never frozen: freezing would pin their translation to one frame. A translation
  counts as moving only when its range over the clip exceeds ``translation_tolerance`` times the
  joint's bone length (the mean length of its translation, at least 1 % of the longest bone):
  exporters write a translation key on every joint with float noise, and constant keys are not
  motion. A joint below the tolerance can freeze; its translation is then held at the key frame
  like its rotation, and the level's error includes what that costs.
- End sites carry no rotation: they give leaf joints a direction, have importance 0 and are never
  in the priority list (they are not joints of a level). A leaf joint *without* an end site has
  no bone to measure, so its importance is 0 and it is eliminated first.
- Long clips: the n x n table is never stored; the core sums each bone's rows (posture_error.hpp).
  Above ``max_frames`` frames, Eqs. 1-3 run on ``max_frames`` evenly spaced frames: key frames
  are then chosen among those frames and eps_j becomes the same mean over a uniform subsample
  (a Riemann sum of the full-rate mean), which changes it by at most the motion between two
  sampled frames. Clips played one after another are sampled clip by clip, in proportion to
  their lengths (clips.spread_over_clips), so that no short clip is skipped.
  ``MotionAnalysis.frames`` records which frames were used.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from .. import _core, rotations
from ..model import Motion, spread_frames
from .clips import spread_over_clips
from .ranking import DEFAULT_RANKING, PAPER_RANKING, RANKINGS, elimination_order, rank_scores


@dataclass(frozen=True)
class MotionAnalysis:
    """Result of :func:`analyze_motion` for a motion with ``J`` joints (end sites included).

    Attributes
    ----------
    key_frames : (J,) int64 key frame t_key_j of every joint (Eq. 2), an index into the motion.
    importance : (J,) float64 joint importance eps_j (Eq. 3); 0 for end sites. With every
        ranking but "paper", Eqs. 1-3 measure a zero-length bone through the points below it
        (child_bones, look_through); "paper" takes Eq. 1's direct children as printed.
    priority : joint indices in elimination order (lowest rank first, ties by index, see
        ranking.py); never the root, end sites, locked joints or translating joints. With the
        "refit" ranking, the importance order until build_motion_chain chooses each level's
        joints (refit_choice.py; the chain's analysis holds the chosen order).
    locked : joint indices the caller locked (never frozen).
    frames : (n,) int64 frames the analysis used (all frames unless subsampled).
    r_max : the normaliser of Eq. 1, in the asset's units; 0 where every bone has zero length.
    translating : joint indices whose translation moves (see translating_joints), never frozen
        unless hidden.
    ranking : the name of the ranking that ordered ``priority`` (ranking.RANKINGS).
    markers : end sites that measure their joint's rotation but belong to no level (a skinned
        leaf joint's skin tips, skin_measure.py): never re-fitted, placed from their joint.
    hidden : points that move nothing measured (no skin on or below them, nor on their parent:
        a rig's IK targets and controls and their end sites, skin_measure.py): the joints first
        in ``priority``, translating or not, and every one left out of every error.
    clips : the frames of each clip of a motion made of several played one after another
        (clips.join_clips); empty for one clip.
    """

    key_frames: np.ndarray
    importance: np.ndarray
    priority: list[int]
    locked: list[int]
    frames: np.ndarray
    r_max: float
    translating: list[int] = field(default_factory=list)
    ranking: str = "importance"
    markers: list[int] = field(default_factory=list)
    hidden: list[int] = field(default_factory=list)
    clips: tuple[slice, ...] = ()

    def clip_of_frames(self, frame_count: int) -> np.ndarray:
        """``(frame_count,)`` int64 index of each frame's clip in ``clips`` (0 for one clip)."""
        label = np.zeros(frame_count, dtype=np.int64)
        for index, clip in enumerate(self.clips):
            label[clip] = index
        return label

    def key_rotations(self, motion: Motion) -> np.ndarray:
        """Key posture (Section 4.2): every joint's local rotation at its key frame, ``(J, 4)``."""
        joints = np.arange(motion.skeleton.joint_count)
        return motion.local_rotations[self.key_frames, joints]

    def key_translations(self, motion: Motion) -> np.ndarray:
        """Every joint's local translation at its key frame, ``(J, 3)`` (offsets unless animated)."""
        return motion.local_translations()[self.key_frames, np.arange(motion.skeleton.joint_count)]


# Default of translating_joints: a translation whose range stays under 1 % of its bone is held.
TRANSLATION_TOLERANCE = 1e-2
# A bone shorter than this fraction of the figure (its longest bone here, the key posture's
# extent in the re-fit and the output skeleton) has no direction: a joint at its parent's
# position. Float32 keys resolve ~1e-7 of a figure, and exporters write noise of that order on the
# translation channels of such joints (a 1e-6 bone in random directions, held as a length, made
# 131_01 with noise on its left hand's translation 18x slower to re-fit); real bones are over 1e-3.
ZERO_LENGTH = 1e-6


def translating_joints(motion: Motion, tolerance: float = TRANSLATION_TOLERANCE) -> np.ndarray:
    """Non-root joints whose local translation moves, ``(J,) bool``.

    A joint translates when the range of its local translation over the clip (the length of the
    per-axis peak-to-peak vector) exceeds ``tolerance`` times its bone length: the mean length of
    that translation, or 1 % of the longest bone when it is shorter (a joint at its parent's
    position has no length of its own to compare with). Float noise and constant keys stay below.
    """
    _check_translation_tolerance(tolerance)
    moving = np.zeros(motion.skeleton.joint_count, bool)
    if motion.joint_translations is None or motion.skeleton.joint_count < 2:
        return moving
    translations = motion.joint_translations[:, 1:]
    bones = np.linalg.norm(translations, axis=-1).mean(axis=0)
    reference = np.maximum(bones, 1e-2 * bones.max())
    spread = np.linalg.norm(np.ptp(translations, axis=0), axis=-1)
    moving[1:] = spread > tolerance * reference
    return moving


def child_bones(motion: Motion, frames: np.ndarray, look_through: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Every joint's bones as seen from its parent's frame.

    Returns ``owners (B,)`` (the joint ``j`` each bone hangs from) and ``vectors (n, B, 3)`` at
    the given frames: ``R_j(t) @ offset_c(t)`` for every child ``c`` of ``j`` (B = J - 1), the
    paper's Eq. 1. With ``look_through``, a child at ``j``'s own position (a zero-length bone,
    which has no direction) is replaced by its own children, recursively: the bones of ``j`` are
    then the vectors to its nearest points that are not at its position, which ``j``'s rotation
    (and the zero-length joints' between them) turns. Eq. 1 as printed gives such a joint (CMU's
    Chest2 or a wrist above a zero-length hand) importance 0, though it turns a whole limb.
    """
    skeleton = motion.skeleton
    parents = skeleton.parents[1:]
    children = np.arange(1, skeleton.joint_count)
    offsets = motion.local_translations()[frames][:, children]
    vectors = rotations.rotate(motion.local_rotations[frames][:, parents], offsets)
    if not look_through:
        return parents.astype(np.int64), vectors
    lengths = np.linalg.norm(offsets, axis=-1).max(axis=0)  # (J - 1,)
    zero = np.concatenate([[False], lengths <= ZERO_LENGTH * max(float(lengths.max(initial=0.0)), 1e-300)])
    # Nearest non-coincident points below each joint: walk down through zero-length children,
    # composing their rotations: v = R_j R_c1 ... R_ck offset_d (the zero-length offsets add 0).
    kids = skeleton.children()
    local = motion.local_rotations[frames]
    translations = motion.local_translations()[frames]
    owners, vectors = [], []
    for joint in range(skeleton.joint_count):  # O(J) Python steps, vectorised over frames
        stack = [(child, local[:, joint]) for child in kids[joint]]
        while stack:
            point, turn = stack.pop()
            if zero[point]:
                stack.extend((child, rotations.multiply(turn, local[:, point])) for child in kids[point])
            else:
                owners.append(joint)
                vectors.append(rotations.rotate(turn, translations[:, point]))
    if not owners:
        return np.zeros(0, np.int64), np.zeros((frames.size, 0, 3))
    return np.array(owners, dtype=np.int64), np.stack(vectors, axis=1)


def posture_error_row_sums(
    motion: Motion, frames: np.ndarray, r_max: float, look_through: bool = False, workers: int = 0
) -> np.ndarray:
    """Row sums ``S[j, a] = sum_b E_j(frames[a], frames[b])`` of Eq. 1's table, ``(J, n)``.

    The arcs of every bone are summed in the core (posture_error.hpp: each pair of frames once,
    no table stored, bones shared by ``workers`` threads, 0 for every core).
    ``look_through``: measure zero-length bones through the points below them (child_bones).
    """
    owners, vectors = child_bones(motion, frames, look_through)
    lengths = np.linalg.norm(vectors, axis=-1)  # r_jc(t), (n, B)
    units = np.divide(vectors, lengths[..., None], out=np.zeros_like(vectors), where=lengths[..., None] > 0.0)
    per_bone = _core.posture_error_row_sums(units, lengths, workers)  # (B, n) arcs, mean radius x angle
    sums = np.zeros((motion.skeleton.joint_count, frames.size))
    np.add.at(sums, owners, per_bone)  # sum over the children c of j (Eq. 1)
    return sums / (2.0 * np.pi * r_max)


def _r_max(motion: Motion) -> float:
    """Summed mean length of the root's child bones (Eq. 1's normaliser), longest bone if zero;
    0 when every bone has zero length."""
    lengths = np.linalg.norm(motion.local_translations()[:, 1:], axis=-1).mean(axis=0)
    root_children = motion.skeleton.parents[1:] == 0
    total = float(lengths[root_children].sum())
    if total > 0.0:
        return total
    return float(lengths.max()) if lengths.size else 0.0


def _check_translation_tolerance(tolerance: float) -> None:
    if not (np.isfinite(tolerance) and tolerance >= 0.0):
        raise ValueError(f"translation_tolerance: must be a finite number >= 0, got {tolerance}")


def check_analysis_options(
    max_frames: int = 600,
    translation_tolerance: float = TRANSLATION_TOLERANCE,
    ranking: str = DEFAULT_RANKING,
    workers: int = 0,
) -> None:
    """ValueError naming the option for values :func:`analyze_motion` refuses whatever the clip."""
    if ranking not in RANKINGS:
        raise ValueError(f"ranking: no ranking named {ranking!r} (choose from {', '.join(RANKINGS)})")
    if max_frames < 2:
        raise ValueError(f"max_frames: must be at least 2, got {max_frames}")
    if workers < 0:
        raise ValueError(f"workers: must be >= 0 (0: every core), got {workers}")
    _check_translation_tolerance(translation_tolerance)


def analyze_motion(
    motion: Motion,
    locked: Iterable[str] = (),
    max_frames: int = 600,
    translation_tolerance: float = TRANSLATION_TOLERANCE,
    ranking: str = DEFAULT_RANKING,
    workers: int = 0,
    clips: Sequence[slice] | None = None,
) -> MotionAnalysis:
    """Key frames, joint importance and elimination priority of a motion (Eqs. 1-3).

    Parameters
    ----------
    motion : the clip, at least two frames.
    locked : names of joints never to freeze (the root never is).
    max_frames : above this many frames, analyse an evenly spaced subsample of this size
        (see the module notes for how that changes the result).
    translation_tolerance : a joint whose translation range exceeds this fraction of its bone
        length translates and is never frozen (translating_joints).
    ranking : how joints are ordered for elimination, one of ranking.RANKINGS.
    workers : threads of Eq. 1's table (0: every core); the result does not depend on it.
    clips : the frames of each clip when the motion is several played one after another
        (clips.join_clips); above ``max_frames``, the subsample spreads over each clip.

    Returns
    -------
    MotionAnalysis; where every bone has zero length (every joint sits on the root in every
    frame), joint positions show no rotation, so Eqs. 1-3 are undefined: r_max 0, importance 0
    and no joint in ``priority`` (nothing freezes).
    """
    check_analysis_options(max_frames, translation_tolerance, ranking, workers)
    motion.require_rigid("motion LoD")
    skeleton = motion.skeleton
    locked_indices = sorted({skeleton.index(name) for name in locked})
    end_site_locks = [skeleton.names[j] for j in locked_indices if skeleton.end_sites[j]]
    if end_site_locks:
        raise ValueError(f"locked: {end_site_locks[0]!r} is an end site, not a joint")

    if motion.frame_count > max_frames:
        frames = (
            spread_frames(motion.frame_count, max_frames) if clips is None else spread_over_clips(clips, max_frames)
        )
    else:
        frames = np.arange(motion.frame_count, dtype=np.int64)
    r_max = _r_max(motion)
    translating = translating_joints(motion, translation_tolerance)
    candidates = np.ones(skeleton.joint_count, bool)
    if r_max > 0.0:
        sums = posture_error_row_sums(motion, frames, r_max, ranking != PAPER_RANKING, workers)
        best = np.argmin(sums, axis=1)  # Eq. 2 (first minimum on ties)
        key_frames = frames[best]
        importance = sums[np.arange(skeleton.joint_count), best] / frames.size  # Eq. 3
    else:  # every joint on the root in every frame: positions show no rotation, nothing freezes
        key_frames = np.full(skeleton.joint_count, frames[0])
        importance = np.zeros(skeleton.joint_count)
        candidates[:] = False
    candidates[0] = False
    candidates[skeleton.end_sites] = False
    candidates[locked_indices] = False
    candidates[translating] = False
    scores = rank_scores(ranking, motion, importance, key_frames, frames, candidates)
    return MotionAnalysis(
        key_frames,
        importance,
        elimination_order(scores, candidates),
        locked_indices,
        frames,
        r_max,
        [int(j) for j in np.flatnonzero(translating)],
        ranking,
        clips=tuple(clips or ()),
    )
