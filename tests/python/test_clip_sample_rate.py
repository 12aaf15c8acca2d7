"""glTF clips are sampled at the rate of their keys (at least 30 fps): a 60 fps clip keeps its
keys through the readers and the commands that write levels, where it was resampled at 30 fps,
also beside a 30 fps clip of the same file."""

from __future__ import annotations

import numpy as np
import pytest

from animlod import synth
from animlod.io import write_glb
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_keyframes import key_sample_rate
from animlod.io.gltf_read import read_gltf


def _key_spacings(path) -> set[float]:
    """The key spacings (rounded to 0.1 ms) of every sampler of every animation in ``path``."""
    doc = GltfDocument(path)
    spacings = set()
    for animation in doc.gltf.animations:
        for sampler in animation.samplers:
            times = doc.accessor(sampler.input, "test")[:, 0].astype(np.float64)
            spacings |= set(np.round(np.diff(times), 4).tolist())
    return spacings


@pytest.fixture(scope="module")
def walk_at_60(tmp_path_factory):
    character = synth.humanoid()
    motion = synth.humanoid_motion(character.skeleton, "walk", cycles=1, fps=60.0)
    path = tmp_path_factory.mktemp("rate") / "walk60.glb"
    write_glb(path, character, [motion])
    return path, motion


_REDUCED_60 = np.delete(np.arange(181) / 60.0, np.s_[2::3])  # every third key of a 60 fps clip dropped
_STEPPED = np.sort(np.concatenate([np.arange(40) * 0.5, np.arange(1, 40) * 0.5 - 0.001]))  # 1 ms before each pose
_HELD = np.sort(np.concatenate([np.arange(40) * 0.5, np.arange(40) * 0.5 + 0.001]))  # 1 ms after each pose


@pytest.mark.parametrize(
    ("key_times", "rate"),
    [
        ([np.arange(61, dtype=np.float32) / np.float32(60)] * 3, 60.0),  # float32 keys, a whole rate
        ([np.arange(31) / 30.0] * 5 + [np.array([0.0, 0.001])], 30.0),  # an instant change among 30 fps keys
        ([_REDUCED_60], 60.0),  # steps of 1/60 and 2/60 s: the 60 fps grid, though most steps are 1/30
        ([_STEPPED], 30.0),  # a pose every 0.5 s, each changed in 1 ms: not a 1000 fps clip
        ([_HELD], 30.0),
        ([np.append(np.arange(31) / 30.0, 1.005)], 30.0),  # one odd step at the end
        ([np.arange(25) / 24.0], 30.0),  # sparser than 30 fps: sampled at 30
        ([np.array([0.0, 1.25])], 30.0),
        ([np.arange(1001) / 1000.0], 240.0),
        ([np.zeros(1)], 30.0),  # no two keys
        ([], 30.0),
    ],
)
def test_key_sample_rate(key_times, rate):
    assert key_sample_rate(key_times) == rate


def test_a_60_fps_clip_is_read_at_60_fps(walk_at_60):
    path, motion = walk_at_60
    read = read_gltf(path).motions[0]
    assert read.fps == 60.0 and read.frame_count == motion.frame_count
    assert read_gltf(path, fps=30.0).motions[0].frame_count == int(np.ceil((motion.frame_count - 1) / 2)) + 1


def test_motion_levels_of_a_60_fps_clip_keep_its_keys(walk_at_60, tmp_path):
    from animlod.pipelines.motion import build_motion_levels

    path, _ = walk_at_60
    report = build_motion_levels(path, tmp_path / "levels", 2)
    level_glbs = sorted((tmp_path / "levels").glob("*.glb"))
    assert len(level_glbs) == 2 and report.motion.fps == 60.0
    assert _key_spacings(level_glbs[-1]) == {round(1 / 60, 4)}


def test_character_clips_of_a_60_fps_clip_keep_its_keys(walk_at_60, tmp_path):
    from animlod.pipelines.character import build_character

    path, _ = walk_at_60
    build_character(path, tmp_path / "character.glb", ratios=(0.5,))
    assert _key_spacings(tmp_path / "character.glb") == {round(1 / 60, 4)}
    from animlod.io import read_lod_chains

    level = read_lod_chains(tmp_path / "character.glb")[0].levels[-1]  # read back at the same rate
    assert {(clip.fps, clip.frame_count) for clip in level.motions} == {(60.0, 66)}


def test_a_60_fps_clip_beside_a_30_fps_one_keeps_its_keys(tmp_path):
    from animlod.pipelines.motion import build_motion_levels

    character = synth.humanoid()
    walk = synth.humanoid_motion(character.skeleton, "walk", cycles=1, fps=60.0)
    run = synth.humanoid_motion(character.skeleton, "run", cycles=8, fps=30.0)  # more keys than the walk
    write_glb(tmp_path / "two.glb", character, [walk, run])
    assert GltfDocument(tmp_path / "two.glb").sample_rate() == 60.0
    build_motion_levels(tmp_path / "two.glb", tmp_path / "levels", 2)
    level = GltfDocument(sorted((tmp_path / "levels").glob("*.glb"))[-1])
    walk_keys = level.accessor(level.gltf.animations[0].samplers[0].input, "test")[:, 0]
    assert len(walk_keys) == walk.frame_count and np.allclose(np.diff(walk_keys), 1 / 60)


def test_info_says_the_rate_the_clips_are_sampled_at(walk_at_60, capsys):
    from animlod.cli import main

    assert main(["info", str(walk_at_60[0])]) == 0
    assert "1 animations, sampled at 60 fps" in capsys.readouterr().out


def _keyed_later(source, path, seconds: float):
    """``source`` with every key of its animations ``seconds`` later: a clip keyed late on a
    timeline, which holds its first pose from 0 (Blender's actions keep their frame numbers)."""
    from animlod.io.glb_builder import GlbBuilder

    doc = GltfDocument(source)
    builder = GlbBuilder.from_document(doc)
    for animation in builder.json["animations"]:
        for sampler in animation["samplers"]:
            times = doc.accessor(sampler["input"], "test").astype(np.float64) + seconds
            sampler["input"] = builder.add(times.astype(np.float32), bounds=True)
    builder.save(path)
    return path


def test_a_clip_keyed_late_drives_and_measures_its_levels_where_it_moves(humanoid_glb, tmp_path):
    # Its frames were spread from 0: nearly all of them the held first pose, so the levels were
    # driven and measured on one pose (a character's coarsest level reported 23x below its error).
    # Its frames now start at its first key.
    from animlod.io.gltf_drawable import read_drawables
    from animlod.pipelines import simplify_document

    late = _keyed_later(humanoid_glb, tmp_path / "late.glb", 20.0)
    (clip,) = read_drawables(GltfDocument(late))[0].clips
    (plain,) = read_drawables(GltfDocument(humanoid_glb))[0].clips
    assert clip.start_frame == 20 * 30 and clip.frame_count == plain.frame_count
    np.testing.assert_allclose(clip.motion.world_positions(), plain.motion.world_positions(), atol=1e-5)
    settings = {"frame_budget": 12, "measured_frames": 4}
    errors = [
        [level.error for level in simplify_document(path, tmp_path / f"{path.stem}_lod.glb", [0.5, 0.2], **settings)
         .drawables[0].levels]
        for path in (humanoid_glb, late)
    ]  # fmt: skip
    assert errors[0][-1] > 0.0
    np.testing.assert_allclose(errors[1], errors[0], rtol=1e-4)  # the keys' float32 times round at 20 s


def _levels_alike(plain, late, folder) -> list:
    """The reports of `motion`'s 3 levels of ``plain`` and of ``late`` (the same clip keyed later),
    having checked that they read as many frames and keep as many joints at errors within 2%: the
    keys' float32 times round at 20 s, and the coarsest level's minimum moves by about 1% (with the
    held frames its mean error was a tenth of the plain clip's, diluted by 600 frames)."""
    from animlod.pipelines.motion import build_motion_levels

    reports = [build_motion_levels(path, folder / path.stem, levels=3) for path in (plain, late)]
    assert reports[1].motion.frame_count == reports[0].motion.frame_count
    plain_levels, late_levels = ([level.report for level in report.chain.levels] for report in reports)
    assert [level.joint_count for level in late_levels] == [level.joint_count for level in plain_levels]
    for statistic in ("mean_error", "max_error"):
        np.testing.assert_allclose(
            [getattr(r, statistic) for r in late_levels],
            [getattr(r, statistic) for r in plain_levels],
            rtol=2e-2,
            atol=1e-9,
        )
    return reports


def test_motion_levels_of_a_clip_keyed_late_start_at_its_first_key(humanoid_glb, tmp_path):
    # `motion` analysed, re-fitted and wrote the held first pose from 0 to the first key too: a
    # walk keyed at 20 s was 666 frames, the moving 66 of them a tenth of the analysis and of the
    # re-fit's trial frames. The level clips now start where the input's does, key for key.
    late = _keyed_later(humanoid_glb, tmp_path / "late.glb", 20.0)
    _levels_alike(humanoid_glb, late, tmp_path)
    written, source = GltfDocument(tmp_path / "late" / "late_lod1.glb"), GltfDocument(late)
    assert written.animation_start(0) == source.animation_start(0) == 20.0
    assert written.animation_duration(0) == source.animation_duration(0)
    assert len(written.sampler_keys(0, 0, 3, "test")[0]) == len(source.sampler_keys(0, 0, 3, "test")[0])


def _split_by_joint(source, path):
    """``source`` with its one animation split into one per node, each with that node's channels,
    as some exporters write a clip (Khronos' Monster: an animation per joint)."""
    from animlod.io.glb_builder import GlbBuilder

    builder = GlbBuilder.from_document(GltfDocument(source))
    (animation,) = builder.json["animations"]
    by_node = {}
    for channel in animation["channels"]:
        by_node.setdefault(channel["target"]["node"], []).append(channel)
    builder.json["animations"] = [
        {
            "name": f"node{node}",
            "samplers": [animation["samplers"][channel["sampler"]] for channel in channels],
            "channels": [{**channel, "sampler": index} for index, channel in enumerate(channels)],
        }
        for node, channels in by_node.items()
    ]
    builder.save(path)
    return path


def test_motion_levels_of_a_clip_split_by_joint_and_keyed_late_start_at_its_first_key(humanoid_glb, tmp_path):
    # `motion` merges the parts of a clip split by joint into one motion, which it sampled from 0:
    # keyed at 20 s, 666 frames for 66, as for a late clip of one animation (above).
    split = _split_by_joint(humanoid_glb, tmp_path / "split.glb")
    late = _keyed_later(split, tmp_path / "late.glb", 20.0)
    reports = _levels_alike(split, late, tmp_path)
    assert all(any("simplifying them as one motion" in note for note in report.notes) for report in reports)
    written = GltfDocument(tmp_path / "late" / "late_lod1.glb")
    assert written.animation_start(0) == 20.0
    assert written.animation_duration(0) == GltfDocument(late).animation_duration(0)


def test_a_morph_animation_keyed_late_starts_at_its_first_key(data_dir, tmp_path):
    # `tdag build` read a late clip's held first shape from 0 as frames of its own.
    source = data_dir / "morph" / "Parrot.glb"
    if not source.exists():
        pytest.skip("Parrot.glb is not in the development data")
    late = _keyed_later(source, tmp_path / "late.glb", 20.0)
    (plain,), (moved,) = (read_gltf(path).morph_animations for path in (source, late))
    assert moved.frame_count == plain.frame_count
    np.testing.assert_allclose(moved.frames, plain.frames, atol=1e-3 * np.ptp(plain.frames))
