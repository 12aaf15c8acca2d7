"""The re-fit in the C++ core against the numpy reference (objective.py) and the Python SLSQP
(refit.py): same objective, gradient and Jacobians; same optimum; bones that hold."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from test_motion_figures import figure_motion

from animlod import _core
from animlod.model import Motion, Skeleton
from animlod.motion_lod import analyze_motion, build_motion_chain
from animlod.motion_lod.chain import _cold_starts, build_level
from animlod.motion_lod.core_refit import core_problem, refit_core
from animlod.motion_lod.frozen import freeze, frozen_motion
from animlod.motion_lod.objective import (
    _rigid_set,
    build_problem,
    handedness_constraints,
    objective,
    rigidity_constraints,
)
from animlod.motion_lod.refit import refit_slsqp
from animlod.options import MotionRefitOptions
from animlod.synth import humanoid, humanoid_motion


@pytest.fixture(scope="module")
def level():
    # The spine's base leans out of the hips' plane; with the spine, chest and shoulders frozen,
    # the hips and the elbows make one handed group and one flat group at this level.
    motion = figure_motion(spine_lean=0.05)
    analysis = analyze_motion(motion)
    frozen = freeze(motion, analysis, analysis.priority[:5])
    problem = build_problem(frozen)
    return motion, frozen, problem, motion.world_positions(), frozen_motion(frozen, motion).world_positions()


def test_core_terms_match_the_numpy_reference(level) -> None:
    _, _, problem, original, _ = level
    assert problem.angle_triples.shape[0] > 0 and problem.handed_quads.shape[0] > 0 and problem.flat_quads.shape[0] > 0
    x = original[:5] + np.random.default_rng(4).normal(scale=0.05, size=original[:5].shape)
    core = core_problem(problem)
    value, gradient = _core.motion_refit_objective(core, x, original[:5])
    reference_value, reference_gradient = objective(problem, x, original[:5])
    np.testing.assert_allclose(value, reference_value, rtol=1e-12)
    np.testing.assert_allclose(gradient, reference_gradient, rtol=1e-10, atol=1e-12 * np.abs(reference_gradient).max())
    for core_function, reference in (
        (_core.motion_refit_equalities, rigidity_constraints),
        (_core.motion_refit_handedness, handedness_constraints),
    ):
        values, jacobian = core_function(core, x)
        reference_values, reference_jacobian = reference(problem, x)
        np.testing.assert_allclose(values, reference_values, rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(jacobian, reference_jacobian, rtol=1e-10, atol=1e-14)


@pytest.mark.parametrize("hard", [False, True])
def test_core_solve_matches_the_python_reference(level, hard) -> None:
    motion, frozen, problem, original, fallback = level
    options = MotionRefitOptions(hard_constraints=hard, ftol_rel=1e-12)
    cold = _cold_starts(frozen, problem, motion, original, fallback) if hard else None
    reference = refit_slsqp(problem, original, fallback, options, chunk_frames=8, cold_starts=cold)
    same_variables = MotionRefitOptions(
        hard_constraints=hard, ftol_rel=1e-12, precondition=False, eliminate_points=False
    )
    plain = refit_core(problem, original, fallback, same_variables, chunk_frames=8, cold_starts=cold)
    fast = refit_core(problem, original, fallback, options, chunk_frames=8, cold_starts=cold)
    assert reference.failures == plain.failures == fast.failures == []
    # The same algorithm in the same variables: the same optimum (nlopt versions may differ in
    # the last steps). Preconditioned, SLSQP takes other paths, and on this non-convex E a path
    # can end in another local minimum: the same optimum on most frames, in fewer evaluations.
    np.testing.assert_allclose(plain.objective, reference.objective, rtol=1e-6)
    same = np.abs(fast.objective - reference.objective) <= 1e-6 * reference.objective
    assert same.mean() >= 0.9
    assert abs(fast.objective.mean() / reference.objective.mean() - 1.0) < 0.01
    assert fast.evaluations.sum() < reference.evaluations.sum()
    if hard:
        violation, _ = rigidity_constraints(problem, fast.positions)
        assert np.abs(violation).max() <= 1e-6


@pytest.mark.parametrize("warm_start", [False, True])
def test_core_solve_is_the_same_on_one_and_two_threads(level, warm_start) -> None:
    """Warm starts run within chunks of frames; without them each frame is a task of its own,
    and the chunk size changes nothing either."""
    _, _, problem, original, fallback = level
    one = refit_core(problem, original, fallback, threads=1, chunk_frames=5, warm_start=warm_start)
    two = refit_core(problem, original, fallback, threads=2, chunk_frames=5, warm_start=warm_start)
    np.testing.assert_array_equal(one.positions, two.positions)
    np.testing.assert_array_equal(one.evaluations, two.evaluations)
    if not warm_start:
        whole = refit_core(problem, original, fallback, threads=2, chunk_frames=len(original))
        np.testing.assert_array_equal(whole.positions, two.positions)


@pytest.mark.parametrize("warm_start", [False, True])
def test_a_long_clip_reports_progress_a_slice_at_a_time_with_the_same_result(level, monkeypatch, warm_start) -> None:
    """A level of a long clip was one call of the core per group of points: its progress sat at 0
    until the whole level was done. Slices of frames (chunk boundaries with warm starts) give
    the same result as one call."""
    from animlod.motion_lod import core_refit

    _, _, problem, original, fallback = level
    original, fallback = (np.tile(a, (7, 1, 1)) for a in (original, fallback))  # 168 frames
    steps: list[float] = []
    sliced = refit_core(problem, original, fallback, chunk_frames=5, warm_start=warm_start, progress=steps.append)
    assert len(steps) == 3 and sum(steps) == len(original)
    assert steps[0] == (65 if warm_start else 64)
    monkeypatch.setattr(core_refit, "_SLICE_FRAMES", len(original))
    whole = refit_core(problem, original, fallback, chunk_frames=5, warm_start=warm_start)
    np.testing.assert_array_equal(sliced.positions, whole.positions)
    np.testing.assert_array_equal(sliced.evaluations, whole.evaluations)
    np.testing.assert_array_equal(sliced.objective, whole.objective)


def test_core_refuses_bad_shapes_and_problems_by_name(level) -> None:
    _, _, problem, original, fallback = level
    core = core_problem(problem)
    with pytest.raises(ValueError, match=r"fallback: expected shape \(24, 16, 3\) like original, got \(3, 16, 3\)"):
        _core.motion_refit_solve(core, original, fallback[:3])
    broken = original.copy()
    broken[2, 5, 1] = np.nan
    with pytest.raises(ValueError, match="original: frame 2, point 5 is not finite"):
        _core.motion_refit_solve(core, broken, fallback)
    with pytest.raises(ValueError, match=r"length_pairs\[0\]: point 99 is outside \[0, 16\)"):
        empty = np.zeros(0)
        _core.MotionRefitProblem(16, np.array([[99, 0]]), [1.0], np.zeros((0, 2), np.int64), np.zeros((0, 4), np.int64),
                                 empty, np.zeros((0, 3), np.int64), empty, 0.2, 0.4, 0.4, 1.0)  # fmt: skip


def test_hard_default_keeps_bones_and_never_falls_back_on_the_walk() -> None:
    skin = humanoid()
    motion = humanoid_motion(skin.skeleton, "walk", cycles=1, fps=15.0)
    chain = build_motion_chain(motion, 5)
    for level in chain.levels:
        assert level.report.bone_variation < 1e-5 and level.report.failures == []
        assert level.report.fk_residual < 1e-5 * chain.figure_size


def test_flat_rigid_groups_hold_their_shape_on_the_walk() -> None:
    # The procedural skeleton's Spine2 with Neck and both shoulders, and a hand with its finger
    # bases, lie in one plane: held by distances alone they left the rigid shape by 2-3e-5 of the
    # figure (forward kinematics against the re-fit) and took 35-45 SLSQP evaluations per frame.
    walk = humanoid_motion(humanoid().skeleton, "walk", cycles=1, fps=15.0)
    analysis = analyze_motion(walk, ranking="importance")
    chain = build_motion_chain(walk, [38, 27, 22], analysis=analysis,
                               slsqp_options=MotionRefitOptions(feasibility_tolerance=1e-6))  # fmt: skip
    for level in chain.levels[1:]:
        assert build_problem(level.frozen).flat_quads.shape[0] > 0
        assert level.report.fk_residual < 1e-6 * chain.figure_size
        assert level.report.evaluations < 15 and level.report.failures == []


def test_pendant_trees_end_where_every_point_as_a_variable_does_on_the_walk() -> None:
    # At the walk's 27-joint level both legs and the head hang from the hips' and spine's rigid
    # groups by held lengths alone: solved inside each evaluation (pendant trees), they leave
    # SLSQP's variables but not its optimum; so do the hips, chest and hands, moved as rigid
    # bodies (a rotation each, their groups' lengths and flat heights held by construction).
    walk = humanoid_motion(humanoid().skeleton, "walk", cycles=1, fps=15.0)
    analysis = analyze_motion(walk, ranking="importance")
    total = len(analysis.priority) + 1
    frozen = freeze(walk, analysis, analysis.priority[: total - 27])
    assert frozen.joint_count == 27
    problem = build_problem(frozen)
    original = walk.world_positions()
    fallback = frozen_motion(frozen, walk).world_positions()
    cold = _cold_starts(frozen, problem, walk, original, fallback)
    options = MotionRefitOptions(ftol_rel=1e-12)
    trees = refit_core(problem, original, fallback, options, cold_starts=cold)
    every_point = refit_core(problem, original, fallback, options, eliminate_points=False, cold_starts=cold)
    assert trees.failures == every_point.failures == []
    np.testing.assert_allclose(trees.objective, every_point.objective, rtol=1e-6, atol=1e-14)
    violation, _ = rigidity_constraints(problem, trees.positions)
    assert np.abs(violation).max() <= 1e-8


def test_hard_solve_finds_the_zero_error_optimum_when_only_twists_are_frozen() -> None:
    # Regression: the walk's Spine only twists (importance ~0); freezing it costs nothing once
    # the re-fit turns the joints above, but a solve started at the frozen key motion stopped at
    # E ~ 1e-4 (and above its start) until hard solves also start from the projected original.
    skin = humanoid()
    motion = humanoid_motion(skin.skeleton, "walk", cycles=1, fps=10.0)
    chain = build_motion_chain(motion, [38, 28], ranking="paper")
    assert "Spine" in chain.levels[1].report.frozen
    assert chain.levels[1].report.energy < 1e-20 and chain.levels[1].report.mean_error < 1e-9


def test_core_and_reference_agree_on_a_real_clip_sample(data_dir) -> None:
    from animlod.io.bvh import read_bvh

    motion = read_bvh(data_dir / "bvh" / "131_01.bvh")
    analysis = analyze_motion(motion, max_frames=120)
    frozen = freeze(motion, analysis, analysis.priority[:21])
    problem = build_problem(frozen)
    frames = np.arange(300, 312)
    original = motion.world_positions()[frames]
    fallback = frozen_motion(frozen, motion).world_positions()[frames]
    options = MotionRefitOptions(ftol_rel=1e-12)
    reference = refit_slsqp(problem, original, fallback, options, chunk_frames=4)
    plain = refit_core(problem, original, fallback, options, precondition=False, eliminate_points=False)
    core = refit_core(problem, original, fallback, options, chunk_frames=4)
    assert reference.failures == plain.failures == core.failures == []
    np.testing.assert_allclose(plain.objective, reference.objective, rtol=1e-6)
    # Without the free points' variables SLSQP takes another path: the same minimum on most
    # frames, another local one (here 0.06 % higher) on some.
    same = np.abs(core.objective - reference.objective) <= 1e-6 * reference.objective
    assert same.mean() >= 0.9
    assert abs(core.objective.mean() / reference.objective.mean() - 1.0) < 0.001


@pytest.mark.parametrize("side", [-1.0, 0.5])
def test_children_on_one_line_through_their_joint_move_as_one_body(side) -> None:
    # Hips exactly at +-x of the root (assimp's Boxing_Toes.bvh), or a second child halfway along
    # the first (a twist joint beside the next bone): bones alone let each child swing on its
    # own, and forward kinematics, which turns them as one, put the second 13 units (8%
    # of the figure) away from its re-fit at the boxer's 4-joint level.
    motion = figure_motion()
    offsets = motion.skeleton.offsets.copy()
    offsets[1] = (0.1, 0.0, 0.0)
    offsets[4] = (0.1 * side, 0.0, 0.0)
    skeleton = Skeleton(motion.skeleton.names, motion.skeleton.parents, offsets, end_sites=motion.skeleton.end_sites)
    motion = Motion(skeleton, motion.root_positions, motion.local_rotations, motion.fps, motion.name)
    analysis = analyze_motion(motion)
    names = skeleton.names
    order = [names.index(n) for n in ("LeftKnee", "RightKnee", "Spine", "Chest", "LeftShoulder", "LeftElbow",
                                      "LeftWrist", "RightShoulder", "RightElbow")]  # fmt: skip
    analysis = dataclasses.replace(analysis, priority=order + [names.index("LeftHip"), names.index("RightHip")])
    level = build_level(motion, analysis, 3)
    assert level.report.fk_residual < 1e-6 and level.report.failures == []
    assert [4, 1] in build_problem(level.frozen).length_pairs.tolist()  # RightHip tied to LeftHip


def test_three_children_on_one_line_make_a_minimal_rigid_set() -> None:
    key = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [2.0, 0.0, 0.0]])
    bones, siblings, handed, flat = _rigid_set(0, [1, 2, 3], key, 1e-9)
    assert len(bones) + len(siblings) == 3 * 3 - 3 and handed == flat == []
    assert siblings == [(2, 1), (3, 1), (3, 2)]
