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
  level's skeleton, which the string term Es (or the hard constraints) asks for.
"""

from __future__ import annotations

import numpy as np

from .. import rotations
from ..model import Motion, Skeleton
from .frozen import FrozenLevel, held_translations
from .ranking import joint_depths

# Child offsets shorter than this fraction of the level's extent give no direction.
_SHORT = 1e-9


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


def _swing(from_vectors: np.ndarray, to_vectors: np.ndarray) -> np.ndarray:
    """Smallest rotations ``(T, 4)`` turning ``from_vectors (T, 3)`` towards ``to_vectors (T, 3)``.

    Identity where either vector is zero; a half turn about a perpendicular axis when opposite.
    """
    a = from_vectors / np.maximum(np.linalg.norm(from_vectors, axis=-1, keepdims=True), 1e-300)
    b = to_vectors / np.maximum(np.linalg.norm(to_vectors, axis=-1, keepdims=True), 1e-300)
    q = np.concatenate([rotations.cross(a, b), 1.0 + np.sum(a * b, axis=-1, keepdims=True)], axis=-1)
    opposite = np.linalg.norm(q, axis=-1) < 1e-12
    if opposite.any():
        helper = np.where(np.abs(a[opposite, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        axis = np.cross(a[opposite], helper)
        q[opposite] = np.concatenate(
            [axis / np.linalg.norm(axis, axis=-1, keepdims=True), np.zeros((axis.shape[0], 1))], -1
        )
    zero = (np.linalg.norm(from_vectors, axis=-1) == 0.0) | (np.linalg.norm(to_vectors, axis=-1) == 0.0)
    q[zero] = rotations.identity()
    return rotations.normalize(q)


def _best_fit_rotation(from_vectors: np.ndarray, to_vectors: np.ndarray) -> np.ndarray:
    """Rotations ``(T, 4)`` minimising sum_i |R a_i - d_i|^2 (Kabsch), ``a, d (T, N, 3)``."""
    covariance = np.einsum("tni,tnj->tij", to_vectors, from_vectors)
    u, _, vt = np.linalg.svd(covariance)
    sign = np.sign(np.linalg.det(u @ vt))
    u[:, :, 2] *= sign[:, None]
    return rotations.from_matrix(u @ vt)


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
    translations = _folded_offsets(level, motion.local_translations())  # (T, K, 3)
    original_world = rotations.from_matrix(motion.world_transforms()[:, kept, :3, :3])
    targets = positions[:, kept]
    scale = level.length_scale()
    children = skeleton.children()
    static_offsets = np.linalg.norm(skeleton.offsets, axis=-1)

    world = np.empty_like(original_world)
    placed = np.empty_like(targets)  # where forward kinematics has put each joint so far
    placed[:, 0] = targets[:, 0]
    translating = level.animated[kept]
    # Children at a fixed offset give a joint its direction; a translating child is placed by its
    # own translation, whatever this rotation is. Aimed by a best-fit rotation when they span a
    # plane, else by the swing towards the longest.
    useful = [[c for c in children[j] if static_offsets[c] > _SHORT * scale and not translating[c]]
              for j in range(skeleton.joint_count)]  # fmt: skip
    planar = np.array([_spans_a_plane(skeleton.offsets[u]) for u in useful], bool)
    depth = joint_depths(skeleton.parents)
    for layer in range(int(depth.max()) + 1):  # joints of one depth at once: O(depth) numpy steps
        joints = np.flatnonzero(depth == layer)
        parents = skeleton.parents[joints]
        if layer > 0:
            moving = translating[joints]  # no fixed bone: the translation follows the re-fit
            if moving.any():
                j, p = joints[moving], parents[moving]
                translations[:, j] = rotations.rotate(rotations.conjugate(world[:, p]), targets[:, j] - placed[:, p])
            placed[:, joints] = placed[:, parents] + rotations.rotate(world[:, parents], translations[:, joints])
        world[:, joints] = original_world[:, joints]
        # Aim from where each joint really is, so that misfits do not pile up down a chain.
        aimed = [j for j in joints if useful[j] and not planar[j]]
        if aimed:
            longest = [useful[j][int(np.argmax(static_offsets[useful[j]]))] for j in aimed]
            offsets = rotations.rotate(world[:, aimed], translations[:, longest])
            wanted = targets[:, longest] - placed[:, aimed]
            world[:, aimed] = rotations.multiply(_swing(offsets, wanted), world[:, aimed])
        for j in (j for j in joints if planar[j]):  # a few per skeleton (hips, chest, hands)
            offsets = rotations.rotate(world[:, j, None], translations[:, useful[j]])
            wanted = targets[:, useful[j]] - placed[:, j, None]
            world[:, j] = rotations.multiply(_best_fit_rotation(offsets, wanted), world[:, j])
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
