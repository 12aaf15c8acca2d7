"""A character whose clip scales a joint (squash and stretch) through the pipelines: geometry
levels are driven and measured with the scale, the character chain keeps every joint (motion
LoD re-fits rigid motions only), and ``animlod motion`` refuses it in one line."""

from __future__ import annotations

import numpy as np
import pytest
from gltf_edits import add_scale_channel, edit_glb

from animlod import synth
from animlod.cli import main
from animlod.io import read_lod_chains, read_skinned, write_glb
from animlod.io.gltf_document import GltfDocument
from animlod.metrics import surface_error
from animlod.model import spread_frames
from animlod.pipelines.character import build_character

QUICK = {"frame_budget": 12, "measured_frames": 3}


@pytest.fixture(scope="module")
def squashing_humanoid(tmp_path_factory):
    """The synthetic humanoid's walk with its Spine stretching up by 40% and thinning by 20%."""
    folder = tmp_path_factory.mktemp("squash")
    character = synth.humanoid()
    write_glb(folder / "humanoid.glb", character, [synth.humanoid_motion(character.skeleton, "walk")])

    def squash(gltf, blob):
        keys = np.linspace(0.0, 1.0, gltf.accessors[gltf.animations[0].samplers[0].input].count)[:, None]
        spine = next(index for index, node in enumerate(gltf.nodes) if node.name == "Spine")
        add_scale_channel(gltf, blob, spine, np.c_[1.0 - 0.2 * keys, 1.0 + 0.4 * keys, 1.0 - 0.2 * keys])

    return edit_glb(folder / "humanoid.glb", folder / "squash.glb", squash)


def test_the_character_chain_keeps_every_joint_and_plays_the_scale(squashing_humanoid, tmp_path):
    output = tmp_path / "chain.glb"
    report = build_character(squashing_humanoid, output, [0.5, 0.25], **QUICK)
    assert any("joint 'Spine' scales in its clips" in note for note in report.notes)
    (levels,) = report.chains.values()
    assert len({level.joints for level in levels}) == 1 and [level.motion_level for level in levels] == [0, 0, 0]
    (chain,) = read_lod_chains(output)
    measured_frames = spread_frames(chain.levels[0].motions[0].frame_count, QUICK["measured_frames"])
    reference = chain.levels[0].mesh.bake(chain.levels[0].motions[0].take_frames(measured_frames))
    unscaled_mesh, (walk,) = read_skinned(squashing_humanoid.parent / "humanoid.glb")
    stretched = float(np.abs(reference.frames - unscaled_mesh.bake(walk.take_frames(measured_frames)).frames).max())
    assert stretched > 0.1 * float(np.ptp(reference.frames[0], axis=0).max())  # the scale is played
    for written, level in zip(chain.levels[1:], levels[1:]):
        played = written.mesh.bake(written.motions[0].take_frames(measured_frames))
        measured = surface_error(reference, played, samples=4000).hausdorff.max()
        assert measured == pytest.approx(level.error, rel=0.1)
        assert measured < 0.5 * stretched  # measured against the scaled input, not the rigid one
    channels = GltfDocument(output).json["animations"][0]["channels"]
    assert any(channel["target"]["path"] == "scale" for channel in channels)  # the input's clip, kept as it was


def test_motion_refuses_the_clip_in_one_line_and_simplify_takes_it(squashing_humanoid, tmp_path, capsys):
    assert main(["motion", str(squashing_humanoid), "-o", str(tmp_path / "motion")]) == 2
    error = capsys.readouterr().err.strip()
    assert len(error.splitlines()) == 1
    assert f"{squashing_humanoid}: animation 'walk': joint 'Spine' scales; motion LoD re-fits rigid motions" in error
    assert not any((tmp_path / "motion").glob("*"))
    assert main(["simplify", str(squashing_humanoid), "-o", str(tmp_path / "levels.glb"), "--ratio", "0.5"]) == 0


def test_motion_leaves_a_scaling_clip_out_of_the_others_levels(tmp_path, capsys):
    """Every clip of a glTF is simplified now: one clip that scales a joint refused the whole file,
    where the first clip alone used to make levels. It is left out, in a note."""
    character = synth.humanoid()
    clips = [synth.humanoid_motion(character.skeleton, kind) for kind in ("walk", "run")]
    write_glb(tmp_path / "two.glb", character, clips)

    def squash_the_run(gltf, blob):
        keys = np.linspace(0.0, 1.0, gltf.accessors[gltf.animations[1].samplers[0].input].count)[:, None]
        spine = next(index for index, node in enumerate(gltf.nodes) if node.name == "Spine")
        add_scale_channel(gltf, blob, spine, np.c_[1.0 - 0.2 * keys, 1.0 + 0.4 * keys, 1.0 - 0.2 * keys], 1)

    source = edit_glb(tmp_path / "two.glb", tmp_path / "squash_run.glb", squash_the_run)
    assert main(["motion", str(source), "-o", str(tmp_path / "motion"), "--levels", "3", "--solver", "newton"]) == 0
    assert "'run' scales joints and motion LoD re-fits rigid motions only: left out of the levels" in (
        capsys.readouterr().err
    )
    (walk,) = read_skinned(tmp_path / "motion" / "squash_run_lod0.glb")[1]
    assert (
        walk.name == "walk" and sorted(p.name for p in (tmp_path / "motion").glob("*.bvh"))[0] == "squash_run_lod0.bvh"
    )
