"""A character in parts: a mesh whose skin lists some of the body's joints (a helmet on the head,
Soldier's visor) plays the body's motion levels (pipelines/skin_parts.py, character.py).

It kept its own joints, animated by the input's clips, at every level: where a level froze the
head, the body's head stayed in its key posture and the helmet moved on without it (Soldier's
visor: 7.8 % of the figure's diagonal apart at its 4-joint level).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pygltflib
import pytest
from rigid_skin import rigid_skin

from animlod import rotations, synth
from animlod.io import read_gltf, read_lod_chains, write_glb
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.model import Motion, Skeleton
from animlod.pipelines.character import build_character
from animlod.pipelines.motion import build_motion_levels

QUICK = {"frame_budget": 12, "measured_frames": 2}


def _box(centre: np.ndarray, half: float) -> tuple[np.ndarray, np.ndarray]:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float32)
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
             [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]  # fmt: skip
    return (centre + half * corners).astype(np.float32), np.array(faces, np.uint16)


def _with_part(
    folder,
    name: str,
    hair: str | None = None,
    plain: Path | None = None,
    targets: Sequence[str] = (),
    defaults: Sequence[float] | None = None,
    hair_bone_alone: bool = False,
    locks: int = 1,
) -> Path:
    """The procedural humanoid walking (or the character of ``plain``), with a box over its head
    skinned by a skin of its own (bound in the body's pose): over Neck and Head, every vertex on
    Head; or with ``hair`` ("still" or "swinging") over Head and a bone "Hair" of its own below
    it, every vertex on Hair (over Hair alone with ``hair_bone_alone``: a skin that lists none of
    the body's joints, as Khronos' RecursiveSkeletons; with ``locks`` such bones side by side
    under Head, "Hair", "Hair2", ..., the box's vertices shared among them). The box has a morph
    target of each name in ``targets``, with the mesh's default weights ``defaults``."""
    if plain is None:
        plain = folder / "humanoid.glb"
        character = synth.humanoid()
        write_glb(plain, character, [synth.humanoid_motion(character.skeleton, "walk")])
    doc = GltfDocument(plain)
    builder = GlbBuilder.from_document(doc)
    nodes = builder.json["nodes"]
    by_name = {node.get("name"): index for index, node in enumerate(nodes)}
    body_skin = builder.json["skins"][0]
    stored = np.asarray(doc.accessor(body_skin["inverseBindMatrices"], "test"), np.float32).reshape(-1, 4, 4)
    head_bind = stored[body_skin["joints"].index(by_name["Head"])].T  # column-major storage
    if hair is None:
        joint_nodes = [by_name["Neck"], by_name["Head"]]
        binds = [stored[body_skin["joints"].index(node)].T for node in joint_nodes]
    else:
        joint_nodes, binds = [by_name["Head"]], [head_bind]
        for lock in range(locks):
            lift = np.eye(4)
            lift[:3, 3] = [0.05 * lock, 0.15, 0.0]
            bone_name = "Hair" if lock == 0 else f"Hair{lock + 1}"
            bone = builder.append("nodes", {"name": bone_name, "translation": lift[:3, 3].tolist()})
            nodes[by_name["Head"]].setdefault("children", []).append(bone)
            joint_nodes.append(bone)
            binds.append(np.linalg.inv(lift) @ head_bind)
        if hair_bone_alone:
            joint_nodes, binds = joint_nodes[1:], binds[1:]
        if hair == "swinging":
            animation = builder.json["animations"][0]
            keys = builder.json["accessors"][animation["samplers"][0]["input"]]["count"]
            angles = np.linspace(0.0, 0.6, keys)
            turns = np.stack([np.sin(angles / 2), 0 * angles, 0 * angles, np.cos(angles / 2)], axis=1)
            animation["samplers"].append({"input": animation["samplers"][0]["input"],
                                          "output": builder.add(turns.astype(np.float32))})  # fmt: skip
            for bone in joint_nodes[-locks:]:
                target = {"node": bone, "path": "rotation"}
                animation["channels"].append({"sampler": len(animation["samplers"]) - 1, "target": target})
    matrices = np.stack([bind.T for bind in binds]).reshape(-1, 16).astype(np.float32)
    skin = builder.append("skins", {"joints": joint_nodes, "inverseBindMatrices": builder.add(matrices)})
    positions, faces = _box(doc.rest_world_matrix(by_name["Head"])[:3, 3] + [0.0, 0.1, 0.0], 0.12)
    joints = np.zeros((len(positions), 4), np.uint16)
    joints[:, 0] = len(joint_nodes) - 1  # Head, or the last lock of Hair
    if hair is not None:  # the locks' vertices side by side
        joints[:, 0] -= (np.arange(len(positions)) * locks // len(positions)).astype(np.uint16)
    weights = np.zeros((len(positions), 4), np.float32)
    weights[:, 0] = 1.0
    attributes = {"POSITION": builder.add(positions, bounds=True), "JOINTS_0": builder.add(joints),
                  "WEIGHTS_0": builder.add(weights)}  # fmt: skip
    primitive = {"attributes": attributes, "indices": builder.add(faces.reshape(-1, 1))}
    mesh = {"name": name, "primitives": [primitive]}
    if targets:
        deltas = np.random.default_rng(len(name)).normal(0.0, 0.02, (len(targets),) + positions.shape)
        primitive["targets"] = [{"POSITION": builder.add(d.astype(np.float32), bounds=True)} for d in deltas]
        mesh["extras"] = {"targetNames": list(targets)}
        if defaults is not None:
            mesh["weights"] = list(defaults)
    mesh = builder.append("meshes", mesh)
    builder.json["scenes"][0]["nodes"].append(builder.append("nodes", {"name": name, "mesh": mesh, "skin": skin}))
    source = folder / f"{name}.glb"
    builder.save(source)
    return source


def _character_with_part(folder, name: str, ratios: list[float], hair: str | None = None) -> tuple:
    """:func:`_with_part`'s LoD GLB and the build's report."""
    output = folder / f"{name}_lod.glb"
    return output, build_character(_with_part(folder, name, hair), output, ratios, solver="newton", **QUICK)


@pytest.fixture(scope="module")
def helmeted(tmp_path_factory):
    return _character_with_part(tmp_path_factory.mktemp("parts"), "helmet", [0.5, 0.25, 0.1])


def _plays_the_bodys_levels(output, part: str) -> int:
    """Asserts that every reduced level of ``part`` is posed by the body's level's joint matrices;
    returns at how many of them the body froze its head."""
    chains = {chain.name: chain for chain in read_lod_chains(output)}
    body, levels = chains["skinned mesh"].levels, chains[part].levels
    frozen_heads = 0
    for body_level, part_level in zip(body[1:], levels[1:]):
        # One skeleton, bound alike and played by the same clips: posed by the same joint matrices.
        assert part_level.skeleton.names == body_level.skeleton.names
        np.testing.assert_allclose(part_level.mesh.inverse_bind, body_level.mesh.inverse_bind, atol=1e-6)
        for mine, theirs in zip(part_level.motions, body_level.motions):
            np.testing.assert_allclose(mine.local_rotations, theirs.local_rotations, atol=1e-6)
            np.testing.assert_allclose(mine.root_positions, theirs.root_positions, atol=1e-6)
        frozen_heads += "Head" not in body_level.skeleton.names
    return frozen_heads


def test_a_helmet_on_the_head_plays_the_bodys_motion_levels(helmeted) -> None:
    output, report = helmeted
    assert "skin 1: its joints belong to skin 0; it plays that skin's motion levels" in report.notes
    helmet = {chain.name: chain for chain in read_lod_chains(output)}["helmet"]
    assert helmet.levels[0].skeleton.names == ["Neck", "Head"]  # the input, as it was
    assert _plays_the_bodys_levels(output, "helmet") >= 1  # the case that tore the helmet off


def test_the_level_clips_list_the_parts_skin_beside_the_bodys(helmeted) -> None:
    # A runtime choosing a chain's clips by extras.animlod.skins finds the body's for the helmet's
    # chain too; one skeleton's clips keep their names (test_character_naming.py).
    output, _ = helmeted
    animations = GltfDocument(output).json["animations"]
    clips = [animation for animation in animations if "animlod" in animation.get("extras", {})]
    assert len(clips) == 3 and all(clip["extras"]["animlod"]["skins"] == [0, 1] for clip in clips)
    assert all("@skin" not in clip["name"] for clip in clips)


def test_hair_on_a_bone_of_its_own_that_holds_still_plays_the_bodys_levels(tmp_path) -> None:
    # VRoid's hair: a skin over the head and hair bones the body's skin does not list. Bones that
    # hold their bind pose on the head move their vertices with it.
    output, report = _character_with_part(tmp_path, "hair", [0.25], hair="still")
    assert "skin 1: its joints hang from those of skin 0; it plays that skin's motion levels" in report.notes
    _plays_the_bodys_levels(output, "hair")


def test_swinging_hair_joins_the_bodys_skeleton(tmp_path) -> None:
    # Hair whose own bone swings kept a skeleton of its own (Head, Hair) with levels of its own:
    # where the body froze the head, the hair went on nodding without it. Its bone now joins the
    # body's skeleton, in every mesh drawn with the body's skin (a second body mesh here), and the
    # hair plays the body's levels: the swing where the level keeps the bone, none where it freezes.
    # A second lock of hair on a bone of the same name joins it too, as a bone of its own.
    first = _with_part(tmp_path, "swinging", hair="swinging")
    source = _with_part(tmp_path, "second lock", hair="swinging", plain=first)
    builder = GlbBuilder.from_document(GltfDocument(source))
    body_node = next(node for node in builder.json["nodes"] if node.get("skin") == 0)
    second = dict(builder.json["meshes"][body_node["mesh"]], name="second body")
    node = builder.append("nodes", {"name": "second body", "mesh": builder.append("meshes", second), "skin": 0})
    builder.json["scenes"][0]["nodes"].append(node)
    builder.save(source)
    output = tmp_path / "swinging_lod.glb"
    report = build_character(source, output, [0.5, 0.25], solver="newton", **QUICK)
    for skin, node in ((1, 42), (2, 44)):
        assert f"skin {skin}: its own joints (node {node} 'Hair') move in its clips and join skin 0; it plays that " \
            "skin's motion levels" in report.notes  # fmt: skip
        assert _plays_the_bodys_levels(output, "swinging" if skin == 1 else "second lock") >= 1
    chains = {chain.name: chain for chain in read_lod_chains(output)}
    assert [level.skeleton.names for level in chains["second body"].levels[1:]] == [
        level.skeleton.names for level in chains["skinned mesh"].levels[1:]
    ]
    swings = []
    for level in chains["swinging"].levels[1:]:
        for bone in {"Hair#42", "Hair#44"} & set(level.skeleton.names):
            turns = level.motions[0].local_rotations[:, level.skeleton.names.index(bone)]
            swings.append(float(2.0 * np.arccos(np.clip(np.abs(turns @ turns[0]), 0.0, 1.0)).max()))
    assert len(swings) >= 2 and min(swings) > 0.5  # the input swings by 0.6 radians


@pytest.mark.parametrize("locks", [1, 2])
@pytest.mark.parametrize("hair", ["still", "swinging"])
def test_hair_whose_skin_lists_its_own_bone_alone_plays_the_bodys_levels(tmp_path, hair, locks) -> None:
    # Its skin lists none of the body's joints, only bones that hang from the head in the node
    # tree: it had levels of its own, posed by the input's head where the body's level froze it,
    # and drifted off the body (with two locks, two trees of joints, until 2026-12-07 evening). It
    # now plays the body's levels like hair that lists the head too: on the head where its bones
    # hold still, its bones joining the body's skeleton where they swing.
    source = _with_part(tmp_path, "own bone", hair=hair, hair_bone_alone=True, locks=locks)
    output = tmp_path / "own_bone_lod.glb"
    report = build_character(source, output, [0.5, 0.25, 0.1], solver="newton", **QUICK)
    bones = ", ".join(["node 42 'Hair'", "node 43 'Hair2'"][:locks])
    relation = (
        "its joints hang from those of" if hair == "still" else f"its own joints ({bones}) move in its clips and join"
    )
    assert f"skin 1: {relation} skin 0; it plays that skin's motion levels" in report.notes
    assert _plays_the_bodys_levels(output, "own bone") >= 1


def test_locks_of_hair_bound_apart_do_not_hang_from_the_head(tmp_path) -> None:
    # Two trees of the hair's own bones give the head one bind only where their binds agree on
    # where the head is: with one lock's bind moved, hanging_rig leaves the skin as it is.
    from animlod.io.gltf_skin import SkinRig
    from animlod.pipelines.skin_parts import hanging_rig

    source = _with_part(tmp_path, "own bone", hair="still", hair_bone_alone=True, locks=2)
    doc = GltfDocument(source)
    body = set(SkinRig(doc, 0).joint_nodes)
    assert hanging_rig(doc, SkinRig(doc, 1), body) is not None
    builder = GlbBuilder.from_document(doc)
    skin = builder.json["skins"][1]
    stored = np.asarray(doc.accessor(skin["inverseBindMatrices"], "test"), np.float32).reshape(-1, 4, 4).copy()
    stored[1, 3, 0] += 0.05  # the second lock's bind, 5 cm along x (column-major storage)
    skin["inverseBindMatrices"] = builder.add(stored.reshape(-1, 16))
    builder.save(tmp_path / "apart.glb")
    apart = GltfDocument(tmp_path / "apart.glb")
    assert hanging_rig(apart, SkinRig(apart, 1), body) is None


def test_a_head_of_its_own_counts_in_the_choice_of_the_bodys_joints(tmp_path) -> None:
    # A modular character: the body's skin weighs nothing to Head, a leaf joint, and the head is a
    # mesh of its own on Neck and Head. Measured by the body's skin alone, Head moved nothing and
    # froze first, and the head, playing the body's levels, lost its nod at the first level.
    names = ["Hips", "Spine", "Neck", "Head", "LeftLeg", "RightLeg"]
    offsets = [[0, 1, 0], [0, 0.3, 0], [0, 0.3, 0], [0, 0.1, 0], [0.1, -0.1, 0], [-0.1, -0.1, 0]]
    skeleton = Skeleton(names, [-1, 0, 1, 2, 0, 0], offsets)
    frames = 30
    phase = np.linspace(0.0, 2.0 * np.pi, frames)
    local = rotations.identity((frames, len(names)))
    for joint, axis, amplitude in ((1, 2, 0.05), (2, 2, 0.05), (3, 0, 0.8), (4, 0, 0.4), (5, 0, -0.4)):
        local[:, joint] = rotations.from_axis_angle(np.eye(3)[axis], amplitude * np.sin(phase))
    motion = Motion(skeleton, np.tile([0.0, 1.0, 0.0], (frames, 1)), local, fps=30.0, name="nod")
    rest = skeleton.rest_world_transforms()[:, :3, 3]
    parts = [(joint, _box(rest[joint] + [0.0, 0.1, 0.0], 0.08)[0]) for joint in (0, 1, 2)]
    parts += [(joint, _box(rest[joint] + [0.0, -0.25, 0.0], 0.08)[0]) for joint in (4, 5)]
    write_glb(tmp_path / "body.glb", rigid_skin(skeleton, parts), [motion])
    source = _with_part(tmp_path, "head", plain=tmp_path / "body.glb")
    build_character(source, tmp_path / "lod.glb", [0.5, 0.25], solver="newton", **QUICK)
    level = {chain.name: chain for chain in read_lod_chains(tmp_path / "lod.glb")}["skinned mesh"].levels[1]
    assert "Head" in level.skeleton.names and len(level.skeleton.names) < len(names)


def _motion_levels_show_every_skin(source: Path, folder: Path) -> list[str]:
    """Asserts that `motion`'s first level GLB of ``source`` draws all of its skinned meshes as the
    input does; returns the build's notes."""
    report = build_motion_levels(source, folder, levels=2)
    assert not any("not in the levels' GLBs" in note for note in report.notes)
    scene = read_gltf(source)
    expected = np.concatenate([mesh.bake(motions[0]).frames for mesh, motions in
                               zip(scene.skinned_meshes, scene.skinned_motions)], axis=1)  # fmt: skip
    written = read_gltf(folder / f"{source.stem}_lod0.glb")
    (skinned,), (motion,) = written.skinned_meshes, written.motions
    np.testing.assert_allclose(skinned.bake(motion).frames, expected, atol=1e-4)
    # The boxes have neither normals nor texture coordinates; the body's are kept all the same.
    body = scene.skinned_meshes[0]
    np.testing.assert_allclose(skinned.normals[: body.vertex_count], body.normals, atol=1e-6)
    np.testing.assert_array_equal(skinned.uvs[: body.vertex_count], body.uvs)
    return report.notes


def test_motion_levels_show_hair_whose_bone_holds_still(tmp_path) -> None:
    # `motion` joins the parts on the body's skeleton into one mesh per level GLB; hair on a bone
    # of its own was left out of them.
    _motion_levels_show_every_skin(_with_part(tmp_path, "hair", hair="still"), tmp_path / "levels")


def test_motion_levels_show_swinging_hair_on_the_bodys_skeleton(tmp_path) -> None:
    # `motion` left hair whose own bone moves in its clips out of the levels' GLBs; its bone now
    # joins the body's skeleton, as in `character`.
    source = _with_part(tmp_path, "hair", hair="swinging")
    notes = _motion_levels_show_every_skin(source, tmp_path / "levels")
    assert f"{source}: node 43 'hair' has joints of its own that move in its clips (node 42 'Hair'); they join the " \
        "skeleton of node 41 'skinned mesh'" in notes  # fmt: skip
    assert "Hair" in read_gltf(tmp_path / "levels" / "hair_lod0.glb").skinned_meshes[0].skeleton.names


def test_motion_levels_show_parts_with_morph_targets_the_body_lacks(tmp_path) -> None:
    # `motion` left out every part whose morph targets were not the first mesh's: a head with
    # blendshapes beside a body without (ReadyPlayerMe, VRoid). Targets join by name: "jaw"
    # moves both parts that have it.
    head = _with_part(tmp_path, "head", targets=["jaw", "blink"])
    teeth = _with_part(tmp_path, "teeth", targets=["jaw"], plain=head)
    _motion_levels_show_every_skin(teeth, tmp_path / "levels")
    scene, written = read_gltf(teeth), read_gltf(tmp_path / "levels" / "teeth_lod0.glb")
    (skinned,), (motion,) = written.skinned_meshes, written.motions
    assert skinned.morph_target_names == ["jaw", "blink"]
    weights = {"jaw": 1.0, "blink": 0.5}
    expected = [
        mesh.bake(motions[0], np.tile([weights[n] for n in mesh.morph_target_names or []], (motion.frame_count, 1)))
        for mesh, motions in zip(scene.skinned_meshes, scene.skinned_motions)
    ]
    posed = skinned.bake(motion, np.tile([1.0, 0.5], (motion.frame_count, 1))).frames
    np.testing.assert_allclose(posed, np.concatenate([each.frames for each in expected], axis=1), atol=1e-4)


def test_motion_levels_show_each_parts_default_morph_weights(tmp_path) -> None:
    # A skinned mesh's default morph weights (glTF's mesh or node `weights`, what a viewer shows
    # where no animation drives them) were read as 0 and written as 0: `motion` drew a Blender
    # shape key left at 1 as if it were off. Parts joined on one mesh keep their own defaults,
    # the head's "jaw" at 1 beside the teeth's at 0.25, the teeth's node overriding its mesh.
    head = _with_part(tmp_path, "head", targets=["jaw", "blink"], defaults=[1.0, 0.5])
    teeth = _with_part(tmp_path, "teeth", targets=["jaw"], plain=head, defaults=[0.0])
    builder = GlbBuilder.from_document(GltfDocument(teeth))
    next(node for node in builder.json["nodes"] if node.get("name") == "teeth")["weights"] = [0.25]
    builder.save(teeth)
    scene = read_gltf(teeth)
    head_mesh, teeth_mesh = scene.skinned_meshes[1:]
    np.testing.assert_array_equal(head_mesh.default_morph_weights, [1.0, 0.5])
    np.testing.assert_array_equal(teeth_mesh.default_morph_weights, [0.25])
    motion = scene.skinned_motions[1][0]
    np.testing.assert_allclose(
        head_mesh.bake(motion).frames, head_mesh.bake(motion, np.tile([1.0, 0.5], (motion.frame_count, 1))).frames
    )
    _motion_levels_show_every_skin(teeth, tmp_path / "levels")


def test_motion_levels_tell_the_hair_bone_from_a_body_bone_of_the_same_name(tmp_path) -> None:
    # `motion` matched a part's joints to the body's by name: hair on a bone of its own named like
    # one of the body's (the left hand, here) was put on that bone and swung with the hand.
    plain = tmp_path / "humanoid.glb"
    character = synth.humanoid()
    write_glb(plain, character, [synth.humanoid_motion(character.skeleton, "walk")])
    builder = GlbBuilder.from_document(GltfDocument(plain))
    next(node for node in builder.json["nodes"] if node.get("name") == "LeftHand")["name"] = "Hair"
    builder.save(plain)
    _motion_levels_show_every_skin(_with_part(tmp_path, "hair", hair="still", plain=plain), tmp_path / "levels")


def _nodes_reversed(source: Path) -> Path:
    """``source`` with its nodes listed in reverse order, every reference to them renumbered."""
    builder = GlbBuilder.from_document(GltfDocument(source))
    gltf = builder.json
    last = len(gltf["nodes"]) - 1
    gltf["nodes"].reverse()
    for node in gltf["nodes"]:
        if "children" in node:
            node["children"] = [last - child for child in node["children"]]
    for scene in gltf["scenes"]:
        scene["nodes"] = [last - node for node in scene["nodes"]]
    for skin in gltf["skins"]:
        skin["joints"] = [last - joint for joint in skin["joints"]]
        if "skeleton" in skin:
            skin["skeleton"] = last - skin["skeleton"]
    for animation in gltf["animations"]:
        for channel in animation["channels"]:
            channel["target"]["node"] = last - channel["target"]["node"]
    reversed_source = source.with_name(f"{source.stem}_reversed.glb")
    builder.save(reversed_source)
    return reversed_source


def test_motion_levels_of_the_body_when_a_part_comes_first_in_the_file(tmp_path) -> None:
    # Files list a visor or a helmet before the body as often as after. `motion` took the first
    # skinned mesh in node order as the skeleton: the helmet's two joints, the body left out
    # (Soldier with its nodes reversed: "the skeleton allows 2 (2 joints ...)"). So did `tdag`.
    from animlod.cli.tdag import read_animation
    from animlod.io import read_skinned

    source = _nodes_reversed(_with_part(tmp_path, "helmet"))
    scene = read_gltf(source)
    helmet, body = scene.skinned_meshes
    assert helmet.skeleton.joint_count < body.skeleton.joint_count and scene.body == 1
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    assert not any("not in the levels' GLBs" in note for note in report.notes)
    (written,) = read_gltf(tmp_path / "levels" / f"{source.stem}_lod0.glb").skinned_meshes
    assert written.skeleton.names == body.skeleton.names
    assert written.vertex_count == body.vertex_count + helmet.vertex_count
    assert read_animation(str(source)).vertex_count == body.vertex_count
    assert read_skinned(source)[0].vertex_count == body.vertex_count


def test_motion_levels_of_the_body_when_hair_of_more_bones_comes_first(tmp_path) -> None:
    # VRoid's hair is skinned to more bones than its body, bones its clips leave alone (a runtime's
    # spring simulation moves them). Chosen by its joint count, its skeleton would be the levels'.
    builder = GlbBuilder.from_document(GltfDocument(_with_part(tmp_path, "hair", hair="still")))
    gltf, doc = builder.json, GltfDocument(tmp_path / "hair.glb")
    hair_skin = gltf["skins"][1]
    binds = np.asarray(doc.accessor(hair_skin["inverseBindMatrices"], "test"), np.float32).reshape(-1, 4, 4)
    lift = np.eye(4, dtype=np.float32)
    lift[3, :3] = -0.01  # column-major storage: the inverse of a 0.01 lift above the Hair bone
    strands = [builder.append("nodes", {"name": f"Strand{index}", "translation": [0.0, 0.01, 0.0]})
               for index in range(len(gltf["skins"][0]["joints"]))]  # fmt: skip
    gltf["nodes"][hair_skin["joints"][1]]["children"] = strands
    hair_skin["joints"] += strands
    strand_binds = np.repeat((binds[1] @ lift)[None], len(strands), axis=0)
    hair_skin["inverseBindMatrices"] = builder.add(np.concatenate([binds, strand_binds]).reshape(-1, 16))
    builder.save(tmp_path / "long_hair.glb")
    source = _nodes_reversed(tmp_path / "long_hair.glb")
    scene = read_gltf(source)
    hair, body = scene.skinned_meshes
    assert hair.skeleton.joint_count > body.skeleton.joint_count and scene.body == 1
    build_motion_levels(source, tmp_path / "levels", levels=2)
    (written,) = read_gltf(tmp_path / "levels" / f"{source.stem}_lod0.glb").skinned_meshes
    assert written.vertex_count == body.vertex_count + hair.vertex_count
    assert set(body.skeleton.names) <= set(written.skeleton.names)


def test_the_helmets_levels_share_the_bodys_skins(helmeted) -> None:
    output, _ = helmeted
    nodes = GltfDocument(output).json["nodes"]
    by_name = {node.get("name"): node for node in nodes}
    for level in (1, 2, 3):
        assert by_name[f"helmet_LOD{level}"]["skin"] == by_name[f"skinned mesh_LOD{level}"]["skin"]
    assert by_name["helmet"]["skin"] != by_name["skinned mesh"]["skin"]


def test_every_node_of_a_motion_level_records_its_skeletons_joints(helmeted) -> None:
    # The helmet's geometry levels at motion level 0 recorded its own skin's 2 joints, while its
    # base node and the body's nodes recorded the skeleton's.
    output, _ = helmeted
    joints: dict[int, set[int]] = {}
    for node in GltfDocument(output).json["nodes"]:
        info = node.get("extras", {}).get("animlod", {})
        if "joints" in info:
            joints.setdefault(info["motion_level"], set()).add(info["joints"])
    assert len(joints) == 4 and all(len(counts) == 1 for counts in joints.values()), joints


def test_a_crowd_poses_the_helmet_at_the_bodys_motion_level(binary, helmeted, tmp_path) -> None:
    # The body's chain and the helmet's choose their levels apart; a crowd draws the finest motion
    # level either chose for both, as for the meshes of one skin: here the body stays at level 0
    # and the helmet would take its coarsest, and MLoD poses exactly what Original poses.
    from animlod.crowd import run_crowd

    output, _ = helmeted
    gltf = pygltflib.GLTF2().load(output)
    for node in gltf.nodes:
        info = (node.extras or {}).get("animlod")
        if info and info.get("level", -1) > 0:
            info["error"] = 1e-9 if node.name.startswith("helmet") else 1e9
    gltf.save(tmp_path / "forced.glb")
    report = run_crowd([tmp_path / "forced.glb"], frames=3, modes="Original,MLoD", pixel_error=1.0, count=12,
                       warmup=2, width=320, height=180)  # fmt: skip
    original, reduced = report.modes["Original"], report.modes["MLoD"]
    assert reduced["drawn"] == original["drawn"] > 0
    assert reduced["joints"] == original["joints"]


def test_the_chains_of_one_skeleton_switch_at_the_same_distance(helmeted) -> None:
    # An engine compares each node's own projected size with its MSFT_screencoverage values: the
    # helmet, a tenth of the body's size, took its 4-joint level at another distance than the body,
    # which drew the other skeleton's head meanwhile. Each level now ends where the later of the two
    # chains asks (a coverage in proportion to each one's size).
    _, report = helmeted
    body, helmet = report.chains["mesh 0 'skinned mesh' with skin 0"], report.chains["mesh 1 'helmet' with skin 1"]
    sizes = [chain[-1].error / chain[-1].relative_error for chain in (body, helmet)]
    assert sizes[1] < 0.2 * sizes[0]
    for mine, theirs in zip(helmet[:-1], body[:-1]):
        assert mine.coverage > 0.0 and sizes[0] / theirs.coverage == pytest.approx(sizes[1] / mine.coverage)
    assert helmet[-1].coverage == body[-1].coverage == 0.0


def _head_and_teeth(folder: Path, teeth_targets: int) -> Path:
    """ReadyPlayerMe's layout: a head with two morph targets and teeth with ``teeth_targets``, two
    meshes on one skin, the walk animating both nodes' weights (the head's from 0 to 1, the
    teeth's held at 0)."""
    source = _with_part(folder, "head", targets=["jaw", "blink"])
    builder = GlbBuilder.from_document(GltfDocument(source))
    nodes = builder.json["nodes"]
    head = next(index for index, node in enumerate(nodes) if node.get("name") == "head")
    teeth_mesh = dict(builder.json["meshes"][nodes[head]["mesh"]], name="teeth")
    primitive = dict(teeth_mesh["primitives"][0])
    primitive["targets"] = primitive["targets"][:teeth_targets]
    teeth_mesh["primitives"] = [primitive]
    teeth_mesh["extras"] = {"targetNames": ["jaw", "blink"][:teeth_targets]}
    teeth = builder.append("nodes", {"name": "teeth", "mesh": builder.append("meshes", teeth_mesh),
                                     "skin": nodes[head]["skin"]})  # fmt: skip
    builder.json["scenes"][0]["nodes"].append(teeth)
    animation = builder.json["animations"][0]
    times = animation["samplers"][0]["input"]
    keys = builder.json["accessors"][times]["count"]
    for node, weights in ((head, np.linspace(0.0, 1.0, 2 * keys)), (teeth, np.zeros(teeth_targets * keys))):
        animation["samplers"].append({"input": times, "output": builder.add(weights.astype(np.float32)[:, None])})
        animation["channels"].append({"sampler": len(animation["samplers"]) - 1,
                                      "target": {"node": node, "path": "weights"}})  # fmt: skip
    path = folder / f"head_and_teeth_{teeth_targets}.glb"
    builder.save(path)
    return path


@pytest.mark.parametrize("teeth_targets", [1, 2])
def test_meshes_on_one_skin_are_measured_with_their_own_morph_weights(tmp_path, teeth_targets) -> None:
    # The skin's clips were read with its last mesh, the teeth: the head was measured with the
    # teeth's weights, refused as "morph_weights: expected shape (12, 2), got (12, 1)" where the
    # teeth have fewer targets, and with the teeth's zeros where they have as many.
    import animlod.pipelines.character as pipeline
    from animlod.io.gltf_drawable import read_drawables

    source = _head_and_teeth(tmp_path, teeth_targets)
    report = build_character(source, tmp_path / "lod.glb", [0.5], solver="newton", **QUICK)
    assert {"mesh 1 'head' with skin 1", "mesh 2 'teeth' with skin 1"} <= set(report.chains)
    by_name = {d.label.split("'")[1]: d for d in read_drawables(GltfDocument(source)) if d.skinned is not None}
    head, teeth = by_name["head"], by_name["teeth"]
    frames = np.arange(0, teeth.clips[0].frame_count, 5)
    np.testing.assert_array_equal(pipeline._morph_weights(teeth.clips[0], head, frames),
                                  head.clips[0].morph_weights[frames])  # fmt: skip
    assert head.clips[0].morph_weights[frames].max() > 0.5
    np.testing.assert_array_equal(pipeline._morph_weights(head.clips[0], teeth, frames), 0.0)


def test_motion_levels_leave_out_a_mesh_only_a_hidden_scene_draws(humanoid_glb, tmp_path) -> None:
    # A collision proxy on the body's skin, listed by a "physics" scene alone: joined into the one
    # scene of the level GLBs, the proxy was drawn over the character.
    builder = GlbBuilder.from_document(GltfDocument(humanoid_glb))
    body = next(node for node in builder.json["nodes"] if "skin" in node)
    mesh = builder.append("meshes", dict(builder.json["meshes"][body["mesh"]], name="proxy"))  # a mesh of its own
    proxy = builder.append("nodes", {"name": "collision proxy", "mesh": mesh, "skin": body["skin"]})
    builder.json["scenes"].append({"name": "physics", "nodes": [proxy]})
    source = tmp_path / "with_proxy.glb"
    builder.save(source)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    assert any(f"node {proxy} 'collision proxy' (in no scene a viewer shows)" in note for note in report.notes)
    (skinned,) = read_gltf(tmp_path / "levels" / "with_proxy_lod0.glb").skinned_meshes
    body_vertices = read_gltf(humanoid_glb).skinned_meshes[0].vertex_count
    assert skinned.vertex_count == body_vertices
    # Where the scene a viewer shows does not draw the character (it sits in a later scene), the
    # scenes tell nothing: every part stays.
    builder.json["scenes"].append({"name": "lights", "nodes": []})
    builder.json["scene"] = 2
    builder.save(source)
    report = build_motion_levels(source, tmp_path / "shown", levels=2)
    assert not any("not in the levels' GLBs" in note for note in report.notes)
    (skinned,) = read_gltf(tmp_path / "shown" / "with_proxy_lod0.glb").skinned_meshes
    assert skinned.vertex_count == 2 * body_vertices


def test_the_body_is_a_mesh_the_shown_scene_draws(humanoid_glb, tmp_path) -> None:
    # The same character drawn twice, on one skin: by its first node in a "physics" scene alone, and
    # by a later node in the scene a viewer shows. The first in node order was the body (`motion`,
    # `tdag build`).
    builder = GlbBuilder.from_document(GltfDocument(humanoid_glb))
    hidden = next(index for index, node in enumerate(builder.json["nodes"]) if "skin" in node)
    original = builder.json["nodes"][hidden]
    mesh = builder.append("meshes", dict(builder.json["meshes"][original["mesh"]], name="shown"))
    shown = builder.append("nodes", {"name": "shown", "mesh": mesh, "skin": original["skin"]})
    scene = builder.json["scenes"][0]
    scene["nodes"] = [node for node in scene["nodes"] if node != hidden] + [shown]
    builder.json["scenes"].append({"name": "physics", "nodes": [hidden]})
    source = tmp_path / "drawn_twice.glb"
    builder.save(source)
    read = read_gltf(source)
    assert read.skinned_nodes[read.body] == shown


@pytest.mark.parametrize("locks", [1, 2])
@pytest.mark.parametrize("hair", ["still", "swinging"])
def test_motion_levels_show_hair_whose_skin_lists_its_own_bone_alone(tmp_path, hair, locks) -> None:
    # A skin over bones hung from the body's Head in the node tree and none of the body's joints
    # (RecursiveSkeletons' layout) was left out as "on another skeleton", as a second character is
    # (with two locks, two trees of joints, until 2026-12-07 evening).
    source = _with_part(tmp_path, "own bone", hair=hair, hair_bone_alone=True, locks=locks)
    notes = _motion_levels_show_every_skin(source, tmp_path / "levels")
    assert any("has joints of its own that move in its clips" in note for note in notes) == (hair == "swinging")


def test_the_lod_glb_is_the_same_whatever_the_threads(tmp_path) -> None:
    # `character` re-fitted on one thread until its default became every core, as `motion`'s is:
    # the frames are solved apart, so the threads must not change a byte.
    source = _with_part(tmp_path, "helmet")
    written = []
    for workers in (1, 2):
        output = tmp_path / f"threads{workers}.glb"
        build_character(source, output, [0.5, 0.25], solver="slsqp", workers=workers, **QUICK)
        written.append(output.read_bytes())
    assert written[0] == written[1]
