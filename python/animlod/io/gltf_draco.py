"""KHR_draco_mesh_compression: a primitive's attributes and indices stored as one Draco-compressed
buffer view (Blender's exporter, gltf-pipeline and glTF-Transform write it), decoded with DracoPy
(Google's Draco decoder) into the accessors that describe them.

The accessors of a compressed primitive have no buffer view; the extension names the compressed
view and, per attribute, its Draco unique id. Decoding keeps Draco's point order (the accessors'
element order) and dequantizes positions, normals and texture coordinates. A primitive that also
carries uncompressed data (its accessors have buffer views: an optional extension's fallback) is
read from that data instead.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pygltflib

from .gltf_decode import is_whole_number

DRACO_EXTENSION = "KHR_draco_mesh_compression"
# Builds the error to raise from (element, reason): the document's FormatError.
Fail = Callable[[str, str], Exception]


@dataclass(frozen=True)
class DracoSource:
    """Where an accessor's elements come from: the compressed buffer view ``view`` and the
    attribute's Draco ``unique_id`` (None for the primitive's indices); ``element`` names the
    primitive's extension in messages."""

    view: int
    unique_id: int | None
    element: str


def draco_sources(gltf: pygltflib.GLTF2, fail: Fail) -> dict[int, DracoSource]:
    """Accessor index -> its :class:`DracoSource`, for every accessor of a compressed primitive
    that has no buffer view of its own; a malformed extension raises ``fail``'s error."""
    sources: dict[int, DracoSource] = {}
    for m, mesh in enumerate(gltf.meshes or []):
        for p, primitive in enumerate(mesh.primitives or []):
            extension = (primitive.extensions or {}).get(DRACO_EXTENSION)
            if extension is None:
                continue
            element = f"mesh {m} primitive {p} {DRACO_EXTENSION}"
            view = extension.get("bufferView") if isinstance(extension, dict) else None
            ids = extension.get("attributes") if isinstance(extension, dict) else None
            well_formed = isinstance(ids, dict) and all(is_whole_number(i) for i in [view, *ids.values()])
            if not well_formed:
                raise fail(element, "needs a bufferView index and an attributes object of Draco ids")
            wanted = [(primitive.indices, None)] if primitive.indices is not None else []
            wanted += [(getattr(primitive.attributes, name, None), unique_id) for name, unique_id in ids.items()]
            for accessor, unique_id in wanted:
                known = is_whole_number(accessor) and accessor < len(gltf.accessors or [])
                if known and gltf.accessors[accessor].bufferView is None:
                    sources[accessor] = DracoSource(view, unique_id, element)
    return sources


def decode_draco(data: bytes, element: str, fail: Fail) -> Any:
    """The DracoPy mesh in ``data``; ``fail``'s error naming ``element`` if it is not one."""
    import DracoPy  # only files that use the extension need it

    try:
        mesh = DracoPy.decode(bytes(data))
    except (DracoPy.FileTypeException, ValueError, RuntimeError) as error:
        raise fail(element, f"the compressed data does not decode ({error})") from None
    if not isinstance(mesh, DracoPy.DracoMesh):
        raise fail(element, "the compressed data is a point cloud, not a triangle mesh")
    return mesh


def draco_elements(mesh: Any, source: DracoSource, count: int, width: int, dtype: np.dtype, fail: Fail) -> np.ndarray:
    """The ``(count, width)`` elements of one accessor from its decoded mesh, as ``dtype``;
    ``fail``'s error when the decoded data does not fit the accessor."""
    if source.unique_id is None:
        what, values = "the indices", np.asarray(mesh.faces).reshape(-1, 1)
    else:
        what = f"attribute {source.unique_id}"
        attribute = mesh.get_attribute_by_unique_id(source.unique_id)
        if attribute is None:
            raise fail(source.element, f"the compressed mesh has no attribute {source.unique_id}")
        values = np.asarray(attribute["data"]).reshape(len(attribute["data"]), -1)
    if values.shape != (count, width):
        raise fail(source.element, f"{what} decode to {values.shape}, the accessor expects ({count}, {width})")
    limits = np.iinfo(dtype) if dtype.kind in "iu" else None
    if limits is not None and values.size and (values.min() < limits.min or values.max() > limits.max):
        raise fail(source.element, f"{what} hold values outside the accessor's {dtype.name}")
    return values.astype(dtype)
