"""Clips from an animation library without the mesh, added to a character by node name
(``animlod character --clips``): a character exported in its rest pose and its clips exported apart,
as Mixamo's downloads come, gave no chain at all ("no skinned mesh with an animation")."""

from __future__ import annotations

import json
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pytest

from animlod import rotations, synth
from animlod.cli import main
from animlod.io.bvh import read_bvh, write_bvh
from animlod.io.errors import FormatError
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf import read_gltf, write_glb
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_drawable import read_drawables
from animlod.io.npz import write_npz
from animlod.model import Motion, Skeleton
from animlod.pipelines.character import build_character
from animlod.pipelines.clip_import import with_clips
from animlod.pipelines.joint_matching import match_joints
from animlod.pipelines.joint_names import side
from animlod.pipelines.motion import build_motion_levels

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
    with pytest.raises(FormatError, match="its skinned meshes have no clip: add clips with --clips"):
        build_character(rest, tmp_path / "none.glb", [0.5], **QUICK)
    with pytest.raises(FormatError, match="has no animation to simplify: add clips with --clips"):
        build_motion_levels(rest, tmp_path / "none", levels=2)
    split = build_character(rest, tmp_path / "split.glb", [0.5], clips=[walk], **QUICK)
    joined = build_character(whole, tmp_path / "whole.glb", [0.5], **QUICK)
    assert any("walk.glb: 1 of its 1 clip(s) added to rest.glb" in note for note in split.notes)
    for ours, theirs in zip(split.chains.values(), joined.chains.values()):
        assert [(level.faces, level.joints) for level in ours] == [(level.faces, level.joints) for level in theirs]
        np.testing.assert_allclose([level.error for level in ours], [level.error for level in theirs], rtol=1e-6)
    played = read_gltf(tmp_path / "split.glb").motions[0].world_positions()  # level 0 plays the clip
    np.testing.assert_allclose(played, read_gltf(whole).motions[0].world_positions(), atol=1e-5)


def test_clips_of_one_name_are_named_apart_by_their_files(split_character, tmp_path):
    """Every Mixamo export names its clip "mixamo.com": added side by side, they kept one name,
    by which engines find clips."""
    whole, rest, walk = split_character
    (name,) = [animation.name for animation in GltfDocument(walk).gltf.animations]
    copy = tmp_path / "walk_again.glb"
    copy.write_bytes(walk.read_bytes())
    notes = []
    document = with_clips(GltfDocument(rest), [walk, copy], notes.append)
    names = [animation.name for animation in document.gltf.animations]
    assert names == [name, f"{name} (walk_again)"]
    assert notes[-1].endswith(f"; renamed where another clip has the name: {name!r} -> '{name} (walk_again)'")
    names = [animation.name for animation in with_clips(GltfDocument(whole), [walk, walk], print).gltf.animations]
    assert names == [name, f"{name} (walk)", f"{name} (walk) 2"]  # the document's own clip first


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
    with pytest.raises(ValueError, match="^joint_map: adds glTF clips to a glTF input, not to a bvh input"):
        build_motion_levels(tmp_path / "walk.bvh", tmp_path / "bvh", levels=2, joint_map=tmp_path / "map.json")


def _bvh_in(folder: Path, name: str, motion: Motion, turn: np.ndarray | None = None, scale: float = 1.0) -> Path:
    """``motion`` as a BVH file, its world turned by ``turn`` (3, 3) and its lengths scaled, as an
    exporter of other axes or units writes the same clip."""
    turn = np.eye(3) if turn is None else turn
    skeleton = motion.skeleton
    q = rotations.from_matrix(turn)
    turned = Skeleton(skeleton.names, skeleton.parents, scale * skeleton.offsets @ turn.T,
                      skeleton.rest_rotations, skeleton.end_sites)  # fmt: skip
    local = rotations.multiply(rotations.multiply(q, motion.local_rotations), rotations.conjugate(q))
    path = folder / f"{name}.bvh"
    write_bvh(path, Motion(turned, scale * motion.root_positions @ turn.T, local, motion.fps, name))
    return path


def _played_frames(document: GltfDocument) -> np.ndarray:
    (drawable,) = read_drawables(document)
    return drawable.clip_frames(drawable.clips[0])


def _rolled(source: Path, target: Path, names: Sequence[str]) -> Path:
    """``source`` with the nodes ``names`` given rest rotations of their own (bone roll, as Blender
    exports), their children's translations and rotations and the skin's inverse binds made up
    for it: the same rest shape and skinning on other joint axes."""
    doc = GltfDocument(source)
    builder = GlbBuilder.from_document(doc)
    nodes = builder.json["nodes"]
    skin = builder.json["skins"][0]
    binds = np.asarray(doc.accessor(skin["inverseBindMatrices"], "test"), np.float64).reshape(-1, 4, 4)
    binds = np.swapaxes(binds, 1, 2)  # stored column-major
    for k, name in enumerate(names):
        index = next(i for i, node in enumerate(nodes) if node.get("name") == name)
        roll = rotations.from_axis_angle(np.array([0.3, 1.0, -0.5]) / np.linalg.norm([0.3, 1.0, -0.5]), 0.7 + k)
        node = nodes[index]
        node["rotation"] = rotations.multiply(node.get("rotation", [0, 0, 0, 1.0]), roll).tolist()
        unroll = rotations.conjugate(roll)
        for child in node.get("children", []):
            nodes[child]["translation"] = rotations.rotate(
                unroll, np.array(nodes[child].get("translation", [0, 0, 0.0]))
            ).tolist()
            nodes[child]["rotation"] = rotations.multiply(unroll, nodes[child].get("rotation", [0, 0, 0, 1.0])).tolist()
        if index in skin["joints"]:
            slot = skin["joints"].index(index)
            undo = np.eye(4)
            undo[:3, :3] = rotations.to_matrix(unroll)
            binds[slot] = undo @ binds[slot]
    skin["inverseBindMatrices"] = builder.add(np.swapaxes(binds, 1, 2).reshape(-1, 16).astype(np.float32))
    builder.save(target)
    return target


def test_a_bvh_clip_of_the_same_skeleton_plays_as_the_gltf_clip_does(split_character, tmp_path):
    # A clip captured on the character's own skeleton often comes as BVH; --clips took glTF
    # files only. Its joints' world rotations carry over relative to the rests, whatever the
    # BVH's axes and units (a Z-up file in centimetres here) and the nodes' own rest rotations.
    whole, rest, _ = split_character
    walk = read_gltf(whole).motions[0]
    expected = _played_frames(GltfDocument(whole))
    z_up = rotations.to_matrix(rotations.from_axis_angle(np.array([1.0, 0.0, 0.0]), np.pi / 2))
    notes = []
    for bvh in (_bvh_in(tmp_path, "walk", walk), _bvh_in(tmp_path, "walk_z_up_cm", walk, z_up, 100.0)):
        for character in (rest, _rolled(rest, tmp_path / "rolled.glb", ["Spine", "LeftUpLeg", "LeftLeg", "Head"])):
            played = _played_frames(with_clips(GltfDocument(character), [bvh], notes.append))
            np.testing.assert_allclose(played, expected, atol=2e-5)
    assert f"{tmp_path / 'walk.bvh'}: its clip added to rest.glb (38 joints)" in notes
    report = build_character(rest, tmp_path / "out.glb", [0.5], clips=[tmp_path / "walk.bvh"], **QUICK)
    assert len(read_gltf(tmp_path / "out.glb").motions) == 1 and report.chains


def test_a_bvh_clip_of_another_rest_pose_and_proportions_moves_every_bone_as_the_clip_does(split_character, tmp_path):
    # A clip captured on another figure of the same skeleton (an A-pose rest, longer legs) turns
    # each bone from the character's rest onto the clip's: every bone points where the clip's does.
    _, rest, _ = split_character
    walk = synth.humanoid_motion(synth.humanoid().skeleton, "walk")
    skeleton = walk.skeleton
    offsets = skeleton.offsets.copy()
    offsets[skeleton.names.index("LeftForeArm")] = rotations.rotate(
        rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), 0.8), offsets[skeleton.names.index("LeftForeArm")]
    )
    offsets[[skeleton.names.index(name) for name in ("LeftLeg", "RightLeg")]] *= 1.3
    other = Skeleton(skeleton.names, skeleton.parents, offsets, skeleton.rest_rotations, skeleton.end_sites)
    clip = Motion(other, walk.root_positions, walk.local_rotations, walk.fps, "a_pose")
    notes = []
    document = with_clips(GltfDocument(rest), [_bvh_in(tmp_path, "a_pose", clip)], notes.append)
    assert "its rest pose differs from the character's by up to 4" in notes[0]
    (drawable,) = read_drawables(document)
    motion = drawable.clips[0].motion
    ours, theirs = motion.world_positions(), clip.world_positions()
    names = motion.skeleton.names
    for joint, name in enumerate(other.names[1:], start=1):
        if other.end_sites is not None and other.end_sites[joint]:
            continue
        parent = other.parents[joint]
        ours_bone = ours[:, names.index(name)] - ours[:, names.index(other.names[parent])]
        theirs_bone = theirs[:, joint] - theirs[:, parent]
        cosine = np.einsum("tc,tc->t", ours_bone, theirs_bone) / (
            np.linalg.norm(ours_bone, axis=1) * np.linalg.norm(theirs_bone, axis=1)
        )
        assert cosine.min() > 1.0 - 1e-9, name


def test_a_bvh_clip_without_a_rest_position_stands_on_the_floor(split_character, tmp_path):
    # CMU's files give the root an OFFSET of zero and channels that are heights above the floor:
    # moved from a zero rest position, the character floated a hip height above it.
    whole, rest, _ = split_character
    walk = read_gltf(whole).motions[0]
    skeleton = walk.skeleton
    offsets = skeleton.offsets.copy()
    offsets[0] = 0.0
    cmu = Skeleton(skeleton.names, skeleton.parents, offsets, skeleton.rest_rotations, skeleton.end_sites)
    bvh = _bvh_in(tmp_path, "cmu_walk", Motion(cmu, walk.root_positions, walk.local_rotations, walk.fps))
    played = _played_frames(with_clips(GltfDocument(rest), [bvh], print))
    expected = _played_frames(GltfDocument(whole))
    height = np.ptp(expected[..., 1])
    assert abs(played[..., 1].min() - expected[..., 1].min()) < 0.01 * height


def _edited(motion: Motion, order: Sequence[str], renamed: dict[str, str] | None = None) -> Motion:
    """``motion`` with its joints in ``order`` (names, parents first; the joints not named are
    left out, each with every joint below it) and ``renamed``: the same clip as another
    exporter writes it."""
    skeleton, renamed = motion.skeleton, renamed or {}
    index = [skeleton.names.index(name) for name in order]
    place = {joint: k for k, joint in enumerate(index)}
    parents = [place.get(int(skeleton.parents[joint]), -1) for joint in index]
    edited = Skeleton([renamed.get(name, name) for name in order], parents, skeleton.offsets[index],
                      skeleton.rest_rotations[index], skeleton.end_sites[index])  # fmt: skip
    return Motion(edited, motion.root_positions, motion.local_rotations[:, index], motion.fps, motion.name)


def _depth_first(skeleton: Skeleton, last_child_first: bool) -> list[str]:
    children = skeleton.children()
    order, pending = [], [0]
    while pending:
        joint = pending.pop()
        order.append(skeleton.names[joint])
        pending.extend(children[joint] if last_child_first else reversed(children[joint]))
    return order


def _played_positions(document: GltfDocument, names: Sequence[str]) -> np.ndarray:
    (drawable,) = read_drawables(document)
    motion = drawable.clips[0].motion
    return motion.world_positions()[:, [motion.skeleton.names.index(name) for name in names]]


def test_a_bvh_clip_of_the_same_skeleton_under_other_names_plays_by_the_skeletons_shape(split_character, tmp_path):
    # CMU's ASF conversions name the joints of the cgspeed rigs otherwise, and some names mean
    # other joints: CMU's 'LeftShoulder' is the rig's upper arm, its 'Neck' the rig's head. By
    # name, such a clip turned the collar with the upper arm's rotation and left most joints out.
    whole, rest, _ = split_character
    walk = read_gltf(whole).motions[0]
    cmu = {"Spine": "lowerback", "Spine1": "Chest", "Spine2": "Chest2", "Neck": "lowerneck", "Head": "Neck",
           "HeadTop_End": "Head"}  # fmt: skip
    limbs = {"Shoulder": "Collar", "Arm": "Shoulder", "ForeArm": "Elbow", "Hand": "Wrist",
             "UpLeg": "Hip", "Leg": "Knee", "Foot": "Ankle", "ToeBase": "Toe"}  # fmt: skip
    cmu |= {side + ours: side + theirs for side in ("Left", "Right") for ours, theirs in limbs.items()}
    # The right side first in the file, as the character's left comes first: only the names' sides pair them.
    clip = _edited(walk, _depth_first(walk.skeleton, last_child_first=True), cmu)
    notes = []
    played = _played_frames(with_clips(GltfDocument(rest), [_bvh_in(tmp_path, "cmu", clip)], notes.append))
    np.testing.assert_allclose(played, _played_frames(GltfDocument(whole)), atol=2e-5)
    assert (
        "(38 joints); joints matched by the two skeletons' shape: 21 to nodes of other names ('RightHip' -> "
        in notes[0]
    )


def test_a_bvh_clip_of_another_shape_plays_by_name_up_to_namespace(split_character, tmp_path):
    # A clip without the character's ring fingers, its joints in Mixamo's namespace: the
    # skeletons differ in shape, and the names match without the namespace.
    whole, rest, _ = split_character
    walk = read_gltf(whole).motions[0]
    names = walk.skeleton.names
    order = [name for name in names if "Ring" not in name]
    clip = _edited(walk, order, {name: f"mixamorig:{name}" for name in names})
    notes = []
    document = with_clips(GltfDocument(rest), [_bvh_in(tmp_path, "mixamo", clip)], notes.append)
    assert (
        "(34 joints); 34 joint(s) matched by name up to case, separators and namespace ('mixamorig:Hips' -> 'Hips'"
        in notes[0]
    )
    kept = [name for name in order if name in names and not name.endswith("_End")]
    np.testing.assert_allclose(
        _played_positions(document, kept), _played_positions(GltfDocument(whole), kept), atol=2e-5
    )
    # A joint the character has no counterpart for (a prop, a tail) is left out, and said so.
    notes = []
    with_clips(GltfDocument(rest), [_bvh_in(tmp_path, "tail", _edited(walk, order, {"Head": "Tail"}))], notes.append)
    assert "; 1 BVH joint(s) with no counterpart in rest.glb left out (Tail)" in notes[0]


def test_a_bvh_clip_of_another_rig_is_refused_naming_the_joint(split_character, tmp_path):
    _, rest, _ = split_character
    walk = synth.humanoid_motion(synth.humanoid().skeleton, "walk")
    write_bvh(tmp_path / "other.bvh", _edited(walk, ["Hips", "Spine"], {"Hips": "a", "Spine": "b"}))
    with pytest.raises(
        FormatError, match="other.bvh: ROOT: its root 'a' matches no node of rest.glb's, by shape, body part or name"
    ):
        with_clips(GltfDocument(rest), [tmp_path / "other.bvh"], print)
    # One joint: nothing to lay a bone of the character's along.
    write_bvh(tmp_path / "hips.bvh", _edited(walk, ["Hips"]))
    with pytest.raises(
        FormatError, match="hips.bvh: HIERARCHY: no bone between two of its joints matched to rest.glb's"
    ):
        with_clips(GltfDocument(rest), [tmp_path / "hips.bvh"], print)
    # Another shape, and names that match only here and there: a few joints would move.
    ringless = [name for name in walk.skeleton.names if "Ring" not in name]
    renamed = {name: f"joint{k}" for k, name in enumerate(ringless) if name not in ("Hips", "Neck", "Head")}
    write_bvh(tmp_path / "few.bvh", _edited(walk, ringless, renamed))
    reason = "HIERARCHY: only 3 of its 34 joints match a node of rest.glb's by name (Hips, Neck, Head), and the sk"
    with pytest.raises(FormatError, match=re.escape(f"few.bvh: {reason}")):
        with_clips(GltfDocument(rest), [tmp_path / "few.bvh"], print)
    # Another shape (no ring fingers) and an arm and a leg named like each other: by name, the
    # arm's joint would drive the leg.
    swapped = {"LeftArm": "LeftUpLeg", "LeftUpLeg": "LeftArm"}
    clip = _edited(walk, ringless, swapped)
    write_bvh(tmp_path / "swapped.bvh", clip)
    with pytest.raises(FormatError, match="swapped.bvh: joint 'LeftUpLeg': hangs from 'LeftShoulder', which is no anc"):
        with_clips(GltfDocument(rest), [tmp_path / "swapped.bvh"], print)


@pytest.mark.parametrize(
    ("name", "expected"),
    [("LeftArm", "left"), ("mixamorig:RightHand", "right"), ("LThumb", "left"), ("hand_l", "left"), ("Arm.R", "right"),
     ("Bip01 R Calf", "right"), ("UpperArmL", "left"), ("lowerback", None), ("lhand", None), ("Root", None)],
)  # fmt: skip
def test_a_joint_names_its_side_as_exporters_write_it(name, expected):
    assert side(name) == expected


def test_a_cmu_clip_drives_the_rig_made_from_its_skeleton(data_dir, tmp_path):
    # delfem2's rig carries the cgspeed names of CMU's skeleton, 131_01 CMU's own: 9 of its 31
    # joint names are the rig's, two of them for other joints (the upper arms).
    rig, clip = data_dir / "gltf" / "rig_transfer_from_bvh.glb", data_dir / "bvh" / "131_01.bvh"
    document, motion = GltfDocument(rig), read_bvh(clip)
    match = match_joints(motion.skeleton, document, str(clip))
    pairs = {motion.skeleton.names[j]: document.gltf.nodes[n].name for j, n in match.node_of.items()}
    assert len(pairs) == 31
    expected = {"LeftShoulder": "LeftArm", "LeftCollar": "LeftShoulder", "Neck": "Neck1", "Head": "Head",
                "RightHip": "RightUpLeg", "Chest2": "Spine1", "RFingers": "RightHandIndex1"}  # fmt: skip
    assert {name: pairs[name] for name in expected} == expected
    # Each matched bone is about as long on the rig as in the clip (the same figure).
    theirs = motion.skeleton.rest_world_transforms()[:, :3, 3]
    ratios = []
    for joint, node in match.node_of.items():
        parent = int(motion.skeleton.parents[joint])
        if parent >= 0 and np.linalg.norm(theirs[joint] - theirs[parent]) > 0.1:
            ours = document.rest_world_matrix(node)[:3, 3] - document.rest_world_matrix(match.node_of[parent])[:3, 3]
            ratios.append(np.linalg.norm(ours) / np.linalg.norm(theirs[joint] - theirs[parent]))
    assert len(ratios) >= 20 and min(ratios) > 0.75 and max(ratios) < 1.35
    build_character(rig, tmp_path / "out.glb", [0.5], clips=[clip], **QUICK)
    assert len(read_gltf(tmp_path / "out.glb").motions) == 1


_CMU_LIMBS = {"Shoulder": "Collar", "Arm": "Shoulder", "ForeArm": "Elbow", "Hand": "Wrist",
              "UpLeg": "Hip", "Leg": "Knee", "Foot": "Ankle", "ToeBase": "Toe"}  # fmt: skip
_BODY = ["Hips", "Spine", "Spine1", "Spine2", "Neck", "Head"] + [
    side + limb for side in ("Left", "Right") for limb in _CMU_LIMBS
]


def test_a_cmu_named_clip_plays_on_a_mixamo_named_rig_by_body_part(split_character, tmp_path):
    # Another naming and another shape (no fingers): CMU's 'LeftShoulder' is Mixamo's 'LeftArm';
    # by name, a few joints matched, two of them the wrong ones, and the clip was refused.
    whole, rest, _ = split_character
    walk = read_gltf(whole).motions[0]
    cmu = {"Spine": "lowerback", "Spine1": "Chest", "Spine2": "Chest2", "Neck": "lowerneck"}
    cmu |= {side + ours: side + theirs for side in ("Left", "Right") for ours, theirs in _CMU_LIMBS.items()}
    order = [name for name in walk.skeleton.names if "Hand" not in name or name.endswith("Hand")]
    notes = []
    document = with_clips(GltfDocument(rest), [_bvh_in(tmp_path, "cmu", _edited(walk, order, cmu))], notes.append)
    assert (
        "joints matched by body part, CMU's naming onto Mixamo's ('Hips' -> 'Hips', 'lowerback' -> 'Spine'" in notes[0]
    )
    expected = _played_positions(GltfDocument(whole), _BODY)
    np.testing.assert_allclose(_played_positions(document, _BODY), expected, atol=2e-5)


def _bandai_like(motion: Motion) -> Motion:
    """``motion`` as Bandai-Namco's files write a clip: Unity's joint names, a ``joint_Root``
    above the hips (turned here, the hips turned back), and each joint's axes laying its first
    child's bone along x (the joint orients baked into the rotations), so that the rest pose, every
    rotation zero, is no pose of the figure. Every joint's world position is the same."""
    skeleton = motion.skeleton
    children = skeleton.children()
    orient = np.array([rotations.identity(()) if not children[j] or not skeleton.offsets[children[j][0]].any()
                       else _turn_onto(np.array([1.0, 0.0, 0.0]), skeleton.offsets[children[j][0]])
                       for j in range(skeleton.joint_count)])  # fmt: skip
    root_turn = rotations.from_axis_angle(np.array([0.0, 1.0, 0.0]), 0.6)
    above = np.concatenate([[root_turn], orient[skeleton.parents[1:]]])  # each joint's parent's axes
    offsets = rotations.rotate(rotations.conjugate(above), skeleton.offsets)
    offsets[0] = 0.0
    local = rotations.multiply(rotations.multiply(rotations.conjugate(above), motion.local_rotations), orient)
    names = {"Spine1": "Chest", "Spine2": "UpperChest"}
    limbs = {"Shoulder": "Shoulder", "Arm": "UpperArm", "ForeArm": "LowerArm", "Hand": "Hand",
             "UpLeg": "UpperLeg", "Leg": "LowerLeg", "Foot": "Foot", "ToeBase": "Toes"}  # fmt: skip
    names |= {side + ours: f"{theirs}_{side[0]}" for side in ("Left", "Right") for ours, theirs in limbs.items()}
    bandai = Skeleton(["joint_Root"] + [names.get(name, name) for name in skeleton.names],
                      np.concatenate([[-1], skeleton.parents + 1]), np.concatenate([[skeleton.offsets[0]], offsets]),
                      end_sites=np.concatenate([[False], skeleton.end_sites]))  # fmt: skip
    frames = motion.frame_count
    local = np.concatenate([np.broadcast_to(root_turn, (frames, 1, 4)), local], axis=1)
    return Motion(bandai, motion.root_positions, local, motion.fps, "bandai")


def _turn_onto(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The quaternion of the smallest turn of direction ``a`` onto direction ``b``."""
    a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
    axis = np.cross(a, b)
    if np.linalg.norm(axis) < 1e-12:
        axis = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))]) if np.dot(a, b) < 0.0 else np.array([1.0, 0.0, 0.0])
    return rotations.from_axis_angle(axis / np.linalg.norm(axis), float(np.arccos(np.clip(np.dot(a, b), -1.0, 1.0))))


def test_a_bandai_like_clip_plays_by_body_part(split_character, tmp_path):
    # Bandai-Namco's motion dataset names the joints as Unity does, puts a joint_Root above the
    # hips and bakes its joint orients into the rotations: by name it was refused; the rest pose
    # laid every bone along x, so that the turn between the files' axes, fitted to it, laid the
    # figure on its side.
    whole, rest, _ = split_character
    walk = read_gltf(whole).motions[0]
    handless = _edited(walk, [name for name in walk.skeleton.names if "Hand" not in name or name.endswith("Hand")])
    clip = _bandai_like(handless)
    np.testing.assert_allclose(clip.world_positions()[:, 1:], handless.world_positions(), atol=1e-9)
    notes = []
    document = with_clips(GltfDocument(rest), [_bvh_in(tmp_path, "bandai", clip)], notes.append)
    assert "joints matched by body part, Unity's naming onto Mixamo's ('Hips' -> 'Hips'" in notes[0]
    assert "its rest pose is no pose of the figure" in notes[0]
    expected = _played_positions(GltfDocument(whole), _BODY)
    np.testing.assert_allclose(_played_positions(document, _BODY), expected, atol=2e-5)


@pytest.mark.parametrize("character", ["Xbot.glb", "Soldier.glb", "rig_transfer_from_bvh.glb"])
@pytest.mark.parametrize("clip", ["131_01.bvh", "dataset-1_run_proud_001.bvh"])
def test_capture_clips_play_on_the_dev_humanoids_with_their_feet_near_the_floor(data_dir, character, clip):
    notes = []
    document = with_clips(GltfDocument(data_dir / "gltf" / character), [data_dir / "bvh" / clip], notes.append)
    assert "by body part" in notes[0] or "by the two skeletons' shape" in notes[0]
    drawables = [drawable for drawable in read_drawables(document) if drawable.clips]
    rest = np.concatenate([drawable.rest_positions()[:, 1] for drawable in drawables])
    played = np.concatenate([drawable.clip_frames(drawable.clips[-1])[..., 1] for drawable in drawables], axis=1)
    lowest = (played.min(axis=1) - rest.min()) / np.ptp(rest)  # the skin's lowest point per frame
    assert lowest.min() > -0.08 and lowest.max() < 0.08


def test_a_joint_map_matches_a_clip_that_no_rule_can(split_character, tmp_path, capsys):
    # Joints named j0, j1, ... on another shape (no fingers): neither shape, body part nor name
    # tells; a table does, by node name or index (a rig of unnamed joints).
    whole, rest, walk_glb = split_character
    walk = read_gltf(whole).motions[0]
    order = [name for name in walk.skeleton.names if "Hand" not in name or name.endswith("Hand")]
    numbered = {name: f"j{k}" for k, name in enumerate(order)}
    bvh = _bvh_in(tmp_path, "numbered", _edited(walk, order, numbered))
    with pytest.raises(FormatError, match="numbered.bvh: ROOT: its root 'j0' matches no node"):
        with_clips(GltfDocument(rest), [bvh], print)
    nodes = [node.name for node in GltfDocument(rest).gltf.nodes]
    table = {numbered[name]: name for name in _BODY} | {numbered["Hips"]: nodes.index("Hips")}
    (tmp_path / "map.json").write_text(json.dumps(table))
    notes = []
    document = with_clips(GltfDocument(rest), [bvh], notes.append, tmp_path / "map.json")
    assert "(22 joints); joints matched by the joint map map.json" in notes[0]
    expected = _played_positions(GltfDocument(whole), _BODY)
    np.testing.assert_allclose(_played_positions(document, _BODY), expected, atol=2e-5)
    out = tmp_path / "out.glb"
    argv = ["character", str(rest), "-o", str(out), "--clips", str(bvh), "--joint-map", str(tmp_path / "map.json")]
    assert main([*argv, "--ratio", "0.5", "--max-frames", "4"]) == 0 and out.is_file()


@pytest.mark.parametrize(
    ("table", "reason"),
    [
        ("{", "map.json: JSON: no joint map: Expecting property name"),
        ('["j0"]', 'map.json: JSON: a joint map is an object {"BVH joint": "node name" or node index, ...}'),
        ('{"j0": 1.5}', "map.json: 'j0': maps to 1.5: a node's name or index is expected"),
        ('{"Hips": "Hips"}', "map.json: 'Hips': is no joint of numbered.bvh (end sites take none)"),
        ('{"j0": "Pelvis"}', "map.json: 'j0': maps to 'Pelvis', no node of rest.glb's (or one of several)"),
        ('{"j0": 999}', "map.json: 'j0': maps to 999, no node of rest.glb's (or one of several)"),
        ('{"j0": "Hips", "j1": "Hips"}', "map.json: 'j1': maps to node 0 'Hips', which another joint drives"),
        ('{"j1": "Spine", "j0": "Hips", "j2": "LeftUpLeg"}', "numbered.bvh: joint 'j2': hangs from 'j1', which is no"),
    ],
)
def test_a_joint_map_that_does_not_fit_is_refused_naming_the_entry(split_character, tmp_path, capsys, table, reason):
    _, rest, walk_glb = split_character
    walk = synth.humanoid_motion(synth.humanoid().skeleton, "walk")
    numbered = {name: f"j{k}" for k, name in enumerate(walk.skeleton.names)}
    bvh = tmp_path / "numbered.bvh"
    write_bvh(bvh, _edited(walk, walk.skeleton.names, numbered))
    (tmp_path / "map.json").write_text(table)
    argv = ["character", str(rest), "-o", str(tmp_path / "out.glb"), "--clips", str(bvh), "--joint-map"]
    assert main([*argv, str(tmp_path / "map.json")]) == 2
    assert reason in capsys.readouterr().err and not (tmp_path / "out.glb").exists()
    assert main(["character", str(rest), "-o", str(tmp_path / "out.glb"), "--clips", str(walk_glb), "--joint-map",
                 str(tmp_path / "map.json")]) == 2  # fmt: skip
    assert "map.json: maps the joints of BVH clips, and no BVH clip is given" in capsys.readouterr().err
