"""Where a glTF document's nodes and skinned vertices are at the first key of an animation, read
straight from its nodes and channels (no animlod reader in between), for tests of written files."""

from __future__ import annotations

import numpy as np

from animlod import rotations
from animlod.io.gltf_document import GltfDocument


def posed_worlds(doc: GltfDocument, animation: int) -> list[np.ndarray]:
    """World matrix of every node at the first key of ``animation``."""
    local = [doc.rest_matrix(n) for n in range(len(doc.gltf.nodes))]
    keyed: dict[int, dict[str, np.ndarray]] = {}
    clip = doc.gltf.animations[animation]
    for channel in clip.channels:
        if channel.target.node is None:  # a KHR_animation_pointer channel
            continue
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


def skinned_vertex(doc: GltfDocument, node: int, vertex: int, worlds: list[np.ndarray]) -> np.ndarray:
    """World position of ``vertex`` of the skinned mesh drawn by ``node``, posed by ``worlds``."""
    primitive = doc.gltf.meshes[doc.gltf.nodes[node].mesh].primitives[0]
    skin = doc.gltf.skins[doc.gltf.nodes[node].skin]
    position = np.append(np.asarray(doc.accessor(primitive.attributes.POSITION, "test"))[vertex], 1.0)
    joints = np.asarray(doc.accessor(primitive.attributes.JOINTS_0, "test"))[vertex]
    weights = np.asarray(doc.accessor(primitive.attributes.WEIGHTS_0, "test"))[vertex]
    inverse_binds = np.asarray(doc.accessor(skin.inverseBindMatrices, "test")).reshape(-1, 4, 4).transpose(0, 2, 1)
    matrix = sum(w * worlds[skin.joints[j]] @ inverse_binds[j] for j, w in zip(joints, weights) if w > 0)
    return (matrix @ position)[:3]


def node_named(doc: GltfDocument, name: str) -> int:
    """The first node called ``name``."""
    return next(n for n, node in enumerate(doc.gltf.nodes) if node.name == name)


def vertex_in_holder(doc: GltfDocument, joint: str, holder: str) -> tuple[int, np.ndarray, float]:
    """A vertex of the input's skinned mesh bound to ``joint`` alone, its place in the frame of
    node ``holder`` at the first key of the clip, and the mesh's size."""
    base = next(n for n, node in enumerate(doc.gltf.nodes) if node.skin is not None)
    primitive = doc.gltf.meshes[doc.gltf.nodes[base].mesh].primitives[0]
    joints = np.asarray(doc.accessor(primitive.attributes.JOINTS_0, "test"))
    weights = np.asarray(doc.accessor(primitive.attributes.WEIGHTS_0, "test"))
    slot = doc.gltf.skins[doc.gltf.nodes[base].skin].joints.index(node_named(doc, joint))
    vertex = int(np.flatnonzero((joints[:, 0] == slot) & (weights[:, 0] > 0.999))[0])
    worlds = posed_worlds(doc, 0)
    place = np.linalg.inv(worlds[node_named(doc, holder)]) @ np.append(skinned_vertex(doc, base, vertex, worlds), 1.0)
    size = np.ptp(np.asarray(doc.accessor(primitive.attributes.POSITION, "test")), axis=0).max()
    return vertex, place[:3], size
