"""One motion from several clips: animations that each move different joints
(:func:`merge_split_clips`), or clips played one after another (:func:`join_clips`).

Some exporters store one motion as many glTF animations, one per joint node (Monster.glb of the
development data: 32 animations of 101 keys, each moving one node). Read one by one they are 32
motions in which a single joint moves, and motion LoD of any one of them has nothing to simplify.
When every clip has the same frames and no joint moves in two of them, they are one motion split
by joint, and :func:`merge_split_clips` puts it back together.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .. import rotations
from ..model import Motion, spread_frames

# A channel moves when it leaves its rest value by more than this (radians, or this fraction of
# the skeleton's longest offset): exporters' float noise stays below.
_MOVE_TOLERANCE = 1e-6


def moving_joints(motion: Motion) -> np.ndarray:
    """Joints whose rotation or translation leaves its rest value in some frame, ``(J,) bool``
    (the root also when it travels)."""
    skeleton = motion.skeleton
    rest = skeleton.rest_rotations
    if rest is None:
        rest = rotations.identity((skeleton.joint_count,))
    turn = np.abs(np.sum(motion.local_rotations * rest, axis=-1))  # |cos(angle / 2)|
    moving = (1.0 - np.minimum(turn, 1.0)).max(axis=0) > 0.5 * _MOVE_TOLERANCE**2
    scale = max(float(np.abs(skeleton.offsets[1:]).max(initial=0.0)), 1e-12)
    translations = motion.local_translations()
    rest_translations = skeleton.offsets.copy()
    rest_translations[0] = translations[0, 0]
    moving |= np.abs(translations - rest_translations).max(axis=(0, 2)) > _MOVE_TOLERANCE * scale
    return moving


def merge_split_clips(motions: Sequence[Motion]) -> Motion | None:
    """The motion the clips were split from, or None when they are not one motion split by joint.

    They are when there are at least two, on one skeleton, with the same frame count and rate,
    and no joint moves in two of them. Each joint then takes its channels from the clip that
    moves it (its rest values where none does).
    """
    if len(motions) < 2:
        return None
    first = motions[0]
    if any(m.skeleton.names != first.skeleton.names for m in motions):
        return None
    if any(m.frame_count != first.frame_count or m.fps != first.fps for m in motions):
        return None
    owners = np.full(first.skeleton.joint_count, -1)
    for index, motion in enumerate(motions):
        moving = moving_joints(motion)
        if np.any(moving & (owners >= 0)):
            return None  # a joint moves in two clips: separate motions, not one split
        owners[moving] = index
    if len(set(owners[owners >= 0].tolist())) < 2:
        return None  # at most one clip moves anything
    source = np.maximum(owners, 0)
    joints = np.arange(first.skeleton.joint_count)
    local = np.stack([m.local_rotations for m in motions])[source, :, joints].transpose(1, 0, 2)
    translations = np.stack([m.local_translations() for m in motions])[source, :, joints].transpose(1, 0, 2)
    moved_translation = any(m.joint_translations is not None for m in motions)
    return Motion(
        first.skeleton,
        translations[:, 0],
        local,
        first.fps,
        "merged",
        translations if moved_translation else None,
    )


def join_clips(motions: Sequence[Motion]) -> tuple[Motion, list[slice]]:
    """The clips one after another as one motion (one analysis, one reduced skeleton for all; the
    caller's to check they share a skeleton and rate), named by their names joined with ``+``, and
    each clip's frames in it."""
    starts = np.cumsum([0] + [motion.frame_count for motion in motions])
    spans = [slice(int(a), int(b)) for a, b in zip(starts[:-1], starts[1:])]
    return Motion.concatenate(list(motions), "+".join(motion.name for motion in motions)), spans


def spread_over_clips(spans: Sequence[slice], count: int) -> np.ndarray:
    """Frame indices of a joined motion (:func:`join_clips`' spans) spread over each clip in
    proportion to its length, both ends of each included, and at least two of each clip's frames
    where it has them: ``count`` evenly spaced frames over the whole would skip a short clip (a
    pose of three frames among thousands), whose joints then seem still."""
    lengths = np.array([span.stop - span.start for span in spans])
    shares = np.maximum(np.minimum(lengths, 2), count * lengths // max(int(lengths.sum()), 1))
    return np.concatenate([span.start + spread_frames(n, k) for span, n, k in zip(spans, lengths, shares)])
