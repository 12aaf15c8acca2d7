"""Nodes hung from a character's joints follow every motion level, in `animlod character`'s LoD GLB
and in `animlod motion`'s level GLBs (pipelines/attachments.py)."""

from __future__ import annotations

import numpy as np
import pytest
from gltf_poses import node_named, posed_worlds, skinned_vertex, vertex_in_holder

from animlod import rotations, synth
from animlod.io import write_glb
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines.character import build_character
from animlod.pipelines.motion import build_motion_levels

QUICK = {"frame_budget": 12, "measured_frames": 2}
# A finger (frozen early), the head and a foot; each socket turned, moved and scaled on its joint.
SOCKET_JOINTS = ["LeftHandIndex2", "Head", "LeftFoot"]


@pytest.fixture(scope="module")
def character_with_sockets(tmp_path_factory):
    """The procedural humanoid walking, with an empty socket node under each of SOCKET_JOINTS and
    an animated one under the right hand; its LoD GLB and the build's report."""
    folder = tmp_path_factory.mktemp("sockets")
    plain = folder / "humanoid.glb"
    character = synth.humanoid()
    write_glb(plain, character, [synth.humanoid_motion(character.skeleton, "walk")])
    builder = GlbBuilder.from_document(GltfDocument(plain))
    nodes = builder.json["nodes"]
    by_name = {node.get("name"): index for index, node in enumerate(nodes)}
    # An armature above the root joint that turns and scales the whole skeleton, as exporters
    # from centimetre tools write: its scale reaches the sockets through their joints' nodes.
    scene = builder.json["scenes"][0]["nodes"]
    armature = {"name": "Armature", "scale": [0.5] * 3, "rotation": [0.0, 0.0, 0.38268343, 0.92387953]}
    armature = builder.append("nodes", {**armature, "children": [by_name["Hips"]]})
    scene[scene.index(by_name["Hips"])] = armature
    # The head joint stretched along its bone at rest: a non-uniform scale its end site does not
    # turn under, so the motion stays rigid and the scale goes into the inverse binds.
    nodes[by_name["Head"]]["scale"] = [1.0, 1.3, 1.0]
    turn = rotations.normalize(np.array([0.2, -0.4, 0.1, 0.9])).tolist()
    for joint in SOCKET_JOINTS:
        socket = {"name": f"socket {joint}", "translation": [0.03, 0.05, -0.02], "rotation": turn, "scale": [2.0] * 3}
        socket = builder.append("nodes", socket)
        nodes[by_name[joint]].setdefault("children", []).append(socket)
    # A socket that slides on the right hand, and a morph target whose weight the clip animates.
    moving = builder.append("nodes", {"name": "moving socket"})
    nodes[by_name["RightHand"]].setdefault("children", []).append(moving)
    animation = builder.json["animations"][0]
    keys = builder.json["accessors"][animation["samplers"][0]["input"]]["count"]
    slide = builder.add(np.linspace([0.0, 0.0, 0.0], [0.0, 0.1, 0.0], keys).astype(np.float32))
    _animate(animation, moving, "translation", slide)
    (base,) = [index for index, node in enumerate(nodes) if "skin" in node]
    mesh = builder.json["meshes"][nodes[base]["mesh"]]
    vertices = builder.json["accessors"][mesh["primitives"][0]["attributes"]["POSITION"]]["count"]
    bulge = np.zeros((vertices, 3), np.float32)
    bulge[:, 2] = 0.01
    mesh["primitives"][0]["targets"] = [{"POSITION": builder.add(bulge, bounds=True)}]
    mesh["weights"] = [0.0]
    _animate(animation, base, "weights", builder.add(np.linspace(0.0, 1.0, keys).astype(np.float32)[:, None]))
    # A rigid hat drawn by the head joint's node itself, with a morph target the clip animates.
    corners = builder.add(np.array([[0.0, 0.1, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.1]], np.float32), bounds=True)
    lift = builder.add(np.array([[0.0, 0.02, 0.0]] * 3, np.float32), bounds=True)
    hat = {"primitives": [{"attributes": {"POSITION": corners}, "targets": [{"POSITION": lift}]}], "weights": [0.0]}
    nodes[by_name["Head"]]["mesh"] = builder.append("meshes", hat)
    lowering = builder.add(np.linspace(1.0, 0.0, keys).astype(np.float32)[:, None])
    _animate(animation, by_name["Head"], "weights", lowering)
    # A material colour the clip animates through KHR_animation_pointer.
    builder.json["materials"] = [{"name": "skin"}]
    mesh["primitives"][0]["material"] = 0
    colour = builder.add(np.linspace([1.0, 1.0, 1.0, 1.0], [1.0, 0.2, 0.2, 1.0], keys).astype(np.float32))
    animation["samplers"].append({"input": animation["samplers"][0]["input"], "output": colour})
    pointer = {"KHR_animation_pointer": {"pointer": "/materials/0/pbrMetallicRoughness/baseColorFactor"}}
    target = {"path": "pointer", "extensions": pointer}
    animation["channels"].append({"sampler": len(animation["samplers"]) - 1, "target": target})
    builder.json.setdefault("extensionsUsed", []).append("KHR_animation_pointer")
    source = folder / "sockets.glb"
    builder.save(source)
    output = folder / "sockets_lod.glb"
    report = build_character(source, output, [0.5, 0.1], solver="newton", **QUICK)
    return source, output, report


def _animate(animation: dict, node: int, path: str, output: int) -> None:
    """A channel of ``animation`` on ``node``'s ``path``, keyed at the animation's first input."""
    animation["samplers"].append({"input": animation["samplers"][0]["input"], "output": output})
    animation["channels"].append({"sampler": len(animation["samplers"]) - 1, "target": {"node": node, "path": path}})


HOLDERS = [*[(joint, f"socket {joint}") for joint in SOCKET_JOINTS], ("Head", "Head")]


@pytest.mark.parametrize("joint, holder", HOLDERS)
def test_a_socket_moves_with_the_vertices_of_its_joint_at_every_motion_level(character_with_sockets, joint, holder):
    # A vertex bound to the socket's joint alone is rigid with the socket (holder: the socket node,
    # or the joint node for the hat it draws): in the input, and at each motion level (where a
    # frozen joint's vertices move with its kept ancestor, posed at the key posture), the vertex
    # sits at the same place in the holder's frame as in its copy's.
    source, output, report = character_with_sockets
    doc_in, doc_out = GltfDocument(source), GltfDocument(output)
    vertex, expected, size = vertex_in_holder(doc_in, joint, holder)
    base = node_named(doc_in, next(node.name for node in doc_in.gltf.nodes if node.skin is not None))
    grid = doc_out.gltf.nodes[base].extras["animlod_grid"][0]  # geometry level 0, each motion level
    frozen_somewhere = False
    for m in range(1, len(grid)):
        animation = next(a for a, clip in enumerate(doc_out.gltf.animations) if clip.name.endswith(f"@motion{m}"))
        worlds = posed_worlds(doc_out, animation)
        copy = node_named(doc_out, f"{holder}@motion{m}")
        level_skin = doc_out.gltf.skins[doc_out.gltf.nodes[grid[m]].skin]
        hung = doc_out.parents[copy]  # from the level's own skeleton, or a static frame node on it
        assert hung in level_skin.joints or doc_out.parents[hung] in level_skin.joints
        frozen_somewhere |= joint not in {doc_out.gltf.nodes[n].name for n in level_skin.joints}
        vertex_world = skinned_vertex(doc_out, grid[m], vertex, worlds)
        seen = (np.linalg.inv(worlds[copy]) @ np.append(vertex_world, 1.0))[:3]
        np.testing.assert_allclose(seen, expected, atol=1e-5 * size)
    if joint == "LeftHandIndex2":
        assert frozen_somewhere  # the frozen path (key posture between the kept ancestor) is tested


@pytest.fixture(scope="module")
def motion_levels_with_sockets(character_with_sockets, tmp_path_factory):
    """``animlod motion``'s level GLBs of the character with sockets, and the notes of the run."""
    source, _, _ = character_with_sockets
    folder = tmp_path_factory.mktemp("socket_motion")
    notes: list[str] = []
    report = build_motion_levels(source, folder, levels=4, ranking="importance", on_note=notes.append)
    return source, [folder / files[-1] for files in report.files], notes


@pytest.mark.parametrize("joint, holder", HOLDERS)
def test_a_socket_moves_with_the_vertices_of_its_joint_in_every_motion_level_glb(
    motion_levels_with_sockets, joint, holder
):
    # As above, in `animlod motion`'s files: one skeleton each, the copy named as the input's
    # node (what a joint node draws: "<joint> content", beside the level's joint node).
    source, levels, _ = motion_levels_with_sockets
    vertex, expected, size = vertex_in_holder(GltfDocument(source), joint, holder)
    frozen_somewhere = False
    for level in levels:
        doc = GltfDocument(level)
        worlds = posed_worlds(doc, 0)
        copy = node_named(doc, f"{holder} content" if holder == joint else holder)
        skin = doc.gltf.skins[0]
        assert doc.parents[copy] in skin.joints or doc.parents[doc.parents[copy]] in skin.joints
        frozen_somewhere |= joint not in {doc.gltf.nodes[n].name for n in skin.joints}
        vertex_world = skinned_vertex(doc, node_named(doc, "skinned mesh"), vertex, worlds)
        seen = (np.linalg.inv(worlds[copy]) @ np.append(vertex_world, 1.0))[:3]
        np.testing.assert_allclose(seen, expected, atol=1e-5 * size)
    if joint == "LeftHandIndex2":
        assert frozen_somewhere


def test_motion_level_glbs_play_the_channels_of_what_hangs_from_the_joints(motion_levels_with_sockets):
    # The sliding socket's translation, the hat's morph weights and the material colour's pointer
    # channel play in every level GLB with the input clip's values; the hat's mesh comes along,
    # and nothing is said to be left out.
    source, levels, notes = motion_levels_with_sockets
    doc_in = GltfDocument(source)
    clip = doc_in.gltf.animations[0]

    def played(doc: GltfDocument, animation, rename: dict[str, str]) -> dict[tuple[str, str], np.ndarray]:
        found = {}
        for channel in animation.channels:
            if channel.target.path == "pointer":
                key = ("pointer", channel.target.extensions["KHR_animation_pointer"]["pointer"])
            else:
                name = doc.gltf.nodes[channel.target.node].name
                key = (rename.get(name, name), channel.target.path)
            if key in hung_channels:
                found[key] = np.asarray(doc.accessor(animation.samplers[channel.sampler].output, "test"))
        return found

    hung_channels = {("moving socket", "translation"), ("Head", "weights"),
                     ("pointer", "/materials/0/pbrMetallicRoughness/baseColorFactor")}  # fmt: skip
    expected = played(doc_in, clip, {})
    assert expected.keys() == hung_channels
    for level in levels:
        doc = GltfDocument(level)
        carried = played(doc, doc.gltf.animations[0], {"Head content": "Head", "Head": "Head joint"})
        assert carried.keys() == expected.keys()
        for key, values in expected.items():
            np.testing.assert_array_equal(carried[key], values)
        assert doc.gltf.nodes[node_named(doc, "Head content")].mesh is not None
        assert "KHR_animation_pointer" in doc.json["extensionsUsed"]
    assert not [note for note in notes if "not " in note and "GLBs" in note]


def test_each_level_clip_plays_what_the_input_clip_moves_besides_the_skeleton(character_with_sockets):
    # The sliding socket's channel and the hat's morph weights go to their copies, the skinned
    # mesh's morph weights to the same mesh node, the material colour's pointer channel as it is;
    # all read the input clip's keys.
    source, output, _ = character_with_sockets
    doc_in, doc_out = GltfDocument(source), GltfDocument(output)
    clip = doc_in.gltf.animations[0]
    outputs = {
        (doc_in.gltf.nodes[channel.target.node].name, channel.target.path): clip.samplers[channel.sampler].output
        for channel in clip.channels
        if channel.target.node is not None
    }
    (colour,) = [channel for channel in clip.channels if channel.target.path == "pointer"]
    levels = [animation for animation in doc_out.gltf.animations if "@motion" in (animation.name or "")]
    assert levels
    level_nodes = set(_level_nodes(doc_out))  # drive_level_nodes's, tested below
    for animation in levels:
        m = animation.name.rsplit("@motion", 1)[1]
        carried = {
            (doc_out.gltf.nodes[channel.target.node].name, path): animation.samplers[channel.sampler].output
            for channel in animation.channels
            for path in [channel.target.path]
            if path != "pointer"
            and channel.target.node not in level_nodes
            and (path == "weights" or "socket" in (doc_out.gltf.nodes[channel.target.node].name or ""))
        }
        (carried_colour,) = [channel for channel in animation.channels if channel.target.path == "pointer"]
        assert carried_colour.target.extensions == colour.target.extensions
        assert animation.samplers[carried_colour.sampler].output == clip.samplers[colour.sampler].output
        base_name = next(node.name for node in doc_in.gltf.nodes if node.skin is not None)
        assert carried == {
            (f"moving socket@motion{m}", "translation"): outputs[("moving socket", "translation")],
            (base_name, "weights"): outputs[(base_name, "weights")],
            (f"Head@motion{m}", "weights"): outputs[("Head", "weights")],  # the hat's, on its copy
        }


def _level_nodes(doc: GltfDocument) -> list[int]:
    """Every node of the skinned mesh's (geometry x motion) grid but its base node."""
    (base,) = [index for index, node in enumerate(doc.gltf.nodes) if node.extras and "animlod_grid" in node.extras]
    return [node for row in doc.gltf.nodes[base].extras["animlod_grid"] for node in row if node != base]


def test_every_level_node_of_the_skinned_mesh_plays_its_morph_weights(character_with_sockets):
    """Each clip's channel of the base node's morph weights drives every node of the grid with the
    same keys: a level is a node of its own, and it held its rest weights (no channel)."""
    _, output, _ = character_with_sockets
    doc = GltfDocument(output)
    (base,) = [index for index, node in enumerate(doc.gltf.nodes) if node.extras and "animlod_grid" in node.extras]
    level_nodes = _level_nodes(doc)
    assert len(level_nodes) >= 3
    for animation in doc.gltf.animations:
        (sampler,) = [c.sampler for c in animation.channels if (c.target.node, c.target.path) == (base, "weights")]
        driven = [c.target.node for c in animation.channels if c.target.path == "weights" and c.sampler == sampler]
        assert sorted(driven) == sorted([base, *level_nodes])


def test_a_hat_too_small_for_levels_stays_as_it_is_and_the_report_says_why(character_with_sockets):
    # The hat, drawn by the head joint's node, is no skinned mesh: it gets levels of its own as a
    # prop (test_character_props.py), but one triangle has no coarser level.
    _, _, report = character_with_sockets
    (hat,) = report.others
    assert hat.label.endswith("mesh 1") and [level.faces for level in hat.levels] == [1]
    assert "not written: the same mesh as the input" in hat.notes[-1]
