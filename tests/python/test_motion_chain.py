"""Motion LoD chains on the procedural walk: levels, errors, skin transfer, the CLI."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from test_motion_figures import figure_motion

from animlod import rotations
from animlod.cli import main
from animlod.motion_lod import analyze_motion
from animlod.motion_lod.chain import build_motion_chain, level_joint_counts
from animlod.motion_lod.frozen import freeze
from animlod.motion_lod.skeleton_reduce import expand_motion
from animlod.motion_lod.skin_transfer import transfer_skin
from animlod.synth import humanoid, humanoid_motion
from animlod.synth.gait import STILL_FINGER_CHAIN


@pytest.fixture(scope="module")
def walk_chain():
    skin = humanoid()
    motion = humanoid_motion(skin.skeleton, "walk", cycles=1, fps=10.0)
    return skin, motion, build_motion_chain(motion, [38, 28, 18, 10], skin=skin)


def test_the_still_finger_chain_has_zero_importance_and_goes_first(walk_chain) -> None:
    _, motion, chain = walk_chain
    still = [motion.skeleton.index(name) for name in STILL_FINGER_CHAIN]
    assert np.all(chain.analysis.importance[still] == 0.0)
    first = set(
        chain.analysis.priority[: int(np.count_nonzero(chain.analysis.importance[chain.analysis.priority] == 0))]
    )
    assert set(still) <= first


def test_levels_have_the_asked_joint_counts_and_growing_error(walk_chain) -> None:
    _, _, chain = walk_chain
    assert [level.report.joint_count for level in chain.levels] == [38, 28, 18, 10]
    frozen = [level.report.frozen for level in chain.levels]
    for finer, coarser in zip(frozen, frozen[1:]):
        assert coarser[: len(finer)] == finer  # frozen once, frozen at every coarser level
    errors = [level.report.mean_error for level in chain.levels]
    # Levels that freeze only still joints have zero error up to round-off (1e-16 here).
    round_off = 1e-12 * chain.figure_size
    assert errors[0] < round_off and all(b >= a - round_off for a, b in zip(errors, errors[1:]))
    assert errors[-1] > errors[0] + 1e-4 * chain.figure_size
    assert all(level.report.failures == [] for level in chain.levels)


def test_a_level_with_every_joint_kept_reproduces_the_original(walk_chain) -> None:
    skin, motion, chain = walk_chain
    level = chain.levels[0]
    np.testing.assert_allclose(level.motion.world_positions(), motion.world_positions(), atol=1e-9)
    np.testing.assert_allclose(level.skin.rest_positions, skin.rest_positions, atol=1e-6)
    np.testing.assert_allclose(level.skin.bake(level.motion).frames, skin.bake(motion).frames, atol=1e-5)


def test_kept_bones_keep_their_key_lengths(walk_chain) -> None:
    _, _, chain = walk_chain
    for level in chain.levels[1:]:
        size = level.frozen.length_scale()
        # The output skeleton's bones have the key posture's lengths by construction ...
        skeleton = level.motion.skeleton
        kept = level.frozen.kept_indices
        key = level.frozen.key_positions
        expected = np.linalg.norm(key[kept[1:]] - key[kept[skeleton.parents[1:]]], axis=-1)
        np.testing.assert_allclose(np.linalg.norm(skeleton.offsets[1:], axis=-1), expected, atol=1e-12)
        # ... and the re-fit (penalties only) keeps them within a small fraction of the figure.
        assert level.report.bone_variation < 0.05
        assert level.report.fk_residual < 0.02 * size


def test_skin_of_a_level_references_kept_joints_and_deforms_like_the_frozen_original(walk_chain) -> None:
    skin, motion, chain = walk_chain
    for level in chain.levels[1:]:
        level_skin = level.skin
        joint_count = level.motion.skeleton.joint_count
        assert level_skin.skeleton.names == level.motion.skeleton.names
        np.testing.assert_allclose(level_skin.weights.sum(axis=1), 1.0, atol=1e-6)
        used = level_skin.weights > 0
        assert level_skin.joints[used].max() < joint_count
        frozen_original = skin.bake(expand_motion(level.frozen, level.motion, motion)).frames
        difference = np.abs(level_skin.bake(level.motion).frames - frozen_original).max()
        assert difference < 1e-3 * chain.figure_size


def test_an_eight_influence_skin_keeps_eight_influences_at_a_level_of_fewer_joints(walk_chain) -> None:
    skin, motion, _ = walk_chain
    wider = ((0, 0), (0, 4))
    eight = dataclasses.replace(skin, joints=np.pad(skin.joints, wider), weights=np.pad(skin.weights, wider))
    analysis = analyze_motion(motion)
    level = freeze(motion, analysis, analysis.priority[:-5])
    kept = level.kept_indices.size
    assert kept < 8
    reduced = transfer_skin(eight, level)
    assert reduced.joints.shape == reduced.weights.shape == (skin.vertex_count, 8)
    np.testing.assert_allclose(reduced.weights.sum(axis=1), 1.0, atol=1e-6)
    assert np.all(reduced.weights[:, kept:] == 0.0) and reduced.joints.max() < kept
    four = transfer_skin(skin, level)
    np.testing.assert_array_equal(reduced.weights[:, :4], four.weights)


def test_level_joint_counts_follow_the_paper_and_refuse_impossible_requests() -> None:
    motion = figure_motion()
    analysis = analyze_motion(motion)
    counts = level_joint_counts(motion, analysis, 8)
    assert counts[0] == 12 and len(counts) == 8 and counts[-1] >= 1
    assert all(b < a for a, b in zip(counts, counts[1:]))
    assert level_joint_counts(motion, analysis, [6, 9]) == [12, 9, 6]
    with pytest.raises(ValueError, match="13 levels"):
        level_joint_counts(motion, analysis, 13)
    with pytest.raises(ValueError, match="must lie in 1..12"):
        level_joint_counts(motion, analysis, [20])


def test_cli_writes_bvh_levels_a_plot_and_refuses_bad_requests(tmp_path, capsys) -> None:
    from animlod.io.bvh import read_bvh, write_bvh

    source = tmp_path / "figure.bvh"
    write_bvh(source, figure_motion())
    out = tmp_path / "out"
    assert main(["motion", str(source), "-o", str(out), "--levels", "3", "--plot"]) == 0
    counts = [int((~read_bvh(out / f"figure_lod{k}.bvh").skeleton.end_sites).sum()) for k in range(3)]
    assert counts[0] == 12 and counts[1] < 12 and counts[2] < counts[1]
    assert (out / "figure_motion_lod.png").stat().st_size > 0
    manifest = json.loads((out / "figure_motion_lod.json").read_text())
    assert [level["joints"] for level in manifest["levels"]] == counts
    assert [level["files"] for level in manifest["levels"]] == [[f"figure_lod{k}.bvh"] for k in range(3)]
    assert manifest["levels"][0]["error"] < 1e-9 < manifest["levels"][2]["error"]
    assert "mean err" in capsys.readouterr().out
    assert main(["motion", str(source), "-o", str(out), "--levels", "99"]) == 2
    assert main(["motion", str(source), "-o", str(out), "--hard", "--solver", "newton"]) == 2
    assert main(["motion", str(source), "-o", str(out), "--lock", "Tail"]) == 2
    assert "no joint named 'Tail'" in capsys.readouterr().err


def test_cli_says_why_a_figure_of_one_point_has_no_relative_error(tmp_path, capsys) -> None:
    """Every joint of glTF's SimpleSkin sits at one point: the summary read "figure size 0", as
    if the size had been lost, beside a max/size column of dashes."""
    from animlod.io.bvh import write_bvh
    from animlod.model import Motion, Skeleton

    skeleton = Skeleton(
        ["a", "b", "end"], np.array([-1, 0, 1]), np.zeros((3, 3)), end_sites=np.array([False, False, True])
    )
    turns = rotations.from_axis_angle(
        np.array([0.0, 0.0, 1.0]), np.radians([[0.0, 0.0, 0.0], [10, 20, 0], [20, 40, 0]])
    )
    write_bvh(tmp_path / "point.bvh", Motion(skeleton, np.zeros((3, 3)), turns, fps=30.0))
    assert main(["motion", str(tmp_path / "point.bvh"), "-o", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "figure size 0: every joint of the key posture sits at one point, so errors are in asset units only" in out


def test_cli_on_a_skinned_glb_writes_a_glb_per_level(tmp_path) -> None:
    from animlod.io.gltf import read_skinned, write_glb

    skin = humanoid()
    source = tmp_path / "walker.glb"
    write_glb(source, skin, [humanoid_motion(skin.skeleton, "walk", cycles=1, fps=10.0)])
    assert main(["motion", str(source), "-o", str(tmp_path / "out"), "--joints", "20"]) == 0
    full, _ = read_skinned(tmp_path / "out" / "walker_lod0.glb")
    coarse, motions = read_skinned(tmp_path / "out" / "walker_lod1.glb")
    assert full.skeleton.joint_count == skin.skeleton.joint_count
    assert coarse.skeleton.joint_count < full.skeleton.joint_count
    assert len(motions) == 1 and motions[0].skeleton.joint_count == coarse.skeleton.joint_count


def test_cli_takes_a_glb_clip_by_name_and_names_the_clips_it_has(tmp_path, capsys) -> None:
    from animlod.io.gltf import read_skinned, write_glb

    skin = humanoid()
    clips = [humanoid_motion(skin.skeleton, kind, cycles=1, fps=10.0) for kind in ("walk", "jump")]
    source = tmp_path / "mover.glb"
    write_glb(source, skin, clips)
    names = [m.name for m in read_skinned(source)[1]]
    assert main(["motion", str(source), "-o", str(tmp_path / "out"), "--joints", "20", "--clip", names[1]]) == 0
    _, written = read_skinned(tmp_path / "out" / "mover_lod0.glb")
    assert [m.name for m in written] == [names[1]]
    assert main(["motion", str(source), "-o", str(tmp_path / "bad"), "--clip", "dance"]) == 2
    error = capsys.readouterr().err
    assert "the animation named 'dance' is not in the file" in error and f"1: {names[1]!r}" in error
    assert not (tmp_path / "bad").exists()


def test_frozen_joints_keep_their_key_angle_on_the_walk(walk_chain) -> None:
    _, motion, chain = walk_chain
    for level in chain.levels[1:]:
        frozen = np.flatnonzero(level.frozen.frozen)
        placed = expand_motion(level.frozen, level.motion, motion).local_rotations[:, frozen]
        key = level.frozen.key_rotations[frozen]
        np.testing.assert_allclose(np.abs(np.sum(placed * key, axis=-1)), 1.0, atol=1e-12)
        assert set(frozen.tolist()) == {motion.skeleton.index(name) for name in level.report.frozen}


def test_a_level_reuses_its_chosen_trial_refit_for_those_frames(monkeypatch) -> None:
    # The refit ranking re-fits each proposal on 16 frames; the chosen one's frames are the
    # level's own solves (every frame is solved on its own), so the level solves only the others.
    import animlod.motion_lod.chain as chain

    motion = humanoid_motion(humanoid().skeleton, "walk", cycles=1, fps=20.0)
    solved_frames: list[int] = []
    refit = chain._refit

    def counting_refit(problem, original, *args, **kwargs):
        solved_frames.append(original.shape[0])
        return refit(problem, original, *args, **kwargs)

    monkeypatch.setattr(chain, "_refit", counting_refit)
    monkeypatch.setattr(chain, "restart_from_neighbours", lambda result, solve, clip_of: result)  # solves of their own
    reused = build_motion_chain(motion, [38, 28, 18, 10], workers=1)
    level_frames = solved_frames[-3:]  # the three re-fitted levels come after the trials
    assert 16 in solved_frames[:-3]  # the trials
    assert all(count == motion.frame_count - 16 for count in level_frames), (level_frames, motion.frame_count)

    solve_level = chain._solve_level
    monkeypatch.setattr(chain, "_solve_level", lambda *args, **kwargs: solve_level(*args[:7], **kwargs))  # no reuse
    solved_frames.clear()
    alone = build_motion_chain(motion, [38, 28, 18, 10], workers=1)
    assert solved_frames[-3:] == [motion.frame_count] * 3
    size = reused.figure_size
    for a, b in zip(reused.levels, alone.levels):
        assert a.report.frozen == b.report.frozen
        assert np.abs(a.positions - b.positions).max() <= 1e-7 * size  # the same solves, inputs equal to rounding
