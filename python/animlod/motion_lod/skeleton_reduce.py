"""The simplified skeleton of a level and its motion, recovered from re-fitted positions.

Section 5.2 ends with "the local transformation value of each joint is recovered from the
optimisation result x_j(t) and the hierarchical information of each joint". Here:

- The level's skeleton keeps the kept points in their original order; each hangs from its
  nearest kept ancestor with the offset of the key posture (frozen joints folded in, see
  frozen.py).
- Each kept joint's world rotation starts from its original world rotation (so a bone keeps its
  original twist) and is corrected by the smallest rotation that carries its children's offsets
  onto the re-fitted child positions, aimed from where forward kinematics has put the joint:
  the swing onto the longest child when it has one child (or only collinear ones), the best-fit
  rotation (Kabsch) when it has several, none when it has no child. A translating joint (no
  fixed bone) takes the translation that puts it at its re-fitted position. Forward kinematics
  then reproduces the re-fitted positions exactly wherever they are rigid with respect to the
  level's skeleton, which the string term Es (or the hard constraints) asks for. The per-frame
  loop is the core's (``recover_world_rotations``, motion_recovery.hpp); this module prepares the
  level's skeleton and which children aim each joint.
"""

from __future__ import annotations

import numpy as np

from .. import _core, rotations
from ..model import Motion, Skeleton
from .analysis import ZERO_LENGTH
from .frozen import FrozenLevel, held_local_translations, held_translations


def reduce_skeleton(level: FrozenLevel) -> Skeleton:
    """The level's skeleton: kept points, parents = nearest kept ancestors, folded key offsets."""
    skeleton = level.skeleton
    kept = level.kept_indices
    new_index = np.full(skeleton.joint_count, -1, dtype=np.int64)
    new_index[kept] = np.arange(kept.size)
    parents = np.where(level.kept_parent[kept] >= 0, new_index[level.kept_parent[kept]], -1)
    offsets = _folded_offsets(level, skeleton.offsets[None])[0]
    offsets[0] = skeleton.offsets[0]
    rest = rotations.multiply(level.fold_rotations[kept], skeleton.rest_rotations[kept])
    return Skeleton([skeleton.names[j] for j in kept], parents, offsets, rest, skeleton.end_sites[kept])


def _folded_offsets(level: FrozenLevel, translations: np.ndarray) -> np.ndarray:
    """Kept points' offsets from their kept parents, ``(T, K, 3)``, given original local
    translations ``(T, J, 3)``."""
    kept = level.kept_indices
    return level.fold_translations[kept] + rotations.rotate(level.fold_rotations[kept], translations[:, kept])


def recover_motion(level: FrozenLevel, positions: np.ndarray, motion: Motion) -> Motion:
    """The level's motion whose forward kinematics follows the re-fitted ``positions``.

    Parameters
    ----------
    level : the frozen/kept split.
    positions : (T, J, 3) re-fitted world positions of every original point (root = original).
    motion : the original motion (for twists, root path, translations, fps).

    Returns
    -------
    Motion on :func:`reduce_skeleton` (level).
    """
    skeleton = reduce_skeleton(level)
    kept = level.kept_indices
    scale = level.length_scale()
    static_offsets = np.linalg.norm(skeleton.offsets, axis=-1)
    translating = level.animated[kept]
    # Children at a fixed offset give a joint its direction; a translating child is placed by its
    # own translation, whatever this rotation is. Aimed by a best-fit rotation when they span a
    # plane, else by the swing towards the longest.
    aims = []
    for children in skeleton.children():
        useful = [c for c in children if static_offsets[c] > ZERO_LENGTH * scale and not translating[c]]
        if useful and not _spans_a_plane(skeleton.offsets[useful]):
            useful = [useful[int(np.argmax(static_offsets[useful]))]]
        aims.append(useful)
    world, translations = _core.recover_world_rotations(
        skeleton.parents,
        translating,
        np.cumsum([0] + [len(a) for a in aims]),
        np.array([c for a in aims for c in a], dtype=np.int64),
        rotations.from_matrix(motion.world_transforms()[:, kept, :3, :3]),
        positions[:, kept],
        _folded_offsets(level, held_local_translations(level, motion)),
    )
    local = world.copy()
    local[:, 1:] = rotations.multiply(rotations.conjugate(world[:, skeleton.parents[1:]]), world[:, 1:])
    joint_translations = translations if motion.joint_translations is not None else None
    return Motion(skeleton, positions[:, 0], local, motion.fps, motion.name, joint_translations)


def _spans_a_plane(vectors: np.ndarray) -> bool:
    """True when the offsets ``(N, 3)`` are not all parallel (a best-fit rotation is unique)."""
    if vectors.shape[0] < 2:
        return False
    units = vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)
    return bool(np.linalg.norm(np.cross(units[:, None], units[None]), axis=-1).max() > 1e-6)


def expand_motion(level: FrozenLevel, reduced: Motion, motion: Motion) -> Motion:
    """The level's motion put back on the original skeleton, frozen joints at their key rotations
    and translations.

    Its forward kinematics equals the level's at every kept point, and places the frozen parts
    where the level implicitly carries them, so errors can be measured on every original point.
    """
    kept = level.kept_indices
    local = motion.local_rotations.copy()
    frozen = np.flatnonzero(level.frozen)
    local[:, frozen] = level.key_rotations[frozen]
    local[:, kept] = rotations.multiply(rotations.conjugate(level.fold_rotations[kept]), reduced.local_rotations)
    translations = held_translations(level, motion)
    return Motion(motion.skeleton, reduced.root_positions, local, motion.fps, motion.name, translations)
