"""Every index property of a glTF 2.0 document (glTF 2.0's schema) with what it refers to, so that a
document can be checked whole when it is read: whole-document writers copy what no reader here
touches (an unused accessor, a material's texture), and a texture -1 or a bufferView 99 would
otherwise go on into every output. Scenes' nodes, nodes' children and animation channels are
checked where the document resolves them (gltf_document.py)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .gltf_document import GltfDocument

LIGHTS_EXTENSION = "KHR_lights_punctual"  # its lights are the document extension's list

# (top-level array, index, the element that refers to it, for messages)
Reference = tuple[str, Any, str]


def index_references(doc: GltfDocument) -> Iterator[Reference]:
    """Every index of ``doc``'s JSON but those of scenes, children and channels, with its referrer
    named as the readers name it (``mesh 0 primitive 1 POSITION``, ``skin 0 joint 3``)."""
    document = doc.json
    for n, node in enumerate(document.get("nodes", [])):
        yield from _optional(node, "mesh", "meshes", doc.node_label(n))
        yield from _optional(node, "skin", "skins", doc.node_label(n))
        yield from _optional(node, "camera", "cameras", f"{doc.node_label(n)} camera")
        light = (node.get("extensions") or {}).get(LIGHTS_EXTENSION)
        yield from _optional(light if isinstance(light, dict) else {}, "light", "lights", f"{doc.node_label(n)} light")
        instancing = (node.get("extensions") or {}).get("EXT_mesh_gpu_instancing")
        attributes = instancing.get("attributes") if isinstance(instancing, dict) else None
        for name, index in attributes.items() if isinstance(attributes, dict) else ():
            yield "accessors", index, f"{doc.node_label(n)} EXT_mesh_gpu_instancing {name}"
    for s, skin in enumerate(document.get("skins", [])):
        yield from (("nodes", joint, f"skin {s} joint {slot}") for slot, joint in enumerate(skin.get("joints", [])))
        yield from _optional(skin, "skeleton", "nodes", f"skin {s} skeleton")
        yield from _optional(skin, "inverseBindMatrices", "accessors", f"skin {s} inverseBindMatrices")
    for m, mesh in enumerate(document.get("meshes", [])):
        for p, primitive in enumerate(mesh.get("primitives", [])):
            element = f"mesh {m} primitive {p}"
            yield from (
                ("accessors", index, f"{element} {name}") for name, index in primitive.get("attributes", {}).items()
            )
            for t, target in enumerate(primitive.get("targets", [])):
                yield from (("accessors", index, f"{element} target {t} {name}") for name, index in target.items())
            yield from _optional(primitive, "indices", "accessors", f"{element} indices")
            yield from _optional(primitive, "material", "materials", f"{element} material")
    for a, accessor in enumerate(document.get("accessors", [])):
        yield from _optional(accessor, "bufferView", "bufferViews", f"accessor {a} bufferView")
        for part in ("indices", "values"):
            sparse = accessor.get("sparse", {}).get(part, {})
            yield from _optional(sparse, "bufferView", "bufferViews", f"accessor {a} sparse {part} bufferView")
    for v, view in enumerate(document.get("bufferViews", [])):
        yield from _optional(view, "buffer", "buffers", f"bufferView {v} buffer")
    for i, image in enumerate(document.get("images", [])):
        yield from _optional(image, "bufferView", "bufferViews", f"image {i} bufferView")
    for a, animation in enumerate(document.get("animations", [])):
        for k, sampler in enumerate(animation.get("samplers", [])):
            for end in ("input", "output"):
                yield from _optional(sampler, end, "accessors", f"{doc.animation_label(a)} sampler {k} {end}")
    for index, material in enumerate(document.get("materials", [])):
        for where, info in _texture_infos(material):
            yield "textures", info.get("index"), f"material {index} {where}"
    for index, texture in enumerate(document.get("textures", [])):
        yield from _optional(texture, "source", "images", f"texture {index} source")
        yield from _optional(texture, "sampler", "samplers", f"texture {index} sampler")
        for name, extension in texture.get("extensions", {}).items():  # KHR_texture_basisu, EXT_texture_webp
            yield from _optional(extension, "source", "images", f"texture {index} extensions.{name}.source")


def _optional(holder: dict, key: str, kind: str, referrer: str) -> Iterator[Reference]:
    """The reference of ``holder[key]`` where it is given (null is absent, as the decoder takes it)."""
    if holder.get(key) is not None:
        yield kind, holder[key], referrer


def _texture_infos(properties: dict, where: str = "") -> Iterator[tuple[str, dict]]:
    """Every textureInfo of a material's JSON, its own and its extensions' (``clearcoatTexture``),
    with its path in the material: the objects under a key ending in "Texture"."""
    for key, value in properties.items():
        if isinstance(value, dict):
            path = f"{where}.{key}" if where else key
            if key.endswith("Texture"):
                yield path, value
            else:
                yield from _texture_infos(value, path)
