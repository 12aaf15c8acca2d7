"""Joint elimination orders: Eq. 3 with zero-length bones looked through, as printed, by depth
and by rotation variance."""

from __future__ import annotations

import numpy as np
import pytest
from test_motion_figures import Z, figure_motion

from animlod import rotations
from animlod.model import Motion, Skeleton
from animlod.motion_lod import RANKINGS, analyze_motion
from animlod.motion_lod.chain import build_level
from animlod.motion_lod.ranking import joint_depths, rotation_variance


def zero_length_motion(frames: int = 20) -> Motion:
    """root -> A (length 1, turns) -> Z (at A's position, still) -> C (length 1) -> C_End.

    A's only child sits on A: as printed, Eq. 1 sees no bone of A and gives it importance 0,
    although A's rotation swings C and its end site.
    """
    skeleton = Skeleton(
        ["root", "A", "Z", "C", "C_End"],
        [-1, 0, 1, 2, 3],
        [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.5, 0.0]],
        end_sites=[False, False, False, False, True],
    )
    local = rotations.identity((frames, 5))
    local[:, 1] = rotations.from_axis_angle(Z, np.linspace(-0.8, 0.8, frames))
    local[:, 3] = rotations.from_axis_angle(Z, 0.3 * np.sin(np.linspace(0, 6, frames)))
    return Motion(skeleton, np.zeros((frames, 3)), local, fps=30.0)


def test_zero_length_bones_are_measured_through_the_joints_below() -> None:
    motion = zero_length_motion()
    names = motion.skeleton.names
    paper = analyze_motion(motion, ranking="paper")
    looked = analyze_motion(motion)
    assert paper.importance[1] == 0.0 and looked.importance[1] > 0.1 * looked.importance.max()
    assert looked.importance[2] == 0.0  # Z never turns: still nothing to lose
    assert [names[j] for j in paper.priority] == ["A", "Z", "C"]  # ties at 0 by index: A first
    assert [names[j] for j in looked.priority] == ["Z", "C", "A"]
    # After the same re-fit: one joint frozen costs nothing either way (Z, at A's position, can
    # take over A's turn), two cost far more in the printed order, which loses A's swing.
    assert build_level(motion, looked, 3).report.max_error < 1e-9
    assert build_level(motion, paper, 3).report.max_error < 1e-9
    looked_error = build_level(motion, looked, 2).report.mean_error
    paper_error = build_level(motion, paper, 2).report.mean_error
    assert looked_error < 0.5 * paper_error


def test_depth_and_variance_orders() -> None:
    motion = figure_motion()
    names = motion.skeleton.names
    depth = joint_depths(motion.skeleton.parents)
    assert depth[names.index("LeftWrist")] == 5 and depth[names.index("Hips")] == 0
    by_depth = analyze_motion(motion, ranking="depth").priority
    assert list(depth[by_depth]) == sorted(depth[by_depth], reverse=True)
    variance = rotation_variance(motion, np.arange(motion.frame_count))
    assert variance[names.index("LeftWrist")] == pytest.approx(0.0, abs=1e-24)
    by_variance = analyze_motion(motion, ranking="variance").priority
    assert names[by_variance[0]] == "LeftWrist" and list(variance[by_variance]) == sorted(variance[by_variance])
    # Every ranking orders the same candidates and shares the key frames but "paper".
    analyses = {name: analyze_motion(motion, ranking=name) for name in RANKINGS}
    assert all(sorted(a.priority) == sorted(by_depth) for a in analyses.values())
    np.testing.assert_array_equal(analyses["depth"].key_frames, analyses["importance"].key_frames)


def test_an_unknown_ranking_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match="ranking: expected one of importance, paper, depth, variance, got 'abc'"):
        analyze_motion(figure_motion(), ranking="abc")
