"""Joint elimination orders: Eq. 3 with zero-length bones looked through, as printed, by depth,
by rotation variance, cumulative, and the default chosen level by level by a trial re-fit."""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
from test_motion_figures import Z, figure_motion

from animlod import _core, rotations
from animlod.model import Motion, Skeleton
from animlod.motion_lod import RANKINGS, analyze_motion, build_motion_chain, level_joint_counts
from animlod.motion_lod.chain import build_level
from animlod.motion_lod.frozen import freeze, frozen_motion
from animlod.motion_lod.ranking import PROPOSING_RANKINGS, joint_depths, rotation_variance, spread_steps
from animlod.motion_lod.refit_choice import NEGLIGIBLE_ERROR, SEARCH_MARGIN, choose_by_refit, proposers
from animlod.synth import humanoid, humanoid_motion, tail_clips


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
    looked = analyze_motion(motion, ranking="importance")
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
    expected = (
        r"ranking: no ranking named 'abc' \(choose from refit, importance, paper, depth, variance, cumulative, spread\)"
    )
    with pytest.raises(ValueError, match=expected):
        analyze_motion(figure_motion(), ranking="abc")


def test_cumulative_order_freezes_the_joint_that_moves_the_figure_least() -> None:
    # Each step against forward kinematics of the frozen key motion: the incremental rigid moves
    # must pick the joint whose freeze, after those before it, gives the lowest mean point error.
    motion = figure_motion()
    analysis = analyze_motion(motion, ranking="cumulative")
    original = motion.world_positions()
    frozen: list[int] = []

    def error(candidate: int) -> float:
        placed = frozen_motion(freeze(motion, analysis, frozen + [candidate]), motion).world_positions()
        return float(np.linalg.norm(placed - original, axis=-1).mean())

    for joint in analysis.priority:
        errors = {c: error(c) for c in analysis.priority if c not in frozen}
        assert errors[joint] <= min(errors.values()) * (1 + 1e-9) + 1e-15
        frozen.append(joint)
    assert analysis.priority[0] == motion.skeleton.index("LeftWrist")  # never turns: costs nothing


def test_the_core_cumulative_ranking_names_bad_arrays() -> None:
    eye = np.broadcast_to(np.eye(4), (2, 3, 4, 4))
    with pytest.raises(ValueError, match=r"key_local: expected shape \(J, 4, 4\) like world, got \(2, 4, 4\)"):
        _core.cumulative_freeze_steps(eye, np.eye(4)[None].repeat(2, 0), np.array([-1, 0, 1]), np.array([0, 1, 1]))
    with pytest.raises(ValueError, match=r"candidates\[0\]: the root cannot freeze"):
        _core.cumulative_freeze_steps(eye, eye[0], np.array([-1, 0, 1]), np.array([1, 1, 1]))


def test_refit_choice_takes_the_proposal_with_the_lowest_trial_error_and_stays_nested() -> None:
    motion = figure_motion()
    analysis = analyze_motion(motion)
    orders = [propose([]) for propose in proposers(motion, analysis)]
    assert len(orders) == len(PROPOSING_RANKINGS) and all(sorted(o) == sorted(analysis.priority) for o in orders)
    depth_first = orders[PROPOSING_RANKINGS.index("depth")]
    counts = level_joint_counts(motion, analysis, [12, 10, 7, 3])
    trials = []

    def trial_error(level, frames) -> float:  # prefers whatever depth proposes
        trials.append(frames.size)
        chosen = set(np.flatnonzero(level.frozen))
        return float(len(chosen - set(depth_first[: len(chosen)])))

    calls: list[tuple[int, int]] = []
    chosen = choose_by_refit(motion, analysis, counts, trial_error, lambda *call: calls.append(call))
    assert calls == [(1, 3), (2, 3), (3, 3)]
    assert chosen.priority[:9] == depth_first[:9] or sorted(chosen.priority[:9]) == sorted(depth_first[:9])
    assert sorted(chosen.priority) == sorted(analysis.priority)
    assert trials and set(trials) == {16}
    # Trial errors that cannot tell the proposals apart keep the first: importance. At the float32
    # keys' resolution the first proposal ends its level's trials; above it every one is tried.
    for error, tries_all in ((NEGLIGIBLE_ERROR, False), (2 * NEGLIGIBLE_ERROR, True)):
        tried: list[int] = []

        def tie(level, frames, error=error, tried=tried) -> float:
            tried.append(int(level.frozen.sum()))
            return error * level.length_scale()

        assert choose_by_refit(motion, analysis, counts, tie).priority == analysis.priority
        assert (len(set(tried)) < len(tried)) == tries_all, tried


def test_refit_choice_carries_a_runner_up_whose_coarser_level_makes_up_for_it() -> None:
    # Trial errors made up so that importance's 2 joints are the lowest at 10 joints (1.0) but
    # bind 8 joints to 10.0, while depth's (1.05) lead to its own 8 at 2.0: the greedy choice
    # (paths=1) takes importance's, the search depth's; a runner-up beyond SEARCH_MARGIN is dropped.
    motion = figure_motion()
    analysis = analyze_motion(motion)
    orders = [propose([]) for propose in proposers(motion, analysis)]
    importance, depth = orders[PROPOSING_RANKINGS.index("importance")], orders[PROPOSING_RANKINGS.index("depth")]
    counts = level_joint_counts(motion, analysis, [12, 10, 8])
    fine, coarse = counts[0] - counts[1], counts[0] - counts[2]
    assert set(importance[:fine]) != set(depth[:fine]) and not set(importance[:fine]) <= set(depth[:coarse])

    def trial_error(level, frames, runner_up=1.05, others=1.1) -> float:
        frozen = set(np.flatnonzero(level.frozen))
        if len(frozen) == fine:
            return 1.0 if frozen == set(importance[:fine]) else runner_up if frozen == set(depth[:fine]) else others
        return 2.0 if frozen == set(depth[:coarse]) else 10.0

    greedy = choose_by_refit(motion, analysis, counts, trial_error, paths=1).priority
    assert set(greedy[:fine]) == set(importance[:fine]) and set(greedy[:coarse]) != set(depth[:coarse])
    assert set(choose_by_refit(motion, analysis, counts, trial_error).priority[:coarse]) == set(depth[:coarse])
    too_far = partial(trial_error, runner_up=1.01 * SEARCH_MARGIN, others=1.01 * SEARCH_MARGIN)
    assert choose_by_refit(motion, analysis, counts, too_far).priority == greedy
    with pytest.raises(ValueError, match="refit_paths: must be at least 1, got 0"):
        build_motion_chain(motion, counts, refit_paths=0)


def test_carrying_two_choices_lowers_the_walks_8_joint_level_below_the_greedy_choice() -> None:
    # README's "Two choices carried": the greedy choice's lowest error at 13 joints binds 8 joints
    # to 0.0158; the runner-up carried from 13 joints reaches 0.0128, and the levels' errors have
    # a lower product.
    walk = humanoid_motion(humanoid().skeleton, "walk", cycles=4)
    errors = {}
    for paths in (1, 2):
        chain = build_motion_chain(walk, 8, refit_paths=paths)
        errors[paths] = np.array([level.report.mean_error for level in chain.levels[1:]])
        assert [level.report.joint_count for level in chain.levels[1:]][5] == 8
    assert errors[2][5] < 0.9 * errors[1][5]
    assert np.log(np.maximum(errors[2], 1e-12)).sum() < np.log(np.maximum(errors[1], 1e-12)).sum()


def test_refit_choice_beats_importance_and_depth_on_the_walk() -> None:
    # README's case: Eq. 3 freezes the nearly still Spine, Spine1, Neck and shoulders together
    # (their small turns add up at the head and hands), leaf-first freezes the fingers; the
    # trial re-fit sees that the spine is nearly free after the re-fit at 27 joints and that the
    # fingers are cheaper at 22.
    walk = humanoid_motion(humanoid().skeleton, "walk", cycles=1, fps=15.0)
    counts = [int(np.count_nonzero(~walk.skeleton.end_sites)), 27, 22]
    errors = {
        name: [level.report.mean_error for level in build_motion_chain(walk, counts, ranking=name).levels[1:]]
        for name in ("refit", "importance", "depth")
    }
    assert errors["refit"][0] <= errors["importance"][0] * (1 + 1e-6) < errors["depth"][0]
    assert errors["refit"][1] < 0.7 * min(errors["importance"][1], errors["depth"][1])


def test_refit_choice_is_no_worse_than_any_proposal_where_they_first_differ() -> None:
    # Later levels are bound by the earlier choices (nested levels), so this holds only where the
    # rankings first part; README lists a 12-level chain of this figure where it loses at 4 joints.
    motion = figure_motion()
    counts = [12, 9]
    default = build_motion_chain(motion, counts).levels[1].report.mean_error
    for name in PROPOSING_RANKINGS:
        other = build_motion_chain(motion, counts, ranking=name).levels[1].report.mean_error
        assert default <= other * (1 + 1e-6) + 1e-12, name


def test_spread_freezes_the_joint_that_makes_the_cheapest_run_of_frozen_joints() -> None:
    # Against the definition, run by run: a random tree, random importances, some joints frozen
    # before and some never candidates.
    rng = np.random.default_rng(4)
    count = 40
    parents = np.array([-1] + [int(rng.integers(0, j)) for j in range(1, count)])
    importance = rng.random(count)
    candidates = rng.random(count) < 0.8
    candidates[0] = False
    frozen = [int(j) for j in np.flatnonzero(candidates)[:5]]
    steps = spread_steps(importance, parents, candidates, frozen)
    assert np.all(np.isinf(steps[frozen])) and np.all(np.isinf(steps[~candidates]))

    def run_cost(frozen_set: set[int], joint: int) -> float:  # the run holding joint, walked
        seen, stack = set(), [joint]
        while stack:
            joint = stack.pop()
            if joint in seen or joint not in frozen_set:
                continue
            seen.add(joint)
            stack += [int(parents[joint])] if joint else []
            stack += [int(c) for c in np.flatnonzero(parents == joint)]
        return float(importance[list(seen)].sum())

    done = list(frozen)
    for joint in np.argsort(steps)[: int(np.isfinite(steps).sum())]:
        left = [j for j in np.flatnonzero(candidates) if j not in done]
        costs = {j: run_cost(set(done) | {j}, j) for j in left}
        assert costs[joint] == pytest.approx(min(costs.values()), rel=1e-12)
        assert joint == min(j for j in left if costs[j] <= min(costs.values()) * (1 + 1e-12))
        done.append(int(joint))


def test_refit_choice_spreads_the_freezes_of_a_tail_whose_half_a_short_clip_also_moves() -> None:
    # The curl raises Eq. 3's importance of the first half a little, so Eq. 3 (and every other
    # proposal) froze the whole second half at once, one rigid piece; spread keeps every other
    # joint or so and the re-fit bends the tail through them.
    motion, spans = tail_clips()
    counts = [20, 8]
    errors = {}
    for ranking in ("refit", "importance", "spread"):
        chain = build_motion_chain(motion, counts, analysis=analyze_motion(motion, clips=spans, ranking=ranking))
        errors[ranking] = chain.levels[1].report.mean_error
        kept = np.flatnonzero(~chain.levels[1].frozen.frozen & ~motion.skeleton.end_sites)
        if ranking != "importance":
            assert np.diff(kept).max() <= 3, (ranking, kept)
    assert errors["refit"] <= errors["spread"] * (1 + 1e-9) < 0.5 * errors["importance"], errors
