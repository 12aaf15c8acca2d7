"""A hand-built LoD GLB in the layout ``animlod character`` writes (README, "The LoD GLB"), for the
crowd tests.

Not a chain builder: levels are made crudely and their errors are set by hand, so that the
crowd binary's reader, level buckets and level switches can be tested in seconds. The
procedural humanoid (walk and run clips) as a 2 x 2 grid of (mesh level g, motion level m):

- g = 1 draws every other triangle of the mesh; m = 1 is a skeleton without the finger joints
  (their weights moved to the nearest kept ancestor) with the clips retargeted onto its own
  joint nodes (``extras.animlod = {"clip", "motion_level": 1}``);
- the MSFT_lod chain is (0, 0) then (1, 1), errors 0 and 0.03, screen coverages 0.3 and 0;
- (1, 0) and (0, 1) are grid-only nodes (error 0, as the character pipeline writes them),
  listed with the chain's in ``base.extras.animlod_grid[g][m]``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib

from animlod import synth
from animlod.io.gltf import write_glb

ERROR = 0.03  # of the chain's level 1
COVERAGES = (0.3, 0.0)
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

    # Mesh level 1: half the triangles. Motion level 1: a skeleton without finger joints, each
    # removed joint's weight on its nearest kept ancestor.
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
    meshes = {
        (1, 0): _mesh(blob, skinned.rest_positions, half, joints, weights),
        (0, 1): _mesh(blob, skinned.rest_positions, skinned.faces, reduced_joints, reduced_weights),
        (1, 1): _mesh(blob, skinned.rest_positions, half, reduced_joints, reduced_weights),
    }
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

    def record(level: int, error: float, g: int, m: int) -> dict:
        return {"animlod": {"level": level, "error": error, "triangles": len(half) if g else len(skinned.faces),
                            "mesh_level": g, "motion_level": m, "joints": len(kept) if m else joint_count}}  # fmt: skip

    grid = [[mesh_node, -1], [-1, -1]]
    for (g, m), mesh in meshes.items():
        on_chain = (g, m) == (1, 1)
        extras = record(1 if on_chain else -1, ERROR if on_chain else 0.0, g, m)
        gltf.nodes.append(pygltflib.Node(name=f"skinned mesh G{g}M{m}", mesh=mesh, skin=m, extras=extras))
        grid[g][m] = len(gltf.nodes) - 1
    gltf.nodes[mesh_node].extras = {**record(0, 0.0, 0, 0), "MSFT_screencoverage": list(COVERAGES),
                                    "animlod_grid": grid}  # fmt: skip
    gltf.nodes[mesh_node].extensions = {"MSFT_lod": {"ids": [grid[1][1]]}}
    gltf.extensionsUsed = sorted({*(gltf.extensionsUsed or []), "MSFT_lod"})
    blob.finish()
    gltf.save_binary(str(path))
    return path


def channels_as_pointers(gltf: pygltflib.GLTF2) -> None:
    """Turn every animation channel of ``gltf`` into a KHR_animation_pointer one at the same node
    property (as Blender 4 writes some), and add one that animates a material's colour from a
    rotation sampler (four floats a key, as a colour has), which animates no node."""
    gltf.extensionsUsed = [*(gltf.extensionsUsed or []), "KHR_animation_pointer"]
    rotation = None
    for animation in gltf.animations:
        for channel in animation.channels:
            if rotation is None and channel.target.path == "rotation":
                rotation = (animation, channel.sampler)
            pointer = f"/nodes/{channel.target.node}/{channel.target.path}"
            channel.target = pygltflib.AnimationChannelTarget(
                path="pointer", extensions={"KHR_animation_pointer": {"pointer": pointer}}
            )
    animation, sampler = rotation
    gltf.materials = gltf.materials or [pygltflib.Material(name="painted")]  # what the pointer names must exist
    colour = {"KHR_animation_pointer": {"pointer": "/materials/0/pbrMetallicRoughness/baseColorFactor"}}
    target = pygltflib.AnimationChannelTarget(path="pointer", extensions=colour)
    animation.channels.insert(0, pygltflib.AnimationChannel(sampler=sampler, target=target))
