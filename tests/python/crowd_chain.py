"""A hand-built LoD GLB (the format of HELPER_PREAMBLE "The LoD GLB format") for the crowd tests.

Not a chain builder: levels are made crudely and their errors are set by hand, so that the
crowd binary's reader, level buckets and level switches can be tested without the character
pipeline. Levels of the procedural humanoid (walk and run clips):

- level 0: the original (``write_glb``), error 0;
- level 1 (mesh level 1, motion level 0): every other triangle of the mesh, error 0.01;
- level 2 (mesh level 1, motion level 1): level 1's triangles on a skeleton without the finger
  joints (weights moved to the nearest kept ancestor), the clips retargeted onto its own joint
  nodes, error 0.03.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib

from animlod import synth
from animlod.io.gltf import write_glb

ERRORS = (0.0, 0.01, 0.03)
COVERAGES = (0.5, 0.2, 0.0)
FINGERS = ("Thumb", "Index", "Middle", "Ring")
_COMPONENT = {np.dtype(np.float32): pygltflib.FLOAT, np.dtype(np.uint16): pygltflib.UNSIGNED_SHORT,
              np.dtype(np.uint32): pygltflib.UNSIGNED_INT}  # fmt: skip
_TYPE = {1: pygltflib.SCALAR, 3: pygltflib.VEC3, 4: pygltflib.VEC4, 16: pygltflib.MAT4}


class _Blob:
    def __init__(self, gltf: pygltflib.GLTF2) -> None:
        self.gltf = gltf
        self.data = bytearray(gltf.binary_blob() or b"")

    def add(self, values: np.ndarray, bounds: bool = False) -> int:
        values = np.ascontiguousarray(values)
        self.data.extend(b"\0" * (-len(self.data) % 4))
        self.gltf.bufferViews.append(
            pygltflib.BufferView(buffer=0, byteOffset=len(self.data), byteLength=values.nbytes)
        )
        self.data.extend(values.tobytes())
        accessor = pygltflib.Accessor(bufferView=len(self.gltf.bufferViews) - 1, componentType=_COMPONENT[values.dtype],
                                      count=values.shape[0], type=_TYPE[values.shape[1]])  # fmt: skip
        if bounds:
            accessor.min, accessor.max = values.min(axis=0).tolist(), values.max(axis=0).tolist()
        self.gltf.accessors.append(accessor)
        return len(self.gltf.accessors) - 1

    def finish(self) -> None:
        self.data.extend(b"\0" * (-len(self.data) % 4))
        self.gltf.buffers = [pygltflib.Buffer(byteLength=len(self.data))]
        self.gltf.set_binary_blob(bytes(self.data))


def _mesh(blob: _Blob, positions: np.ndarray, faces: np.ndarray, joints: np.ndarray, weights: np.ndarray) -> int:
    attributes = pygltflib.Attributes(
        POSITION=blob.add(positions.astype(np.float32), bounds=True),
        JOINTS_0=blob.add(joints.astype(np.uint16)),
        WEIGHTS_0=blob.add(weights.astype(np.float32)),
    )
    primitive = pygltflib.Primitive(attributes=attributes, indices=blob.add(faces.reshape(-1, 1).astype(np.uint32)))
    blob.gltf.meshes.append(pygltflib.Mesh(primitives=[primitive]))
    return len(blob.gltf.meshes) - 1


def write_hand_built_chain(path: Path, seed: int = 0) -> Path:
    """Write the three-level chain described above to ``path`` (a .glb) and return ``path``."""
    skinned = synth.humanoid(seed=seed)
    motions = [synth.humanoid_motion(skinned.skeleton, kind, cycles=1, seed=seed) for kind in ("walk", "run")]
    write_glb(path, skinned, motions)
    gltf = pygltflib.GLTF2.load(str(path))
    blob = _Blob(gltf)
    skeleton = skinned.skeleton
    joint_count = skeleton.joint_count
    mesh_node = next(i for i, node in enumerate(gltf.nodes) if node.mesh is not None)
    joints = np.pad(skinned.joints, ((0, 0), (0, 4 - skinned.joints.shape[1])))
    weights = np.pad(skinned.weights, ((0, 0), (0, 4 - skinned.weights.shape[1])))
    half = skinned.faces[::2]

    # Level 1: half the triangles on the original skin.
    level1 = _mesh(blob, skinned.rest_positions, half, joints, weights)
    # Level 2: a skeleton without finger joints; each removed joint's weight goes to its nearest kept ancestor.
    kept = [j for j, name in enumerate(skeleton.names) if not any(f in name for f in FINGERS)]
    target = np.arange(joint_count)
    for j in range(joint_count):
        while target[j] not in kept:
            target[j] = skeleton.parents[target[j]]
    new_index = {j: i for i, j in enumerate(kept)}
    remapped = np.vectorize(new_index.get)(target[joints])
    merged = np.zeros((len(joints), len(kept)))
    np.add.at(merged, (np.arange(len(joints))[:, None], remapped), weights)
    order = np.argsort(-merged, axis=1)[:, :4]
    reduced_joints, reduced_weights = order, np.take_along_axis(merged, order, axis=1)
    reduced_weights /= reduced_weights.sum(axis=1, keepdims=True)
    first_new = len(gltf.nodes)
    for j in kept:
        original = gltf.nodes[j]
        children = [first_new + new_index[c] for c in (original.children or []) if c in new_index]
        gltf.nodes.append(pygltflib.Node(name=original.name, translation=original.translation,
                                         rotation=original.rotation, children=children or None))  # fmt: skip
    inverse_bind = skinned.inverse_bind[kept].transpose(0, 2, 1).reshape(len(kept), 16).astype(np.float32)
    gltf.skins.append(pygltflib.Skin(joints=[first_new + i for i in range(len(kept))], skeleton=first_new,
                                     inverseBindMatrices=blob.add(inverse_bind)))  # fmt: skip
    level2 = _mesh(blob, skinned.rest_positions, half, reduced_joints, reduced_weights)
    for index in range(len(gltf.animations)):
        original = gltf.animations[index]
        channels = [
            pygltflib.AnimationChannel(sampler=c.sampler, target=pygltflib.AnimationChannelTarget(
                node=first_new + new_index[c.target.node], path=c.target.path))
            for c in original.channels if c.target.node in new_index
        ]  # fmt: skip
        extras = {"animlod": {"clip": index, "motion_level": 1}}
        name = f"{original.name} (motion level 1)"
        gltf.animations.append(
            pygltflib.Animation(name=name, samplers=original.samplers, channels=channels, extras=extras)
        )

    levels = [(mesh_node, 0, 0, joint_count), (None, 1, 0, joint_count), (None, 1, 1, len(kept))]
    ids = []
    for level, (node, mesh_level, motion_level, joints_animated) in enumerate(levels):
        triangles = len(half) if level else len(skinned.faces)
        record = {"level": level, "error": ERRORS[level], "triangles": triangles, "mesh_level": mesh_level,
                  "motion_level": motion_level, "joints": joints_animated}  # fmt: skip
        extras = {"animlod": record}
        if node is None:
            gltf.nodes.append(pygltflib.Node(name=f"skinned mesh LOD{level}", mesh=(level1, level2)[level - 1],
                                             skin=level - 1, extras=extras))  # fmt: skip
            ids.append(len(gltf.nodes) - 1)
        else:
            gltf.nodes[node].extras = {**extras, "MSFT_screencoverage": list(COVERAGES)}
    gltf.nodes[mesh_node].extensions = {"MSFT_lod": {"ids": ids}}
    gltf.extensionsUsed = sorted({*(gltf.extensionsUsed or []), "MSFT_lod"})
    blob.finish()
    gltf.save_binary(str(path))
    return path
