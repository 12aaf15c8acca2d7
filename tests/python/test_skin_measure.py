"""Leaf joints measured by their skin's points (motion_lod/skin_measure.py).

A glTF leaf joint has no point below it, so its rotation moved no joint: the paper's measures
gave it nothing to lose, and Blender characters lost their heads' motion at the first level.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from rigid_skin import rigid_skin

from animlod import rotations
from animlod.cli import main
from animlod.io import read_gltf, write_bvh, write_glb
from animlod.model import Motion, Skeleton, SkinnedMesh
from animlod.motion_lod import analyze_motion
from animlod.motion_lod.chain import build_motion_chain, joint_floor
from animlod.motion_lod.skin_measure import (
    analyze_skinned_motion,
    build_skinned_motion_chain,
    hidden_note,
    measured_by_skin,
    skin_trial_measure,
    with_skin_tips,
    without_skin_tips,
)
from animlod.motion_lod.skin_transfer import transfer_skin
from animlod.pipelines import motion as motion_pipeline
from animlod.pipelines.motion import build_motion_levels

NAMES = ["root", "spine", "head", "control"]


def _box(centre, size, n=4) -> np.ndarray:
    axes = [np.linspace(c - s / 2, c + s / 2, n) for c, s in zip(centre, size)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)


@pytest.fixture(scope="module")
def rig():
    """A body on the spine, a wide head on the leaf joint 'head' that turns about the neck's
    own axis (which moves no joint), and a leaf 'control' with no skin that swings widely."""
    skeleton = Skeleton(NAMES, [-1, 0, 1, 0], [[0, 0, 0], [0, 1, 0], [0, 1, 0], [0.5, 0, 0]])
    body, head = _box([0, 1.0, 0], [0.6, 1.0, 0.3]), _box([0, 2.3, 0], [0.6, 0.4, 0.5])
    faces = np.array([[0, 1, 2], [len(body), len(body) + 1, len(body) + 2]])
    skin = rigid_skin(skeleton, [(1, body), (2, head)], faces)
    frames = 24
    angle = np.linspace(0.0, 1.2, frames)
    local = rotations.identity((frames, 4))
    local[:, 1] = rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.05 * angle)  # a slight bend
    local[:, 2] = rotations.from_axis_angle(np.array([0.0, 1.0, 0.0]), angle)  # the head turns
    local[:, 3] = rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), 2.0 * angle)
    motion = Motion(skeleton, np.zeros((frames, 3)), local, fps=24.0, name="turn")
    return skin, motion


def _skin_error(skin, motion, level) -> float:
    reduced = transfer_skin(skin, level.frozen)
    return float(np.abs(reduced.bake(level.motion).frames - skin.bake(motion).frames).max())


def test_the_points_of_a_skinned_leaf_keep_its_joint_where_the_bare_skeleton_froze_it(rig) -> None:
    skin, motion = rig
    bare = build_motion_chain(motion, [3])
    assert bare.levels[1].report.frozen == ["head"]  # nothing measured its turn: the failure
    assert _skin_error(skin, motion, bare.levels[1]) > 0.2

    level = build_skinned_motion_chain(motion, skin, [3]).levels[1]
    assert level.report.frozen == ["control"]  # it carries no skin: freezing it costs nothing seen
    assert _skin_error(skin, motion, level) < 1e-5


def test_tips_sit_on_the_main_axes_of_the_skin_and_leave_the_levels_on_the_input_joints(rig) -> None:
    skin, motion = rig
    tipped = with_skin_tips(motion, [skin])
    assert tipped.skeleton.names == NAMES + ["head_tip0", "head_tip1"]  # 'control' has no skin
    assert tipped.skeleton.end_sites.tolist() == [False] * 4 + [True, True]
    tips = tipped.skeleton.offsets[4:]
    # The head's skin in its frame: centred 0.3 above the joint, widest along x, then z (the
    # axes' signs are the eigensolver's).
    head = skin.rest_positions[skin.joints[:, 0] == 2] - [0, 2, 0]
    spread = head.std(axis=0)
    np.testing.assert_allclose(np.abs(tips), [[spread[0], 0.3, 0.0], [0.0, 0.3, spread[2]]], atol=1e-6)

    # Markers: measured, never in a level (a kept leaf's own rotation places them).
    markers = measured_by_skin(analyze_motion(tipped), motion, [skin])
    assert markers.markers == [4, 5]
    for level in build_motion_chain(tipped, [4, 3, 2], analysis=markers).levels:
        assert not level.frozen.kept[4:].any() and level.motion.skeleton.names[-1] in NAMES

    chain = build_skinned_motion_chain(motion, skin, [4, 3, 2])
    for level in chain.levels:
        names = level.motion.skeleton.names
        assert set(names) <= set(NAMES) and level.skin.skeleton.names == names
        assert level.frozen.skeleton is motion.skeleton and level.positions.shape[1] == 4
    assert chain.levels[2].report.frozen == ["control", "spine"]  # the slight bend goes before the head

    # The errors are measured on the tips: with the spine locked, the head must go, and it shows.
    bare = build_motion_chain(motion, [2], locked=["spine"]).levels[1]
    tipped_level = build_skinned_motion_chain(motion, skin, [2], locked=["spine"]).levels[1]
    assert set(bare.report.frozen) == set(tipped_level.report.frozen) == {"head", "control"}
    assert bare.report.max_error < 1e-9 and tipped_level.report.max_error > 0.1


def test_a_skin_on_no_leaf_joint_leaves_the_motion_as_it_is(rig) -> None:
    skin, motion = rig
    on_spine = SkinnedMesh(skin.rest_positions, skin.faces, np.where(skin.joints == 2, 1, skin.joints),
                           skin.weights, skin.inverse_bind, skin.skeleton)  # fmt: skip
    assert with_skin_tips(motion, [on_spine]) is motion


@pytest.fixture(scope="module")
def twisting_arm():
    """A slab on 'arm' that turns about the arm's own bone, towards 'hand', a leaf without skin
    (so the turn moves no point the joints' error sees), and a spine that bends slightly."""
    names = ["root", "spine", "arm", "hand"]
    skeleton = Skeleton(names, [-1, 0, 1, 2], [[0, 0, 0], [0, 1, 0], [0, 1, 0], [0, 1, 0]])
    body, slab = _box([0, 1.5, 0], [0.3, 1.0, 0.3]), _box([0, 2.5, 0], [1.0, 0.8, 0.1])
    skin = rigid_skin(skeleton, [(1, body), (2, slab)])
    frames = 24
    angle = np.linspace(0.0, 1.2, frames)
    local = rotations.identity((frames, 4))
    local[:, 1] = rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.1 * np.sin(4.0 * angle))
    local[:, 2] = rotations.from_axis_angle(np.array([0.0, 1.0, 0.0]), angle)
    return skin, Motion(skeleton, np.zeros((frames, 3)), local, fps=24.0, name="twist")


def _mean_skin_distance(skin, motion, level) -> float:
    reduced = transfer_skin(skin, level.frozen)
    return float(np.linalg.norm(reduced.bake(level.motion).frames - skin.bake(motion).frames, axis=-1).mean())


def test_the_joints_each_level_freezes_are_chosen_by_the_skin(twisting_arm, tmp_path) -> None:
    skin, motion = twisting_arm
    # By the joints' error, freezing the arm's turn costs nothing: the failure.
    bare = build_motion_chain(motion, [4, 2]).levels[1]
    assert bare.report.frozen == ["arm", "hand"]
    assert _mean_skin_distance(skin, motion, bare) > 0.05

    level = build_skinned_motion_chain(motion, skin, [4, 2]).levels[1]
    assert level.report.frozen == ["hand", "spine"]  # the bend, of which the re-fit repairs most
    assert _mean_skin_distance(skin, motion, level) < 0.2 * _mean_skin_distance(skin, motion, bare)

    write_glb(tmp_path / "twist.glb", skin, [motion])
    assert main(["motion", str(tmp_path / "twist.glb"), "-o", str(tmp_path / "levels"), "--joints", "4", "2"]) == 0
    levels = json.loads((tmp_path / "levels" / "twist_motion_lod.json").read_text())["levels"]
    kept = read_gltf(tmp_path / "levels" / levels[1]["files"][-1]).skinned_meshes[0].skeleton.names
    assert kept == ["root", "arm"]


def test_the_skin_trial_measure_is_the_mean_distance_of_the_skin_on_the_input_joints(rig) -> None:
    skin, motion = rig
    tipped, analysis, measure = analyze_skinned_motion(motion, [skin])
    assert tipped.skeleton.joint_count == 6  # the head's tips: the levels scored carry them
    frames = np.array([0, 11, 23])
    original = skin.bake(motion.take_frames(frames)).frames
    chain = build_motion_chain(tipped, [4, 3, 2], analysis=analysis)
    on_input = without_skin_tips(chain, motion).levels
    for level, untipped in zip(chain.levels, on_input):
        played = level.motion.take_frames(frames)
        distances = np.linalg.norm(transfer_skin(skin, untipped.frozen).bake(played).frames - original, axis=-1)
        assert measure(level.frozen, played, frames) == pytest.approx(float(distances.mean()), rel=1e-6, abs=1e-9)
    assert measure(chain.levels[0].frozen, chain.levels[0].motion.take_frames(frames), frames) < 1e-6
    assert measure(chain.levels[2].frozen, chain.levels[2].motion.take_frames(frames), frames) > 1e-3
    # Several skins: the mean over all their vertices.
    level = chain.levels[2]
    both = skin_trial_measure(motion, [skin, skin])(level.frozen, level.motion.take_frames(frames), frames)
    assert both == pytest.approx(measure(level.frozen, level.motion.take_frames(frames), frames), rel=1e-6)


def test_motion_reports_the_skins_largest_distance_for_a_skinned_gltf(twisting_arm, tmp_path, monkeypatch) -> None:
    skin, motion = twisting_arm
    write_glb(tmp_path / "twist.glb", skin, [motion])
    monkeypatch.setattr(motion_pipeline, "_MEASURED_PER_STEP", 7 * skin.vertex_count * 2)  # 7 frames a step
    measured = []
    report = build_motion_levels(
        tmp_path / "twist.glb", tmp_path / "levels", joints=[4, 2], on_measure=lambda *step: measured.append(step)
    )
    frames = report.motion.frame_count
    assert measured == [(min(done, frames), frames) for done in range(7, frames + 7, 7)] and report.skin_seconds > 0
    levels = json.loads((tmp_path / "levels" / "twist_motion_lod.json").read_text())["levels"]
    assert levels[0]["skin_error"] < 1e-5
    level = report.chain.levels[1]  # the level's skin, moved onto its joints, with its clip
    input_skin = report.chain.levels[0].skin  # the skin as the GLB read it
    expected = np.linalg.norm(level.skin.bake(level.motion).frames - input_skin.bake(report.motion).frames, axis=-1)
    assert expected.max() > 0.01 and levels[1]["skin_error"] == pytest.approx(float(expected.max()), rel=1e-6)
    write_bvh(tmp_path / "twist.bvh", motion)  # no skin, no skin error
    build_motion_levels(tmp_path / "twist.bvh", tmp_path / "bvh_levels", joints=[4, 2])
    levels = json.loads((tmp_path / "bvh_levels" / "twist_motion_lod.json").read_text())["levels"]
    assert all("skin_error" not in level for level in levels)


def test_motion_on_a_gltf_character_keeps_its_skinned_leaf(rig, tmp_path) -> None:
    skin, motion = rig
    write_glb(tmp_path / "turn.glb", skin, [motion])
    assert main(["motion", str(tmp_path / "turn.glb"), "-o", str(tmp_path / "levels"), "--joints", "4", "3"]) == 0
    levels = json.loads((tmp_path / "levels" / "turn_motion_lod.json").read_text())["levels"]
    assert levels[1]["joints"] == 3 and levels[1]["error"] < 1e-6
    kept = read_gltf(tmp_path / "levels" / levels[1]["files"][-1]).skinned_meshes[0].skeleton.names
    assert kept == ["root", "spine", "head"]  # 'control' froze, the head turns


def test_a_joint_that_moves_no_skin_freezes_first_even_translating_and_counts_in_no_error(rig) -> None:
    # 'control' carries no skin, nor does its parent: a rig's IK target. Let it translate too.
    skin, motion = rig
    translations = np.broadcast_to(motion.skeleton.offsets, (motion.frame_count, 4, 3)).copy()
    translations[:, 3, 1] = np.linspace(0.0, 0.5, motion.frame_count)
    moving = dataclasses.replace(motion, joint_translations=translations)
    bare = analyze_motion(moving)
    assert bare.translating == [3] and joint_floor(moving, bare).fewest == 2  # it could never freeze

    tipped = with_skin_tips(moving, [skin])
    measured = measured_by_skin(analyze_motion(tipped), moving, [skin])
    assert measured.hidden == [3] and measured.translating == [3] and measured.priority[0] == 3
    assert hidden_note(measured, moving) == "1 joint moves no skin (control): frozen first, counted in no error"
    assert hidden_note(bare, moving) is None
    assert joint_floor(tipped, measured).fewest == 1
    level = without_skin_tips(build_motion_chain(tipped, [3], analysis=measured), moving, skin).levels[1]
    assert level.report.frozen == ["control"] and level.report.max_error < 1e-9  # held, unmeasured
    # Something hung from it (a prop under an IK target) shows: then it is measured as before.
    attached = measured_by_skin(analyze_motion(tipped), moving, [skin], attached=[3])
    assert attached.hidden == [] and 3 not in attached.priority


def test_a_hidden_joint_takes_its_end_site_along(rig) -> None:
    # A skeleton from a BVH (animlod's glTF of one) ends its leaves in end sites: the control's
    # goes with it, unmeasured, and never into the elimination order (freeze() refuses one).
    skin, motion = rig
    skeleton = motion.skeleton
    ended = Skeleton([*skeleton.names, "control_end"], [*skeleton.parents, 3], [*skeleton.offsets, [0.3, 0, 0]],
                     end_sites=[False] * 4 + [True])  # fmt: skip
    local = np.concatenate([motion.local_rotations, rotations.identity((motion.frame_count, 1))], axis=1)
    moving = Motion(ended, motion.root_positions, local, motion.fps)
    on_ended = dataclasses.replace(
        skin, skeleton=ended, inverse_bind=np.concatenate([skin.inverse_bind, np.eye(4)[None]])
    )
    tipped = with_skin_tips(moving, [on_ended])
    measured = measured_by_skin(analyze_motion(tipped), moving, [on_ended])
    assert measured.hidden == [3, 4] and 4 not in measured.priority
    assert hidden_note(measured, moving) == "1 joint moves no skin (control): frozen first, counted in no error"
    level = without_skin_tips(build_motion_chain(tipped, [3], analysis=measured), moving).levels[1]
    assert level.report.frozen == ["control"] and level.report.max_error < 1e-9  # its end site swung, unmeasured
