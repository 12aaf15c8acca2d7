"""Clips from an animation library without the mesh, added to a character by node name
(``animlod character --clips``): a character exported in its rest pose and its clips exported apart,
as Mixamo's downloads come, gave no chain at all ("no skinned mesh with an animation")."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from animlod import synth
from animlod.cli import main
from animlod.io.bvh import write_bvh
from animlod.io.errors import FormatError
from animlod.io.gltf import read_gltf, write_glb
from animlod.io.npz import write_npz
from animlod.model import Motion, Skeleton
from animlod.pipelines.character import build_character

QUICK = {"solver": "newton", "frame_budget": 12, "measured_frames": 2}


@pytest.fixture(scope="module")
def split_character(tmp_path_factory) -> tuple[Path, Path, Path]:
    """The humanoid with its walk, the humanoid alone, and the walk alone (no mesh)."""
    folder = tmp_path_factory.mktemp("split")
    character = synth.humanoid()
    walk = synth.humanoid_motion(character.skeleton, "walk")
    write_glb(folder / "whole.glb", character, [walk])
    write_glb(folder / "rest.glb", character, [])
    write_glb(folder / "walk.glb", None, [walk])
    return folder / "whole.glb", folder / "rest.glb", folder / "walk.glb"


def test_a_character_plays_the_clips_of_an_animation_library(split_character, tmp_path):
    whole, rest, walk = split_character
    with pytest.raises(FormatError, match="no skinned mesh with an animation"):
        build_character(rest, tmp_path / "none.glb", [0.5], **QUICK)
    split = build_character(rest, tmp_path / "split.glb", [0.5], clips=[walk], **QUICK)
    joined = build_character(whole, tmp_path / "whole.glb", [0.5], **QUICK)
    assert any("walk.glb: 1 of its 1 clip(s) added to rest.glb" in note for note in split.notes)
    for ours, theirs in zip(split.chains.values(), joined.chains.values()):
        assert [(level.faces, level.joints) for level in ours] == [(level.faces, level.joints) for level in theirs]
        np.testing.assert_allclose([level.error for level in ours], [level.error for level in theirs], rtol=1e-6)
    played = read_gltf(tmp_path / "split.glb").motions[0].world_positions()  # level 0 plays the clip
    np.testing.assert_allclose(played, read_gltf(whole).motions[0].world_positions(), atol=1e-5)


def test_a_clip_of_other_proportions_is_refused_naming_the_joint(split_character, tmp_path, capsys):
    _, rest, _ = split_character
    skeleton = synth.humanoid().skeleton
    taller = Skeleton(
        skeleton.names, skeleton.parents, skeleton.offsets * 1.2, skeleton.rest_rotations, skeleton.end_sites
    )
    write_glb(tmp_path / "tall_walk.glb", None, [synth.humanoid_motion(taller, "walk")])
    code = main(["character", str(rest), "-o", str(tmp_path / "out.glb"), "--clips", str(tmp_path / "tall_walk.glb")])
    assert code == 2
    error = capsys.readouterr().err
    assert "tall_walk.glb: node 0 'Hips': its translation is animated and it rests at" in error
    assert "another figure's proportions" in error and not (tmp_path / "out.glb").exists()


def test_a_clip_of_another_rig_is_refused(split_character, tmp_path):
    _, rest, _ = split_character
    skeleton = synth.humanoid().skeleton
    renamed = Skeleton([f"other:{name}" for name in skeleton.names], skeleton.parents, skeleton.offsets,
                       skeleton.rest_rotations, skeleton.end_sites)  # fmt: skip
    walk = synth.humanoid_motion(skeleton, "walk")
    write_glb(tmp_path / "other_rig.glb", None, [Motion(renamed, walk.root_positions, walk.local_rotations, walk.fps)])
    with pytest.raises(FormatError, match="other_rig.glb: animations: none moves a node of rest.glb's by name"):
        build_character(rest, tmp_path / "out.glb", [0.5], clips=[tmp_path / "other_rig.glb"], **QUICK)


def test_simplify_drives_the_skinned_levels_with_added_clips(split_character, tmp_path, capsys):
    from animlod.pipelines.lod_document import simplify_document

    whole, rest, walk = split_character
    split = simplify_document(rest, tmp_path / "split.glb", [0.5, 0.25], clips=[walk], frame_budget=12)
    joined = simplify_document(whole, tmp_path / "whole.glb", [0.5, 0.25], frame_budget=12)
    assert [level.error for level in split.drawables[0].levels] == [level.error for level in joined.drawables[0].levels]
    assert split.drawables[0].clips == 1 and split.notes == [f"{walk}: 1 of its 1 clip(s) added to rest.glb"]
    assert len(read_gltf(tmp_path / "split.glb").motions) == 1
    write_npz(tmp_path / "bar.npz", synth.twisting_bar(frames=3, rings=6, segments=6))
    assert main(["simplify", str(tmp_path / "bar.npz"), "-o", str(tmp_path / "out"), "--clips", str(walk)]) == 2
    assert "--clips: adds glTF clips to a glTF input, not to a npz input" in capsys.readouterr().err


def test_motion_levels_of_a_character_with_added_clips(split_character, tmp_path):
    from animlod.pipelines.motion import build_motion_levels

    whole, rest, walk = split_character
    split = build_motion_levels(rest, tmp_path / "split", levels=3, clips=[walk], solver="newton")
    joined = build_motion_levels(whole, tmp_path / "whole", levels=3, solver="newton")
    assert [level.report.max_error for level in split.chain.levels] == [
        level.report.max_error for level in joined.chain.levels
    ]
    assert f"{walk}: 1 of its 1 clip(s) added to rest.glb" in split.notes
    assert (tmp_path / "split" / "rest_lod2.glb").is_file()
    write_bvh(tmp_path / "walk.bvh", read_gltf(whole).motions[0])
    with pytest.raises(ValueError, match="clips: adds glTF clips to a glTF input, not to a bvh input"):
        build_motion_levels(tmp_path / "walk.bvh", tmp_path / "bvh", levels=2, clips=[walk])
