"""Re-fit (Eqs. 4-8): analytic derivatives, SLSQP against Newton, skeleton recovery, failures."""

from __future__ import annotations

import nlopt
import numpy as np
import pytest
from test_motion_figures import figure_motion

from animlod.motion_lod import analyze_motion
from animlod.motion_lod.frozen import freeze, frozen_motion
from animlod.motion_lod.newton import refit_newton
from animlod.motion_lod.objective import (
    Weights,
    build_problem,
    half_hessian,
    objective,
    rigidity_constraints,
    split_problem,
)
from animlod.motion_lod.refit import refit_slsqp
from animlod.motion_lod.skeleton_reduce import expand_motion, recover_motion, reduce_skeleton
from animlod.options import MotionRefitOptions


@pytest.fixture(scope="module")
def figure():
    motion = figure_motion()
    return motion, analyze_motion(motion), motion.world_positions()


def _numeric_derivative(function, x: np.ndarray, step: float = 1e-6) -> np.ndarray:
    """Central differences of ``function (F, P, 3) -> (F, ...)`` over the non-root points."""
    columns = []
    for point in range(1, x.shape[1]):
        for axis in range(3):
            plus, minus = x.copy(), x.copy()
            plus[:, point, axis] += step
            minus[:, point, axis] -= step
            columns.append((function(plus) - function(minus)) / (2.0 * step))
    return np.stack(columns, axis=-1)


def test_gradient_hessian_and_constraint_jacobian_match_finite_differences(figure) -> None:
    motion, analysis, original = figure
    level = freeze(motion, analysis, analysis.priority[:6])
    problem = build_problem(level, Weights(0.2, 0.4, 0.4))
    assert problem.angle_triples.shape[0] > 0 and problem.length_pairs.shape[0] > 0
    x = original[:3] + np.random.default_rng(7).normal(scale=0.05, size=original[:3].shape)

    _, gradient = objective(problem, x, original[:3])
    numeric = _numeric_derivative(lambda y: objective(problem, y, original[:3])[0], x)
    np.testing.assert_allclose(gradient[:, 1:].reshape(3, -1), numeric, atol=1e-7 * np.abs(numeric).max())

    hessian = half_hessian(problem, x)
    numeric = _numeric_derivative(lambda y: 0.5 * objective(problem, y, original[:3])[1][:, 1:].reshape(3, -1), x)
    np.testing.assert_allclose(hessian, numeric, atol=1e-6 * np.abs(numeric).max())

    _, jacobian = rigidity_constraints(problem, x)
    numeric = _numeric_derivative(lambda y: rigidity_constraints(problem, y)[0], x)
    np.testing.assert_allclose(jacobian[:, :, 1:].reshape(3, jacobian.shape[1], -1), numeric, atol=1e-7)


def test_nothing_frozen_means_zero_error_at_the_original(figure) -> None:
    motion, analysis, original = figure
    level = freeze(motion, analysis, [])
    value, gradient = objective(build_problem(level), original, original)
    assert np.all(value < 1e-28) and np.abs(gradient).max() < 1e-13
    reduced = recover_motion(level, original, motion)
    np.testing.assert_allclose(reduced.world_positions(), original, atol=1e-12)
    np.testing.assert_allclose(
        reduced.local_rotations * np.sign(reduced.local_rotations[..., 3:]),
        motion.local_rotations * np.sign(motion.local_rotations[..., 3:]),
        atol=1e-12,
    )


def test_slsqp_and_newton_reach_the_same_optimum(figure) -> None:
    motion, analysis, original = figure
    level = freeze(motion, analysis, analysis.priority[:6])
    problem = build_problem(level)
    fallback = frozen_motion(level, motion).world_positions()
    slsqp = refit_slsqp(problem, original, fallback, MotionRefitOptions(hard_constraints=False, ftol_rel=1e-12))
    newton = refit_newton(problem, original)
    assert slsqp.failures == [] and newton.failures == []
    start = objective(problem, original, original)[0]
    assert np.all(newton.objective < start)
    np.testing.assert_allclose(newton.objective, slsqp.objective, rtol=1e-6)
    np.testing.assert_allclose(newton.positions, slsqp.positions, atol=1e-4 * problem.length_scale)


def test_hard_constraints_keep_lengths_and_fk_reproduces_the_refit(figure) -> None:
    motion, analysis, original = figure
    level = freeze(motion, analysis, analysis.priority[:6])
    problem = build_problem(level)
    fallback = frozen_motion(level, motion).world_positions()
    result = refit_slsqp(problem, original, fallback, MotionRefitOptions(hard_constraints=True), chunk_frames=8)
    assert result.failures == []
    violation, _ = rigidity_constraints(problem, result.positions)
    assert np.abs(violation).max() <= 1e-6
    reduced = recover_motion(level, result.positions, motion)
    assert reduced.skeleton.joint_count == level.kept.sum()
    fk = reduced.world_positions()
    np.testing.assert_allclose(fk, result.positions[:, level.kept_indices], atol=1e-6 * problem.length_scale)
    # Expanding back to the original skeleton moves no kept point and puts frozen joints at key.
    expanded = expand_motion(level, reduced, motion)
    np.testing.assert_allclose(expanded.world_positions()[:, level.kept_indices], fk, atol=1e-12)
    frozen = np.flatnonzero(level.frozen)
    np.testing.assert_array_equal(
        expanded.local_rotations[:, frozen],
        np.broadcast_to(level.key_rotations[frozen], expanded.local_rotations[:, frozen].shape),
    )


def test_frozen_angles_and_key_lengths_hold_approximately_with_penalties(figure) -> None:
    motion, analysis, original = figure
    level = freeze(motion, analysis, analysis.priority[:6])
    problem = build_problem(level)
    result = refit_newton(problem, original)
    frozen_triples = problem.angle_triples
    u = result.positions[:, frozen_triples[:, 0]] - result.positions[:, frozen_triples[:, 1]]
    v = result.positions[:, frozen_triples[:, 2]] - result.positions[:, frozen_triples[:, 1]]
    cos = np.sum(u * v, -1) / np.linalg.norm(u, axis=-1) / np.linalg.norm(v, axis=-1)
    start_u = original[:, frozen_triples[:, 0]] - original[:, frozen_triples[:, 1]]
    start_v = original[:, frozen_triples[:, 2]] - original[:, frozen_triples[:, 1]]
    start_cos = np.sum(start_u * start_v, -1) / np.linalg.norm(start_u, axis=-1) / np.linalg.norm(start_v, axis=-1)
    # The re-fit moves frozen angles towards the key posture and lengths to their key values.
    assert np.abs(cos - problem.key_cosines).mean() < 0.5 * np.abs(start_cos - problem.key_cosines).mean()
    pairs = problem.length_pairs
    lengths = np.linalg.norm(result.positions[:, pairs[:, 0]] - result.positions[:, pairs[:, 1]], axis=-1)
    start_lengths = np.linalg.norm(original[:, pairs[:, 0]] - original[:, pairs[:, 1]], axis=-1)
    assert np.abs(lengths - problem.key_lengths).max() < np.abs(start_lengths - problem.key_lengths).max()
    assert np.abs(lengths - problem.key_lengths).max() < 0.01 * problem.length_scale


def test_reduced_skeleton_hangs_kept_joints_from_kept_ancestors(figure) -> None:
    motion, analysis, _ = figure
    names = motion.skeleton.names
    level = freeze(motion, analysis, [names.index("Spine"), names.index("LeftWrist")])
    skeleton = reduce_skeleton(level)
    assert "Spine" not in skeleton.names and "LeftWrist" not in skeleton.names
    assert "LeftWrist_End" not in skeleton.names  # dropped with its joint
    assert skeleton.names[skeleton.parents[skeleton.index("Chest")]] == "Hips"
    assert level.joint_count == 10 and int(skeleton.end_sites.sum()) == 3
    # The folded offset is the key posture's Hips->Chest vector in the Hips frame.
    key = level.key_positions
    np.testing.assert_allclose(
        np.linalg.norm(skeleton.offsets[skeleton.index("Chest")]),
        np.linalg.norm(key[names.index("Chest")] - key[names.index("Hips")]),
        rtol=1e-12,
    )


def test_failed_solves_are_reported_and_fall_back(figure, monkeypatch) -> None:
    motion, analysis, original = figure
    level = freeze(motion, analysis, analysis.priority[:6])
    problem = build_problem(level)
    fallback = frozen_motion(level, motion).world_positions()
    # A solver that returns NaN: every frame must be retried, then fall back, visibly.
    monkeypatch.setattr(nlopt.opt, "optimize", lambda self, z: np.full_like(z, np.nan))
    result = refit_slsqp(problem, original[:4], fallback[:4])
    assert [f.frame for f in result.failures] == [0, 1, 2, 3]
    assert all(f.reason == "non-finite result" and f.outcome == "fallback" for f in result.failures)
    np.testing.assert_array_equal(result.positions, fallback[:4])
    assert np.all(np.isfinite(result.objective))


def test_freezing_the_root_or_an_end_site_is_refused(figure) -> None:
    motion, analysis, _ = figure
    with pytest.raises(ValueError, match="'Hips' cannot be frozen"):
        freeze(motion, analysis, [0])
    with pytest.raises(ValueError, match="'LeftKnee_End' cannot be frozen"):
        freeze(motion, analysis, [motion.skeleton.index("LeftKnee_End")])


def test_a_zero_length_bone_is_held_together_and_survives_hard_constraints() -> None:
    from animlod.model import Motion, Skeleton

    motion = figure_motion()
    skeleton = motion.skeleton
    offsets = skeleton.offsets.copy()
    offsets[skeleton.index("LeftHip")] = 0.0  # LeftHip sits on Hips, as CMU's LHipJoint does
    zero = Skeleton(skeleton.names, skeleton.parents, offsets, end_sites=skeleton.end_sites)
    motion = Motion(zero, motion.root_positions, motion.local_rotations, motion.fps)
    analysis = analyze_motion(motion)
    level = freeze(motion, analysis, [skeleton.index("LeftKnee")])
    problem = build_problem(level)
    assert problem.coincident_pairs.tolist() == [[skeleton.index("LeftHip"), 0]]
    original = motion.world_positions()
    fallback = frozen_motion(level, motion).world_positions()
    result = refit_slsqp(problem, original, fallback, MotionRefitOptions(hard_constraints=True))
    assert result.failures == []
    np.testing.assert_allclose(result.positions[:, skeleton.index("LeftHip")], original[:, 0], atol=1e-9)
    reduced = recover_motion(level, result.positions, motion)
    np.testing.assert_allclose(reduced.world_positions(), result.positions[:, level.kept_indices], atol=1e-6)


def test_worker_processes_give_the_same_result(figure) -> None:
    motion, analysis, original = figure
    level = freeze(motion, analysis, analysis.priority[:6])
    problem = build_problem(level)
    fallback = frozen_motion(level, motion).world_positions()
    alone = refit_slsqp(problem, original[:8], fallback[:8], chunk_frames=4)
    pooled = refit_slsqp(problem, original[:8], fallback[:8], chunk_frames=4, workers=2)
    np.testing.assert_array_equal(pooled.positions, alone.positions)
    np.testing.assert_array_equal(pooled.evaluations, alone.evaluations)
    finished = []
    alone = refit_newton(problem, original[:8], chunk_frames=4)
    pooled = refit_newton(problem, original[:8], chunk_frames=4, workers=2, progress=finished.append)
    np.testing.assert_array_equal(pooled.positions, alone.positions)
    np.testing.assert_array_equal(pooled.evaluations, alone.evaluations)
    assert sum(finished) == pytest.approx(8.0)  # every group's chunks add up to the 8 frames


def test_newton_worker_processes_give_the_same_result(figure) -> None:
    motion, analysis, original = figure
    problem = build_problem(freeze(motion, analysis, analysis.priority[:6]))
    alone = refit_newton(problem, original, chunk_frames=8)
    pooled = refit_newton(problem, original, chunk_frames=8, workers=2)
    np.testing.assert_array_equal(pooled.positions, alone.positions)


def test_newton_reports_frames_stopped_by_the_damping_limit(figure, monkeypatch) -> None:
    import animlod.motion_lod.newton as newton

    motion, analysis, original = figure
    level = freeze(motion, analysis, analysis.priority[:6])
    problem = build_problem(level)
    frames = original[:3]
    exact = newton.objective

    def no_step_succeeds(problem, x, target):
        value, gradient = exact(problem, x, target)
        moved = np.any(x != target, axis=(1, 2))  # every trial point: the start is the original
        return np.where(moved, np.nan, value), gradient

    # Every trial is rejected, so the damping grows until the frame gives up, well before 100
    # steps (ftol_rel=0: a promise shrunk by the damping does not count as converged).
    monkeypatch.setattr(newton, "objective", no_step_succeeds)
    result = refit_newton(problem, frames, ftol_rel=0.0)
    assert [(f.frame, f.reason, f.outcome) for f in result.failures] == [
        (t, "damping limit", "kept best point") for t in range(3)
    ]
    np.testing.assert_array_equal(result.positions, frames)
    assert np.all(result.evaluations < 100 * len(split_problem(problem)[0]))


def test_newton_counts_rounding_level_error_as_solved(figure) -> None:
    motion, analysis, original = figure
    level = freeze(motion, analysis, [])
    problem = build_problem(level)
    # Nothing frozen: E at the original is rounding error (> 0 on some frames), where no step
    # can gain; that is the optimum, not a failure.
    assert np.any(objective(problem, original, original)[0] > 0.0)
    result = refit_newton(problem, original)
    assert result.failures == []
    np.testing.assert_array_equal(result.positions, original)


def test_newton_reports_no_false_failures_on_a_real_clip(data_dir) -> None:
    from animlod.io.bvh import read_bvh

    motion = read_bvh(data_dir / "bvh" / "131_01.bvh")
    analysis = analyze_motion(motion, max_frames=200)
    problem = build_problem(freeze(motion, analysis, analysis.priority[:15]))
    # Groups untouched by the frozen joints start at rounding-level E; they are solved there.
    result = refit_newton(problem, motion.world_positions()[:40])
    assert result.failures == []
