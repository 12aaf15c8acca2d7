"""A clip channel that drives the morph weights of a mesh without morph targets: glTF does not
allow it, and it changes nothing. Blender writes one where it applies modifiers to a mesh with
shape keys, which drops the keys the clip animates; every command read such a file without a
word, and a user looking for the face's animation found none in the levels."""

from __future__ import annotations

import numpy as np
import pygltflib
import pytest
from gltf_edits import append_accessor, edit_glb

from animlod import synth
from animlod.cli import main
from animlod.io.gltf import write_glb
from animlod.io.gltf_document import GltfDocument


def _with_idle_weights(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
    node = next(index for index, node in enumerate(gltf.nodes) if node.mesh is not None)
    animation = gltf.animations[0]
    output = append_accessor(gltf, blob, np.zeros((0, 1), np.float32).reshape(-1, 1), "SCALAR")
    animation.samplers.append(pygltflib.AnimationSampler(input=animation.samplers[0].input, output=output))
    target = pygltflib.AnimationChannelTarget(node=node, path="weights")
    animation.channels.append(pygltflib.AnimationChannel(sampler=len(animation.samplers) - 1, target=target))


@pytest.fixture(scope="module")
def idle_glb(tmp_path_factory):
    folder = tmp_path_factory.mktemp("idle")
    figure = synth.humanoid()
    write_glb(folder / "plain.glb", figure, [synth.humanoid_motion(figure.skeleton, "walk", cycles=1)])
    return edit_glb(folder / "plain.glb", folder / "idle.glb", _with_idle_weights)


def test_the_document_names_the_channel(idle_glb):
    doc = GltfDocument(idle_glb)
    node = next(index for index, node in enumerate(doc.gltf.nodes) if node.mesh is not None)
    channel = len(doc.gltf.animations[0].channels) - 1
    note = doc.idle_weight_channels_note()
    assert note is not None and note.startswith("morph weights animated on a mesh without morph targets")
    assert note.endswith(f"{doc.animation_label(0)} channel {channel} ({doc.node_label(node)})")
    assert GltfDocument(idle_glb.with_name("plain.glb")).idle_weight_channels_note() is None


@pytest.mark.parametrize("command", ["info", "simplify", "character", "motion"])
def test_every_command_says_so(idle_glb, tmp_path, capsys, command):
    arguments = [command, str(idle_glb)] + ([] if command == "info" else ["-o", str(tmp_path / "out")])
    assert main(arguments + (["--levels", "2"] if command == "motion" else [])) == 0
    printed = capsys.readouterr()
    assert "morph weights animated on a mesh without morph targets" in printed.out + printed.err
