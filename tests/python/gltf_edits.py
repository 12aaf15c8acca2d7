"""Edits of GLB files through pygltflib for the tests: the shapes exporters write that animlod's
own writer does not (animated scale, among others)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pygltflib


def edit_glb(source: Path, target: Path, edit: Callable[[pygltflib.GLTF2, bytearray], None]) -> Path:
    """Copy a GLB through pygltflib, letting ``edit`` change its JSON and binary chunk."""
    gltf = pygltflib.GLTF2.load_from_bytes(source.read_bytes())
    blob = bytearray(gltf.binary_blob())
    edit(gltf, blob)
    gltf.set_binary_blob(bytes(blob))
    gltf.buffers[0].byteLength = len(blob)
    target.write_bytes(b"".join(gltf.save_to_bytes()))
    return target


_COMPONENTS = {
    "f4": pygltflib.FLOAT,
    "i1": pygltflib.BYTE,
    "i2": pygltflib.SHORT,
    "u1": pygltflib.UNSIGNED_BYTE,
    "u2": pygltflib.UNSIGNED_SHORT,
    "u4": pygltflib.UNSIGNED_INT,
}


def append_accessor(
    gltf: pygltflib.GLTF2, blob: bytearray, values: np.ndarray, accessor_type: str, normalized: bool = False
) -> int:
    """``values`` (float32, int8, int16, uint8, uint16 or uint32; one row per element) appended to the binary
    chunk, 4-byte aligned, with a bufferView and an accessor; returns the accessor's index."""
    values = np.asarray(values)
    code = f"{values.dtype.kind}{values.dtype.itemsize}"
    data = np.ascontiguousarray(values, "<" + code).tobytes()
    offset = len(blob) + (-len(blob)) % 4
    blob.extend(bytes(offset - len(blob)) + data)
    gltf.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=offset, byteLength=len(data)))
    view = len(gltf.bufferViews) - 1
    accessor = pygltflib.Accessor(
        bufferView=view, componentType=_COMPONENTS[code], count=len(values), type=accessor_type, normalized=normalized
    )
    gltf.accessors.append(accessor)
    return len(gltf.accessors) - 1


def add_scale_channel(
    gltf: pygltflib.GLTF2, blob: bytearray, node: int, keys: np.ndarray, animation_index: int = 0
) -> None:
    """A scale channel on ``node`` of animation ``animation_index``, keyed at its first sampler's times."""
    output = append_accessor(gltf, blob, keys.astype(np.float32), "VEC3")
    animation = gltf.animations[animation_index]
    sampler = pygltflib.AnimationSampler(input=animation.samplers[0].input, output=output)
    animation.samplers.append(sampler)
    target = pygltflib.AnimationChannelTarget(node=node, path="scale")
    animation.channels.append(pygltflib.AnimationChannel(sampler=len(animation.samplers) - 1, target=target))


def share_one_vertex_buffer(gltf: pygltflib.GLTF2, blob: bytearray, parts: int = 2) -> None:
    """Every mesh's first primitive split into ``parts`` primitives by runs of its triangles, all
    on the same attribute accessors (each primitive listing every vertex of the mesh), with
    their own index accessors, as UniVRM writes VRM avatars (one primitive per material)."""
    for mesh in gltf.meshes:
        primitive = mesh.primitives[0]
        accessor = gltf.accessors[primitive.indices]
        dtype = {pygltflib.UNSIGNED_BYTE: "<u1", pygltflib.UNSIGNED_SHORT: "<u2", pygltflib.UNSIGNED_INT: "<u4"}
        start = (gltf.bufferViews[accessor.bufferView].byteOffset or 0) + (accessor.byteOffset or 0)
        indices = np.frombuffer(bytes(blob), dtype[accessor.componentType], accessor.count, start).reshape(-1, 3)
        split = []
        for run in np.array_split(indices, parts):
            run_indices = append_accessor(gltf, blob, run.ravel().astype(np.uint32), "SCALAR")
            split.append(pygltflib.Primitive(**{**vars(primitive), "indices": run_indices}))
        mesh.primitives[:1] = split


def squash_and_stretch(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
    """The root grows by half, the middle joint stretches along y and thins along x, and the tip
    shrinks to nothing (how clips hide a part), over the 'bend' clip's six keys."""
    k = np.linspace(0.0, 1.0, 6)[:, None]
    add_scale_channel(gltf, blob, 0, np.repeat(1.0 + 0.5 * k, 3, axis=1))
    add_scale_channel(gltf, blob, 1, np.c_[1.0 - 0.3 * k, 1.0 + 0.6 * k, np.ones_like(k)])
    add_scale_channel(gltf, blob, 2, np.repeat(1.0 - k, 3, axis=1))


def draco_compressed(source: Path, target: Path) -> Path:
    """A copy of the GLB at ``source`` whose triangle primitives keep their attributes and indices
    only in a KHR_draco_mesh_compression buffer view (positions quantized to 16 bits, the other
    attributes exact, the point order kept), the extension required, as Draco encoders write it."""
    import DracoPy

    from animlod.io.gltf_document import GltfDocument

    doc = GltfDocument(source)

    def compress(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        for mesh in gltf.meshes:
            for primitive in mesh.primitives:
                if primitive.mode not in (None, pygltflib.TRIANGLES) or primitive.indices is None:
                    continue
                names = [name for name, value in vars(primitive.attributes).items() if isinstance(value, int)]
                values = {name: doc.accessor(getattr(primitive.attributes, name), "draco test") for name in names}
                others = {20 + k: values[name] for k, name in enumerate(names) if name != "POSITION"}
                faces = doc.accessor(primitive.indices, "draco test").reshape(-1, 3)
                data = DracoPy.encode(
                    values["POSITION"], faces, quantization_bits=16, preserve_order=True, generic_attributes=others
                )
                decoded = DracoPy.decode(data)
                (position_id,) = [a["unique_id"] for a in decoded.attributes if a["attribute_type"] == 0]
                ids = {name: 20 + k for k, name in enumerate(names) if name != "POSITION"}
                offset = len(blob) + (-len(blob)) % 4
                blob.extend(bytes(offset - len(blob)) + data)
                gltf.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=offset, byteLength=len(data)))
                extension = {"bufferView": len(gltf.bufferViews) - 1, "attributes": {"POSITION": position_id, **ids}}
                primitive.extensions = {**(primitive.extensions or {}), "KHR_draco_mesh_compression": extension}
                for accessor in [primitive.indices, *(getattr(primitive.attributes, name) for name in names)]:
                    gltf.accessors[accessor].bufferView = gltf.accessors[accessor].byteOffset = None
        for listed in ("extensionsUsed", "extensionsRequired"):
            setattr(gltf, listed, [*(getattr(gltf, listed) or []), "KHR_draco_mesh_compression"])

    return edit_glb(source, target, compress)


def meshopt_compressed(
    source: Path, target: Path, extension_name: str = "EXT_meshopt_compression", vertex_codec: int = 0
) -> Path:
    """A copy of the GLB at ``source`` whose buffer views (one accessor each, as animlod writes
    them) hold meshoptimizer-coded data (without filters, vertex codec version ``vertex_codec``),
    ``extension_name`` required, as gltfpack writes it. The views' own bytes, the fallback, are
    zeroed: only decoding reads right.
    Written with animlod's GlbBuilder: pygltflib repacks the binary chunk by buffer view and would
    drop the compressed bytes, which only the extension refers to."""
    import meshoptimizer

    from animlod.io.glb_builder import GlbBuilder
    from animlod.io.gltf_document import GltfDocument

    builder = GlbBuilder.from_document(GltfDocument(source))
    js, blob = builder.json, builder.blob
    index_accessors = {p["indices"] for mesh in js["meshes"] for p in mesh["primitives"] if "indices" in p}
    sizes = {pygltflib.UNSIGNED_BYTE: 1, pygltflib.UNSIGNED_SHORT: 2, pygltflib.UNSIGNED_INT: 4, pygltflib.FLOAT: 4}
    widths = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
    views = [a["bufferView"] for a in js["accessors"] if "bufferView" in a]
    for index, accessor in enumerate(js["accessors"]):
        if "bufferView" not in accessor or views.count(accessor["bufferView"]) != 1:
            continue
        view = js["bufferViews"][accessor["bufferView"]]
        stride = sizes[accessor["componentType"]] * widths[accessor["type"]]
        start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
        if view.get("byteStride", stride) != stride or (index not in index_accessors and stride % 4):
            continue
        raw = bytes(blob[start : start + stride * accessor["count"]])
        if index in index_accessors:
            indices = np.frombuffer(raw, {2: np.uint16, 4: np.uint32}[stride]).astype(np.uint32)
            data = meshoptimizer.encode_index_buffer(indices, len(indices), int(indices.max()) + 1)
            mode = "TRIANGLES"
        else:
            vertices = np.frombuffer(raw, np.float32).reshape(accessor["count"], stride // 4)
            meshoptimizer.encode_vertex_version(vertex_codec)
            try:
                data, mode = meshoptimizer.encode_vertex_buffer(vertices, accessor["count"], stride), "ATTRIBUTES"
            finally:
                meshoptimizer.encode_vertex_version(0)
        blob[start : start + len(raw)] = bytes(len(raw))
        offset = builder._append(data)
        extension = {"buffer": 0, "byteOffset": offset, "byteLength": len(data), "byteStride": stride}
        view["extensions"] = {extension_name: {**extension, "count": accessor["count"], "mode": mode}}
    for listed in ("extensionsUsed", "extensionsRequired"):
        js.setdefault(listed, []).append(extension_name)
    builder.save(target)
    return target
