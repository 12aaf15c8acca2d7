"""Write a skinned mesh and its motions to one binary glTF 2.0 file (GLB).

The file holds one node per joint (rest translation and rotation, parents before children,
end sites marked with ``extras.animlod_end_site``), a mesh node with the skin, one mesh
primitive (POSITION, NORMAL and TEXCOORD_0 when present, JOINTS_0/WEIGHTS_0 and, for 8
influences, JOINTS_1/WEIGHTS_1, uint16/uint32 indices, morph targets with their names in
``extras.targetNames``), and one LINEAR animation per motion: the root's translation and every
joint's rotation at every frame (and every joint's translation when the motion has per-frame
``joint_translations``). pygltflib builds the JSON and the GLB container; the binary chunk is
packed here with 4-byte aligned buffer views.
"""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np
import pygltflib

from ..model import Motion, SkinnedMesh
from .atomic import atomic_write
from .gltf_skin import END_SITE_EXTRA

_COMPONENT_TYPES = {
    np.dtype("float32"): pygltflib.FLOAT,
    np.dtype("uint8"): pygltflib.UNSIGNED_BYTE,
    np.dtype("uint16"): pygltflib.UNSIGNED_SHORT,
    np.dtype("uint32"): pygltflib.UNSIGNED_INT,
}
_ACCESSOR_TYPES = {1: pygltflib.SCALAR, 2: pygltflib.VEC2, 3: pygltflib.VEC3, 4: pygltflib.VEC4, 16: pygltflib.MAT4}
_INFLUENCES_PER_SET = 4


def write_glb(
    path: str | os.PathLike,
    skinned: SkinnedMesh,
    motions: Sequence[Motion] = (),
    names: Sequence[str] | None = None,
) -> None:
    """Write ``skinned`` and ``motions`` (on its skeleton) to the GLB file ``path``, atomically.

    Parameters
    ----------
    path : output file, replaced only once the whole file is written.
    skinned : the mesh; K < 4 influences are padded with zero weights to glTF's 4.
    motions : animations on ``skinned.skeleton`` (same joint names, parents and offsets).
    names : animation names, one per motion; defaults to each motion's name, or "motion<i>".

    Raises
    ------
    ValueError if a motion is on another skeleton or ``names`` has the wrong length.
    """
    names = _animation_names(motions, names)
    for index, motion in enumerate(motions):
        _check_same_skeleton(skinned, motion, index)
    builder = _GlbBuilder()
    skeleton = skinned.skeleton
    joint_count = skeleton.joint_count
    children = skeleton.children()
    nodes = [
        pygltflib.Node(
            name=skeleton.names[j],
            translation=skeleton.offsets[j].tolist(),
            rotation=skeleton.rest_rotations[j].tolist(),
            children=children[j] or None,
            extras={END_SITE_EXTRA: True} if skeleton.end_sites[j] else {},
        )
        for j in range(joint_count)
    ]
    nodes.append(pygltflib.Node(name="skinned mesh", mesh=0, skin=0))
    inverse_bind = skinned.inverse_bind.transpose(0, 2, 1).reshape(joint_count, 16)  # column-major
    skin = pygltflib.Skin(
        inverseBindMatrices=builder.add(inverse_bind.astype(np.float32)), joints=list(range(joint_count)), skeleton=0
    )
    builder.gltf.nodes = nodes
    builder.gltf.skins = [skin]
    builder.gltf.meshes = [_mesh(builder, skinned)]
    builder.gltf.animations = [_animation(builder, motion, name) for motion, name in zip(motions, names)]
    builder.gltf.scenes = [pygltflib.Scene(nodes=[0, joint_count])]
    builder.gltf.scene = 0
    builder.save(path)


def _animation_names(motions: Sequence[Motion], names: Sequence[str] | None) -> list[str]:
    if names is None:
        return [motion.name or f"motion{index}" for index, motion in enumerate(motions)]
    if len(names) != len(motions):
        raise ValueError(f"names: {len(names)} animation names for {len(motions)} motions")
    return [str(name) for name in names]


def _check_same_skeleton(skinned: SkinnedMesh, motion: Motion, index: int) -> None:
    mesh_skeleton, skeleton = skinned.skeleton, motion.skeleton
    same = (
        skeleton.names == mesh_skeleton.names
        and np.array_equal(skeleton.parents, mesh_skeleton.parents)
        and np.allclose(skeleton.offsets[1:], mesh_skeleton.offsets[1:], rtol=1e-6, atol=1e-9)
    )
    if not same:
        raise ValueError(
            f"motion {index} ({motion.name!r}): its skeleton differs from the skinned mesh's "
            "(joint names, parents or bone offsets); a GLB animation can only drive the mesh's own joints"
        )


def _mesh(builder: _GlbBuilder, skinned: SkinnedMesh) -> pygltflib.Mesh:
    vertex_count = skinned.vertex_count
    attributes = pygltflib.Attributes(POSITION=builder.add(skinned.rest_positions, pygltflib.ARRAY_BUFFER, bounds=True))
    if skinned.normals is not None:
        attributes.NORMAL = builder.add(skinned.normals, pygltflib.ARRAY_BUFFER)
    if skinned.uvs is not None:
        attributes.TEXCOORD_0 = builder.add(skinned.uvs, pygltflib.ARRAY_BUFFER)
    influence_sets = -(-skinned.joints.shape[1] // _INFLUENCES_PER_SET)
    width = influence_sets * _INFLUENCES_PER_SET
    pad = ((0, 0), (0, width - skinned.joints.shape[1]))
    joint_dtype = np.uint8 if skinned.skeleton.joint_count <= 256 else np.uint16
    joints = np.pad(skinned.joints, pad).astype(joint_dtype)
    weights = np.pad(skinned.weights, pad).astype(np.float32)
    for k in range(influence_sets):
        columns = slice(k * _INFLUENCES_PER_SET, (k + 1) * _INFLUENCES_PER_SET)
        setattr(attributes, f"JOINTS_{k}", builder.add(joints[:, columns], pygltflib.ARRAY_BUFFER))
        setattr(attributes, f"WEIGHTS_{k}", builder.add(weights[:, columns], pygltflib.ARRAY_BUFFER))
    # 0xFFFF is the primitive-restart value glTF forbids as an index, hence "<".
    index_dtype = np.uint16 if vertex_count < 0xFFFF else np.uint32
    primitive = pygltflib.Primitive(
        attributes=attributes,
        indices=builder.add(skinned.faces.reshape(-1, 1).astype(index_dtype), pygltflib.ELEMENT_ARRAY_BUFFER),
        mode=pygltflib.TRIANGLES,
    )
    mesh = pygltflib.Mesh(name="skinned mesh", primitives=[primitive])
    if skinned.morph_targets is not None:
        primitive.targets = [
            {"POSITION": builder.add(delta, pygltflib.ARRAY_BUFFER, bounds=True)} for delta in skinned.morph_targets
        ]
        mesh.weights = [0.0] * len(skinned.morph_targets)
        if skinned.morph_target_names is not None:
            mesh.extras = {"targetNames": list(skinned.morph_target_names)}
    return mesh


def _animation(builder: _GlbBuilder, motion: Motion, name: str) -> pygltflib.Animation:
    times = (np.arange(motion.frame_count) / motion.fps).astype(np.float32)[:, None]
    time_accessor = builder.add(times, bounds=True)
    joint_count = motion.skeleton.joint_count
    tracks = [(0, "translation", motion.root_positions)]
    if motion.joint_translations is not None:  # bones that stretch or slide get their own tracks
        tracks += [(j, "translation", motion.joint_translations[:, j]) for j in range(1, joint_count)]
    local_rotations = _sign_continuous(motion.local_rotations)
    tracks += [(j, "rotation", local_rotations[:, j]) for j in range(joint_count)]
    samplers, channels = [], []
    for node, path, values in tracks:
        channels.append(
            pygltflib.AnimationChannel(
                sampler=len(samplers), target=pygltflib.AnimationChannelTarget(node=node, path=path)
            )
        )
        output = builder.add(np.ascontiguousarray(values, dtype=np.float32))
        sampler = pygltflib.AnimationSampler(input=time_accessor, output=output, interpolation=pygltflib.ANIM_LINEAR)
        samplers.append(sampler)
    return pygltflib.Animation(name=name, samplers=samplers, channels=channels)


def _sign_continuous(quaternions: np.ndarray) -> np.ndarray:
    """``(T, J, 4)`` with signs flipped so consecutive keys have a non-negative dot product.

    q and -q are the same rotation, but a viewer interpolating from q to -q' may take the long
    way round; each flip is carried forward to every later frame.
    """
    dots = np.sum(quaternions[1:] * quaternions[:-1], axis=-1)
    signs = np.cumprod(np.where(dots < 0.0, -1.0, 1.0), axis=0)
    return quaternions * np.concatenate([np.ones((1,) + signs.shape[1:]), signs])[..., None]


class _GlbBuilder:
    """A glTF document under construction with its binary chunk."""

    def __init__(self) -> None:
        self.gltf = pygltflib.GLTF2(asset=pygltflib.Asset(generator="animlod", version="2.0"))
        self.blob = bytearray()

    def add(self, values: np.ndarray, target: int | None = None, bounds: bool = False) -> int:
        """Append ``values (count, width)`` as a tightly packed buffer view and accessor; its index.

        ``bounds`` records min and max, which glTF requires for POSITION and animation inputs.
        """
        values = np.ascontiguousarray(values)
        count, width = values.shape
        self.blob.extend(b"\0" * (-len(self.blob) % 4))
        view = pygltflib.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=values.nbytes, target=target)
        self.blob.extend(values.astype(values.dtype.newbyteorder("<")).tobytes())
        accessor = pygltflib.Accessor(
            bufferView=len(self.gltf.bufferViews),
            componentType=_COMPONENT_TYPES[values.dtype],
            count=count,
            type=_ACCESSOR_TYPES[width],
        )
        if bounds:
            accessor.min = values.min(axis=0).tolist()
            accessor.max = values.max(axis=0).tolist()
        self.gltf.bufferViews.append(view)
        self.gltf.accessors.append(accessor)
        return len(self.gltf.accessors) - 1

    def save(self, path: str | os.PathLike) -> None:
        self.blob.extend(b"\0" * (-len(self.blob) % 4))
        self.gltf.buffers = [pygltflib.Buffer(byteLength=len(self.blob))]
        self.gltf.set_binary_blob(bytes(self.blob))
        with atomic_write(path, "wb") as handle:
            for chunk in self.gltf.save_to_bytes():
                handle.write(chunk)
