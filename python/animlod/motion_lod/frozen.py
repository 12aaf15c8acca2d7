"""Frozen joints (Section 5.1): what one level keeps, and the key-posture geometry it holds.

A frozen joint keeps the local transform of its key frame (Eq. 2) for the whole clip. Every
kept point then hangs from its *nearest kept ancestor* through the frozen joints between them,
whose key transforms fold into one constant transform: the kept point's new offset is
``fold_translation + fold_rotation @ offset`` and its rotation is preceded by ``fold_rotation``.

End sites (see analysis.py) are never counted as joints of a level; an end site is kept when its
joint is kept and dropped with it when that joint is frozen. Markers (MotionAnalysis.markers) are
never kept: placed from their joint, they are measured and not re-fitted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import rotations
from ..model import Motion, Skeleton
from .analysis import MotionAnalysis


@dataclass(frozen=True)
class FrozenLevel:
    """One level's split of the original skeleton into kept and frozen points (``J`` points).

    Attributes
    ----------
    skeleton : the original skeleton.
    frozen : (J,) bool joints frozen at this level.
    kept : (J,) bool points in the level's skeleton (not frozen, not an end site of a frozen joint,
        not a marker).
    kept_parent : (J,) int64 nearest kept ancestor of each kept point, -1 for the root and for
        points that are not kept.
    key_rotations : (J, 4) local rotations of the key posture (Section 4.2).
    key_translations : (J, 3) local translations of the key posture (root at the origin).
    key_positions : (J, 3) world positions of the key posture.
    fold_rotations : (J, 4) product of the key rotations of the frozen joints between a kept
        point and its kept parent (identity when there are none).
    fold_translations : (J, 3) their combined translation, in the kept parent's frame.
    animated : (J,) bool translating joints (analysis.translating_joints): their bone is not rigid.
    measured : (J,) bool points the level's errors count (all but MotionAnalysis.hidden).
    """

    skeleton: Skeleton
    frozen: np.ndarray
    kept: np.ndarray
    kept_parent: np.ndarray
    key_rotations: np.ndarray
    key_translations: np.ndarray
    key_positions: np.ndarray
    fold_rotations: np.ndarray
    fold_translations: np.ndarray
    animated: np.ndarray
    measured: np.ndarray

    @property
    def kept_indices(self) -> np.ndarray:
        """Original indices of the kept points, in order (the level skeleton's joint order)."""
        return np.flatnonzero(self.kept)

    @property
    def joint_count(self) -> int:
        """Joints of the level, end sites not counted."""
        return int(np.count_nonzero(self.kept & ~self.skeleton.end_sites))

    def length_scale(self) -> float:
        """Diagonal of the key posture's bounding box, the objective's length unit; 1 where every
        point coincides (every bone of zero length: analyze_motion freezes nothing then, so the
        only level is the input's, with nothing to re-fit)."""
        extent = float(np.linalg.norm(np.ptp(self.key_positions, axis=0)))
        return extent if extent > 0.0 else 1.0


def freeze(motion: Motion, analysis: MotionAnalysis, frozen_joints: list[int] | np.ndarray) -> FrozenLevel:
    """Freeze ``frozen_joints`` (original indices) of ``motion`` at their key frames.

    Raises ValueError for the root, an end site, a locked joint or a translating one that is not
    hidden (MotionAnalysis.hidden; its translation is then held at the key posture).
    """
    skeleton = motion.skeleton
    count = skeleton.joint_count
    frozen = np.zeros(count, bool)
    frozen[np.asarray(frozen_joints, dtype=np.int64)] = True
    animated = np.zeros(count, bool)
    animated[analysis.translating] = True
    hidden = np.zeros(count, bool)
    hidden[analysis.hidden] = True
    forbidden = frozen & (skeleton.end_sites | (animated & ~hidden))
    forbidden[0] |= frozen[0]
    forbidden[analysis.locked] |= frozen[analysis.locked]
    if forbidden.any():
        name = skeleton.names[int(np.argmax(forbidden))]
        raise ValueError(f"frozen joints: {name!r} cannot be frozen (root, end site, locked or translating)")

    kept = ~frozen
    end_site_parents = skeleton.parents[skeleton.end_sites]
    kept[np.flatnonzero(skeleton.end_sites)[frozen[end_site_parents]]] = False
    kept[analysis.markers] = False
    measured = ~hidden

    key_rotations = analysis.key_rotations(motion)
    key_translations = analysis.key_translations(motion)
    key_translations[0] = 0.0
    key_motion = Motion(
        skeleton, key_translations[None, 0], key_rotations[None], fps=1.0, joint_translations=key_translations[None]
    )
    key_positions = key_motion.world_positions()[0]

    kept_parent = np.full(count, -1, dtype=np.int64)
    fold_rotations = rotations.identity((count,))
    fold_translations = np.zeros((count, 3))
    for joint in np.flatnonzero(kept)[1:]:
        chain = []
        ancestor = int(skeleton.parents[joint])
        while frozen[ancestor]:
            chain.append(ancestor)
            ancestor = int(skeleton.parents[ancestor])
        kept_parent[joint] = ancestor
        for frozen_joint in reversed(chain):  # top-down: T(t_r1) R_r1 T(t_r2) R_r2 ...
            fold_translations[joint] += rotations.rotate(fold_rotations[joint], key_translations[frozen_joint])
            fold_rotations[joint] = rotations.multiply(fold_rotations[joint], key_rotations[frozen_joint])
    return FrozenLevel(
        skeleton,
        frozen,
        kept,
        kept_parent,
        key_rotations,
        key_translations,
        key_positions,
        fold_rotations,
        fold_translations,
        animated,
        measured,
    )


def frozen_motion(level: FrozenLevel, motion: Motion) -> Motion:
    """``motion`` with every frozen joint held at its key rotation and translation (no re-fit).

    Its positions satisfy every bone length and frozen angle of the level exactly, so they are
    the re-fit's safe fallback and a good starting point.
    """
    local = motion.local_rotations.copy()
    frozen = np.flatnonzero(level.frozen)
    local[:, frozen] = level.key_rotations[frozen]
    return Motion(
        motion.skeleton, motion.root_positions, local, motion.fps, motion.name, held_translations(level, motion)
    )


def held_translations(level: FrozenLevel, motion: Motion) -> np.ndarray | None:
    """``motion.joint_translations`` with every joint that does not translate held at its key
    frame's translation, or None when the motion has none: a frozen joint (one with a small real
    translation can freeze) and a kept joint whose bone the level holds rigid. Exporters key
    every joint's translation, with float noise (or a motion under the translation tolerance);
    the re-fit holds those bones at their key lengths, and forward kinematics through the
    per-frame keys missed its positions by that noise, as did the frozen motion, the re-fit's
    fallback, whose lengths must hold exactly."""
    if motion.joint_translations is None:
        return None
    return held_local_translations(level, motion)


def held_local_translations(level: FrozenLevel, motion: Motion) -> np.ndarray:
    """``motion.local_translations()`` (root positions in column 0) with the translations of
    :func:`held_translations`; the input's own where nothing is frozen (no re-fit: the level is
    the input)."""
    translations = motion.local_translations()
    if not level.frozen.any():
        return translations
    held = ~level.animated
    held[0] = False  # the root's column is its path
    translations[:, held] = level.key_translations[held]
    return translations
