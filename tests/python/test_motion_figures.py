"""Small hand-built motions for the motion LoD tests (imported by the other test_motion_* files)."""

from __future__ import annotations

import numpy as np

from animlod import rotations
from animlod.model import Motion, Skeleton

Z = np.array([0.0, 0.0, 1.0])
X = np.array([1.0, 0.0, 0.0])


def chain_motion(angles_a: np.ndarray, root_angles: np.ndarray | None = None) -> Motion:
    """root -> A (length 1) -> B (length 2) -> B_End (length 0.5); A turns about z by ``angles_a``.

    B never rotates; the root turns about x by ``root_angles`` (zero by default).
    """
    angles_a = np.asarray(angles_a, dtype=np.float64)
    frames = angles_a.size
    skeleton = Skeleton(
        ["root", "A", "B", "B_End"],
        [-1, 0, 1, 2],
        [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.5, 0.0]],
        end_sites=[False, False, False, True],
    )
    local = rotations.identity((frames, 4))
    local[:, 1] = rotations.from_axis_angle(Z, angles_a)
    if root_angles is not None:
        local[:, 0] = rotations.from_axis_angle(X, np.asarray(root_angles, dtype=np.float64))
    return Motion(skeleton, np.zeros((frames, 3)), local, fps=30.0)


def figure_motion(frames: int = 24, spine_lean: float = 0.0) -> Motion:
    """A 12-joint, 4-end-site figure with two legs, a spine and two arms, every joint moving
    except ``LeftWrist``; the root walks forward and sways. The hips and the spine's base lie in
    one plane (a flat rigid group) unless ``spine_lean`` moves the spine's base out of it."""
    rows = [
        ("Hips", -1, (0.0, 1.0, 0.0)),
        ("LeftHip", 0, (0.1, -0.05, 0.0)),
        ("LeftKnee", 1, (0.0, -0.45, 0.02)),
        ("LeftKnee_End", 2, (0.0, -0.45, -0.02)),
        ("RightHip", 0, (-0.1, -0.05, 0.0)),
        ("RightKnee", 4, (0.0, -0.45, 0.02)),
        ("RightKnee_End", 5, (0.0, -0.45, -0.02)),
        ("Spine", 0, (0.0, 0.2, spine_lean)),
        ("Chest", 7, (0.0, 0.25, 0.01)),
        ("LeftShoulder", 8, (0.18, 0.1, 0.0)),
        ("LeftElbow", 9, (0.28, 0.0, 0.0)),
        ("LeftWrist", 10, (0.25, 0.0, 0.01)),
        ("LeftWrist_End", 11, (0.08, 0.0, 0.0)),
        ("RightShoulder", 8, (-0.18, 0.1, 0.0)),
        ("RightElbow", 13, (-0.28, 0.0, 0.0)),
        ("RightElbow_End", 14, (-0.25, 0.0, 0.01)),
    ]
    names = [r[0] for r in rows]
    skeleton = Skeleton(
        names,
        [r[1] for r in rows],
        [r[2] for r in rows],
        end_sites=[n.endswith("_End") for n in names],
    )
    t = np.linspace(0.0, 2.0 * np.pi, frames, endpoint=False)
    amplitude = {
        "Hips": 0.1, "LeftHip": 0.5, "LeftKnee": 0.6, "RightHip": -0.5, "RightKnee": 0.5, "Spine": 0.08,
        "Chest": 0.12, "LeftShoulder": 0.3, "LeftElbow": 0.7, "RightShoulder": -0.3, "RightElbow": 0.6,
    }  # fmt: skip
    local = rotations.identity((frames, len(names)))
    for k, (name, value) in enumerate(amplitude.items()):
        axis = np.array([1.0, 0.3 * np.sin(k), 0.2 * np.cos(k)])
        angle = value * np.sin(t + 0.4 * k) + 0.2 * value
        local[:, names.index(name)] = rotations.from_axis_angle(axis / np.linalg.norm(axis), angle)
    root = np.stack([0.05 * np.sin(2 * t), 1.0 + 0.02 * np.cos(2 * t), 0.3 * t], axis=-1)
    return Motion(skeleton, root, local, fps=30.0, name="figure")


def test_figure_motion_is_a_valid_clip() -> None:
    motion = figure_motion()
    positions = motion.world_positions()
    assert positions.shape == (24, 16, 3)
    # Left wrist never rotates: the wrist-to-end vector is fixed in the elbow's frame.
    wrist = motion.local_rotations[:, motion.skeleton.index("LeftWrist")]
    assert np.array_equal(wrist, np.broadcast_to(wrist[0], wrist.shape))
