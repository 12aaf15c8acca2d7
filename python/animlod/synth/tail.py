"""A tail with two clips: one joint choice must serve a clip that moves all of it and one that
moves part of it (animal captures: a tail's idle beside a clip of its base alone)."""

from __future__ import annotations

import numpy as np

from .. import rotations
from ..model import Motion, Skeleton
from ..motion_lod.clips import join_clips


def tail_clips(joints: int = 20, wave_frames: int = 60, fps: float = 12.0) -> tuple[Motion, list[slice]]:
    """A tail of ``joints`` joints in a row along y (bones of 0.1) and an end site: a wave that
    runs down all of it (0.15 rad about z, one cycle a second, each joint 0.03 s behind its
    parent), then a one-second curl of its first half alone (0.1 rad about x); the two clips
    played one after another (:func:`~animlod.motion_lod.clips.join_clips`), with their frames."""
    skeleton = Skeleton(
        [f"J{j}" for j in range(joints)] + ["J_End"],
        list(range(-1, joints)),
        [[0.0, 0.0, 0.0]] + [[0.0, 0.1, 0.0]] * joints,
        end_sites=[False] * joints + [True],
    )
    t = np.arange(wave_frames) / fps
    wave = rotations.identity((wave_frames, joints + 1))
    delay = 0.03 * np.arange(1, joints)
    wave[:, 1:joints] = rotations.from_axis_angle(
        np.array([0.0, 0.0, 1.0]), 0.15 * np.sin(2 * np.pi * (t[:, None] - delay))
    )
    curl_frames = int(round(fps))
    curl = rotations.identity((curl_frames, joints + 1))
    turn = rotations.from_axis_angle(np.array([1.0, 0.0, 0.0]), 0.1 * np.sin(np.pi * np.arange(curl_frames) / fps))
    curl[:, 1 : joints // 2] = turn[:, None]
    clips = [Motion(skeleton, np.zeros((len(r), 3)), r, fps=fps, name=n) for n, r in (("wave", wave), ("curl", curl))]
    return join_clips(clips)
