"""glTF 2.0 / GLB reading and writing (animlod.io.gltf)."""

from __future__ import annotations

import base64
import json
import os
import re
import subprocess
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pygltflib
import pytest
from gltf_edits import (
    add_scale_channel,
    append_accessor,
    draco_compressed,
    edit_glb,
    meshopt_compressed,
    share_one_vertex_buffer,
    squash_and_stretch,
)

from animlod import rotations, synth
from animlod.io import FormatError
from animlod.io.gltf import read_gltf, read_skinned, write_glb
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_keyframes import frame_times, sample_keyframes
from animlod.io.gltf_mesh import read_mesh_geometry
from animlod.model import Motion, Skeleton, SkinnedMesh

# ---- a 3-joint chain skinning a box, built by hand --------------------------------------


def _chain_skeleton() -> Skeleton:
    return Skeleton(
        names=["root", "mid", "tip"],
        parents=[-1, 0, 1],
        offsets=[[0.5, 0.0, -0.25], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        rest_rotations=rotations.from_axis_angle(np.eye(3)[[2, 0, 1]], np.array([0.1, -0.2, 0.3])),
        end_sites=[False, False, True],
    )


def _box_along_y(rings: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """A square tube of ``rings`` rings of 4 vertices from y = 0 to y = 2, capped; (V, 3), (M, 3)."""
    square = np.array([[-0.2, -0.2], [0.2, -0.2], [0.2, 0.2], [-0.2, 0.2]])
    heights = np.linspace(0.0, 2.0, rings)
    x, z = np.tile(square[:, 0], rings), np.tile(square[:, 1], rings)
    positions = np.stack([x, np.repeat(heights, 4), z], axis=-1)
    faces = []
    for ring in range(rings - 1):
        for side in range(4):
            a, b = ring * 4 + side, ring * 4 + (side + 1) % 4
            faces += [[a, b, b + 4], [a, b + 4, a + 4]]
    last = (rings - 1) * 4
    faces += [[0, 2, 1], [0, 3, 2], [last, last + 1, last + 2], [last, last + 2, last + 3]]
    return positions.astype(np.float32), np.array(faces, np.int32)


def _chain_mesh(extras: bool = True) -> SkinnedMesh:
    skeleton = _chain_skeleton()
    positions, faces = _box_along_y()
    vertex_count = len(positions)
    # Weights fall off with the distance along the chain from each joint (rest heights 0, 1, 2).
    height = positions[:, 1:2]
    raw = np.maximum(1.0 - np.abs(height - np.array([[0.0, 1.0, 2.0]])), 0.0) + 0.05
    joints = np.zeros((vertex_count, 4), np.int32)
    weights = np.zeros((vertex_count, 4))
    joints[:, :3] = [0, 1, 2]
    weights[:, :3] = raw
    # Bound in a straight pose that differs from the skeleton's rest pose, as in real files.
    bind_pose = Skeleton(skeleton.names, skeleton.parents, [[0, 0, 0], [0, 1, 0], [0, 1, 0]])
    inverse_bind = np.linalg.inv(bind_pose.rest_world_transforms())
    rng = np.random.default_rng(7)
    return SkinnedMesh(
        rest_positions=positions,
        faces=faces,
        joints=joints,
        weights=weights,
        inverse_bind=inverse_bind,
        skeleton=skeleton,
        uvs=rng.random((vertex_count, 2)).astype(np.float32) if extras else None,
        normals=_unit(rng.normal(size=(vertex_count, 3))) if extras else None,
        morph_targets=rng.normal(scale=0.01, size=(2, vertex_count, 3)).astype(np.float32) if extras else None,
        morph_target_names=["bulge", "twist"] if extras else None,
    )


def _unit(vectors: np.ndarray) -> np.ndarray:
    return (vectors / np.linalg.norm(vectors, axis=1, keepdims=True)).astype(np.float32)


def _chain_motion(skeleton: Skeleton, frames: int = 6, fps: float = 24.0, name: str = "bend") -> Motion:
    t = np.arange(frames) / fps
    angles = np.stack([0.4 * np.sin(3 * t), 0.8 * t, -0.5 * t], axis=1)
    axes = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.6, 0.8]])
    local = rotations.multiply(skeleton.rest_rotations, rotations.from_axis_angle(axes, angles))
    root = skeleton.offsets[0] + np.stack([t, 0.1 * t**2, -t], axis=1)
    return Motion(skeleton, root, local, fps=fps, name=name)


@pytest.fixture
def chain_glb(tmp_path: Path) -> tuple[Path, SkinnedMesh, Motion]:
    mesh = _chain_mesh()
    motion = _chain_motion(mesh.skeleton)
    path = tmp_path / "chain.glb"
    write_glb(path, mesh, [motion])
    return path, mesh, motion


def _accessor_view(gltf: pygltflib.GLTF2, blob: bytearray, index: int, dtype: str) -> np.ndarray:
    """A writable ``(count, width)`` view of a non-sparse accessor inside ``blob``."""
    accessor = gltf.accessors[index]
    view = gltf.bufferViews[accessor.bufferView]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}[accessor.type]
    itemsize = np.dtype(dtype).itemsize
    stride = view.byteStride or width * itemsize
    start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
    flat = np.frombuffer(blob, dtype, ((accessor.count - 1) * stride) // itemsize + width, start)
    return np.lib.stride_tricks.as_strided(flat, (accessor.count, width), (stride, itemsize))


def _transform(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def _viewer_skinning(gltf: pygltflib.GLTF2, blob: bytearray, mesh_node: int, animation: str, key: int) -> np.ndarray:
    """Skinned positions ``(V, 3)`` of the first primitive of ``mesh_node`` at key ``key`` of an
    animation, evaluated the way a glTF viewer does: 4x4 node matrices multiplied down the tree
    (scale included), ``world @ inverse bind`` per joint, weights normalised. Independent of
    animlod's skeleton building, so that baking can be checked against it.
    """
    clip = next(a for a in gltf.animations if a.name == animation)
    keys = {
        (c.target.node, c.target.path): _accessor_view(gltf, blob, clip.samplers[c.sampler].output, "<f4")
        for c in clip.channels
    }
    parents = {child: index for index, node in enumerate(gltf.nodes) for child in node.children or []}

    def world(node: int) -> np.ndarray:
        n = gltf.nodes[node]
        trs = {
            "translation": n.translation or [0, 0, 0],
            "rotation": n.rotation or [0, 0, 0, 1],
            "scale": n.scale or [1, 1, 1],
        }
        trs.update({path: keys[(node, path)][key] for path in trs if (node, path) in keys})
        local = rotations.compose_transform(*(np.array(trs[p]) for p in ("translation", "rotation", "scale")))
        return local if node not in parents else world(parents[node]) @ local

    skin = gltf.skins[gltf.nodes[mesh_node].skin]
    attributes = gltf.meshes[gltf.nodes[mesh_node].mesh].primitives[0].attributes
    positions = _accessor_view(gltf, blob, attributes.POSITION, "<f4").astype(np.float64)
    joint_dtype = "<u2" if gltf.accessors[attributes.JOINTS_0].componentType == pygltflib.UNSIGNED_SHORT else "u1"
    joints = _accessor_view(gltf, blob, attributes.JOINTS_0, joint_dtype)
    weights = _accessor_view(gltf, blob, attributes.WEIGHTS_0, "<f4").astype(np.float64)
    weights = weights / weights.sum(axis=1, keepdims=True)
    inverse_bind = _accessor_view(gltf, blob, skin.inverseBindMatrices, "<f4").reshape(-1, 4, 4).transpose(0, 2, 1)
    skinning = np.stack([world(j) @ inverse_bind[k] for k, j in enumerate(skin.joints)])
    homogeneous = np.c_[positions, np.ones(len(positions))]
    per_influence = np.einsum("vkij,vj->vki", skinning[joints][..., :3, :], homogeneous)
    return np.einsum("vk,vki->vi", weights, per_influence)


# ---- keyframe interpolation ---------------------------------------------------------------


def test_frame_times_cover_the_clip_and_tolerate_float32_key_times():
    assert len(frame_times(1.4, 30.0)) == 43
    assert len(frame_times(float(np.float32(21 / 30)), 30.0)) == 22  # 0.7 s stored a hair below
    assert len(frame_times(0.0, 30.0)) == 1
    np.testing.assert_allclose(frame_times(0.1, 30.0), [0.0, 1 / 30, 2 / 30, 3 / 30])
    np.testing.assert_allclose(frame_times(1.25, 30.0), np.r_[np.arange(38) / 30, 1.25])  # its end, not 37 / 30


def test_step_and_linear_interpolation():
    times = np.array([0.0, 1.0, 3.0])
    values = np.array([[0.0], [10.0], [30.0]])
    at = np.array([-1.0, 0.0, 0.5, 1.0, 2.0, 3.0, 4.0])
    np.testing.assert_allclose(sample_keyframes(times, values, "STEP", at)[:, 0], [0, 0, 0, 10, 10, 30, 30])
    np.testing.assert_allclose(sample_keyframes(times, values, "LINEAR", at)[:, 0], [0, 0, 5, 10, 20, 30, 30])


def test_linear_rotation_is_slerp():
    z = np.array([0.0, 0.0, 1.0])
    keys = rotations.from_axis_angle(np.stack([z, z]), np.array([0.0, np.pi / 2]))
    half = sample_keyframes(np.array([0.0, 1.0]), keys, "LINEAR", np.array([0.5]), rotation=True)
    np.testing.assert_allclose(half[0], rotations.from_axis_angle(z, np.pi / 4), atol=1e-12)


def test_cubic_spline_reproduces_a_line_with_matching_tangents():
    times = np.array([0.0, 0.5, 2.0])
    slope = 3.0
    keys = slope * times[:, None] + 1.0
    tangents = np.full_like(keys, slope)  # glTF tangents are per second, scaled by the interval
    values = np.stack([tangents, keys, tangents], axis=1)
    at = np.linspace(0.0, 2.0, 9)
    np.testing.assert_allclose(sample_keyframes(times, values, "CUBICSPLINE", at)[:, 0], slope * at + 1.0)
    # Zero tangents give smoothstep: the midpoint of an interval lies halfway.
    flat = np.stack([np.zeros_like(keys), keys, np.zeros_like(keys)], axis=1)
    midpoint = sample_keyframes(times, flat, "CUBICSPLINE", np.array([1.25]))[0, 0]
    assert midpoint == pytest.approx((keys[1, 0] + keys[2, 0]) / 2)


def test_cubic_spline_rotations_come_out_normalised():
    keys = rotations.from_axis_angle(np.array([[1.0, 0, 0], [0, 1.0, 0]]), np.array([0.3, 1.2]))
    tangents = np.full_like(keys, 0.7)
    values = np.stack([tangents, keys, tangents], axis=1)
    result = sample_keyframes(np.array([0.0, 1.0]), values, "CUBICSPLINE", np.linspace(0, 1, 5), rotation=True)
    np.testing.assert_allclose(np.linalg.norm(result, axis=1), 1.0)
    np.testing.assert_allclose(result[[0, -1]], keys, atol=1e-12)


# ---- round trips --------------------------------------------------------------------------


def _assert_same_skinned(read: SkinnedMesh, written: SkinnedMesh) -> None:
    np.testing.assert_array_equal(read.rest_positions, written.rest_positions)
    np.testing.assert_array_equal(read.faces, written.faces)
    np.testing.assert_array_equal(read.joints, written.joints)
    np.testing.assert_allclose(read.weights, written.weights, atol=1e-7)
    np.testing.assert_allclose(read.inverse_bind, written.inverse_bind.astype(np.float32), rtol=0, atol=1e-7)
    assert read.skeleton.names == written.skeleton.names
    np.testing.assert_array_equal(read.skeleton.parents, written.skeleton.parents)
    np.testing.assert_allclose(read.skeleton.offsets, written.skeleton.offsets, atol=1e-7)
    np.testing.assert_allclose(read.skeleton.rest_rotations, written.skeleton.rest_rotations, atol=1e-7)
    np.testing.assert_array_equal(read.skeleton.end_sites, written.skeleton.end_sites)
    for name in ("uvs", "normals", "morph_targets"):
        expected = getattr(written, name)
        if expected is None:
            assert getattr(read, name) is None
        else:
            np.testing.assert_allclose(getattr(read, name), expected, atol=1e-6)
    assert read.morph_target_names == written.morph_target_names


def test_round_trip_keeps_mesh_skin_and_motion(chain_glb):
    path, mesh, motion = chain_glb
    read, motions = read_skinned(path, fps=motion.fps)
    _assert_same_skinned(read, mesh)
    assert [m.name for m in motions] == ["bend"]
    assert motions[0].frame_count == motion.frame_count and motions[0].fps == motion.fps
    assert motions[0].joint_translations is None
    np.testing.assert_allclose(motions[0].world_transforms(), motion.world_transforms(), atol=1e-6)
    np.testing.assert_allclose(read.bake(motions[0]).frames, mesh.bake(motion).frames, atol=1e-5)


def test_written_rotation_keys_have_no_sign_flips(tmp_path):
    mesh = _chain_mesh()
    motion = _chain_motion(mesh.skeleton)
    flipped = motion.local_rotations * np.where(np.arange(motion.frame_count) % 2, -1.0, 1.0)[:, None, None]
    path = tmp_path / "flips.glb"
    write_glb(path, mesh, [Motion(mesh.skeleton, motion.root_positions, flipped, motion.fps, "flips")])
    gltf = pygltflib.GLTF2.load_from_bytes(path.read_bytes())
    blob = bytearray(gltf.binary_blob())
    animation = gltf.animations[0]
    for channel in animation.channels:
        if channel.target.path == "rotation":
            keys = _accessor_view(gltf, blob, animation.samplers[channel.sampler].output, "<f4")
            assert np.all(np.sum(keys[1:] * keys[:-1], axis=1) > 0.0)
    _, (read,) = read_skinned(path, fps=motion.fps)
    np.testing.assert_allclose(read.world_transforms(), motion.world_transforms(), atol=1e-6)


def _eight_influences() -> SkinnedMesh:
    """The procedural humanoid with four more influences per vertex, each on a joint the vertex
    does not use yet (glTF allows a joint once per vertex), weighted lightly."""
    character = synth.humanoid()
    rows = np.arange(character.vertex_count)[:, None]
    used = np.zeros((character.vertex_count, character.skeleton.joint_count), bool)
    np.logical_or.at(used, (rows, character.joints), character.weights > 0.0)
    spare = np.argsort(used, axis=1, kind="stable")[:, :4]
    return SkinnedMesh(
        character.rest_positions,
        character.faces,
        np.concatenate([character.joints, spare], axis=1),
        np.concatenate([character.weights, np.full(spare.shape, 0.05)], axis=1),
        character.inverse_bind,
        character.skeleton,
    )


def test_merged_duplicate_influences_keep_a_vertex_where_a_shader_puts_it():
    # Exporters can list one joint twice for a vertex: a shader adds both; glTF forbids it.
    character = synth.humanoid()
    twice = SkinnedMesh(
        character.rest_positions,
        character.faces,
        np.concatenate([character.joints, character.joints], axis=1),
        np.concatenate([character.weights, character.weights], axis=1) / 2.0,
        character.inverse_bind,
        character.skeleton,
    )
    np.testing.assert_array_equal(twice.joints[:, :4], character.joints)
    np.testing.assert_allclose(twice.weights[:, :4], character.weights, atol=1e-6)
    assert not twice.weights[:, 4:].any()


def test_round_trip_eight_influences_and_no_optional_attributes(tmp_path):
    mesh = _eight_influences()
    assert (np.count_nonzero(mesh.weights, axis=1) > 4).all()  # every vertex needs the second set
    path = tmp_path / "k8.glb"
    write_glb(path, mesh, [])
    read, motions = read_skinned(path)
    assert read.joints.shape == (mesh.vertex_count, 8)
    _assert_same_skinned(read, mesh)
    assert motions == []


def test_round_trip_of_stretching_bones_keeps_joint_translations(tmp_path):
    mesh = _chain_mesh()
    base = _chain_motion(mesh.skeleton)
    stretch = np.broadcast_to(mesh.skeleton.offsets, (base.frame_count, 3, 3)).copy()
    stretch[:, 2, 1] *= 1.0 + 0.5 * np.arange(base.frame_count) / base.frame_count
    motion = Motion(base.skeleton, base.root_positions, base.local_rotations, base.fps, "stretch", stretch)
    path = tmp_path / "stretch.glb"
    write_glb(path, mesh, [motion])
    _, (read,) = read_skinned(path, fps=motion.fps)
    assert read.joint_translations is not None
    np.testing.assert_allclose(read.joint_translations[:, 1:], stretch[:, 1:], atol=1e-6)
    np.testing.assert_allclose(read.world_positions(), motion.world_positions(), atol=1e-6)


def test_round_trip_of_procedural_humanoid(tmp_path):
    mesh = synth.humanoid()
    walk = synth.humanoid_motion(mesh.skeleton, "walk")
    path = tmp_path / "humanoid.glb"
    write_glb(path, mesh, [walk])
    read, (read_walk,) = read_skinned(path, fps=walk.fps)
    _assert_same_skinned(read, mesh)
    assert read_walk.frame_count == walk.frame_count and read_walk.name == "walk"
    np.testing.assert_allclose(read_walk.world_positions(), walk.world_positions(), atol=1e-5)
    np.testing.assert_allclose(read.bake(read_walk).frames, mesh.bake(walk).frames, atol=1e-5)


def test_animation_names_override_and_mismatched_skeleton_is_refused(tmp_path):
    mesh = _chain_mesh()
    motion = _chain_motion(mesh.skeleton)
    path = tmp_path / "named.glb"
    write_glb(path, mesh, [motion, motion], names=["first", "second"])
    assert [m.name for m in read_skinned(path)[1]] == ["first", "second"]
    with pytest.raises(ValueError, match="names"):
        write_glb(path, mesh, [motion], names=["a", "b"])
    other = Skeleton(["a", "b", "c"], [-1, 0, 1], mesh.skeleton.offsets)
    with pytest.raises(ValueError, match="motion 0"):
        write_glb(tmp_path / "bad.glb", mesh, [Motion(other, motion.root_positions, motion.local_rotations, 24.0)])
    assert not (tmp_path / "bad.glb").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["named.glb"]  # no temporary left behind


def test_a_clip_duration_puts_the_last_key_at_the_clips_end(tmp_path):
    """The last frame of a glTF clip is sampled at the clip's end (frame_times), so its key goes
    there; a duration that would put it at or before the frame before it is refused."""
    mesh = _chain_mesh()
    motion = _chain_motion(mesh.skeleton)
    end = (motion.frame_count - 2 + 0.25) / motion.fps
    write_glb(tmp_path / "end.glb", mesh, [motion], durations=[end])
    written = GltfDocument(tmp_path / "end.glb")
    times, _, _ = written.sampler_keys(0, 0, 3, "root")
    assert len(times) == motion.frame_count and times[-1] == pytest.approx(end)
    with pytest.raises(ValueError, match="duration"):
        write_glb(tmp_path / "bad.glb", mesh, [motion], durations=[(motion.frame_count - 2) / motion.fps])
    assert not (tmp_path / "bad.glb").exists()


def test_read_gltf_on_a_written_file_lists_the_skin_and_motion(chain_glb):
    path, mesh, _ = chain_glb
    scene = read_gltf(path)
    assert len(scene.skinned_meshes) == 1 and scene.skinned_meshes[0].vertex_count == mesh.vertex_count
    assert [m.name for m in scene.motions] == ["bend"]
    assert scene.skinned_motions == [scene.motions]
    assert scene.morph_animations == [] and scene.static_meshes == []


def test_a_sampler_that_no_channel_uses_does_not_set_the_clips_length(chain_glb, tmp_path, capsys):
    # Exporters leave such samplers behind; one keyed to 10 s made a 1-second clip's levels
    # hold still for 9 s, and info report 10 s.
    from animlod.cli import main

    path, mesh, motion = chain_glb

    def leftover_sampler(gltf, blob):
        times = append_accessor(gltf, blob, np.float32([[0.0], [10.0]]), "SCALAR")
        gltf.accessors[times].min, gltf.accessors[times].max = [0.0], [10.0]
        values = append_accessor(gltf, blob, np.float32([[0, 0, 0], [1, 1, 1]]), "VEC3")
        gltf.animations[0].samplers.append(pygltflib.AnimationSampler(input=times, output=values))

    edited = edit_glb(path, tmp_path / "leftover.glb", leftover_sampler)
    duration = (motion.frame_count - 1) / motion.fps
    assert GltfDocument(edited).animation_duration(0) == pytest.approx(duration)
    assert read_skinned(edited, fps=motion.fps)[1][0].frame_count == motion.frame_count
    assert main(["info", str(edited)]) == 0
    assert f"channels, {duration:.2f} s" in capsys.readouterr().out


# ---- skeleton building --------------------------------------------------------------------


def test_joints_out_of_topological_order_are_reordered_and_remapped(chain_glb, tmp_path):
    path, mesh, motion = chain_glb

    def reverse_joints(gltf, blob):
        gltf.skins[0].joints = gltf.skins[0].joints[::-1]  # tip, mid, root
        matrices = _accessor_view(gltf, blob, gltf.skins[0].inverseBindMatrices, "<f4")
        matrices[:] = matrices[::-1].copy()
        attributes = gltf.meshes[0].primitives[0].attributes
        joints = _accessor_view(gltf, blob, attributes.JOINTS_0, "u1")
        joints[:] = 2 - joints

    read, motions = read_skinned(edit_glb(path, tmp_path / "reversed.glb", reverse_joints), fps=motion.fps)
    assert read.skeleton.names == ["root", "mid", "tip"]
    np.testing.assert_array_equal(read.skeleton.parents, [-1, 0, 1])
    np.testing.assert_allclose(read.bake(motions[0]).frames, mesh.bake(motion).frames, atol=1e-5)


def test_armature_above_the_root_is_folded_into_the_pose(chain_glb, tmp_path):
    path, mesh, motion = chain_glb
    rotation = rotations.from_axis_angle(np.array([1.0, 0.0, 0.0]), -np.pi / 2)
    armature = rotations.compose_transform(np.array([1.0, 2.0, 3.0]), rotation, np.full(3, 0.01))

    def add_armature(gltf, blob):
        armature_node = pygltflib.Node(name="Armature", children=[0], translation=[1.0, 2.0, 3.0])
        armature_node.rotation, armature_node.scale = rotation.tolist(), [0.01] * 3
        gltf.nodes.append(armature_node)
        gltf.scenes[0].nodes = [len(gltf.nodes) - 1, 3]

    read, motions = read_skinned(edit_glb(path, tmp_path / "armature.glb", add_armature), fps=motion.fps)
    expected = _transform(armature, mesh.bake(motion).frames.astype(np.float64))
    np.testing.assert_allclose(read.bake(motions[0]).frames, expected, atol=1e-6)
    # The rigid skeleton carries the 0.01 in its offsets, the inverse bind matrices the rest.
    np.testing.assert_allclose(np.linalg.norm(read.skeleton.offsets[1:], axis=1), 0.01, rtol=1e-6)


def _split_chain_under_an_armature(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
    """Armature -> [root, mid -> tip]: the skin's joints now form two trees."""
    gltf.nodes[0].children = []
    gltf.nodes.append(pygltflib.Node(name="Armature", children=[0, 1], translation=[0.0, 0.0, 2.0]))
    gltf.scenes[0].nodes = [len(gltf.nodes) - 1, 3]


def test_joints_in_several_trees_get_their_common_ancestor_as_root(chain_glb, tmp_path):
    path, _, motion = chain_glb
    split = edit_glb(path, tmp_path / "split.glb", _split_chain_under_an_armature)
    read, (read_motion,) = read_skinned(split, fps=motion.fps)
    assert read.skeleton.names == ["Armature", "root", "mid", "tip"]
    np.testing.assert_array_equal(read.skeleton.parents, [-1, 0, 0, 2])
    assert read.joints.max() <= 3 and not np.any(read.weights[read.joints == 0] > 0)  # nothing bound to it
    gltf = pygltflib.GLTF2.load_from_bytes(split.read_bytes())
    baked = read.bake(read_motion).frames
    for frame in (0, 3, motion.frame_count - 1):
        expected = _viewer_skinning(gltf, bytearray(gltf.binary_blob()), 3, "bend", frame)
        np.testing.assert_allclose(baked[frame], expected, atol=1e-5)


def test_joints_in_trees_without_a_common_node_are_refused(chain_glb, tmp_path):
    path, _, _ = chain_glb

    def two_scene_roots(gltf, blob):
        gltf.nodes[0].children = []
        gltf.scenes[0].nodes = [0, 1, 3]

    reason = "joints form 2 node trees with no node in common: node 0 'root', the child of no node; node 1 'mid',"
    with pytest.raises(FormatError, match=f"skin 0: {reason}"):
        read_skinned(edit_glb(path, tmp_path / "forest.glb", two_scene_roots))


def test_a_joint_left_out_of_the_armature_is_named_as_the_one_apart(chain_glb, tmp_path):
    """Blender's flattened deform bones can leave one joint out of the armature's children: the
    message listed every top joint as a tree of its own, though all but one hang from the armature."""
    path, _, _ = chain_glb

    def armature_of_two_with_one_left_out(gltf, blob):
        gltf.nodes[0].children = []  # root, mid, tip: mid and tip under a new armature, root apart
        gltf.nodes[1].children = []
        gltf.nodes.append(pygltflib.Node(name="Armature", children=[1, 2]))
        gltf.scenes[0].nodes = [0, 3, len(gltf.nodes) - 1]

    reason = "2 node trees with no node in common: node 0 'root', the child of no node; "
    reason += "2 under node 4 'Armature' (node 1 'mid', node 2 'tip'); one root is needed"
    with pytest.raises(FormatError, match=re.escape(f"skin 0: joints form {reason}")):
        read_skinned(edit_glb(path, tmp_path / "apart.glb", armature_of_two_with_one_left_out))


def test_mesh_node_transform_moves_the_rest_mesh_but_not_the_skinned_result(chain_glb, tmp_path):
    path, mesh, motion = chain_glb

    def move_mesh_node(gltf, blob):
        gltf.nodes[3].translation = [5.0, 0.0, 0.0]

    read, motions = read_skinned(edit_glb(path, tmp_path / "moved.glb", move_mesh_node), fps=motion.fps)
    np.testing.assert_allclose(read.rest_positions, mesh.rest_positions + [5.0, 0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(read.bake(motions[0]).frames, mesh.bake(motion).frames, atol=1e-5)


def test_primitives_of_one_mesh_are_merged(chain_glb, tmp_path):
    path, mesh, _ = chain_glb

    def duplicate_primitive(gltf, blob):
        primitive = gltf.meshes[0].primitives[0]
        gltf.meshes[0].primitives.append(
            pygltflib.Primitive(attributes=primitive.attributes, indices=primitive.indices, targets=primitive.targets)
        )

    read, _ = read_skinned(edit_glb(path, tmp_path / "two.glb", duplicate_primitive))
    vertex_count = mesh.vertex_count
    assert read.vertex_count == 2 * vertex_count
    np.testing.assert_array_equal(read.faces[mesh.face_count :], mesh.faces + vertex_count)
    np.testing.assert_array_equal(read.rest_positions[vertex_count:], mesh.rest_positions)


# ---- meshes without a skin, from a hand-written .gltf -------------------------------------


def _write_quad_gltf(folder: Path, buffer_uri: str | None) -> Path:
    """A .gltf whose one mesh has a TRIANGLE_STRIP and a TRIANGLE_FAN primitive over the same
    quad and one sparse morph target (vertex 3 lifted by 0.5 in z, weight 1); node 0 places it
    with TRS, node 1 with a mirroring matrix. ``buffer_uri`` None embeds the buffer as a data URI.
    """
    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], "<f4")
    strip, fan = np.array([0, 1, 2, 3], "<u2"), np.array([0, 1, 3, 2], "<u2")
    sparse_index, sparse_value = np.array([3, 0], "<u2"), np.array([[0, 0, 0.5]], "<f4")  # index padded to 4 bytes
    chunks = [positions, strip, fan, sparse_index, sparse_value]
    data = b"".join(c.tobytes() for c in chunks)
    starts = np.cumsum([0] + [c.nbytes for c in chunks])
    views = [{"buffer": 0, "byteOffset": int(start), "byteLength": c.nbytes} for c, start in zip(chunks, starts)]
    views[3]["byteLength"] = 2
    if buffer_uri is None:
        uri = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    else:
        (folder / buffer_uri).write_bytes(data)
        uri = buffer_uri
    targets = [{"POSITION": 3}]
    document = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(data), "uri": uri}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 4, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5123, "count": 4, "type": "SCALAR"},
            {
                "componentType": 5126,
                "count": 4,
                "type": "VEC3",
                "sparse": {
                    "count": 1,
                    "indices": {"bufferView": 3, "componentType": 5123},
                    "values": {"bufferView": 4},
                },
            },
        ],
        "meshes": [
            {
                "primitives": [
                    {"attributes": {"POSITION": 0}, "indices": 1, "mode": 5, "targets": targets},
                    {"attributes": {"POSITION": 0}, "indices": 2, "mode": 6, "targets": targets},
                ],
                "weights": [1.0],
            }
        ],
        "nodes": [
            {"mesh": 0, "translation": [0, 0, 5]},
            {"mesh": 0, "matrix": [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1]},
        ],
        "scenes": [{"nodes": [0, 1]}],
        "scene": 0,
    }
    path = folder / "quad.gltf"
    path.write_text(json.dumps(document))
    return path


@pytest.mark.parametrize("buffer_uri", [None, "quad.bin"])
def test_static_meshes_strips_fans_sparse_targets_and_mirroring(tmp_path, buffer_uri):
    scene = read_gltf(_write_quad_gltf(tmp_path, buffer_uri))
    assert scene.skinned_meshes == [] and scene.morph_animations == []
    placed, mirrored = scene.static_meshes
    quad = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]])
    # Strip triangles (0 1 2) (1 3 2); fan triangles (1 3 0) (3 2 0), offset by the strip's 4 vertices.
    faces = np.array([[0, 1, 2], [1, 3, 2], [5, 7, 4], [7, 6, 4]])
    np.testing.assert_array_equal(placed.faces, faces)
    np.testing.assert_allclose(placed.frames[0], np.vstack([quad, quad]) + [0, 0, 5])
    assert placed.fps is None
    # A mirroring node keeps the triangles front-facing by reversing their corners.
    np.testing.assert_array_equal(mirrored.faces, faces[:, ::-1])
    np.testing.assert_allclose(mirrored.frames[0], np.vstack([quad, quad]) * [-1, 1, 1] + [10, 0, 0])


def test_missing_external_buffer_is_reported(tmp_path):
    path = _write_quad_gltf(tmp_path, "quad.bin")
    (tmp_path / "quad.bin").unlink()
    with pytest.raises(FormatError, match=r"quad.gltf: buffer 0: cannot read .*quad.bin"):
        read_gltf(path)


# ---- bad input ----------------------------------------------------------------------------


def test_garbage_bytes_are_not_a_gltf(tmp_path):
    path = tmp_path / "garbage.glb"
    path.write_bytes(np.random.default_rng(1).integers(0, 256, 500, dtype=np.uint8).tobytes())
    with pytest.raises(FormatError, match="not a glTF file") as caught:
        read_gltf(path)
    assert str(path) in str(caught.value)


def test_truncated_glb_is_reported(chain_glb, tmp_path):
    path, _, _ = chain_glb
    data = path.read_bytes()
    for cut in (len(data) // 2, 16):
        truncated = tmp_path / f"cut{cut}.glb"
        truncated.write_bytes(data[:cut])
        with pytest.raises(FormatError, match="truncated") as caught:
            read_skinned(truncated)
        assert str(truncated) in str(caught.value)


def test_missing_skin_names_the_file_and_the_skin(chain_glb):
    path, _, _ = chain_glb
    with pytest.raises(FormatError, match=r"skin 5: not in the file") as caught:
        read_skinned(path, skin=5)
    assert str(path) in str(caught.value)
    with pytest.raises(FormatError, match=r"skin 'Hero'"):
        read_skinned(path, skin="Hero")
    assert read_skinned(path, skin=0)[0].vertex_count == read_skinned(path, skin="skinned mesh")[0].vertex_count


def test_required_extension_animlod_cannot_read(chain_glb, tmp_path):
    path, _, _ = chain_glb

    def require_meshopt(gltf, blob):
        gltf.extensionsUsed = gltf.extensionsRequired = ["VENDOR_mesh_compression"]

    with pytest.raises(FormatError, match=r"extensionsRequired: needs VENDOR_mesh_compression"):
        read_gltf(edit_glb(path, tmp_path / "meshopt.glb", require_meshopt))


def test_accessor_index_out_of_range(chain_glb, tmp_path):
    path, _, _ = chain_glb

    def break_position(gltf, blob):
        gltf.meshes[0].primitives[0].attributes.POSITION = 999

    with pytest.raises(FormatError, match=r"mesh 0 primitive 0 POSITION: refers to accessor 999"):
        read_skinned(edit_glb(path, tmp_path / "oob.glb", break_position))


def test_nan_in_positions(chain_glb, tmp_path):
    path, _, _ = chain_glb

    def poison(gltf, blob):
        _accessor_view(gltf, blob, gltf.meshes[0].primitives[0].attributes.POSITION, "<f4")[3, 1] = np.nan

    with pytest.raises(FormatError, match=r"accessor 1 \(mesh 0 primitive 0 POSITION\): non-finite value at element 3"):
        read_skinned(edit_glb(path, tmp_path / "nan.glb", poison))


def test_quantized_morph_deltas_read_as_numbers(chain_glb, tmp_path):
    # KHR_mesh_quantization lets morph deltas be plain SHORT (the node's scale makes them metres).
    path, mesh, _ = chain_glb
    stored = np.rint(mesh.morph_targets * 1000.0).astype(np.int16)

    def quantize(gltf, blob) -> None:
        for target, deltas in zip(gltf.meshes[0].primitives[0].targets, stored):
            target["POSITION"] = append_accessor(gltf, blob, deltas, "VEC3")
        gltf.extensionsUsed = [*(gltf.extensionsUsed or []), "KHR_mesh_quantization"]

    read, _ = read_skinned(edit_glb(path, tmp_path / "quantized.glb", quantize))
    np.testing.assert_array_equal(read.morph_targets, stored.astype(np.float32))


def test_draco_compressed_primitives_read_as_the_uncompressed_ones(chain_glb, tmp_path):
    path, _, motion = chain_glb
    compressed = draco_compressed(path, tmp_path / "draco.glb")
    gltf = pygltflib.GLTF2.load_from_bytes(compressed.read_bytes())
    primitive = gltf.meshes[0].primitives[0]
    assert gltf.accessors[primitive.attributes.POSITION].bufferView is None  # only Draco holds them
    expected, (expected_motion,) = read_skinned(path, fps=motion.fps)
    read, (read_motion,) = read_skinned(compressed, fps=motion.fps)
    np.testing.assert_array_equal(read.faces, expected.faces)
    np.testing.assert_array_equal(read.joints, expected.joints)
    np.testing.assert_array_equal(read.weights, expected.weights)
    np.testing.assert_array_equal(read.uvs, expected.uvs)
    np.testing.assert_array_equal(read.morph_targets, expected.morph_targets)  # Draco leaves targets alone
    extent = float(np.ptp(expected.rest_positions, axis=0).max())
    np.testing.assert_allclose(read.rest_positions, expected.rest_positions, atol=extent / 2**15)  # 16-bit grid
    np.testing.assert_array_equal(read_motion.local_rotations, expected_motion.local_rotations)


def test_draco_data_that_does_not_decode_is_named(chain_glb, tmp_path):
    path, _, _ = chain_glb
    compressed = draco_compressed(path, tmp_path / "draco.glb")

    def garble(gltf, blob):
        view = gltf.bufferViews[gltf.meshes[0].primitives[0].extensions["KHR_draco_mesh_compression"]["bufferView"]]
        blob[view.byteOffset : view.byteOffset + 8] = b"notdraco"

    broken = edit_glb(compressed, tmp_path / "broken.glb", garble)
    with pytest.raises(FormatError, match=r"mesh 0 primitive 0 KHR_draco_mesh_compression: the compressed data does"):
        read_skinned(broken)


def _rotated_to_lowest(faces: np.ndarray) -> np.ndarray:
    """Each triangle rotated to start at its lowest index (the same triangle, same winding)."""
    first = np.argmin(faces, axis=1)[:, None]
    return np.take_along_axis(faces, (first + np.arange(3)) % 3, axis=1)


@pytest.mark.parametrize(
    "extension, codec", [("EXT_meshopt_compression", 0), ("KHR_meshopt_compression", 1)], ids=["EXT", "KHR-v1"]
)
def test_meshopt_compressed_views_read_as_the_uncompressed_ones(chain_glb, tmp_path, extension, codec):
    path, _, motion = chain_glb
    compressed = meshopt_compressed(path, tmp_path / "meshopt.glb", extension, codec)
    expected, (expected_motion,) = read_skinned(path, fps=motion.fps)
    read, (read_motion,) = read_skinned(compressed, fps=motion.fps)
    # The index codec may start a triangle at another corner; the triangles are the same.
    np.testing.assert_array_equal(_rotated_to_lowest(read.faces), _rotated_to_lowest(expected.faces))
    for name in ("rest_positions", "joints", "weights", "uvs", "normals", "inverse_bind", "morph_targets"):
        np.testing.assert_array_equal(getattr(read, name), getattr(expected, name), err_msg=name)
    np.testing.assert_array_equal(read_motion.local_rotations, expected_motion.local_rotations)


def test_meshopt_filters_turn_decoded_integers_into_vectors():
    import meshoptimizer

    from animlod.io.gltf_meshopt import decode_meshopt_view

    # Octahedral int8 (x, y, K, w): (127, 0) is +X, whatever the raw third component says.
    raw = np.array([[127, 0, 127, 7], [0, 0, 127, 9]], np.int8)
    coded = meshoptimizer.encode_vertex_buffer(raw.view(np.float32), 2, 4)
    extension = {"count": 2, "byteStride": 4, "mode": "ATTRIBUTES", "filter": "OCTAHEDRAL"}
    decoded = decode_meshopt_view(extension, coded, "bufferView 0", ValueError, 2**20)
    np.testing.assert_array_equal(np.frombuffer(decoded, np.int8).reshape(2, 4), [[127, 0, 0, 7], [0, 0, 127, 9]])
    with pytest.raises(ValueError, match="mode 'QUADS' or filter 'NONE' is not defined"):
        decode_meshopt_view({**extension, "mode": "QUADS", "filter": "NONE"}, coded, "bufferView 0", ValueError, 2**20)
    with pytest.raises(ValueError, match="filter 'COLOR' is not decoded"):  # KHR_meshopt_compression's
        decode_meshopt_view({**extension, "filter": "COLOR"}, coded, "bufferView 0", ValueError, 2**20)
    with pytest.raises(ValueError, match="claims 1000000 x 4 bytes, more than the file can justify"):
        decode_meshopt_view({**extension, "count": 10**6}, coded, "bufferView 0", ValueError, 2**20)


def _rest_scale(node: int, scale: list[float]) -> Callable[[pygltflib.GLTF2, bytearray], None]:
    """An edit giving ``node`` the rest ``scale``."""
    return lambda gltf, blob: setattr(gltf.nodes[node], "scale", scale)


def _viewer_frame(path: Path, frame: int, animated: bool = True) -> np.ndarray:
    """_viewer_skinning of the chain's skinned node at key ``frame`` (the rest pose when not animated)."""
    gltf = pygltflib.GLTF2.load_from_bytes(path.read_bytes())
    if not animated:
        gltf.animations[0].channels = []
    return _viewer_skinning(gltf, bytearray(gltf.binary_blob()), 3, "bend", frame)


def test_a_non_uniform_rest_scale_is_skinned_as_a_viewer_does(chain_glb, tmp_path):
    # 'mid' stretched along y in the rest pose: its children turn under it, a shear in glTF.
    path, _, motion = chain_glb
    stretched = edit_glb(path, tmp_path / "stretched.glb", _rest_scale(1, [1.0, 2.0, 1.0]))
    read, (read_motion,) = read_skinned(stretched, fps=motion.fps)
    assert read_motion.joint_deformations is not None
    baked = read.bake(read_motion).frames
    for frame in range(motion.frame_count):
        np.testing.assert_allclose(baked[frame], _viewer_frame(stretched, frame), atol=1e-5)
    # The rest pose a viewer shows (no animation) has the stretch too.
    np.testing.assert_allclose(read.rest_pose(), _viewer_frame(stretched, 0, animated=False), atol=1e-5)


def test_float_noise_in_a_rest_scale_leaves_the_motion_rigid(chain_glb, tmp_path):
    # 3ds Max's Biped writes scales off 1 by up to 1.5e-4 on each axis, which chains of them add up:
    # a shear of a few 1e-4 under the turning tip is float noise, and the viewer's skin is still met.
    path, _, motion = chain_glb
    noisy = edit_glb(path, tmp_path / "noisy.glb", _rest_scale(1, [1.0, 1.0003, 0.9997]))
    read, (read_motion,) = read_skinned(noisy, fps=motion.fps)
    assert read_motion.joint_deformations is None
    extent = float(np.ptp(read.rest_positions, axis=0).max())
    np.testing.assert_allclose(read.bake(read_motion).frames[4], _viewer_frame(noisy, 4), atol=1e-3 * extent)


def test_a_stretched_leaf_leaves_the_motion_rigid(chain_glb, tmp_path):
    path, _, motion = chain_glb
    stretched = edit_glb(path, tmp_path / "leaf.glb", _rest_scale(2, [1.0, 3.0, 1.0]))
    read, (read_motion,) = read_skinned(stretched, fps=motion.fps)
    assert read_motion.joint_deformations is None  # nothing turns under the tip: motion LoD can take it
    np.testing.assert_allclose(read.bake(read_motion).frames[4], _viewer_frame(stretched, 4), atol=1e-5)


def test_a_mirrored_joint_is_skinned_as_a_viewer_does(chain_glb, tmp_path):
    # 3ds Max and Maya write mirrored bones with a negative scale: the rotations below stay rigid.
    path, _, motion = chain_glb
    mirrored = edit_glb(path, tmp_path / "mirrored.glb", _rest_scale(1, [-1.0, 1.0, 1.0]))
    read, (read_motion,) = read_skinned(mirrored, fps=motion.fps)
    assert read_motion.joint_deformations is None
    baked = read.bake(read_motion).frames
    for frame in range(motion.frame_count):
        np.testing.assert_allclose(baked[frame], _viewer_frame(mirrored, frame), atol=1e-5)


def test_a_flattened_joint_is_refused(chain_glb, tmp_path):
    path, _, _ = chain_glb
    flattened = edit_glb(path, tmp_path / "flat.glb", _rest_scale(1, [0.0, 1.0, 1.0]))
    with pytest.raises(FormatError, match=r"skin 0: scale \[0.0, 1.0, 1.0\] of node 1 'mid' has a zero component"):
        read_skinned(flattened)


def test_animated_scale_is_skinned_as_a_viewer_does(chain_glb, tmp_path):
    path, _, motion = chain_glb
    scaled = edit_glb(path, tmp_path / "squash.glb", squash_and_stretch)
    read, (read_motion,) = read_skinned(scaled, fps=motion.fps)
    assert read_motion.joint_deformations is not None
    gltf = pygltflib.GLTF2.load_from_bytes(scaled.read_bytes())
    baked = read.bake(read_motion).frames
    for frame in range(motion.frame_count):
        expected = _viewer_skinning(gltf, bytearray(gltf.binary_blob()), 3, "bend", frame)
        np.testing.assert_allclose(baked[frame], expected, atol=1e-5)
    # A joint's position follows its parent's scale; the skeleton's rest pose does not scale.
    np.testing.assert_allclose(np.linalg.norm(read_motion.local_translations()[-1, 1:], axis=1), [1.5, 1.6 * 1.5])
    np.testing.assert_allclose(read.rest_pose(), read.bake(read.skeleton.rest_motion(1)).frames[0])


def _as_pointer_channels(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
    """Every channel written as KHR_animation_pointer, plus one animating a material's colour."""
    animation = gltf.animations[0]
    for channel in animation.channels:
        pointer = f"/nodes/{channel.target.node}/{channel.target.path}"
        channel.target = pygltflib.AnimationChannelTarget(path="pointer")
        channel.target.extensions = {"KHR_animation_pointer": {"pointer": pointer}}
    gltf.materials = gltf.materials or [pygltflib.Material(name="painted")]  # what the pointer names must exist
    colour = pygltflib.AnimationChannelTarget(path="pointer")
    colour.extensions = {"KHR_animation_pointer": {"pointer": "/materials/0/pbrMetallicRoughness/baseColorFactor"}}
    animation.channels.append(pygltflib.AnimationChannel(sampler=1, target=colour))  # a VEC4 output
    gltf.extensionsUsed = [*(gltf.extensionsUsed or []), "KHR_animation_pointer"]


def test_pointer_channels_of_nodes_pose_them_and_others_are_left_alone(chain_glb, tmp_path):
    path, _, motion = chain_glb
    pointers = edit_glb(path, tmp_path / "pointers.glb", _as_pointer_channels)
    _, (expected,) = read_skinned(path, fps=motion.fps)
    _, (read,) = read_skinned(pointers, fps=motion.fps)
    np.testing.assert_array_equal(read.local_rotations, expected.local_rotations)
    np.testing.assert_array_equal(read.root_positions, expected.root_positions)

    def without_pointer(gltf, blob):
        gltf.animations[0].channels[0].target = pygltflib.AnimationChannelTarget(path="pointer")

    with pytest.raises(FormatError, match=r"animation 0 channel 0 target: path 'pointer' needs a KHR_animation"):
        read_skinned(edit_glb(path, tmp_path / "bare.glb", without_pointer))


def test_primitives_sharing_one_vertex_buffer_keep_only_the_vertices_they_use(chain_glb, tmp_path):
    path, _, _ = chain_glb
    shared = edit_glb(path, tmp_path / "shared.glb", lambda gltf, blob: share_one_vertex_buffer(gltf, blob, 3))
    geometry = read_mesh_geometry(GltfDocument(shared), 0, skinned=True)
    plain = read_mesh_geometry(GltfDocument(path), 0, skinned=True)
    assert len(geometry.primitives) == 3
    for primitive in geometry.primitives:
        assert np.unique(primitive.faces).size == primitive.vertex_count  # nothing unused

    # The same triangles at the same positions, with the same skin, as the one primitive had.
    def corners(g):
        rows = np.concatenate([g.positions[g.faces], g.weights[g.faces]], axis=2).reshape(len(g.faces), -1)
        return rows[np.lexsort(rows.T[::-1])]

    np.testing.assert_array_equal(corners(geometry), corners(plain))
    assert len(geometry.positions) < 2 * len(plain.positions)  # each vertex once, but at the runs' borders


def test_morph_target_names_on_the_primitive_as_univrm_writes_them(chain_glb, tmp_path):
    path, _, _ = chain_glb

    def names_on_the_primitive(gltf, blob):
        gltf.meshes[0].primitives[0].extras = {"targetNames": gltf.meshes[0].extras.pop("targetNames")}

    moved = edit_glb(path, tmp_path / "moved.glb", names_on_the_primitive)
    assert "targetNames" not in GltfDocument(moved).json["meshes"][0].get("extras", {})
    assert read_mesh_geometry(GltfDocument(moved), 0, skinned=True).target_names == ["bulge", "twist"]


def test_scale_keys_at_the_rest_scale_leave_the_motion_rigid(chain_glb, tmp_path):
    path, _, motion = chain_glb
    held = edit_glb(path, tmp_path / "held.glb", lambda g, b: add_scale_channel(g, b, 1, np.full((6, 3), 1.00001)))
    assert read_skinned(held, fps=motion.fps)[1][0].joint_deformations is None


# ---- the tinygltf probe -------------------------------------------------------------------


def test_tinygltf_loads_what_animlod_writes(tmp_path):
    probe = os.environ.get("ANIMLOD_GLTF_PROBE")
    if not probe:
        pytest.skip("ANIMLOD_GLTF_PROBE is not set (make test sets it to the built animlod_gltf_probe)")
    mesh = _chain_mesh()
    motions = [_chain_motion(mesh.skeleton), _chain_motion(mesh.skeleton, frames=11, fps=30.0, name="long")]
    path = tmp_path / "probe.glb"
    write_glb(path, mesh, motions)
    result = subprocess.run([probe, str(path)], capture_output=True, text=True, check=True, timeout=60)
    summary = json.loads(result.stdout)
    assert summary["vertices"] == mesh.vertex_count
    assert summary["triangles"] == mesh.face_count
    assert summary["joints"] == mesh.skeleton.joint_count
    assert summary["morph_targets"] == 2
    assert summary["position_sum"] == pytest.approx(float(mesh.rest_positions.astype(np.float64).sum()), rel=1e-6)
    inverse_bind_sum = float(mesh.inverse_bind.astype(np.float32).astype(np.float64).sum())
    assert summary["inverse_bind_sum"] == pytest.approx(inverse_bind_sum, rel=1e-6)
    assert summary["weight_sum"] == pytest.approx(float(mesh.weights.astype(np.float64).sum()), rel=1e-6)
    assert summary["animations"] == [{"channels": 1 + 3, "keys": 6}, {"channels": 1 + 3, "keys": 11}]


# ---- the real development files -----------------------------------------------------------


@pytest.fixture(scope="module")
def soldier(data_dir):
    path = data_dir / "gltf" / "Soldier.glb"
    return path, read_gltf(path)


def test_rigged_figure(data_dir):
    mesh, motions = read_skinned(data_dir / "gltf" / "RiggedFigure.glb")
    assert (mesh.vertex_count, mesh.face_count, mesh.skeleton.joint_count, len(motions)) == (370, 256, 19, 1)
    assert np.all(mesh.skeleton.parents[1:] < np.arange(1, 19))
    np.testing.assert_allclose(mesh.weights.sum(axis=1), 1.0, atol=1e-6)  # the file's own sums reach 0.2
    assert motions[0].frame_count == 39 and motions[0].fps == 30.0  # 1.25 s at 30 fps, and its end
    _assert_rest_bake_matches(mesh)
    frames = mesh.bake(motions[0]).frames
    assert np.all(np.isfinite(frames))
    assert np.abs(frames - mesh.rest_positions).max() > 0.01  # it does move


def _assert_rest_bake_matches(mesh: SkinnedMesh) -> None:
    """Baking the rest pose reproduces the bind mesh (these files are consistent)."""
    skeleton = mesh.skeleton
    rest = Motion(skeleton, skeleton.offsets[None, 0], skeleton.rest_rotations[None], fps=30.0)
    baked = mesh.bake(rest).frames[0]
    extent = np.ptp(mesh.rest_positions, axis=0).max()
    np.testing.assert_allclose(baked.min(axis=0), mesh.rest_positions.min(axis=0), atol=1e-3 * extent)
    np.testing.assert_allclose(baked.max(axis=0), mesh.rest_positions.max(axis=0), atol=1e-3 * extent)
    assert np.abs(baked - mesh.rest_positions).max() < 1e-3 * extent


def test_soldier_counts_and_placement(soldier):
    _, scene = soldier
    body, visor = scene.skinned_meshes
    assert [m.skeleton.joint_count for m in scene.skinned_meshes] == [49, 2]
    assert body.vertex_count + visor.vertex_count == 7434
    assert body.face_count + visor.face_count == 11376
    for motions in scene.skinned_motions:
        assert [m.name for m in motions] == ["Idle", "Run", "TPose", "Walk"]
        assert [m.frame_count for m in motions] == [60, 22, 2, 32]  # 1.97, 0.70, 0.03, 1.03 s
    # The armature's 0.01 scale and Z-up rotation are folded in: a 1.8 m figure standing on y = 0.
    height = body.rest_positions[:, 1]
    assert height.min() == pytest.approx(0.0, abs=0.01) and height.max() == pytest.approx(1.83, abs=0.02)
    for mesh in scene.skinned_meshes:
        _assert_rest_bake_matches(mesh)
    assert scene.morph_animations == [] and scene.static_meshes == []


def test_soldier_run_matches_a_direct_glTF_skinning(soldier):
    path, scene = soldier
    gltf = pygltflib.GLTF2.load_from_bytes(path.read_bytes())
    blob = bytearray(gltf.binary_blob())
    for mesh, motions, mesh_node in zip(scene.skinned_meshes, scene.skinned_motions, (1, 2)):
        baked = mesh.bake(next(m for m in motions if m.name == "Run")).frames
        for frame in (0, 7, 21):  # Run's keys sit at 30 fps, so frame k is key k
            expected = _viewer_skinning(gltf, blob, mesh_node, "Run", frame)
            np.testing.assert_allclose(baked[frame], expected, atol=2e-5)


def test_read_skinned_picks_a_skin_by_name(soldier):
    path, scene = soldier
    visor, motions = read_skinned(path, skin="vanguard_visor")
    assert visor.skeleton.names == ["mixamorig:Neck", "mixamorig:Head"]
    np.testing.assert_array_equal(visor.rest_positions, scene.skinned_meshes[1].rest_positions)
    assert [m.name for m in motions] == ["Idle", "Run", "TPose", "Walk"]


def test_flamingo_morph_animation(data_dir):
    path = data_dir / "meshseq" / "Flamingo-morph-glTF" / "Flamingo.glb"
    scene = read_gltf(path)
    assert scene.skinned_meshes == [] and scene.motions == [] and scene.static_meshes == []
    (flight,) = scene.morph_animations
    assert flight.frames.shape == (43, 337, 3) and flight.face_count == 542 and flight.fps == 30.0  # 1.4 s
    gltf = pygltflib.GLTF2.load_from_bytes(path.read_bytes())
    blob = bytearray(gltf.binary_blob())
    primitive = gltf.meshes[0].primitives[0]
    assert len(primitive.targets) == 14
    rest = _accessor_view(gltf, blob, primitive.attributes.POSITION, "<f4")
    deltas = np.stack([_accessor_view(gltf, blob, t["POSITION"], "<f4") for t in primitive.targets])
    sampler = gltf.animations[0].samplers[0]
    weights = _accessor_view(gltf, blob, sampler.output, "<f4").reshape(-1, 14)
    times = _accessor_view(gltf, blob, sampler.input, "<f4")[:, 0]
    np.testing.assert_allclose(times, np.arange(15) / 10, atol=1e-6)  # keys every 0.1 s up to 1.4 s
    # Frame 9 (0.3 s) sits on key 3; frame 10 (1/3 s) a third of the way from key 3 to key 4.
    np.testing.assert_allclose(flight.frames[9], rest + np.einsum("n,nvc->vc", weights[3], deltas), atol=1e-4)
    between = weights[3] + (weights[4] - weights[3]) / 3
    np.testing.assert_allclose(flight.frames[10], rest + np.einsum("n,nvc->vc", between, deltas), atol=1e-4)
    with pytest.raises(FormatError, match="Flamingo.glb: skins: no node draws a skinned mesh"):
        read_skinned(path)


def _edit_quad_gltf(folder: Path, edit: Callable[[dict], None]) -> Path:
    """The quad .gltf of :func:`_write_quad_gltf` (external buffer) with ``edit`` applied to its JSON."""
    path = _write_quad_gltf(folder, "quad.bin")
    document = json.loads(path.read_text())
    edit(document)
    path.write_text(json.dumps(document))
    return path


@pytest.mark.parametrize("stride", [8, 14, 256])
def test_byte_stride_outside_the_spec_is_refused(tmp_path, stride):
    def set_stride(document):
        document["bufferViews"][0]["byteStride"] = stride

    path = _edit_quad_gltf(tmp_path, set_stride)
    with pytest.raises(FormatError) as caught:
        read_gltf(path)
    reason = f"byteStride {stride} must be a multiple of 4 from 12 (the element size of accessor 0"
    assert str(caught.value).startswith(f"{path}: bufferView 0: {reason}")


@pytest.mark.parametrize(
    ("element", "owner"),
    [
        ("bufferView 1", lambda document: document["bufferViews"][1]),
        ("accessor 1 (mesh 0 primitive 0 indices)", lambda document: document["accessors"][1]),
        (
            "accessor 3 (mesh 0 primitive 0 target 0 POSITION) sparse indices",
            lambda document: document["accessors"][3]["sparse"]["indices"],
        ),
    ],
)
def test_negative_byte_offset_is_refused(tmp_path, element, owner):
    path = _edit_quad_gltf(tmp_path, lambda document: owner(document).update(byteOffset=-4))
    with pytest.raises(FormatError) as caught:
        read_gltf(path)
    assert str(caught.value) == f"{path}: {element}: byteOffset -4 is not a whole number >= 0"


def test_signed_sparse_indices_are_refused(tmp_path):
    def signed_indices(document):
        document["accessors"][3]["sparse"]["indices"]["componentType"] = 5122

    path = _edit_quad_gltf(tmp_path, signed_indices)
    with pytest.raises(FormatError, match=r"sparse indices: componentType 5122 is not one of \(5121, 5123, 5125\)"):
        read_gltf(path)


def test_node_with_a_missing_mesh_names_it_in_the_singular(tmp_path):
    def break_mesh(document):
        document["nodes"][1]["mesh"] = 7

    with pytest.raises(FormatError, match=r"refers to mesh 7, but the file has 1 meshes"):
        read_gltf(_edit_quad_gltf(tmp_path, break_mesh))


def test_sparse_accessor_without_indices(tmp_path):
    def drop_indices(document):
        del document["accessors"][3]["sparse"]["indices"]

    path = _edit_quad_gltf(tmp_path, drop_indices)
    with pytest.raises(FormatError) as caught:
        read_gltf(path)
    assert (
        str(caught.value)
        == f"{path}: accessor 3 (mesh 0 primitive 0 target 0 POSITION) sparse: needs both indices and values"
    )


def test_data_uri_with_non_ascii_text(tmp_path):
    path = _write_quad_gltf(tmp_path, None)
    path.write_text(path.read_text().replace(";base64,", ";base64,\u00e9"))
    with pytest.raises(FormatError, match=r"quad.gltf: buffer 0: malformed base64 data URI"):
        read_gltf(path)


def test_key_time_far_beyond_any_clip_is_refused(chain_glb, tmp_path):
    path, _, _ = chain_glb

    def stretch_last_key(gltf, blob):
        times = _accessor_view(gltf, blob, gltf.animations[0].samplers[0].input, "<f4")
        times[-1, 0] = 1e7

    message = r"animation 'bend': lasts 1e\+07 s: 300000001 frames at 30 fps, more than the limit of 100000"
    with pytest.raises(FormatError, match=message):
        read_skinned(edit_glb(path, tmp_path / "long.glb", stretch_last_key))


def test_zero_rotation_key_is_refused(chain_glb, tmp_path):
    path, _, _ = chain_glb

    def zero_rotation(gltf, blob):
        animation = gltf.animations[0]
        channel = next(c for c in animation.channels if c.target.path == "rotation")
        _accessor_view(gltf, blob, animation.samplers[channel.sampler].output, "<f4")[:] = 0.0

    with pytest.raises(
        FormatError, match=r"animation 'bend' channel \d+: quaternion: index \(\d+,\) has a zero or non-finite norm"
    ):
        read_skinned(edit_glb(path, tmp_path / "zero.glb", zero_rotation))


def test_null_inside_an_array_is_refused(tmp_path):
    def null_accessor(document):
        document["accessors"][2] = None

    path = _edit_quad_gltf(tmp_path, null_accessor)
    with pytest.raises(FormatError) as caught:
        read_gltf(path)
    assert str(caught.value) == f"{path}: accessors[2]: null (glTF arrays hold no nulls)"


@pytest.mark.parametrize("count", [2**32, -1])  # a JSON type that is no integer: test_gltf_decode.py
def test_accessor_count_that_is_no_uint32(tmp_path, count):
    def set_count(document):
        document["accessors"][3]["count"] = count

    with pytest.raises(
        FormatError, match=rf"accessor 3 \(mesh 0 primitive 0 target 0 POSITION\): invalid count {count}"
    ):
        read_gltf(_edit_quad_gltf(tmp_path, set_count))
