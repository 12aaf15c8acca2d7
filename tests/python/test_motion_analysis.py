"""Motion analysis (Eqs. 1-3): hand-computed values, still joints, priority, subsampling."""

from __future__ import annotations

import numpy as np
import pytest
from test_motion_figures import chain_motion, figure_motion

from animlod.motion_lod import analyze_motion
from animlod.motion_lod.analysis import child_bones, posture_error_row_sums


def test_eq1_to_eq3_on_a_three_joint_chain() -> None:
    # A turns by 0, 0.5, 1.0 rad; its child bone has r = 2 in every frame; r_max = |root->A| = 1.
    # E_A(a, b) = (2 + 2) / 2 |phi_a - phi_b| / (2 pi) = |phi_a - phi_b| / pi (Eq. 1: an arc of
    # the mean radius), so the row sums are 1.5/pi, 1/pi, 1.5/pi.
    motion = chain_motion([0.0, 0.5, 1.0])
    sums = posture_error_row_sums(motion, np.arange(3), r_max=1.0)
    np.testing.assert_allclose(sums[1], [1.5 / np.pi, 1 / np.pi, 1.5 / np.pi], rtol=1e-14)
    analysis = analyze_motion(motion)
    assert analysis.r_max == pytest.approx(1.0)
    assert analysis.key_frames[1] == 1  # Eq. 2: the middle frame has the smallest row sum
    assert analysis.importance[1] == pytest.approx(1 / (3 * np.pi), rel=1e-14)  # Eq. 3
    assert analysis.importance[2] == 0.0  # B never rotates
    assert analysis.importance[3] == 0.0  # an end site
    assert analysis.priority == [2, 1]  # lowest first; never the root or an end site


def _numpy_row_sums(motion, frames, r_max, look_through):
    """Eq. 1's row sums from full (n, n) angle tables (Kahan's form on every pair), per bone."""
    owners, vectors = child_bones(motion, frames, look_through)
    lengths = np.linalg.norm(vectors, axis=-1)
    units = np.divide(vectors, lengths[..., None], out=np.zeros_like(vectors), where=lengths[..., None] > 0.0)
    a, b = units[:, None], units[None, :]  # (n, 1, B, 3), (1, n, B, 3)
    theta = 2.0 * np.arctan2(np.linalg.norm(a - b, axis=-1), np.linalg.norm(a + b, axis=-1))  # (n, n, B)
    arcs = 0.5 * (lengths[:, None] + lengths[None, :]) * theta
    sums = np.zeros((motion.skeleton.joint_count, frames.size))
    np.add.at(sums, owners, arcs.sum(axis=1).T)
    return sums / (2.0 * np.pi * r_max)


@pytest.mark.parametrize("look_through", [False, True])
def test_core_row_sums_match_full_angle_tables(look_through: bool) -> None:
    motion = figure_motion(frames=30)
    frames = np.arange(30)
    expected = _numpy_row_sums(motion, frames, 0.7, look_through)
    for workers in (1, 2):
        got = posture_error_row_sums(motion, frames, 0.7, look_through, workers)
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-15 * expected.max())


def test_a_still_joint_has_zero_importance_however_its_ancestors_move() -> None:
    still = analyze_motion(chain_motion([0.0, 0.5, 1.0], root_angles=[0.0, 0.7, -0.4]))
    assert still.importance[2] == 0.0
    assert still.importance[0] > 0.0  # the root's own turn is measured
    # A's error is measured in the root's frame, so the root's turn does not change it.
    assert still.importance[1] == pytest.approx(1 / (3 * np.pi), rel=1e-12)


def test_figure_priority_puts_the_still_wrist_first_and_respects_locks() -> None:
    motion = figure_motion()
    analysis = analyze_motion(motion)
    names = motion.skeleton.names
    assert names[analysis.priority[0]] == "LeftWrist"
    assert analysis.importance[names.index("LeftWrist")] == 0.0
    assert len(analysis.priority) == 11  # 12 joints, not the root
    locked = analyze_motion(motion, locked=["LeftWrist", "Chest"])
    assert names.index("LeftWrist") not in locked.priority
    assert names.index("Chest") not in locked.priority
    assert len(locked.priority) == 9
    key = analysis.key_rotations(motion)
    joints = np.arange(motion.skeleton.joint_count)
    np.testing.assert_array_equal(key, motion.local_rotations[analysis.key_frames, joints])


def test_subsampling_analyses_evenly_spaced_frames() -> None:
    motion = figure_motion(frames=40)
    analysis = analyze_motion(motion, max_frames=10)
    assert analysis.frames.size == 10
    assert analysis.frames[0] == 0 and analysis.frames[-1] == 39
    assert np.all(np.isin(analysis.key_frames, analysis.frames))
    full = analyze_motion(motion)
    # A uniform subsample estimates the same mean: close, not equal.
    moving = full.importance > 0
    np.testing.assert_allclose(analysis.importance[moving], full.importance[moving], rtol=0.25)


def test_a_single_pose_analyses_to_no_motion_and_freezes_exactly() -> None:
    """One frame (a pose; a glTF clip of one key): no joint moves, so every importance is 0 and
    every key posture is that frame, and the fewest joints reproduce it to rounding. It was
    refused ("at least 2 frames"), and with it `animlod character` on a posed character."""
    from animlod.motion_lod import build_motion_chain

    motion = figure_motion().take_frames(np.array([5]))
    analysis = analyze_motion(motion)
    assert np.all(analysis.importance == 0.0) and np.all(analysis.key_frames == 0)
    chain = build_motion_chain(motion, 3)
    assert chain.levels[-1].report.joint_count < chain.levels[0].report.joint_count
    assert max(level.report.max_error for level in chain.levels) < 1e-9


def test_bad_input_is_refused_with_a_reason() -> None:
    with pytest.raises(ValueError, match="no joint named 'Elbow'"):
        analyze_motion(chain_motion([0.0, 1.0]), locked=["Elbow"])
    with pytest.raises(ValueError, match="end site"):
        analyze_motion(chain_motion([0.0, 1.0]), locked=["B_End"])
    with pytest.raises(ValueError, match="workers: must be >= 0"):
        analyze_motion(chain_motion([0.0, 1.0]), workers=-1)


def test_real_clip_analysis(data_dir) -> None:
    from animlod.io.bvh import read_bvh

    motion = read_bvh(data_dir / "bvh" / "131_01.bvh")
    analysis = analyze_motion(motion, max_frames=200)
    skeleton = motion.skeleton
    assert len(analysis.priority) == int((~skeleton.end_sites).sum()) - 1
    assert np.all(analysis.importance >= 0.0)
    assert np.all(analysis.importance[skeleton.end_sites] == 0.0)
    ordered = analysis.importance[analysis.priority]
    assert np.all(np.diff(ordered) >= 0.0)


def test_a_long_run_of_clips_is_analysed_clip_by_clip() -> None:
    """Above max_frames the analysis took evenly spaced frames over the whole joined motion, and a
    short clip among long ones (a three-frame pose) fell between them: its bend was never seen."""
    from animlod.motion_lod.clips import join_clips

    walk = figure_motion(frames=400)
    pose = figure_motion(frames=3)
    joined, spans = join_clips([walk, pose, walk])
    evenly = analyze_motion(joined, max_frames=50)
    by_clip = analyze_motion(joined, max_frames=50, clips=spans)
    assert not np.isin(np.arange(400, 403), evenly.frames).any()
    assert np.isin([400, 402], by_clip.frames).all() and len(by_clip.frames) <= 50 + 2 * len(spans)
