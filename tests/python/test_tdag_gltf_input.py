"""``animlod tdag build`` of glTF files: the frames are what a viewer plays, morph weights and the
mesh node's own animation included."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from gltf_edits import edit_glb
from simplify_inputs import tube, two_bone_tube

from animlod import rotations
from animlod.cli import main
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf import write_glb
from animlod.tdag import TemporalDag


def _built_frames(source: Path, capsys) -> tuple[np.ndarray, str]:
    """(F, V, 3) the input frames the TDAG built from ``source`` holds, and what the build said on stderr."""
    target = source.with_suffix(".tdag")
    assert main(["tdag", "build", str(source), "-o", str(target)]) == 0
    dag = TemporalDag.load(target)
    frames = np.stack([dag.frame_positions(frame)[dag.input_points] for frame in range(dag.frame_count)])
    return frames, capsys.readouterr().err


@pytest.mark.parametrize("joints_move", [True, False], ids=["bend and smile", "smile alone"])
def test_a_skinned_clip_of_morph_weights_is_in_the_frames(tmp_path, capsys, joints_move):
    """A character's facial blendshapes: the body's clip drives its morph weights, with or without
    its joints. The morph animation was left out of every frame, and a clip of morph weights alone
    was refused ("no morph-animated mesh and no animated skinned mesh")."""
    skinned, bend = two_bone_tube()
    lift = np.zeros((1, skinned.vertex_count, 3), np.float32)
    lift[0, :, 1] = np.where(skinned.rest_positions[:, 0] > 0.5, 0.3, 0.0)  # the far end rises 0.3
    skinned = dataclasses.replace(skinned, morph_targets=lift, morph_target_names=["smile"])
    motion = bend if joints_move else skinned.skeleton.rest_motion(bend.frame_count, bend.fps)
    smile = np.linspace(0.0, 1.0, motion.frame_count)[:, None]
    source = tmp_path / "face.glb"
    write_glb(source, skinned, [motion], morph_weights=[smile])
    if not joints_move:  # only the weights channel: a clip that poses no joint

        def weights_only(gltf, blob) -> None:
            animation = gltf.animations[0]
            animation.channels = [channel for channel in animation.channels if channel.target.path == "weights"]

        edit_glb(source, source, weights_only)
    frames, _ = _built_frames(source, capsys)
    expected = skinned.bake(motion, smile).frames
    assert np.abs(expected - skinned.bake(motion).frames).max() > 0.25  # the smile moves the far end
    np.testing.assert_allclose(frames, expected, atol=1e-4)


def _moving_morph_glb(path: Path, node_motion: str) -> Path:
    """A tube with one morph target (doubling its radius) whose one clip of one second turns the
    weight from 0 to 1 and moves the tube's node: by its own "translation" (0 to 10 along x) or
    "scale" (1 to 2), or by a "parent" turning a quarter turn about z that holds the tube 2 units up."""
    positions, faces = tube()
    builder = GlbBuilder()
    position = builder.add(positions, bounds=True)
    widen = builder.add((positions * [0.0, 1.0, 1.0]).astype(np.float32), bounds=True)
    indices = builder.add(faces.astype(np.uint32).reshape(-1, 1))
    primitive = {"attributes": {"POSITION": position}, "indices": indices, "targets": [{"POSITION": widen}]}
    builder.append("meshes", {"primitives": [primitive], "weights": [0.0]})
    if node_motion == "parent":
        builder.append("nodes", {"name": "carrier", "children": [1]})
        builder.append("nodes", {"mesh": 0, "name": "tube", "translation": [0.0, 2.0, 0.0]})
    else:
        builder.append("nodes", {"mesh": 0, "name": "tube"})
    tube_node = len(builder.json["nodes"]) - 1
    keys = {
        "translation": [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]],
        "scale": [[1.0, 1.0, 1.0], [2.0, 2.0, 2.0]],
        "parent": [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.5**0.5, 0.5**0.5]],
    }[node_motion]
    moved = {"node": 0, "path": "rotation"} if node_motion == "parent" else {"node": tube_node, "path": node_motion}
    times = builder.add(np.array([[0.0], [1.0]], np.float32), bounds=True)
    samplers = [
        {"input": times, "output": builder.add(np.array([[0.0], [1.0]], np.float32))},
        {"input": times, "output": builder.add(np.array(keys, np.float32))},
    ]
    channels = [{"sampler": 0, "target": {"node": tube_node, "path": "weights"}}, {"sampler": 1, "target": moved}]
    builder.append("animations", {"samplers": samplers, "channels": channels})
    builder.json["scenes"], builder.json["scene"] = [{"nodes": [0]}], 0
    builder.save(path)
    return path


@pytest.mark.parametrize("node_motion", ["translation", "parent", "scale"])
def test_a_morph_animated_node_moves_as_its_clip_moves_it(tmp_path, capsys, node_motion):
    """The clip that drives the morph weights also moves the node, itself or through its parent:
    the frames stayed at the node's rest world transform (a node that only scales, which is no
    joint of the animated node tree that placed them, until 2026-12-06, with a warning)."""
    frames, err = _built_frames(_moving_morph_glb(tmp_path / "moving.glb", node_motion), capsys)
    at = np.linspace(0.0, 1.0, 31)  # 30 fps over the one second
    widened = tube()[0] * np.stack([np.ones_like(at), 1.0 + at, 1.0 + at], -1)[:, None]  # the weight 0 to 1
    if node_motion == "parent":
        half_angles = at * np.pi / 4  # a quarter turn about z over the second
        turns = rotations.to_matrix(np.stack([0.0 * at, 0.0 * at, np.sin(half_angles), np.cos(half_angles)], -1))
        expected = (widened + [0.0, 2.0, 0.0]) @ np.swapaxes(turns, 1, 2)
    elif node_motion == "scale":
        expected = widened * (1.0 + at)[:, None, None]
    else:
        expected = widened + 10.0 * at[:, None, None] * [1.0, 0.0, 0.0]
    np.testing.assert_allclose(frames, expected, atol=1e-4)
    assert "warning" not in err.lower()
