"""Structures of real-world glTF exports that the development files do not have (the Khronos sample
characters, Mixamo, VRM, Blender and 3ds Max exports), rebuilt small from procedural meshes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib
import pytest
from gltf_edits import append_accessor, edit_glb
from gltf_poses import posed_worlds
from simplify_inputs import ellipsoid, tube, two_bone_tube

from animlod import rotations, synth
from animlod.io.errors import FormatError
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf import read_gltf, read_node_motions, write_glb
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines.character import build_character
from animlod.pipelines.lod_document import simplify_document
from animlod.pipelines.motion import build_motion_levels


def _morph_tube_glb(path: Path, node_weights: list[float] | None, clip: str | None = None) -> Path:
    """A tube with one morph target (doubling its height), mesh weights [0], drawn by one node
    whose ``weights`` override the mesh's when given (glTF 2.0, 3.7.2.2); with ``clip``, a clip
    stretching it over one second, by a "weights" channel or a KHR_animation_pointer ("pointer"), or
    turning it a quarter turn ("rotation", as a truck's wheels turn)."""
    positions, faces = tube()
    builder = GlbBuilder()
    position = builder.add(positions.astype(np.float32), bounds=True)
    stretch = builder.add((positions * [0.0, 1.0, 0.0]).astype(np.float32), bounds=True)
    indices = builder.add(faces.astype(np.uint32).reshape(-1, 1))
    primitive = {"attributes": {"POSITION": position}, "indices": indices, "targets": [{"POSITION": stretch}]}
    builder.append("meshes", {"primitives": [primitive], "weights": [0.0]})
    node = {"mesh": 0, "name": "tall"} | ({} if node_weights is None else {"weights": node_weights})
    builder.append("nodes", node)
    builder.json["scenes"], builder.json["scene"] = [{"nodes": [0]}], 0
    if clip is not None:
        times = builder.add(np.array([[0.0], [1.0]], np.float32), bounds=True)
        sampler = {"input": times, "output": builder.add(np.array([[0.0], [1.0]], np.float32))}
        target = {"node": 0, "path": "weights"}
        if clip == "rotation":
            turn = np.array([[0.0, 0.0, 0.0, 1.0], [0.0, 0.5**0.5, 0.0, 0.5**0.5]], np.float32)
            sampler, target = {"input": times, "output": builder.add(turn)}, {"node": 0, "path": "rotation"}
        if clip == "pointer":
            target = {"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": "/nodes/0/weights"}}}
            builder.add_extension_used("KHR_animation_pointer")
        builder.append("animations", {"samplers": [sampler], "channels": [{"sampler": 0, "target": target}]})
    builder.save(path)
    return path


def _two_bone_glb(path: Path) -> Path:
    skinned, motion = two_bone_tube()
    write_glb(path, skinned, [motion])
    return path


def test_primitives_with_four_and_eight_influences_keep_integer_joints(tmp_path: Path) -> None:
    """A mesh whose first primitive has 8 influences (JOINTS_1/WEIGHTS_1, as Mixamo and VRM exports
    write for dense areas) and whose second has 4: the 4-influence primitive is padded with joint 0 at
    weight 0. The padding was float32 and turned every joint slot into a float (IndexError)."""

    def second_set_on_a_copy(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        primitive = gltf.meshes[0].primitives[0]
        count = gltf.accessors[primitive.attributes.POSITION].count
        eight = pygltflib.Primitive(
            **{**vars(primitive), "attributes": pygltflib.Attributes(**vars(primitive.attributes))}
        )
        eight.attributes.JOINTS_1 = append_accessor(gltf, blob, np.ones((count, 4), np.uint8), "VEC4")
        eight.attributes.WEIGHTS_1 = append_accessor(gltf, blob, np.zeros((count, 4), np.float32), "VEC4")
        gltf.meshes[0].primitives = [eight, primitive]

    source = edit_glb(_two_bone_glb(tmp_path / "plain.glb"), tmp_path / "mixed.glb", second_set_on_a_copy)
    skinned = read_gltf(source).skinned_meshes[0]
    assert skinned.joints.dtype.kind in "iu"
    reference = read_gltf(tmp_path / "plain.glb").skinned_meshes[0]
    vertices = len(reference.rest_positions)
    np.testing.assert_allclose(skinned.rest_positions[vertices:], reference.rest_positions, atol=1e-6)
    report = simplify_document(source, tmp_path / "lod.glb")
    assert report.drawables and (tmp_path / "lod.glb").is_file()


def test_level_nodes_keep_the_morph_weights_of_their_base_node(tmp_path: Path) -> None:
    """A node's morph weights override its mesh's: the base node shows the tube stretched, and so must
    every level that stands in for it. Level nodes copied the transform only, so an MSFT_lod viewer
    switching levels showed the tube at half its height."""
    source = _morph_tube_glb(tmp_path / "tall.glb", [1.0])
    simplify_document(source, tmp_path / "lod.glb")
    nodes = GltfDocument(tmp_path / "lod.glb").json["nodes"]
    levels = nodes[0]["extensions"]["MSFT_lod"]["ids"]
    assert levels and all(nodes[level].get("weights") == [1.0] for level in levels)
    # Without node weights, levels show the mesh's own (and get none of their own).
    simplify_document(_morph_tube_glb(tmp_path / "plain.glb", None), tmp_path / "plain_lod.glb")
    plain = GltfDocument(tmp_path / "plain_lod.glb").json["nodes"]
    assert all("weights" not in plain[level] for level in plain[0]["extensions"]["MSFT_lod"]["ids"])


@pytest.mark.parametrize("clip", ["weights", "pointer", "rotation"])
def test_every_level_node_plays_the_clip_of_its_base_node(tmp_path: Path, clip: str) -> None:
    """A clip's channel animates one node, and each MSFT_lod level is a node of its own: the levels had
    no channel, so a viewer switching to one showed the tube at its rest weights, or not turning."""
    simplify_document(_morph_tube_glb(tmp_path / "tall.glb", None, clip), tmp_path / "lod.glb")
    doc = GltfDocument(tmp_path / "lod.glb")
    levels = doc.json["nodes"][0]["extensions"]["MSFT_lod"]["ids"]
    (channels,) = doc.channel_targets
    path = "rotation" if clip == "rotation" else "weights"
    assert levels and channels == [(0, path), *[(level, path) for level in levels]]
    assert {channel.sampler for channel in doc.gltf.animations[0].channels} == {0}


def test_a_static_node_shows_its_own_morph_weights(tmp_path: Path) -> None:
    """read_gltf places a static morphed mesh with its node's weights (they override the mesh's
    [0]): the tube drawn stretched to twice its cross-section height. The mesh's weights were used."""
    positions, _ = tube()
    (stretched,) = read_gltf(_morph_tube_glb(tmp_path / "tall.glb", [1.0])).static_meshes
    np.testing.assert_allclose(stretched.frames[0], positions * [1.0, 2.0, 1.0], atol=1e-6)
    (plain,) = read_gltf(_morph_tube_glb(tmp_path / "plain.glb", None)).static_meshes
    np.testing.assert_allclose(plain.frames[0], positions, atol=1e-6)


def _trs_matrix(translation, rotation, scale) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = rotations.to_matrix(np.asarray(rotation, np.float64)) * np.asarray(scale, np.float64)
    matrix[:3, 3] = translation
    return matrix


def test_a_mirrored_joint_is_posed_as_a_viewer_poses_it(tmp_path: Path) -> None:
    """A joint with scale (-1, 1, 1), as 3ds Max and Maya write mirrored bones, between a turning root
    and a turning child. The skin is baked exactly as glTF's node matrices pose it, and the motion stays
    rigid (the mirroring is in the rest shape), so motion LoD takes it. Such files were refused."""
    positions, faces = tube(rings=8, segments=6, length=1.0)
    positions = positions[:, [1, 0, 2]] + [0.5, 0.5, 0.0]  # along y, over the mirrored joint and its child
    weights = np.clip(positions[:, 1], 0.0, 1.0)
    joints = np.tile(np.array([[2, 1, 0, 0]], np.uint16), (len(positions), 1))
    weights = np.stack([weights, 1.0 - weights, np.zeros_like(weights), np.zeros_like(weights)], -1)
    trs = [
        ([0, 0, 0], [0, 0, 0, 1], [1, 1, 1]),
        ([0.5, 0, 0], [0, 0, 0, 1], [-1, 1, 1]),
        ([0, 1, 0], [0, 0, 0, 1], [1, 1, 1]),
    ]
    rest = [_trs_matrix(*trs[0])]
    for node in (1, 2):
        rest.append(rest[-1] @ _trs_matrix(*trs[node]))
    keys = {0: rotations.from_axis_angle([0, 1, 0], [0.0, 0.7]), 2: rotations.from_axis_angle([0, 0, 1], [0.0, 0.9])}

    builder = GlbBuilder()
    primitive = {
        "attributes": {
            "POSITION": builder.add(positions.astype(np.float32), bounds=True),
            "JOINTS_0": builder.add(joints),
            "WEIGHTS_0": builder.add(weights.astype(np.float32)),
        },
        "indices": builder.add(faces.astype(np.uint32).reshape(-1, 1)),
    }
    builder.append("meshes", {"primitives": [primitive]})
    inverse_bind = np.linalg.inv(np.stack(rest)).transpose(0, 2, 1).reshape(3, 16)
    builder.append("skins", {"joints": [0, 1, 2], "inverseBindMatrices": builder.add(inverse_bind.astype(np.float32))})
    for node, (translation, rotation, scale) in enumerate(trs):
        node_json = {"name": f"joint{node}", "translation": translation, "rotation": rotation, "scale": scale}
        builder.append("nodes", node_json | ({"children": [node + 1]} if node < 2 else {}))
    builder.append("nodes", {"name": "body", "mesh": 0, "skin": 0})
    times = builder.add(np.array([[0.0], [1.0]], np.float32), bounds=True)
    samplers = [{"input": times, "output": builder.add(keys[node].astype(np.float32))} for node in keys]
    channels = [{"sampler": k, "target": {"node": node, "path": "rotation"}} for k, node in enumerate(keys)]
    builder.append("animations", {"name": "turn", "samplers": samplers, "channels": channels})
    builder.json["scenes"], builder.json["scene"] = [{"nodes": [0, 3]}], 0
    builder.save(tmp_path / "mirrored.glb")

    scene = read_gltf(tmp_path / "mirrored.glb")
    skinned, (motion,) = scene.skinned_meshes[0], scene.motions
    assert motion.joint_deformations is None
    baked = skinned.bake(motion).frames
    for frame, key in ((0, 0), (-1, 1)):
        world = [_trs_matrix(trs[0][0], keys[0][key], trs[0][2])]
        world.append(world[0] @ _trs_matrix(*trs[1]))
        world.append(world[1] @ _trs_matrix(trs[2][0], keys[2][key], trs[2][2]))
        matrices = np.stack(world) @ np.linalg.inv(np.stack(rest))
        blended = np.einsum("vk,vkij->vij", weights, matrices[joints])
        expected = np.einsum("vij,vj->vi", blended[:, :3, :3], positions) + blended[:, :3, 3]
        np.testing.assert_allclose(baked[frame], expected, atol=1e-5)


def test_motion_levels_show_every_part_of_a_character_on_one_skin(tmp_path: Path) -> None:
    """A character in parts (BrainStem's meshes, a body and its clothes) shares one skin; a part's
    node has a transform of its own, which skinning ignores. Each motion level's GLB shows every
    part, posed as the input poses it; it showed the first part alone."""

    def second_part(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        gltf.meshes.append(pygltflib.Mesh(primitives=gltf.meshes[0].primitives, name="clothes"))
        gltf.nodes.append(pygltflib.Node(name="clothes", mesh=1, skin=0, translation=[0.0, 3.0, 0.0], scale=[2.0] * 3))
        gltf.scenes[gltf.scene or 0].nodes.append(len(gltf.nodes) - 1)

    source = edit_glb(_two_bone_glb(tmp_path / "body.glb"), tmp_path / "parts.glb", second_part)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    scene = read_gltf(source)
    expected = np.concatenate([mesh.bake(scene.motions[0]).frames for mesh in scene.skinned_meshes], axis=1)
    written = read_gltf(tmp_path / "levels" / "parts_lod0.glb")
    (skinned,), (motion,) = written.skinned_meshes, written.motions
    np.testing.assert_allclose(skinned.bake(motion).frames, expected, atol=1e-4)
    assert any("one mesh" in note for note in report.notes)


def test_motion_level_clips_last_as_long_as_the_input_clips(tmp_path: Path) -> None:
    """A glTF clip's last key may fall between two frames at 30 fps: the level GLBs' clips ended up
    to a frame short of it, the last key's pose lost (a STEP clip's only change). The clip's length
    is its animation's, found also after an animation that moves none of the skeleton's nodes."""
    _, motion = two_bone_tube()

    def late_last_key_after_a_prop_clip(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        times = (np.arange(motion.frame_count) / motion.fps * 1.05).astype(np.float32)[:, None]
        late = append_accessor(gltf, blob, times, "SCALAR")
        gltf.accessors[late].min, gltf.accessors[late].max = [float(times[0, 0])], [float(times[-1, 0])]
        for sampler in gltf.animations[0].samplers:
            sampler.input = late
        gltf.nodes.append(pygltflib.Node(name="prop"))
        gltf.scenes[gltf.scene or 0].nodes.append(len(gltf.nodes) - 1)
        keys = append_accessor(gltf, blob, np.array([[0.0], [5.0]], np.float32), "SCALAR")
        gltf.accessors[keys].min, gltf.accessors[keys].max = [0.0], [5.0]
        moves = append_accessor(gltf, blob, np.array([[0, 0, 0], [1, 0, 0]], np.float32), "VEC3")
        prop = pygltflib.AnimationChannelTarget(node=len(gltf.nodes) - 1, path="translation")
        gltf.animations.insert(0, pygltflib.Animation(
            name="prop", samplers=[pygltflib.AnimationSampler(input=keys, output=moves)],
            channels=[pygltflib.AnimationChannel(sampler=0, target=prop)]))  # fmt: skip

    source = edit_glb(_two_bone_glb(tmp_path / "body.glb"), tmp_path / "late.glb", late_last_key_after_a_prop_clip)
    clip_end = GltfDocument(source).animation_duration(1)
    assert clip_end * 30.0 % 1.0 > 0.1  # between two frames
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    for files in report.files:
        written = GltfDocument(tmp_path / "levels" / files[-1])
        assert written.animation_duration(0) == pytest.approx(clip_end, abs=1e-6)


def test_a_clip_that_ends_between_two_frames_keeps_its_last_pose(tmp_path: Path) -> None:
    """The elbow's last key comes 10 ms after a 30 fps frame and turns it by 90 degrees more. The
    clip was sampled on the frame grid only, so its last frame and the levels' last key held the
    pose of the frame before: the snap was lost (13% of a character's size in a helper's file)."""
    snap = rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.pi)  # elbow at 180 degrees

    def late_snap(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        frames = 8
        times = (np.arange(frames) / 30.0).astype(np.float32)[:, None]
        times[-1] = times[-2] + 0.01
        late = append_accessor(gltf, blob, times, "SCALAR")
        gltf.accessors[late].min, gltf.accessors[late].max = [float(times[0, 0])], [float(times[-1, 0])]
        animation = gltf.animations[0]
        for sampler in animation.samplers:
            sampler.input = late
        elbow = next(c.sampler for c in animation.channels if c.target.node == 1 and c.target.path == "rotation")
        keys = two_bone_tube(frames)[1].local_rotations[:, 1].copy()
        keys[-1] = snap
        animation.samplers[elbow].output = append_accessor(gltf, blob, keys.astype(np.float32), "VEC4")

    source = edit_glb(_two_bone_glb(tmp_path / "body.glb"), tmp_path / "snap.glb", late_snap)
    clip_end = GltfDocument(source).animation_duration(0)
    motion = read_gltf(source).motions[0]
    assert motion.frame_count == 8
    np.testing.assert_allclose(np.abs(motion.local_rotations[-1, 1] @ snap), 1.0, atol=1e-6)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    written = GltfDocument(tmp_path / "levels" / report.files[0][-1])
    assert written.animation_duration(0) == pytest.approx(clip_end, abs=1e-6)
    channels = written.gltf.animations[0].channels
    elbow = next(c.sampler for c in channels if c.target.path == "rotation" and c.target.node == 1)
    times, keys, _ = written.sampler_keys(0, elbow, 4, "elbow")
    assert times[-1] == pytest.approx(clip_end, abs=1e-6) and times[-2] < times[-1] - 0.005
    np.testing.assert_allclose(np.abs(keys[-1] @ snap), 1.0, atol=1e-6)


def test_motion_levels_say_what_their_glbs_leave_out(tmp_path: Path) -> None:
    """The motion levels' GLBs hold the skinned mesh, its skeleton and its clips: a file's
    materials, props and cameras were left out of them without a word."""

    def material_and_camera(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        gltf.materials.append(pygltflib.Material(name="skin"))
        gltf.meshes[0].primitives[0].material = 0
        gltf.cameras.append(
            pygltflib.Camera(type="perspective", perspective=pygltflib.Perspective(yfov=0.8, znear=0.1))
        )
        gltf.nodes.append(pygltflib.Node(name="camera", camera=0))
        gltf.scenes[gltf.scene or 0].nodes.append(len(gltf.nodes) - 1)

    plain = _two_bone_glb(tmp_path / "body.glb")
    dressed = edit_glb(plain, tmp_path / "dressed.glb", material_and_camera)
    left_out = [
        note for note in build_motion_levels(dressed, tmp_path / "dressed", levels=2).notes if "not its" in note
    ]
    assert left_out and "material" in left_out[0] and "cameras and lights" in left_out[0]
    assert not [note for note in build_motion_levels(plain, tmp_path / "plain", levels=2).notes if "not its" in note]


def test_motion_levels_keep_the_materials(tmp_path: Path) -> None:
    """The motion levels' GLBs drew the character without its materials and textures: each
    material's faces are now a primitive of their own, over the vertices they use."""
    skinned, _ = two_bone_tube()
    halves = np.array_split(skinned.faces, 2)
    png = b"\x89PNG\r\n\x1a\n" + bytes(24)  # an image is copied by its bytes, never decoded

    def two_materials_one_textured(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        primitive = gltf.meshes[0].primitives[0]
        parts = []
        for material, faces in enumerate(halves):
            indices = append_accessor(gltf, blob, faces.astype(np.uint32).reshape(-1, 1), "SCALAR")
            parts.append(pygltflib.Primitive(attributes=primitive.attributes, indices=indices, material=material))
        gltf.meshes[0].primitives = parts
        offset = len(blob)
        blob.extend(png)
        gltf.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=offset, byteLength=len(png)))
        gltf.images.append(pygltflib.Image(bufferView=len(gltf.bufferViews) - 1, mimeType="image/png"))
        gltf.textures.append(pygltflib.Texture(source=0))
        info = pygltflib.TextureInfo(index=0)
        gltf.materials += [pygltflib.Material(name="cloth", pbrMetallicRoughness=pygltflib.PbrMetallicRoughness(
            baseColorTexture=info)), pygltflib.Material(name="skin")]  # fmt: skip

    source = edit_glb(_two_bone_glb(tmp_path / "body.glb"), tmp_path / "dressed.glb", two_materials_one_textured)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    assert not [note for note in report.notes if "not its" in note]
    for level, files in enumerate(report.files):
        written = GltfDocument(tmp_path / "levels" / files[-1])
        assert [material["name"] for material in written.json["materials"]] == ["cloth", "skin"]
        assert written.view_bytes(written.json["images"][0]["bufferView"], "image") == png
        primitives = written.json["meshes"][0]["primitives"]
        assert [primitive["material"] for primitive in primitives] == [0, 1]
        for primitive, faces in zip(primitives, halves):
            used = np.unique(faces)
            np.testing.assert_array_equal(used[written.accessor(primitive["indices"], "test").reshape(-1, 3)], faces)
            if level == 0:  # the input's skin (a coarser level's bind differs)
                stored = written.accessor(primitive["attributes"]["POSITION"], "test")
                np.testing.assert_allclose(stored, skinned.rest_positions[used], atol=1e-6)


def test_motion_levels_keep_the_morph_weight_channels(tmp_path: Path) -> None:
    """A clip that drives the skinned mesh's morph weights as well as its joints (a face's
    expression over a walk): the levels' GLBs dropped the weights channel."""
    skinned, motion = two_bone_tube()
    ramp = np.linspace(0.0, 1.0, motion.frame_count, dtype=np.float32)

    def swelling_clip(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        swell = append_accessor(gltf, blob, (skinned.rest_positions * [0.0, 0.5, 0.5]).astype(np.float32), "VEC3")
        gltf.accessors[swell].min, gltf.accessors[swell].max = [0.0, -0.1, -0.1], [0.0, 0.1, 0.1]
        gltf.meshes[0].primitives[0].targets = [{"POSITION": swell}]
        gltf.meshes[0].weights = [0.0]
        animation = gltf.animations[0]
        output = append_accessor(gltf, blob, ramp[:, None], "SCALAR")
        animation.samplers.append(pygltflib.AnimationSampler(input=animation.samplers[0].input, output=output))
        node = next(index for index, node in enumerate(gltf.nodes) if node.skin is not None)
        target = pygltflib.AnimationChannelTarget(node=node, path="weights")
        animation.channels.append(pygltflib.AnimationChannel(sampler=len(animation.samplers) - 1, target=target))

    source = edit_glb(_two_bone_glb(tmp_path / "body.glb"), tmp_path / "swelling.glb", swelling_clip)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    assert not [note for note in report.notes if "morph weight" in note]
    for files in report.files:
        written = GltfDocument(tmp_path / "levels" / files[-1])
        (animation,) = written.json["animations"]
        (channel,) = [channel for channel in animation["channels"] if channel["target"]["path"] == "weights"]
        assert "mesh" in written.json["nodes"][channel["target"]["node"]]
        values = written.accessor(animation["samplers"][channel["sampler"]]["output"], "test").ravel()
        np.testing.assert_allclose(values[: motion.frame_count], ramp, atol=1e-6)


def test_motion_levels_show_a_part_on_a_skin_of_its_own_over_the_same_joints(tmp_path: Path) -> None:
    """Exporters may give each mesh a skin of its own over the joints it uses (Soldier's visor): such
    a part was left out of every motion level's GLB. It joins the character where its skin was bound
    in the same pose; a part bound in another pose stays out, and a note says so."""

    def part_on_own_skin(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        joints = list(reversed(gltf.skins[0].joints))  # the same joints, listed in another order
        stored = gltf.skins[0].inverseBindMatrices
        view = gltf.bufferViews[gltf.accessors[stored].bufferView]
        start = (view.byteOffset or 0) + (gltf.accessors[stored].byteOffset or 0)
        matrices = np.frombuffer(bytes(blob[start : start + 64 * len(joints)]), np.float32).reshape(-1, 16)
        elsewhere = matrices[::-1].copy()
        elsewhere[0, 12:15] += 1.0  # one joint bound a unit away (column-major: the translation)
        for name, rows in (("visor", matrices[::-1].copy()), ("posed elsewhere", elsewhere)):
            skin = pygltflib.Skin(joints=joints, inverseBindMatrices=append_accessor(gltf, blob, rows, "MAT4"))
            gltf.skins.append(skin)
            gltf.meshes.append(pygltflib.Mesh(primitives=gltf.meshes[0].primitives, name=name))
            gltf.nodes.append(pygltflib.Node(name=name, mesh=len(gltf.meshes) - 1, skin=len(gltf.skins) - 1))
            gltf.scenes[gltf.scene or 0].nodes.append(len(gltf.nodes) - 1)

    source = edit_glb(_two_bone_glb(tmp_path / "body.glb"), tmp_path / "parts.glb", part_on_own_skin)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    scene = read_gltf(source)
    expected = np.concatenate(
        [mesh.bake(motions[0]).frames for mesh, motions in zip(scene.skinned_meshes[:2], scene.skinned_motions)], axis=1
    )
    written = read_gltf(tmp_path / "levels" / "parts_lod0.glb")
    (skinned,), (motion,) = written.skinned_meshes, written.motions
    np.testing.assert_allclose(skinned.bake(motion).frames, expected, atol=1e-4)
    left_out = (
        "skinned mesh not in the levels' GLBs: node 4 'posed elsewhere' (on other joints or bound in another pose)"
    )
    assert any(left_out in note for note in report.notes)


def test_character_level_nodes_are_named_by_their_place_in_the_grid(tmp_path: Path) -> None:
    """Chain levels are ``<base>_LOD<i>`` and grid-only nodes ``<base>_G<g>M<m>``, each name once: every
    level node was named ``<base>_LOD-1`` (the grid's placeholder level), which importers then told
    apart as .001, .002, ..."""
    character = synth.humanoid()
    write_glb(tmp_path / "humanoid.glb", character, [synth.humanoid_motion(character.skeleton, "walk")])
    build_character(
        tmp_path / "humanoid.glb",
        tmp_path / "lod.glb",
        [0.5, 0.25],
        solver="newton",
        frame_budget=12,
        measured_frames=2,
    )
    nodes = GltfDocument(tmp_path / "lod.glb").json["nodes"]
    base = next(node for node in nodes if "MSFT_lod" in node.get("extensions", {}))
    chain = [nodes[index]["name"] for index in base["extensions"]["MSFT_lod"]["ids"]]
    assert chain == [f"{base['name']}_LOD1", f"{base['name']}_LOD2"]
    grid = [nodes[index] for row in base["extras"]["animlod_grid"] for index in row]
    for node in grid[1:]:
        info = node["extras"]["animlod"]
        if info["level"] < 0:
            assert node["name"] == f"{base['name']}_G{info['mesh_level']}M{info['motion_level']}"
    names = [node["name"] for node in grid]
    assert len(set(names)) == len(names)


def test_motion_levels_of_a_skin_without_inverse_bind_matrices_keep_the_frozen_bones(tmp_path: Path) -> None:
    """Without inverseBindMatrices every bind is the identity (glTF 2.0, 3.7.3.1), so a frozen joint
    re-posed from the bind pose had no bone: its vertices moved by the bone's length. In the frame
    closest to the key posture a level shows its input as it is, matrices or none."""

    def no_inverse_binds(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        gltf.skins[0].inverseBindMatrices = None

    with_matrices = _two_bone_glb(tmp_path / "body.glb")
    for source in (with_matrices, edit_glb(with_matrices, tmp_path / "no_ibm.glb", no_inverse_binds)):
        build_motion_levels(source, tmp_path / source.stem, levels=2)
        scene, level = read_gltf(source), read_gltf(tmp_path / source.stem / f"{source.stem}_lod1.glb")
        assert level.skinned_meshes[0].skeleton.joint_count < scene.skinned_meshes[0].skeleton.joint_count
        expected = scene.skinned_meshes[0].bake(scene.motions[0]).frames
        distance = np.abs(level.skinned_meshes[0].bake(level.motions[0]).frames - expected).max(axis=(1, 2))
        assert distance.min() < 1e-4, source.name


def _animation_library(source: Path, target: Path) -> Path:
    """``source`` (animlod's GLB of one skinned mesh) as animation libraries are exported: no skin,
    the mesh drawn by a prop node held in a hand, a keyless fingertip, and a camera and a sword moving
    beside."""

    def strip(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        mesh_node = len(gltf.nodes) - 1  # write_glb appends the skinned mesh's node last
        gltf.scenes[0].nodes.remove(mesh_node)
        gltf.nodes[mesh_node] = pygltflib.Node(name="prop", mesh=0)
        gltf.skins = []
        names = [node.name for node in gltf.nodes]
        hand, finger = names.index("RightHand"), names.index("LeftHandIndex2")
        gltf.nodes[hand].children = [*(gltf.nodes[hand].children or []), mesh_node]
        gltf.nodes.append(pygltflib.Node(name="LeftHandIndex3", translation=[0.02, 0.0, 0.0]))
        gltf.nodes[finger].children = [*(gltf.nodes[finger].children or []), len(gltf.nodes) - 1]
        gltf.cameras = [pygltflib.Camera(type="perspective", perspective=pygltflib.Perspective(yfov=0.8, znear=0.1))]
        animation = gltf.animations[0]
        for node in (pygltflib.Node(name="camera", camera=0), pygltflib.Node(name="sword")):
            gltf.nodes.append(node)
            gltf.scenes[0].nodes.append(len(gltf.nodes) - 1)
            animation.channels.append(
                pygltflib.AnimationChannel(
                    sampler=animation.channels[0].sampler,  # the root's translation keys
                    target=pygltflib.AnimationChannelTarget(node=len(gltf.nodes) - 1, path="translation"),
                )
            )

    return edit_glb(source, target, strip)


def test_motion_levels_of_an_animation_library_without_skins(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A glTF of clips on a node tree and no skin was refused ("no node draws a skinned mesh"); its
    animated nodes and the keyless nodes below them that draw nothing are the skeleton, and each level's
    GLB holds the level's skeleton and clip. ``info`` names that skeleton."""
    from animlod.cli import main

    character = synth.humanoid()
    skinned = tmp_path / "humanoid.glb"
    write_glb(skinned, character, [synth.humanoid_motion(character.skeleton, "walk")])
    source = _animation_library(skinned, tmp_path / "clips.glb")
    (motion,), left_out = read_node_motions(source)
    assert motion.skeleton.names == [*character.skeleton.names, "LeftHandIndex3"]
    assert left_out == ["node 44 'sword'"]
    expected = read_gltf(skinned).motions[0].world_positions()
    np.testing.assert_allclose(motion.world_positions()[:, :-1], expected, atol=1e-5)

    report = build_motion_levels(source, tmp_path / "levels", levels=3)
    assert any("no skinned mesh; the skeleton is its animated node tree (42 joints" in note for note in report.notes)
    assert any("under no node in common with the skeleton's left out: node 44 'sword'" in n for n in report.notes)
    assert any("GLBs hold the skeleton, its clips" in note and "not its cameras and lights" in note
               for note in report.notes)  # fmt: skip
    document = GltfDocument(source)
    held = posed_worlds(document, 0)[[node.name for node in document.gltf.nodes].index("prop")]
    for index, level in enumerate(report.chain.levels):
        assert report.files[index][1].name == f"clips_lod{index}.glb"
        (written,), _ = read_node_motions(tmp_path / "levels" / report.files[index][1])
        assert written.skeleton.names == level.motion.skeleton.names
        np.testing.assert_allclose(written.world_positions(), level.motion.world_positions(), atol=1e-4)
        # The prop in the hand comes along, held by the hand or, once it is frozen, by the kept
        # arm with the hand's key posture between.
        doc = GltfDocument(tmp_path / "levels" / report.files[index][1])
        prop = [node.name for node in doc.gltf.nodes].index("prop")
        assert doc.gltf.nodes[prop].mesh is not None
        holder = doc.gltf.nodes[doc.parents[prop]].name
        assert holder == "RightHand" if "RightHand" in written.skeleton.names else holder == "RightHand frame"
        if index == 0:
            np.testing.assert_allclose(posed_worlds(doc, 0)[prop], held, atol=1e-5)
    assert report.chain.levels[-1].report.joint_count < 42
    assert report.chain.levels[-1].report.joint_count < 42
    capsys.readouterr()
    assert main(["info", str(source)]) == 0
    assert "no skin; animated node tree: 42 joints, root 'Hips'; other animated trees: node 44 'sword'" in (
        capsys.readouterr().out
    )
    with pytest.raises(ValueError, match="motions: a GLB without a skinned mesh needs a motion"):
        write_glb(tmp_path / "empty.glb", None, [])
    assert not (tmp_path / "empty.glb").exists()


def test_a_gltf_without_skins_or_moving_nodes_has_no_skeleton_for_motion(tmp_path: Path) -> None:
    source = _morph_tube_glb(tmp_path / "tube.glb", None, clip="weights")
    with pytest.raises(FormatError, match="tube.glb: animations: no skin, and no animation translates, turns or"):
        build_motion_levels(source, tmp_path / "levels", levels=2)


def _placed_glb(path: Path, translation: list[float]) -> Path:
    """A bumpy sphere of 2 units across drawn by one node at ``translation``."""
    sphere = ellipsoid(frames=1, rings=24, segments=32)
    positions = sphere.frames[0] * (1.0 + 0.05 * np.sin(7.0 * sphere.frames[0][:, :1]))
    builder = GlbBuilder()
    attributes = {"POSITION": builder.add(positions.astype(np.float32), bounds=True)}
    indices = builder.add(sphere.faces.astype(np.uint32).reshape(-1, 1))
    builder.append("meshes", {"primitives": [{"attributes": attributes, "indices": indices}]})
    builder.append("nodes", {"mesh": 0, "translation": translation})
    builder.json["scenes"], builder.json["scene"] = [{"nodes": [0]}], 0
    builder.save(path)
    return path


def test_a_mesh_placed_far_from_the_origin_simplifies_as_at_the_origin(tmp_path: Path) -> None:
    """Georeferenced scenes place meshes a million units out, where float32 steps by 0.0625: the
    levels were computed and written back from world positions on that grid (at half the faces, 14
    times the error at the origin: a tenth of the radius). The node's placement stays out of the
    float32 positions."""
    reports, positions = [], []
    for name, translation in (("origin", [0.0, 0.0, 0.0]), ("far", [1e6, -2e6, 5e5])):
        reports.append(
            simplify_document(_placed_glb(tmp_path / f"{name}.glb", translation), tmp_path / f"{name}_lod.glb")
        )
        doc = GltfDocument(tmp_path / f"{name}_lod.glb")
        positions.append(
            [doc.accessor(mesh["primitives"][0]["attributes"]["POSITION"], "") for mesh in doc.json["meshes"]]
        )
    errors = [[level.error for level in report.drawables[0].levels] for report in reports]
    assert len(errors[0]) > 1 and errors[0] == errors[1]
    for near, far in zip(*positions):
        np.testing.assert_array_equal(near, far)


def _triangle_soup(source: Path, target: Path) -> Path:
    """``source`` with every primitive's attributes spread to its corners and its indices dropped:
    three vertices per triangle, as Khronos's Fox and many exporters' flat-shaded meshes are."""
    doc = GltfDocument(source)
    builder = GlbBuilder.from_document(doc)

    def spread(index: int, corners: np.ndarray) -> int:
        accessor = builder.json["accessors"][index]
        values = np.asarray(doc.accessor(index, "attribute"))[corners]
        return builder.add(values, bounds="min" in accessor, normalized=accessor.get("normalized", False))

    for mesh in builder.json["meshes"]:
        for primitive in mesh["primitives"]:
            corners = np.asarray(doc.accessor(primitive.pop("indices"), "indices"))[:, 0]
            primitive["attributes"] = {name: spread(index, corners) for name, index in primitive["attributes"].items()}
    builder.prune()
    builder.save(target)
    return target


def test_a_character_without_indices_simplifies_as_the_indexed_one(tmp_path: Path) -> None:
    # glTF allows triangles without an index buffer (glTF 2.0, 3.7.2.1); the weld joins the
    # corners that share a position and attributes back into the indexed mesh's vertices.
    character = synth.humanoid()
    write_glb(tmp_path / "indexed.glb", character, [synth.humanoid_motion(character.skeleton, "walk")])
    soup = _triangle_soup(tmp_path / "indexed.glb", tmp_path / "soup.glb")
    (read,) = read_gltf(soup).skinned_meshes
    assert read.vertex_count == 3 * character.face_count
    reports = [
        simplify_document(source, tmp_path / f"{source.stem}_lod.glb") for source in (tmp_path / "indexed.glb", soup)
    ]
    levels = [[(level.faces, level.error) for level in report.drawables[0].levels] for report in reports]
    assert len(levels[0]) > 2 and levels[0] == levels[1]


def test_simplify_and_character_point_an_animation_library_to_motion(tmp_path: Path) -> None:
    character = synth.humanoid()
    write_glb(tmp_path / "humanoid.glb", character, [synth.humanoid_motion(character.skeleton, "walk")])

    def no_prop(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        gltf.nodes[next(i for i, node in enumerate(gltf.nodes) if node.name == "prop")].mesh = None

    source = edit_glb(
        _animation_library(tmp_path / "humanoid.glb", tmp_path / "with_prop.glb"), tmp_path / "clips.glb", no_prop
    )
    with pytest.raises(
        FormatError,
        match="no node draws a triangle mesh, nothing to simplify .its animations are `animlod motion`'s input",
    ):
        simplify_document(source, tmp_path / "lod.glb")
    with pytest.raises(FormatError, match="a character chain needs both .it draws no mesh: `animlod motion` takes its"):
        build_character(source, tmp_path / "lod.glb")


def test_motion_levels_of_every_clip_share_one_skeleton_per_level(tmp_path: Path) -> None:
    """A glTF's clips (a character's walk, run, idle) need one skeleton per level at run time; its
    first clip alone was simplified and the others dropped without a word. They are simplified
    together now, one after another: each level writes a BVH per clip and one GLB with every clip."""
    from animlod.io.bvh import read_bvh
    from animlod.io.manifest import read_lod_manifest

    skinned, motion = two_bone_tube()
    back = motion.take_frames(np.arange(motion.frame_count)[::-1])
    write_glb(tmp_path / "clips.glb", skinned, [motion, back], names=["Armature|Bend", "Armature|Bend"])
    report = build_motion_levels(tmp_path / "clips.glb", tmp_path / "levels", levels=2)
    assert any("its 2 animations simplified together" in note for note in report.notes)
    frames = motion.frame_count
    for index, level in enumerate(report.chain.levels):
        clip_files = [f"clips_lod{index}_Armature_Bend_{k}.bvh" for k in range(2)]
        assert [path.name for path in report.files[index]] == [*clip_files, f"clips_lod{index}.glb"]
        written = read_gltf(tmp_path / "levels" / f"clips_lod{index}.glb").motions
        assert [clip.name for clip in written] == ["Armature|Bend"] * 2
        for k, span in enumerate((slice(0, frames), slice(frames, 2 * frames))):
            expected = level.motion.take_frames(span).world_positions()
            np.testing.assert_allclose(written[k].world_positions(), expected, atol=1e-5)
            from_bvh = read_bvh(tmp_path / "levels" / clip_files[k]).world_positions()
            np.testing.assert_allclose(from_bvh, expected, atol=1e-4)
    # Each clip's largest error at each level, for a runtime that picks a level per clip.
    manifest = read_lod_manifest(tmp_path / "levels" / "clips_motion_lod.json")
    for level, row in zip(report.chain.levels, manifest["levels"]):
        errors = [clip["error"] for clip in row["clips"]]
        assert [clip["name"] for clip in row["clips"]] == ["Armature|Bend"] * 2
        assert max(errors) == pytest.approx(level.report.max_error, rel=1e-12, abs=1e-15)
    # A clip and its reverse: the same error, up to the solver's tolerance (each frame's solve
    # starts from the frame before, and the tube's skinned tip is re-fitted, skin_measure.py).
    first, reverse = (clip["error"] for clip in manifest["levels"][-1]["clips"])
    assert first == pytest.approx(reverse, rel=1e-6)


def test_meshes_on_skins_of_the_same_joints_share_one_skeleton_per_motion_level(tmp_path: Path) -> None:
    """Exporters may give every mesh a skin of its own over the same joints: each skin got a chain
    of its own, so the LoD GLB held a reduced skeleton and re-fitted clips per mesh, each animated
    at run time. One skeleton per motion level now serves every such mesh."""
    character = synth.humanoid()
    write_glb(tmp_path / "humanoid.glb", character, [synth.humanoid_motion(character.skeleton, "walk")])

    def hair_on_own_skin(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        skin = pygltflib.Skin(joints=list(gltf.skins[0].joints), inverseBindMatrices=gltf.skins[0].inverseBindMatrices)
        gltf.skins.append(skin)
        gltf.meshes.append(pygltflib.Mesh(primitives=gltf.meshes[0].primitives, name="hair"))
        gltf.nodes.append(pygltflib.Node(name="hair", mesh=1, skin=1))
        gltf.scenes[0].nodes.append(len(gltf.nodes) - 1)

    source = edit_glb(tmp_path / "humanoid.glb", tmp_path / "two_skins.glb", hair_on_own_skin)
    report = build_character(
        source, tmp_path / "lod.glb", [0.5, 0.25], solver="newton", frame_budget=12, measured_frames=2
    )
    assert "skin 1: the joints of skin 0; it plays the same motion levels" in report.notes
    doc = GltfDocument(tmp_path / "lod.glb")
    assert len(doc.gltf.animations) == 3  # the input's clip and one per reduced motion level
    joints_by_level: dict[int, set] = {}
    for node in doc.json["nodes"]:
        info = (node.get("extras") or {}).get("animlod")
        if info and info["motion_level"] > 0 and "skin" in node:
            joints_by_level.setdefault(info["motion_level"], set()).add(
                tuple(doc.json["skins"][node["skin"]]["joints"])
            )
    assert sorted(joints_by_level) == [1, 2] and all(len(joints) == 1 for joints in joints_by_level.values())


def test_motion_level_clips_last_as_long_as_the_clip_they_stand_for(tmp_path: Path) -> None:
    # A clip keyed at 25 fps (or 120, as BVH clips added with --clips are) sampled at 30 fps
    # ended up to a frame early at every motion level: a player looping each clip by its own
    # length (the crowd benchmark does) drifted between levels by that much per loop.
    character = synth.humanoid()
    walk = synth.humanoid_motion(character.skeleton, "walk", cycles=1, fps=25.0)
    duration = (walk.frame_count - 1) / walk.fps
    assert duration * 30.0 % 1.0 > 0.1  # not a whole number of 30-fps frames
    write_glb(tmp_path / "walk25.glb", character, [walk])
    build_character(tmp_path / "walk25.glb", tmp_path / "lod.glb", [0.5], solver="newton",
                    frame_budget=12, measured_frames=2)  # fmt: skip
    doc = GltfDocument(tmp_path / "lod.glb")
    ends = {
        animation["name"]: max(doc.accessor(s["input"], "t").max() for s in animation["samplers"])
        for animation in doc.json["animations"]
    }
    assert len(ends) > 1 and all(end == pytest.approx(duration, abs=1e-6) for end in ends.values()), ends
