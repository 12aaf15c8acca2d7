"""What `animlod motion`'s level GLBs carry of a glTF input beyond the skeleton and the skin:
meshes on and between joints, channels and extensions, and the notes on what they leave out
(pipelines/motion.py, pipelines/attachments.py, io/gltf_write.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from gltf_poses import node_named, posed_worlds, skinned_vertex, vertex_in_holder

from animlod import rotations, synth
from animlod.cli import main
from animlod.io import write_glb
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines.motion import build_motion_levels

TURN = rotations.normalize(np.array([0.3, -0.2, 0.1, 0.9])).tolist()
COLOUR = "/materials/0/pbrMetallicRoughness/baseColorFactor"


@pytest.fixture(scope="module")
def walker(tmp_path_factory) -> Path:
    """animlod's GLB of the procedural humanoid walking, with one material."""
    path = tmp_path_factory.mktemp("walker") / "walker.glb"
    character = synth.humanoid()
    write_glb(path, character, [synth.humanoid_motion(character.skeleton, "walk")])
    builder = GlbBuilder.from_document(GltfDocument(path))
    builder.json["materials"] = [{"name": "skin"}]
    (skinned,) = [node for node in builder.json["nodes"] if "skin" in node]
    builder.json["meshes"][skinned["mesh"]]["primitives"][0]["material"] = 0
    builder.save(path)
    return path


def _edited(source: Path, target: Path, edit) -> Path:
    builder = GlbBuilder.from_document(GltfDocument(source))
    edit(builder, {node.get("name"): index for index, node in enumerate(builder.json["nodes"])})
    builder.save(target)
    return target


def _box(builder: GlbBuilder, name: str) -> int:
    corners = np.array([[x, y, z] for x in (0, 0.02) for y in (0, 0.3) for z in (0, 0.02)], np.float32)
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5]], np.uint16).reshape(-1, 1)
    primitive = {"attributes": {"POSITION": builder.add(corners, bounds=True)}, "indices": builder.add(faces)}
    return builder.append("meshes", {"name": name, "primitives": [primitive]})


def _channel(builder: GlbBuilder, node: int | None, path: str, values: np.ndarray, pointer: str = "") -> None:
    """A channel of the first animation on its first sampler's keys (``values`` interpolated over them)."""
    animation = builder.json["animations"][0]
    times = animation["samplers"][0]["input"]
    keys = builder.json["accessors"][times]["count"]
    output = builder.add(np.linspace(values[0], values[1], keys).astype(np.float32).reshape(keys, -1))
    animation["samplers"].append({"input": times, "output": output})
    target = {"node": node, "path": path}
    if pointer:
        target = {"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": pointer}}}
        builder.add_extension_used("KHR_animation_pointer")
    animation["channels"].append({"sampler": len(animation["samplers"]) - 1, "target": target})


def test_a_node_tree_keeps_what_its_joints_draw_once_and_in_place(walker, tmp_path):
    """An animation library whose joints draw meshes (a rigid robot's links): each joint node's
    mesh was copied with the joint's own channels on the copy, so it moved twice; a static mesh
    node holding an animated joint ("gripper" over "jaw") came along as a copy holding that joint
    again; a mesh that only scaled was read as a bone and the motion refused. Now each mesh sits
    where the input draws it, and every node is there once."""

    def robot(builder: GlbBuilder, named: dict) -> None:
        js = builder.json
        (skinned,) = [index for index, node in enumerate(js["nodes"]) if "skin" in node]
        js["scenes"][0]["nodes"].remove(skinned)
        del js["skins"], js["nodes"][skinned]["skin"]
        js["nodes"][named["Head"]]["mesh"] = _box(builder, "helmet")
        gripper = builder.append("nodes", {"name": "gripper", "mesh": _box(builder, "gripper"), "rotation": TURN})
        jaw = builder.append("nodes", {"name": "jaw", "translation": [0.0, 0.05, 0.0]})
        js["nodes"][gripper]["children"] = [jaw]
        js["nodes"][named["LeftHand"]]["children"].append(gripper)
        _channel(builder, jaw, "rotation", np.array([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.38268343, 0.92387953]]))
        # A light that only scales (blinks): a prop on the head, not a bone that would make the
        # motion scale (refused: motion LoD re-fits rigid motions only).
        led = builder.append("nodes", {"name": "led", "mesh": _box(builder, "led")})
        js["nodes"][named["Head"]]["children"].append(led)
        _channel(builder, led, "scale", np.array([[1.0, 1, 1], [0.1, 0.1, 0.1]]))

    source = _edited(walker, tmp_path / "robot.glb", robot)
    report = build_motion_levels(source, tmp_path / "levels", levels=3)
    document = GltfDocument(source)
    expected, input_names = posed_worlds(document, 0), [node.name for node in document.gltf.nodes]
    for index, files in enumerate(report.files):
        doc = GltfDocument(tmp_path / "levels" / files[-1])
        names = [node.name for node in doc.gltf.nodes]
        assert len(names) == len(set(names)), sorted(name for name in names if names.count(name) > 1)
        animated = {names[c.target.node] for c in doc.gltf.animations[0].channels if c.target.node is not None}
        assert not animated & {"Head content", "gripper"} and "led" in animated  # the joints' channels stay theirs
        assert ("jaw" in animated) == ("jaw" in names)  # a joint, frozen at the coarser levels
        if index == 0:  # the input's pose: level 0's clip plays it unchanged
            worlds = posed_worlds(doc, 0)
            for copy, original in (("Head content", "Head"), ("gripper", "gripper"), ("jaw", "jaw"), ("led", "led")):
                np.testing.assert_allclose(worlds[names.index(copy)], expected[input_names.index(original)], atol=1e-5)


def test_a_spur_under_a_node_between_joints_follows_the_foot(walker, tmp_path):
    """A helper node between two joints (assimp's ``LeftFoot_$AssimpFbx$_PostRotation``, here
    between the foot and the toes) holding a spur: it was left out of every level and called
    scenery. Now it hangs from the foot through a copy of the helper, which plays the helper's
    own channel (a turn that starts away from its rest rotation): at the first key the spur sits
    where the input has it against the foot's vertices, at every level."""

    def helper(builder: GlbBuilder, named: dict) -> None:
        nodes = builder.json["nodes"]
        foot = nodes[named["LeftFoot"]]
        post = builder.append("nodes", {"name": "LeftFoot_post", "rotation": TURN, "children": foot["children"]})
        foot["children"] = [post]
        spur = {"name": "spur", "mesh": _box(builder, "spur"), "translation": [0, 0.1, 0]}
        nodes[post]["children"].append(builder.append("nodes", spur))
        _channel(builder, post, "rotation", np.array([[0.0, 0.0, 0.38268343, 0.92387953], [0.0, 0.0, 0.0, 1.0]]))

    source = _edited(walker, tmp_path / "helper.glb", helper)
    notes: list[str] = []
    report = build_motion_levels(source, tmp_path / "levels", levels=5, ranking="importance", on_note=notes.append)
    assert not [note for note in notes if "mesh without a skin" in note]
    vertex, expected, size = vertex_in_holder(GltfDocument(source), "LeftFoot", "spur")
    for files in report.files:
        doc = GltfDocument(tmp_path / "levels" / files[-1])
        worlds, spur = posed_worlds(doc, 0), node_named(doc, "spur")
        turned = [c.target.node for c in doc.gltf.animations[0].channels if c.target.path == "rotation"]
        assert doc.parents[spur] == node_named(doc, "LeftFoot_post") and doc.parents[spur] in turned
        vertex_world = skinned_vertex(doc, node_named(doc, "skinned mesh"), vertex, worlds)
        # Where the foot is frozen (the coarsest level, the toes kept: the helper's turn moves
        # them), its vertices ride the kept ancestor as the level's skin binds them and the spur
        # the foot's key posture; measured apart by 5e-5 of the figure.
        frozen = "LeftFoot" not in {doc.gltf.nodes[joint].name for joint in doc.gltf.skins[0].joints}
        np.testing.assert_allclose((np.linalg.inv(worlds[spur]) @ np.append(vertex_world, 1.0))[:3], expected,
                                   atol=(1e-4 if frozen else 1e-5) * size)  # fmt: skip


def test_level_glbs_keep_the_extensions_and_channels_they_can_hold_and_name_the_others(walker, tmp_path):
    """A material's colour animated through KHR_animation_pointer was dropped unless something hung
    from the joints; a pointer at a prop node's translation was said to be left out though it was
    carried; document-level extensions a prop's mesh refers to (KHR_materials_variants) were
    dropped, while a node extension that names an input node by index went on unchanged (wrong in
    the level's numbering); KHR_mesh_quantization stayed required with nothing quantized."""

    def dressed(builder: GlbBuilder, named: dict) -> None:
        js = builder.json
        js["materials"] += [{"name": "visor red"}, {"name": "visor blue"}]
        mesh = _box(builder, "visor")
        js["meshes"][mesh]["primitives"][0]["extensions"] = {
            "KHR_materials_variants": {"mappings": [{"material": 1, "variants": [0]}, {"material": 2, "variants": [1]}]}
        }
        visor = {"name": "visor", "mesh": mesh, "extensions": {"EXT_rig_links": {"source": named["Neck"]}}}
        visor = builder.append("nodes", visor)
        js["nodes"][named["Head"]]["children"].append(visor)
        js["extensions"] = {"KHR_materials_variants": {"variants": [{"name": "red"}, {"name": "blue"}]},
                            "EXT_rig_links": {"root": named["Hips"]}}  # fmt: skip
        for name in ("KHR_materials_variants", "EXT_rig_links", "KHR_mesh_quantization"):
            builder.add_extension_used(name)
        js["extensionsRequired"] = ["KHR_mesh_quantization"]
        _channel(builder, None, "pointer", np.array([[1.0, 1, 1, 1], [1.0, 0.2, 0.2, 1]]), COLOUR)
        _channel(builder, None, "pointer", np.array([[0.0, 0.1, 0], [0.0, 0.15, 0]]), f"/nodes/{visor}/translation")

    source = _edited(walker, tmp_path / "dressed.glb", dressed)
    notes: list[str] = []
    report = build_motion_levels(source, tmp_path / "levels", levels=3, on_note=notes.append)
    (left_out,) = [note for note in notes if "GLBs hold" in note]
    assert "the extensions EXT_rig_links" in left_out and "KHR_animation_pointer" not in left_out
    for files in report.files:
        doc = GltfDocument(tmp_path / "levels" / files[-1])
        js = doc.json
        assert sorted(js["extensionsUsed"]) == ["KHR_animation_pointer", "KHR_materials_variants"]
        assert "extensionsRequired" not in js and list(js["extensions"]) == ["KHR_materials_variants"]
        visor = node_named(doc, "visor")
        assert "extensions" not in js["nodes"][visor]
        pointers = [c["target"]["extensions"]["KHR_animation_pointer"]["pointer"]
                    for c in js["animations"][0]["channels"] if c["target"]["path"] == "pointer"]  # fmt: skip
        moved = [c["target"]["path"] for c in js["animations"][0]["channels"] if c["target"].get("node") == visor]
        assert pointers == [COLOUR] and moved == ["translation"]


def test_clips_and_nodes_the_levels_do_not_play_are_named(walker, tmp_path, capsys):
    """A clip that moves no joint (a fan's spin alone) and an animated node at the scene's root
    were left out without a word, and ``--clip spin`` said the file had no such animation."""

    def extras(builder: GlbBuilder, named: dict) -> None:
        js = builder.json
        fan = builder.append("nodes", {"name": "fan", "mesh": _box(builder, "fan")})
        js["nodes"][named["Head"]]["children"].append(fan)
        target = builder.append("nodes", {"name": "look target"})
        js["scenes"][0]["nodes"].append(target)
        _channel(builder, target, "translation", np.array([[0.0, 1, 2], [1.0, 1, 2]]))
        keys = builder.add(np.array([[0.0, 0, 0, 1], [0.0, 0.38268343, 0.0, 0.92387953]], np.float32))
        times = builder.add(np.array([[0.0], [1.0]], np.float32), bounds=True)
        turn = {"sampler": 0, "target": {"node": fan, "path": "rotation"}}
        js["animations"].append({"name": "spin", "samplers": [{"input": times, "output": keys}], "channels": [turn]})

    source = _edited(walker, tmp_path / "extras.glb", extras)
    notes: list[str] = []
    build_motion_levels(source, tmp_path / "levels", levels=2, on_note=notes.append)
    assert "animation 'spin' moves no joint of the skeleton: not in the levels" in " ".join(notes)
    (left_out,) = [note for note in notes if "GLBs hold" in note]
    assert "the animation of 1 node that hangs from no joint" in left_out
    assert main(["motion", str(source), "-o", str(tmp_path / "spin"), "--clip", "spin"]) == 2
    assert "clip: the animation named 'spin' moves no joint of the skeleton; those that move it: 0:" in (
        capsys.readouterr().err
    )


def test_a_prop_drawn_as_instances_leaves_the_inputs_other_data_out(walker, tmp_path):
    """EXT_mesh_gpu_instancing names accessors from a node, where the pruning did not look: a prop
    drawn as instances kept every mesh and accessor of the input in each level file (twice the
    size of the level). Now its accessors are followed and the rest goes."""
    offsets = np.array([[0.0, 0, 0], [0.05, 0, 0], [0.1, 0, 0]], np.float32)

    def studs(builder: GlbBuilder, named: dict) -> None:
        instancing = {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": builder.add(offsets)}}}
        studs = builder.append("nodes", {"name": "studs", "mesh": _box(builder, "stud"), "extensions": instancing})
        builder.json["nodes"][named["Spine"]]["children"].append(studs)
        builder.add_extension_used("EXT_mesh_gpu_instancing")

    source = _edited(walker, tmp_path / "studs.glb", studs)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    plain = build_motion_levels(walker, tmp_path / "plain", levels=2)
    for files, plain_files in zip(report.files, plain.files):
        doc = GltfDocument(tmp_path / "levels" / files[-1])
        assert [mesh["name"] for mesh in doc.json["meshes"]] == ["stud", "skinned mesh"]
        studs = doc.json["nodes"][node_named(doc, "studs")]
        translation = studs["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["TRANSLATION"]
        np.testing.assert_array_equal(doc.accessor(translation, "test"), offsets)
        size, plain_size = (path.stat().st_size for path in (tmp_path / "levels" / files[-1],
                                                             tmp_path / "plain" / plain_files[-1]))  # fmt: skip
        assert size < 1.1 * plain_size  # the input's own skinned mesh kept would double it


def _renamed_body(builder: GlbBuilder, named: dict) -> None:
    body = builder.json["nodes"][named["skinned mesh"]]
    body["name"] = "Body"
    builder.json["meshes"][body["mesh"]]["name"] = "Body mesh"


def _with_a_skinned_hat(builder: GlbBuilder, named: dict) -> None:
    """The body renamed, and a box skinned to the head on the body's skin (a part, joined)."""
    _renamed_body(builder, named)
    hat = _box(builder, "hat")
    head = builder.json["skins"][0]["joints"].index(named["Head"])
    attributes = builder.json["meshes"][hat]["primitives"][0]["attributes"]
    attributes["JOINTS_0"] = builder.add(np.tile(np.array([[head, 0, 0, 0]], np.uint16), (8, 1)))
    attributes["WEIGHTS_0"] = builder.add(np.tile(np.array([[1.0, 0, 0, 0]], np.float32), (8, 1)))
    builder.json["scenes"][0]["nodes"].append(builder.append("nodes", {"name": "Hat", "mesh": hat, "skin": 0}))


@pytest.mark.parametrize(
    ("edit", "node", "mesh"),
    [(_renamed_body, "Body", "Body mesh"), (_with_a_skinned_hat, "Body + Hat", "Body mesh + hat")],
)
def test_level_glbs_keep_the_names_of_the_skinned_mesh(walker, tmp_path, edit, node, mesh):
    """The level files named their skinned mesh and its node "skinned mesh" whatever the input called
    them (RiggedFigure's mesh 'Proxy'): they keep the input's names, and joined parts say so."""
    source = _edited(walker, tmp_path / "named.glb", edit)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    for files in report.files:
        doc = GltfDocument(tmp_path / "levels" / files[-1])
        (skinned,) = [written for written in doc.json["nodes"] if "skin" in written]
        assert (skinned["name"], doc.json["meshes"][skinned["mesh"]]["name"]) == (node, mesh)


def test_level_glbs_keep_only_the_cameras_and_lights_that_hang_from_the_joints(walker, tmp_path):
    """The note said the levels leave out the input's cameras and lights elsewhere, but each level
    GLB still held every camera (and every light of KHR_lights_punctual where one hung from a
    joint), at the input's indices, used by no node. Now only those of the joints' copies are
    there, renumbered with the pointers at them."""
    yfov = "/cameras/1/perspective/yfov"

    def staged(builder: GlbBuilder, named: dict) -> None:
        js = builder.json
        lens = {"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}
        js["cameras"] = [{"name": "scene camera", **lens}, {"name": "head camera", **lens}]
        js["extensions"] = {"KHR_lights_punctual": {"lights": [{"name": "sun", "type": "directional"},
                                                               {"name": "torch", "type": "point"}]}}  # fmt: skip
        builder.add_extension_used("KHR_lights_punctual")
        js["scenes"][0]["nodes"] += [builder.append("nodes", {"name": "scene camera", "camera": 0}),
                                     builder.append("nodes", {"name": "sun", "extensions": {
                                         "KHR_lights_punctual": {"light": 0}}})]  # fmt: skip
        head_camera = builder.append("nodes", {"name": "head camera", "camera": 1, "translation": [0, 0.1, 0]})
        torch = builder.append("nodes", {"name": "torch", "extensions": {"KHR_lights_punctual": {"light": 1}}})
        js["nodes"][named["Head"]]["children"] += [head_camera, torch]
        _channel(builder, None, "pointer", np.array([[0.7], [0.5]]), yfov)

    source = _edited(walker, tmp_path / "staged.glb", staged)
    notes: list[str] = []
    report = build_motion_levels(source, tmp_path / "levels", levels=2, on_note=notes.append)
    (left_out,) = [note for note in notes if "GLBs hold" in note]
    assert "its cameras and lights elsewhere" in left_out
    for files in report.files:
        js = GltfDocument(tmp_path / "levels" / files[-1]).json
        assert [camera["name"] for camera in js["cameras"]] == ["head camera"]
        assert [light["name"] for light in js["extensions"]["KHR_lights_punctual"]["lights"]] == ["torch"]
        holders = {node["name"]: node for node in js["nodes"] if "camera" in node or "extensions" in node}
        assert sorted(holders) == ["head camera", "torch"] and holders["head camera"]["camera"] == 0
        assert holders["torch"]["extensions"]["KHR_lights_punctual"]["light"] == 0
        pointers = [c["target"]["extensions"]["KHR_animation_pointer"]["pointer"]
                    for c in js["animations"][0]["channels"] if c["target"]["path"] == "pointer"]  # fmt: skip
        assert pointers == ["/cameras/0/perspective/yfov"]


def test_level_glbs_of_a_figure_with_a_camera_elsewhere_hold_none(walker, tmp_path):
    """A camera and a light at the scene's root only: the level GLBs hold no camera array."""

    def filmed(builder: GlbBuilder, named: dict) -> None:
        builder.json["cameras"] = [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}]
        builder.json["extensions"] = {"KHR_lights_punctual": {"lights": [{"type": "spot"}]}}
        builder.add_extension_used("KHR_lights_punctual")
        spot = {"name": "spot", "extensions": {"KHR_lights_punctual": {"light": 0}}}
        builder.json["scenes"][0]["nodes"] += [builder.append("nodes", {"name": "camera", "camera": 0}),
                                               builder.append("nodes", spot)]  # fmt: skip

    source = _edited(walker, tmp_path / "filmed.glb", filmed)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    for files in report.files:
        js = GltfDocument(tmp_path / "levels" / files[-1]).json
        assert "cameras" not in js and "extensions" not in js and "extensionsUsed" not in js
