"""Motion levels spread to the floor: joint counts, translating joints and the CLI's bad input."""

from __future__ import annotations

import numpy as np
import pytest
from bvh_edits import with_a_second_root
from test_motion_figures import figure_motion

from animlod import rotations
from animlod.cli import main
from animlod.io.bvh import write_bvh
from animlod.model import Motion, Skeleton
from animlod.motion_lod import analyze_motion, joint_floor, level_joint_counts
from animlod.motion_lod.analysis import translating_joints
from animlod.motion_lod.chain import build_level, build_motion_chain
from animlod.motion_lod.frozen import freeze
from animlod.pipelines.motion import build_motion_levels


def tree_motion(joints: int = 20, translating: tuple[int, ...] = (), frames: int = 16, seed: int = 3) -> Motion:
    """A root with three chains of joints (an end site each), every joint turning; the joints in
    ``translating`` also slide along their bone by up to 30 % of it."""
    rng = np.random.default_rng(seed)
    parents, offsets = [-1], [[0.0, 1.0, 0.0]]
    for joint in range(1, joints):
        parents.append(0 if joint <= 3 else joint - 3)
        offsets.append([0.1 * (joint % 3 - 1), 0.2, 0.05 * (joint % 2)])
    ends = list(range(joints - 3, joints))
    for end in ends:
        parents.append(end)
        offsets.append([0.0, 0.1, 0.0])
    count = len(parents)
    names = [f"j{k}" for k in range(joints)] + [f"j{e}_End" for e in ends]
    skeleton = Skeleton(names, parents, offsets, end_sites=[k >= joints for k in range(count)])
    time = np.linspace(0.0, 2.0 * np.pi, frames)[:, None]
    angles = 0.4 * np.sin(time + rng.uniform(0, np.pi, count))
    axes = rng.normal(size=(count, 3))
    local = rotations.from_axis_angle(axes / np.linalg.norm(axes, axis=-1, keepdims=True), angles)
    local[:, joints:] = rotations.identity()
    translations = np.broadcast_to(skeleton.offsets, (frames, count, 3)).copy()
    for joint in translating:
        translations[:, joint] *= 1.0 + 0.3 * np.sin(time + joint)
    root = np.concatenate([time, np.zeros((frames, 1)), 0.1 * np.cos(time)], axis=1)
    return Motion(skeleton, root, local, 30.0, joint_translations=translations if translating else None)


@pytest.mark.parametrize(
    ("translating", "locked", "floor"),
    [((1,), (), 2), ((1, 5), ("j2", "j9"), 5), (tuple(range(1, 15)), (), 15)],
)
def test_eight_levels_spread_down_to_the_floor(translating, locked, floor) -> None:
    motion = tree_motion(20, translating)
    analysis = analyze_motion(motion, locked=locked)
    info = joint_floor(motion, analysis)
    assert (info.total, info.fewest) == (20, floor)
    possible = 20 - floor + 1
    levels = min(8, possible)
    counts = level_joint_counts(motion, analysis, levels)
    assert counts[0] == 20 and counts[-1] == max(floor, info.paper_fewest) and len(counts) == levels
    assert all(b < a for a, b in zip(counts, counts[1:]))
    if floor == 2:  # the paper's fractions fit: 100, 82, 70, 58, 45, 33, 20, 8 % of 20 joints
        assert counts == [20, 16, 14, 12, 9, 7, 4, 2]
    if floor == 15:  # only 6 counts exist: all of them, and 8 levels are refused by name
        assert counts == [20, 19, 18, 17, 16, 15]
        with pytest.raises(ValueError, match=r"8 levels need 8 distinct joint counts, but the skeleton allows 6"):
            level_joint_counts(motion, analysis, 8)
    if floor == 5:  # above the paper's 8 %: the fractions are mapped onto 5..20
        assert counts[-1] == 5 and "2 locked (j2, j9), 2 translating (j1, j5)" in info.explain()
    for levels in (4.5, [20, 10.7]):  # int() truncated 10.7 and iterated 4.5 ("not iterable")
        with pytest.raises(ValueError, match="levels: expected a whole number of levels or a list of joint counts"):
            level_joint_counts(motion, analysis, levels)


def test_a_translating_non_root_joint_stays_and_the_rest_freeze() -> None:
    # Bandai's shape: the root does not move, its child (Hips) carries the translation.
    motion = tree_motion(12, translating=(1,))
    assert translating_joints(motion).tolist() == [False, True] + [False] * 13
    analysis = analyze_motion(motion)
    counts = level_joint_counts(motion, analysis, 8)
    assert counts[-1] == 2 and 1 not in analysis.priority
    level = build_level(motion, analysis, counts[-1])
    assert level.report.joint_count == 2 and level.report.failures == []


def test_noisy_keys_beside_a_translating_joint_leave_the_level_rigid() -> None:
    # Exporters key every joint's translation with float noise, and a clip with one translating
    # joint (hips under a static root joint, as game rigs have) keeps all those keys. The re-fit
    # holds the other bones at their key lengths, but forward kinematics ran through the noisy
    # keys: it missed the re-fitted positions by the noise (3e-7 of the figure on Soldier given a
    # root joint, where the frozen motion, the re-fit's fallback, broke its lengths too and
    # frames fell back to it).
    from animlod.motion_lod.frozen import frozen_motion

    motion = tree_motion(12, translating=(1,))
    noisy = motion.joint_translations.copy()
    noisy[:, 2:] *= 1.0 + 1e-6 * np.random.default_rng(1).normal(size=noisy[:, 2:].shape)
    motion = Motion(motion.skeleton, motion.root_positions, motion.local_rotations, 30.0, joint_translations=noisy)
    analysis = analyze_motion(motion)
    assert analysis.translating == [1]
    size = np.ptp(motion.world_positions().reshape(-1, 3), axis=0).max()
    level = build_level(motion, analysis, 6)
    assert level.report.fk_residual < 1e-8 * size and level.report.failures == []  # 8e-8 through the noisy keys
    held = frozen_motion(freeze(motion, analysis, analysis.priority[:6]), motion).joint_translations
    np.testing.assert_array_equal(held[:, 2:], np.broadcast_to(held[0, 2:], held[:, 2:].shape))
    np.testing.assert_array_equal(held[:, 1], noisy[:, 1])  # the translating joint keeps its path


def test_float_noise_and_constant_keys_are_not_translation() -> None:
    motion = tree_motion(12)
    noisy = np.broadcast_to(motion.skeleton.offsets, motion.local_rotations.shape[:2] + (3,)).copy()
    noisy[:, 1:] *= 1.0 + 1e-7 * np.random.default_rng(0).normal(size=noisy[:, 1:].shape)
    motion = Motion(motion.skeleton, motion.root_positions, motion.local_rotations, 30.0, joint_translations=noisy)
    assert not translating_joints(motion).any()
    assert joint_floor(motion, analyze_motion(motion)).fewest == 1


def _with_a_zero_length_hand(motion: Motion) -> Motion:
    """``motion`` with a turning LeftHand at LeftWrist's position, above LeftWrist_End (as CMU's
    and Bandai's skeletons have zero-length joints)."""
    skeleton = motion.skeleton
    wrist = skeleton.index("LeftWrist")
    order = [*range(wrist + 1), -1, *range(wrist + 1, skeleton.joint_count)]  # -1: the new joint
    parents = [int(skeleton.parents[j]) if j >= 0 else wrist for j in order]
    parents = [p + (p > wrist) for p in parents]
    parents[order.index(wrist + 1)] = wrist + 1  # LeftWrist_End hangs from the hand
    names = [skeleton.names[j] if j >= 0 else "LeftHand" for j in order]
    offsets = [skeleton.offsets[j] if j >= 0 else np.zeros(3) for j in order]
    ends = [bool(skeleton.end_sites[j]) if j >= 0 else False for j in order]
    turn = rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.3 * np.sin(np.arange(motion.frame_count) / 3))
    local = np.insert(motion.local_rotations, wrist + 1, turn, axis=1)
    return Motion(Skeleton(names, parents, offsets, end_sites=ends), motion.root_positions, local, fps=motion.fps)


def test_noise_on_a_zero_length_bone_leaves_the_levels_of_the_clean_clip() -> None:
    # Exporters write translation keys on every joint; on a zero-length bone their float noise
    # (~1e-8 of the figure in 131_01 and Bandai's exports) is a bone in random directions, which
    # is no bone to hold or turn.
    clean = _with_a_zero_length_hand(figure_motion())
    hand = clean.skeleton.index("LeftHand")
    translations = np.broadcast_to(clean.skeleton.offsets, clean.local_rotations.shape[:2] + (3,)).copy()
    translations[:, hand] = 3e-8 * np.random.default_rng(3).standard_normal((clean.frame_count, 3))  # 2e-8 of it
    noisy = Motion(clean.skeleton, clean.root_positions, clean.local_rotations, 30.0, joint_translations=translations)
    expected, got = (build_motion_chain(m, 6, ranking="importance") for m in (clean, noisy))
    assert [level.report.joint_count for level in got.levels] == [level.report.joint_count for level in expected.levels]
    size = expected.figure_size
    for a, b in zip(expected.levels, got.levels):
        assert abs(a.report.mean_error - b.report.mean_error) < 1e-5 * size
        assert abs(a.report.max_error - b.report.max_error) < 1e-5 * size


def test_a_small_real_translation_freezes_at_its_key_and_its_error_is_reported() -> None:
    from animlod.motion_lod.frozen import frozen_motion

    motion = tree_motion(12, translating=(4,))
    # Joint 4 slides over 60 % of its bone (+-30 %): translating at the default tolerance, not at 80 %.
    assert analyze_motion(motion).translating == [4]
    analysis = analyze_motion(motion, translation_tolerance=0.8)
    assert analysis.translating == [] and 4 in analysis.priority
    level = freeze(motion, analysis, [4])
    key = motion.joint_translations[analysis.key_frames[4], 4]
    np.testing.assert_array_equal(level.key_translations[4], key)
    held = frozen_motion(level, motion)  # the slide held at the key frame, like the rotation
    np.testing.assert_array_equal(held.joint_translations[:, 4], np.broadcast_to(key, (16, 3)))
    assert np.linalg.norm(held.world_positions() - motion.world_positions(), axis=-1)[:, 7].max() > 0.01
    # A level that freezes joint 4 measures what holding the slide costs.
    count = 11 - analysis.priority.index(4)
    report = build_level(motion, analysis, count).report
    assert "j4" in report.frozen and report.failures == [] and report.max_error > 0.01


def test_every_skinned_gltf_reaches_a_few_joints_in_eight_levels(data_dir) -> None:
    from animlod.io.gltf import read_skinned

    checked = 0
    for path in sorted((data_dir / "gltf").glob("*.gl*")):
        try:
            _, motions = read_skinned(path)
        except ValueError:
            continue  # no skinned mesh (a static scan)
        for motion in motions:
            if motion.frame_count < 2 or np.linalg.norm(motion.skeleton.offsets[1:], axis=-1).max() == 0.0:
                continue  # a one-frame pose, or every joint at one point (nothing to measure)
            analysis = analyze_motion(motion, max_frames=60)
            floor = joint_floor(motion, analysis)
            counts = level_joint_counts(motion, analysis, min(8, floor.possible_levels))
            assert counts[-1] == max(floor.fewest, floor.paper_fewest), path.name
            assert counts[-1] <= max(7, floor.fewest), (path.name, motion.name, counts)
            checked += 1
    assert checked >= 10


def test_the_bandai_clip_spreads_to_two_joints(data_dir) -> None:
    from animlod.io.bvh import read_bvh

    motion = read_bvh(data_dir / "bvh" / "dataset-1_run_proud_001.bvh")
    analysis = analyze_motion(motion)
    assert [motion.skeleton.names[j] for j in analysis.translating] == ["Hips"]
    assert level_joint_counts(motion, analysis, 8) == [22, 18, 15, 13, 10, 7, 5, 2]


def _write(tmp_path, motion: Motion, name: str = "clip.bvh"):
    path = tmp_path / name
    write_bvh(path, motion)
    return path


def test_a_clip_far_from_the_origin_gives_the_levels_it_gives_at_the_origin() -> None:
    # 1e9 units away, the positions' rounding broke the held lengths: frames fell back to the
    # frozen motion, a level's error went from 5.5% to 20% and a run took 60 s instead of 2.
    from dataclasses import replace

    motion = figure_motion()
    far = replace(motion, root_positions=motion.root_positions + [1e9, 0.0, -1e9])
    near_chain, far_chain = build_motion_chain(motion, 4, workers=1), build_motion_chain(far, 4, workers=1)
    for near_level, far_level in zip(near_chain.levels, far_chain.levels):
        assert far_level.report.frozen == near_level.report.frozen and not far_level.report.failures
        assert far_level.report.max_error == pytest.approx(near_level.report.max_error, rel=1e-4)  # measured at 1e9
        np.testing.assert_allclose(far_level.motion.local_rotations, near_level.motion.local_rotations, atol=1e-6)


def test_cli_levels_above_the_skeleton_name_the_file_in_one_line(tmp_path, capsys) -> None:
    source = _write(tmp_path, tree_motion(20, tuple(range(1, 15))))
    assert main(["motion", str(source), "-o", str(tmp_path / "out"), "--levels", "8"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert str(source) in err and "the skeleton allows 6" in err and "14 translating" in err


def test_cli_unknown_ranking_is_one_line(tmp_path, capsys) -> None:
    source = _write(tmp_path, figure_motion())
    assert main(["motion", str(source), "-o", str(tmp_path / "out"), "--ranking", "alphabetical"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        f"animlod motion: error: {source}: ranking: no ranking named 'alphabetical' (choose from refit, importance, "
        "paper, depth, variance, cumulative, spread)"
    )


def test_levels_and_joint_counts_together_are_refused_before_the_clip_is_read(tmp_path) -> None:
    # joints used to win silently over levels; the clip is not even read (an absent file here).
    with pytest.raises(ValueError, match="^levels and joints: give one of them, not both$"):
        build_motion_levels(tmp_path / "absent.bvh", tmp_path / "out", 3, joints=[8, 4])


def test_cli_a_level_that_cannot_be_written_leaves_no_level_beside_the_folders_files(tmp_path, capsys) -> None:
    # A folder where the last level's file goes: the first levels were written, then the error,
    # and they stayed beside no manifest (or an earlier run's).
    source = _write(tmp_path, figure_motion())
    out = tmp_path / "out"
    (out / "clip_lod2.bvh").mkdir(parents=True)
    assert main(["motion", str(source), "-o", str(out), "--levels", "3"]) == 2
    assert f"{out / 'clip_lod2.bvh'}: Is a directory" in capsys.readouterr().err
    assert sorted(path.name for path in out.iterdir()) == ["clip_lod2.bvh"]


def test_cli_names_the_level_files_an_earlier_run_left_in_the_folder(tmp_path, capsys) -> None:
    source = _write(tmp_path, figure_motion())
    out = tmp_path / "out"
    assert main(["motion", str(source), "-o", str(out), "--levels", "4"]) == 0
    capsys.readouterr()
    assert main(["motion", str(source), "-o", str(out), "--levels", "2"]) == 0
    assert "holds level files this run did not write, of an earlier run with other levels or clips: " \
        "clip_lod2.bvh, clip_lod3.bvh" in capsys.readouterr().err  # fmt: skip


def test_cli_an_output_that_is_a_file_or_a_clip_of_a_bvh_is_refused_before_the_work(
    tmp_path, capsys, monkeypatch
) -> None:
    import animlod.motion_lod.chain as chain

    def no_work(*args, **kwargs):
        raise AssertionError("the levels were built before the refusal")

    monkeypatch.setattr(chain, "build_motion_chain", no_work)
    source = _write(tmp_path, figure_motion())
    (tmp_path / "taken").write_text("")
    assert main(["motion", str(source), "-o", str(tmp_path / "taken")]) == 2
    assert f"{tmp_path / 'taken'}: is a file where the output needs a folder" in capsys.readouterr().err
    assert main(["motion", str(source), "-o", str(tmp_path / "out"), "--clip", "1"]) == 2
    assert "clip: picks one of a glTF input's animations; a bvh file holds one clip" in capsys.readouterr().err


def test_cli_a_clip_whose_every_joint_translates_writes_one_level(tmp_path, capsys) -> None:
    source = _write(tmp_path, tree_motion(8, tuple(range(1, 8))))
    out = tmp_path / "out"
    assert main(["motion", str(source), "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert "nothing can freeze (8 joints, all kept: root, 7 translating" in captured.err
    assert sorted(p.name for p in out.iterdir()) == ["clip_lod0.bvh", "clip_motion_lod.json"]
    assert f"wrote 2 files to {out} in " in captured.out.splitlines()[-1]  # where, and how long in all


def test_cli_a_skeleton_of_zero_length_bones_writes_one_level(tmp_path, capsys) -> None:
    # Every joint on the root in every frame: positions show no rotation, Eqs. 1-3 are undefined
    # and nothing freezes (the input's motion is the one level).
    skeleton = Skeleton(["root", "a"], [-1, 0], [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    local = rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.linspace(0, 1, 4)[:, None] * [0.0, 1.0])
    source = _write(tmp_path, Motion(skeleton, np.zeros((4, 3)), local, 30.0))
    out = tmp_path / "out"
    assert main(["motion", str(source), "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert (
        "nothing can freeze (2 joints, all kept: root, every bone of zero length (joint positions show no "
        "rotation))" in captured.err
    )
    assert sorted(p.name for p in out.iterdir()) == ["clip_lod0.bvh", "clip_motion_lod.json"]


def test_cli_summary_says_why_the_floor_is_above_the_paper(tmp_path, capsys) -> None:
    source = _write(tmp_path, tree_motion(20, (1, 5, 9)))
    assert main(["motion", str(source), "-o", str(tmp_path / "out"), "--levels", "3"]) == 0
    out = capsys.readouterr().out
    assert "fewest joints: 4 of 20, above the paper's 8% (2): root, 3 translating (j1, j5, j9) never freeze" in out


def test_levels_of_a_bvh_keep_its_rotation_channel_orders(tmp_path) -> None:
    """Each joint of every level is written in the rotation order its input channels have (here
    XYZ, ZYX on the root): the levels were all written ZXY, whatever the input's layout."""
    motion = tree_motion(8)
    orders = {name: "XYZ" for name in motion.skeleton.names} | {"j0": "ZYX"}
    source = tmp_path / "clip.bvh"
    write_bvh(source, motion, rotation_order=orders)
    assert main(["motion", str(source), "-o", str(tmp_path / "out"), "--levels", "3"]) == 0
    for level in sorted((tmp_path / "out").glob("clip_lod*.bvh")):
        channels = [line.split()[2:] for line in level.read_text().splitlines() if "CHANNELS" in line]
        assert channels[0][3:] == ["Zrotation", "Yrotation", "Xrotation"]
        assert all(joint[-3:] == ["Xrotation", "Yrotation", "Zrotation"] for joint in channels[1:]), level.name


def test_cli_a_bvh_of_two_roots_is_simplified_below_one_and_says_so(tmp_path, capsys) -> None:
    """Two ROOTs, each a copy of the tree clip's skeleton: one motion, a note naming them."""
    source = with_a_second_root(_write(tmp_path, tree_motion(8), "one.bvh"), tmp_path / "two.bvh",
                                {"ROOT j0": "ROOT k0", "JOINT j": "JOINT k"})  # fmt: skip
    assert main(["motion", str(source), "-o", str(tmp_path / "out"), "--levels", "3"]) == 0
    printed = capsys.readouterr()
    assert "its 2 ROOTs (j0, k0) are joints below one ROOT of its own, 'Roots'" in printed.out + printed.err
    assert "\r" not in printed.err  # progress bars are for a terminal: in a log, \r and cursor moves
    assert len(list((tmp_path / "out").glob("two_lod*.bvh"))) == 3


def test_cli_without_a_terminal_logs_a_line_as_each_level_starts(tmp_path, capsys) -> None:
    """The bars draw only on a terminal: with the output redirected to a log, a 36,000-frame
    clip printed nothing for minutes, until its summary."""
    source = _write(tmp_path, figure_motion())
    assert main(["motion", str(source), "-o", str(tmp_path / "out"), "--levels", "3"]) == 0
    lines = capsys.readouterr().out.splitlines()
    started = [line for line in lines if line.startswith("level ") and " of 2: " in line]
    assert [line.split(":")[0] for line in started] == ["level 0 of 2", "level 1 of 2", "level 2 of 2"]
    assert lines[0].startswith("choosing the joints of 2 levels")
