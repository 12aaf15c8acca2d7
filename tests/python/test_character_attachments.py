"""Nodes hung from a character's joints follow every motion level (pipelines/attachments.py)."""

from __future__ import annotations

import numpy as np
import pytest

from animlod import rotations, synth
from animlod.io import write_glb
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines.character import build_character

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
    turn = rotations.normalize(np.array([0.2, -0.4, 0.1, 0.9])).tolist()
    for joint in SOCKET_JOINTS:
        socket = {"name": f"socket {joint}", "translation": [0.03, 0.05, -0.02], "rotation": turn, "scale": [2.0] * 3}
        socket = builder.append("nodes", socket)
        nodes[by_name[joint]].setdefault("children", []).append(socket)
    moving = builder.append("nodes", {"name": "moving socket"})
    nodes[by_name["RightHand"]].setdefault("children", []).append(moving)
    animation = builder.json["animations"][0]
    animation["channels"].append({"sampler": 0, "target": {"node": moving, "path": "translation"}})
    still = builder.add(np.zeros((_key_count(builder, animation), 3), np.float32))
    animation["samplers"].append({"input": animation["samplers"][0]["input"], "output": still})
    source = folder / "sockets.glb"
    builder.save(source)
    output = folder / "sockets_lod.glb"
    report = build_character(source, output, [0.5, 0.1], solver="newton", **QUICK)
    return source, output, report


def _key_count(builder: GlbBuilder, animation: dict) -> int:
    return builder.json["accessors"][animation["samplers"][0]["input"]]["count"]


def _posed_worlds(doc: GltfDocument, animation: int) -> list[np.ndarray]:
    """World matrix of every node at the first key of ``animation``."""
    local = [doc.rest_matrix(n) for n in range(len(doc.gltf.nodes))]
    keyed: dict[int, dict[str, np.ndarray]] = {}
    clip = doc.gltf.animations[animation]
    for channel in clip.channels:
        values = np.asarray(doc.accessor(clip.samplers[channel.sampler].output, "test"))
        keyed.setdefault(channel.target.node, {})[channel.target.path] = values[0]
    for node, paths in keyed.items():
        translation, rotation, scale = doc.rest_trs(node)
        local[node] = rotations.compose_transform(
            paths.get("translation", translation), rotations.normalize(paths.get("rotation", rotation)), scale
        )
    worlds = []
    for node in range(len(local)):
        world = local[node]
        for ancestor in doc.ancestors(node):
            world = local[ancestor] @ world
        worlds.append(world)
    return worlds


def _skinned_vertex(doc: GltfDocument, node: int, vertex: int, worlds: list[np.ndarray]) -> np.ndarray:
    """World position of ``vertex`` of the skinned mesh drawn by ``node``, posed by ``worlds``."""
    primitive = doc.gltf.meshes[doc.gltf.nodes[node].mesh].primitives[0]
    skin = doc.gltf.skins[doc.gltf.nodes[node].skin]
    position = np.append(np.asarray(doc.accessor(primitive.attributes.POSITION, "test"))[vertex], 1.0)
    joints = np.asarray(doc.accessor(primitive.attributes.JOINTS_0, "test"))[vertex]
    weights = np.asarray(doc.accessor(primitive.attributes.WEIGHTS_0, "test"))[vertex]
    inverse_binds = np.asarray(doc.accessor(skin.inverseBindMatrices, "test")).reshape(-1, 4, 4).transpose(0, 2, 1)
    matrix = sum(w * worlds[skin.joints[j]] @ inverse_binds[j] for j, w in zip(joints, weights) if w > 0)
    return (matrix @ position)[:3]


def _node(doc: GltfDocument, name: str) -> int:
    return next(n for n, node in enumerate(doc.gltf.nodes) if node.name == name)


@pytest.mark.parametrize("joint", SOCKET_JOINTS)
def test_a_socket_moves_with_the_vertices_of_its_joint_at_every_motion_level(character_with_sockets, joint):
    # A vertex bound to the socket's joint alone is rigid with the socket: in the input, and at
    # each motion level (where a frozen joint's vertices move with its kept ancestor, posed at the
    # key posture), the vertex sits at the same place in the socket's frame.
    source, output, report = character_with_sockets
    doc_in, doc_out = GltfDocument(source), GltfDocument(output)
    base = _node(doc_in, next(node.name for node in doc_in.gltf.nodes if node.skin is not None))
    primitive = doc_in.gltf.meshes[doc_in.gltf.nodes[base].mesh].primitives[0]
    joints = np.asarray(doc_in.accessor(primitive.attributes.JOINTS_0, "test"))
    weights = np.asarray(doc_in.accessor(primitive.attributes.WEIGHTS_0, "test"))
    slot = doc_in.gltf.skins[doc_in.gltf.nodes[base].skin].joints.index(_node(doc_in, joint))
    vertex = int(np.flatnonzero((joints[:, 0] == slot) & (weights[:, 0] > 0.999))[0])
    worlds = _posed_worlds(doc_in, 0)
    socket = worlds[_node(doc_in, f"socket {joint}")]
    expected = (np.linalg.inv(socket) @ np.append(_skinned_vertex(doc_in, base, vertex, worlds), 1.0))[:3]
    grid = doc_out.gltf.nodes[base].extras["animlod_grid"][0]  # geometry level 0, each motion level
    size = np.ptp(np.asarray(doc_in.accessor(primitive.attributes.POSITION, "test")), axis=0).max()
    frozen_somewhere = False
    for m in range(1, len(grid)):
        animation = next(a for a, clip in enumerate(doc_out.gltf.animations) if clip.name.endswith(f"@motion{m}"))
        worlds = _posed_worlds(doc_out, animation)
        copy = _node(doc_out, f"socket {joint}@motion{m}")
        level_skin = doc_out.gltf.skins[doc_out.gltf.nodes[grid[m]].skin]
        assert doc_out.parents[copy] in level_skin.joints  # hung from the level's own skeleton
        frozen_somewhere |= joint not in {doc_out.gltf.nodes[n].name for n in level_skin.joints}
        vertex_world = _skinned_vertex(doc_out, grid[m], vertex, worlds)
        seen = (np.linalg.inv(worlds[copy]) @ np.append(vertex_world, 1.0))[:3]
        np.testing.assert_allclose(seen * 2.0, expected * 2.0, atol=1e-5 * size)  # socket scale 2
    if joint == "LeftHandIndex2":
        assert frozen_somewhere  # the frozen path (key posture between the kept ancestor) is tested


def test_an_animated_node_on_a_joint_is_reported_not_copied(character_with_sockets):
    _, output, report = character_with_sockets
    assert any("'moving socket'" in note and "animated" in note for note in report.notes)
    assert not any((node.name or "").startswith("moving socket@") for node in GltfDocument(output).gltf.nodes)
