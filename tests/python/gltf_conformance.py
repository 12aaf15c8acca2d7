"""The glTF 2.0 rules that the Khronos glTF-Validator reports as errors, checked on a GLB.

Written apart from animlod's readers (its own accessor decoding) so that a reader's mistake
cannot hide a writer's. Codes and tolerances follow the validator's (ISSUES.md, errors.dart):
unit lengths within 0.00674 (VEC3) and 0.00769 (VEC4), a vertex's float32 weight sum exactly 1
for up to two weights and within (n + 1) // 2 - 1 steps of 1/255 for n, declared min and max
equal to the float32 values. ``problems(path)`` lists ``(code, where, detail)`` of a GLB or a
.gltf; empty is conformant. Not checked: JSON schema details, warnings, textures' pixels,
extensions' own schemas, compressed data (Draco, meshopt: the validator skips it too).
"""

from __future__ import annotations

import base64
import json
import struct
import urllib.parse
from pathlib import Path

import numpy as np

_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
_DTYPES = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_UNIT_VEC3, _UNIT_VEC4, _SUM_STEP = 0.00674, 0.00769, 0.0039216
_FLOAT, _UBYTE, _USHORT, _UINT, _BYTE, _SHORT = 5126, 5121, 5123, 5125, 5120, 5122
# Accessor formats (componentType, type, normalized) per attribute, KHR_mesh_quantization's included.
_QUANTIZED = {(t, n) for t in (_BYTE, _UBYTE, _SHORT, _USHORT) for n in (True, False)}


def _formats(semantic: str, quantized: bool) -> set[tuple[int, str, bool]]:
    base = semantic.split("_")[0]
    if base in ("POSITION", "NORMAL"):
        extra = {(t, "VEC3", n) for t, n in _QUANTIZED} if quantized else set()
        if base == "NORMAL" and quantized:
            extra = {(t, "VEC3", True) for t in (_BYTE, _SHORT)}
        return {(_FLOAT, "VEC3", False)} | extra
    if base == "TANGENT":
        return {(_FLOAT, "VEC4", False)} | ({(t, "VEC4", True) for t in (_BYTE, _SHORT)} if quantized else set())
    if base == "TEXCOORD":
        extra = {(t, "VEC2", n) for t, n in _QUANTIZED} if quantized else set()
        return {(_FLOAT, "VEC2", False), (_UBYTE, "VEC2", True), (_USHORT, "VEC2", True)} | extra
    if base == "COLOR":
        return {(c, v, c != _FLOAT) for c in (_FLOAT, _UBYTE, _USHORT) for v in ("VEC3", "VEC4")}
    if base == "JOINTS":
        return {(_UBYTE, "VEC4", False), (_USHORT, "VEC4", False)}
    if base == "WEIGHTS":
        return {(_FLOAT, "VEC4", False), (_UBYTE, "VEC4", True), (_USHORT, "VEC4", True)}
    return set()  # application-specific (_NAME) attributes: any format


class _Glb:
    """A GLB, or a .gltf with its buffers (files beside it or data URIs): JSON and buffer bytes."""

    def __init__(self, path: Path, report) -> None:
        data = path.read_bytes()
        self.report = report
        self.bin = b""
        if data[:4] != b"glTF":
            self.json = json.loads(data.decode("utf-8", "replace"))
        else:
            self.json = self._chunks(data, report)
        self.buffers = [self.bin if "uri" not in buffer else self._external(path, buffer["uri"])
                        for buffer in self.json.get("buffers", [])]  # fmt: skip

    def _chunks(self, data: bytes, report) -> dict:
        magic, version, length = struct.unpack_from("<4sII", data, 0)
        if version != 2:
            report("GLB_INVALID_VERSION", "header", str(version))
        if length != len(data):
            report("GLB_LENGTH_MISMATCH", "header", f"declared {length}, file {len(data)}")
        chunks, offset = [], 12
        while offset + 8 <= len(data):
            size, kind = struct.unpack_from("<I4s", data, offset)
            if size % 4:
                report("GLB_CHUNK_LENGTH_UNALIGNED", kind.decode("latin-1"), f"{size} bytes")
            chunks.append((kind, data[offset + 8 : offset + 8 + size]))
            offset += 8 + size
        if not chunks or chunks[0][0] != b"JSON":
            raise AssertionError("the first chunk is not JSON")
        if len(chunks) > 1 and chunks[1][0] != b"BIN\0":
            report("GLB_UNEXPECTED_BIN_CHUNK", "chunks", f"second chunk {chunks[1][0]!r}")
        self.bin = chunks[1][1] if len(chunks) > 1 and chunks[1][0] == b"BIN\0" else b""
        return json.loads(chunks[0][1].decode("utf-8", "replace"))

    @staticmethod
    def _external(path: Path, uri: str) -> bytes:
        if uri.startswith("data:"):
            return base64.b64decode(uri.split(",", 1)[1])
        return (path.parent / urllib.parse.unquote(uri)).read_bytes()

    def view_bytes(self, index: int) -> bytes:
        view = self.json["bufferViews"][index]
        start = view.get("byteOffset", 0)
        return self.buffers[view["buffer"]][start : start + view["byteLength"]]

    def accessor(self, index: int, normalize: bool = True) -> np.ndarray | None:
        """(count, components), normalized integers scaled as a viewer reads them; None where the
        values are compressed (see _has_plain_data)."""
        accessor = self.json["accessors"][index]
        if not _has_plain_data(self.json, accessor):
            return None
        width, dtype = _COMPONENTS[accessor["type"]], np.dtype(_DTYPES[accessor["componentType"]])
        count = accessor["count"]
        values = np.zeros((count, width), dtype)
        if "bufferView" in accessor:
            raw = self.view_bytes(accessor["bufferView"])
            stride = self.json["bufferViews"][accessor["bufferView"]].get("byteStride", width * dtype.itemsize)
            strided = np.lib.stride_tricks.as_strided(
                np.frombuffer(raw, np.uint8, offset=accessor.get("byteOffset", 0)),
                shape=(count, width * dtype.itemsize), strides=(stride, 1),
            )  # fmt: skip
            values = np.ascontiguousarray(strided).view(dtype).reshape(count, width).copy()
        sparse = accessor.get("sparse")
        if sparse:
            indices, replaced = sparse["indices"], sparse["values"]
            rows = np.frombuffer(self.view_bytes(indices["bufferView"]), _DTYPES[indices["componentType"]],
                                 count=sparse["count"], offset=indices.get("byteOffset", 0))  # fmt: skip
            values[rows] = np.frombuffer(self.view_bytes(replaced["bufferView"]), dtype, count=sparse["count"] * width,
                                         offset=replaced.get("byteOffset", 0)).reshape(-1, width)  # fmt: skip
        if normalize and accessor.get("normalized"):
            bits = 8 * dtype.itemsize
            if np.issubdtype(dtype, np.signedinteger):
                return np.maximum(values / (2 ** (bits - 1) - 1), -1.0)
            return values / (2**bits - 1)
        return values.astype(np.float64) if dtype != np.float32 else values


def problems(path: str | Path) -> list[tuple[str, str, str]]:
    """Every validator error found in the GLB at ``path``."""
    found: list[tuple[str, str, str]] = []
    report = lambda code, where, detail="": found.append((code, where, detail))  # noqa: E731
    glb = _Glb(Path(path), report)
    doc = glb.json
    if doc.get("asset", {}).get("version") != "2.0":
        report("UNKNOWN_ASSET_MAJOR_VERSION", "/asset", str(doc.get("asset")))
    _check_extensions(doc, report)
    _check_buffers_and_views(glb, report)
    _check_accessors(glb, report)
    _check_nodes(doc, report)
    _check_meshes(glb, report)
    _check_skins(glb, report)
    _check_animations(glb, report)
    _check_images(glb, report)
    return found


def added_problems(source: str | Path, output: str | Path) -> list[tuple[str, str, str]]:
    """The problems of ``output`` that its input ``source`` does not have at the same place (a
    LoD GLB keeps the input's objects at their indices, and with them what was wrong there)."""
    inherited = {(code, where) for code, where, _ in problems(source)}
    return [problem for problem in problems(output) if problem[:2] not in inherited]


def _extension_names(value, names: set[str]) -> None:
    if isinstance(value, dict):
        for key, item in value.items():
            if key == "extensions" and isinstance(item, dict):
                names.update(item)
            if key != "extras":
                _extension_names(item, names)
    elif isinstance(value, list):
        for item in value:
            _extension_names(item, names)


def _check_extensions(doc: dict, report) -> None:
    used, names = set(doc.get("extensionsUsed", [])), set()
    _extension_names(doc, names)
    for name in sorted(names - used):
        report("UNDECLARED_EXTENSION", "/extensionsUsed", name)
    for name in sorted(set(doc.get("extensionsRequired", [])) - used):
        report("UNUSED_EXTENSION_REQUIRED", "/extensionsRequired", name)
    if len(used) != len(doc.get("extensionsUsed", [])):
        report("DUPLICATE_ELEMENTS", "/extensionsUsed", "")


def _check_buffers_and_views(glb: _Glb, report) -> None:
    doc = glb.json
    buffers = doc.get("buffers", [])
    for index, buffer in enumerate(buffers):
        if "uri" in buffer:
            if len(glb.buffers[index]) < buffer["byteLength"]:
                report("BUFFER_EXTERNAL_BYTELENGTH_MISMATCH", f"/buffers/{index}", "")
        elif index == 0:
            if buffer["byteLength"] > len(glb.bin):
                report(
                    "BUFFER_EMBEDDED_BYTELENGTH_MISMATCH",
                    f"/buffers/{index}",
                    f"{buffer['byteLength']} > {len(glb.bin)}",
                )
        elif not (buffer.get("extensions") or {}).get("EXT_meshopt_compression", {}).get("fallback"):
            report("BUFFER_NON_FIRST_GLB", f"/buffers/{index}", "")
    for index, view in enumerate(doc.get("bufferViews", [])):
        buffer = buffers[view["buffer"]] if view["buffer"] < len(buffers) else None
        if buffer is None:
            report("UNRESOLVED_REFERENCE", f"/bufferViews/{index}/buffer", str(view["buffer"]))
        elif view.get("byteOffset", 0) + view["byteLength"] > buffer["byteLength"]:
            report("BUFFER_VIEW_TOO_LONG", f"/bufferViews/{index}", "")
        stride = view.get("byteStride")
        if stride is not None and (stride < 4 or stride > 252 or stride % 4):
            report("VALUE_NOT_IN_RANGE", f"/bufferViews/{index}/byteStride", str(stride))


def _check_accessors(glb: _Glb, report) -> None:
    doc = glb.json
    for index, accessor in enumerate(doc.get("accessors", [])):
        where = f"/accessors/{index}"
        kind = accessor["componentType"]
        if kind not in _DTYPES:
            report("INVALID_GL_VALUE", where + "/componentType", str(kind))
            continue
        if accessor.get("normalized") and kind in (_FLOAT, _UINT):
            report("ACCESSOR_NORMALIZED_INVALID", where, "")
        size, width = np.dtype(_DTYPES[kind]).itemsize, _COMPONENTS[accessor["type"]]
        if accessor["count"] < 1:
            report("VALUE_NOT_IN_RANGE", where + "/count", str(accessor["count"]))
            continue
        if "bufferView" in accessor:
            view = doc["bufferViews"][accessor["bufferView"]]
            offset = accessor.get("byteOffset", 0)
            if offset % size:
                report("ACCESSOR_OFFSET_ALIGNMENT", where, str(offset))
            if (view.get("byteOffset", 0) + offset) % size:
                report("ACCESSOR_TOTAL_OFFSET_ALIGNMENT", where, str(view.get("byteOffset", 0) + offset))
            stride = view.get("byteStride", width * size)
            if stride < width * size:
                report("ACCESSOR_SMALL_BYTESTRIDE", where, f"{stride} < {width * size}")
            if offset + stride * (accessor["count"] - 1) + width * size > view["byteLength"]:
                report("ACCESSOR_TOO_LONG", where, "")
                continue
        values = glb.accessor(index, normalize=False)
        if values is None:
            continue
        if kind == _FLOAT and not np.isfinite(values).all():
            report("ACCESSOR_INVALID_FLOAT", where, f"{int((~np.isfinite(values)).sum())} values")
            continue
        for bound, actual in (("min", values.min(axis=0)), ("max", values.max(axis=0))):
            if bound not in accessor:
                continue
            declared = np.asarray(accessor[bound], np.float64)
            if kind == _FLOAT:
                declared = declared.astype(np.float32).astype(np.float64)
            if declared.shape != actual.shape or not np.array_equal(declared, actual.astype(np.float64)):
                report(
                    f"ACCESSOR_{bound.upper()}_MISMATCH", where, f"declared {accessor[bound]}, actual {actual.tolist()}"
                )


def _has_plain_data(doc: dict, accessor: dict) -> bool:
    """Whether the accessor's values are in the file as they are: not in a compressed buffer view
    (EXT_meshopt_compression) nor left to a Draco primitive (no buffer view, no sparse values),
    which the validator does not decode either."""
    if "bufferView" not in accessor:
        return "sparse" in accessor
    return "EXT_meshopt_compression" not in (doc["bufferViews"][accessor["bufferView"]].get("extensions") or {})


def _parents(doc: dict, report) -> dict[int, int]:
    parent: dict[int, int] = {}
    for index, node in enumerate(doc.get("nodes", [])):
        for child in node.get("children", []):
            if child in parent:
                report("NODE_PARENT_OVERRIDE", f"/nodes/{index}/children", str(child))
            parent[child] = index
    return parent


def _scene_nodes(doc: dict, scene: dict) -> list[int]:
    """Every node of ``scene``'s trees."""
    found, stack = [], list(scene.get("nodes", []))
    while stack:
        node = stack.pop()
        if node not in found:
            found.append(node)
            stack.extend(doc["nodes"][node].get("children", []))
    return found


def _check_nodes(doc: dict, report) -> None:
    nodes = doc.get("nodes", [])
    parent = _parents(doc, report)
    for start in range(len(nodes)):
        seen, node = set(), start
        while node in parent:
            if node in seen:
                report("NODE_LOOP", f"/nodes/{start}", "")
                break
            seen.add(node)
            node = parent[node]
    for scene_index, scene in enumerate(doc.get("scenes", [])):
        for node in scene.get("nodes", []):
            if node in parent:
                report("SCENE_NON_ROOT_NODE", f"/scenes/{scene_index}/nodes", str(node))
    animated = {(c["target"].get("node")) for a in doc.get("animations", []) for c in a["channels"]
                if c["target"].get("path") in ("translation", "rotation", "scale")}  # fmt: skip
    for index, node in enumerate(nodes):
        where = f"/nodes/{index}"
        if "matrix" in node and any(key in node for key in ("translation", "rotation", "scale")):
            report("NODE_MATRIX_TRS", where, "")
        if "matrix" in node and index in animated:
            report("ANIMATION_CHANNEL_TARGET_NODE_MATRIX", where, "")
        if "rotation" in node and abs(np.linalg.norm(node["rotation"]) - 1.0) > _UNIT_VEC4:
            report("NODE_ROTATION_NON_UNIT", where, str(node["rotation"]))
        mesh = doc["meshes"][node["mesh"]] if "mesh" in node else None
        if "skin" in node and (mesh is None or not any("JOINTS_0" in p["attributes"] for p in mesh["primitives"])):
            report("NODE_SKIN_WITH_NON_SKINNED_MESH", where, "")
        if "weights" in node and mesh is not None:
            targets = len(mesh["primitives"][0].get("targets", []))
            if len(node["weights"]) != targets:
                report("NODE_WEIGHTS_INVALID", where, f"{len(node['weights'])} weights, {targets} targets")
        for lod in (node.get("extensions") or {}).get("MSFT_lod", {}).get("ids", []):
            if not 0 <= lod < len(nodes):
                report("UNRESOLVED_REFERENCE", where + "/extensions/MSFT_lod/ids", str(lod))


def _check_meshes(glb: _Glb, report) -> None:
    doc = glb.json
    quantized = "KHR_mesh_quantization" in doc.get("extensionsUsed", [])
    usage: dict[int, str] = {}
    view_usage: dict[int, str] = {}
    skins_of_mesh: dict[int, list[int]] = {}
    for node in doc.get("nodes", []):
        if "mesh" in node and "skin" in node:
            skins_of_mesh.setdefault(node["mesh"], []).append(len(doc["skins"][node["skin"]]["joints"]))
    for mesh_index, mesh in enumerate(doc.get("meshes", [])):
        target_counts = {len(p.get("targets", [])) for p in mesh["primitives"]}
        if len(target_counts) > 1:
            report("MESH_PRIMITIVES_UNEQUAL_TARGETS_COUNT", f"/meshes/{mesh_index}", str(target_counts))
        if "weights" in mesh and len(mesh["weights"]) != max(target_counts):
            report("MESH_INVALID_WEIGHTS_COUNT", f"/meshes/{mesh_index}", "")
        for primitive_index, primitive in enumerate(mesh["primitives"]):
            where = f"/meshes/{mesh_index}/primitives/{primitive_index}"
            attributes = primitive["attributes"]
            counts = {doc["accessors"][a]["count"] for a in attributes.values()}
            if len(counts) > 1:
                report("MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT", where, str(counts))
            vertex_count = min(counts) if counts else 0
            for semantic, index in attributes.items():
                accessor = doc["accessors"][index]
                fmt = (accessor["componentType"], accessor["type"], bool(accessor.get("normalized")))
                allowed = _formats(semantic, quantized)
                if allowed and fmt not in allowed:
                    report(
                        "MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT", f"{where}/attributes/{semantic}", str(fmt)
                    )
                _set_usage(usage, view_usage, doc, index, "vertex", report)
                if "bufferView" in accessor:
                    view = doc["bufferViews"][accessor["bufferView"]]
                    if (view.get("byteOffset", 0) + accessor.get("byteOffset", 0)) % 4 or view.get("byteStride", 4) % 4:
                        report("MESH_PRIMITIVE_ACCESSOR_UNALIGNED", f"{where}/attributes/{semantic}", "")
            if "POSITION" in attributes and not {"min", "max"} <= set(doc["accessors"][attributes["POSITION"]]):
                report("MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS", where, "")
            _check_unit_vectors(glb, attributes, where, report)
            if "indices" in primitive:
                _check_indices(glb, primitive["indices"], vertex_count, where, report)
                _set_usage(usage, view_usage, doc, primitive["indices"], "index", report)
            joint_limits = skins_of_mesh.get(mesh_index)
            if joint_limits and "JOINTS_0" in attributes:
                _check_influences(glb, attributes, min(joint_limits) - 1, where, report)
            for target_index, target in enumerate(primitive.get("targets", [])):
                for semantic, index in target.items():
                    if semantic not in attributes:
                        report(
                            "MESH_PRIMITIVE_MORPH_TARGET_NO_BASE_ACCESSOR", f"{where}/targets/{target_index}", semantic
                        )
                    elif doc["accessors"][index]["count"] != vertex_count:
                        report(
                            "MESH_PRIMITIVE_MORPH_TARGET_INVALID_ATTRIBUTE_COUNT",
                            f"{where}/targets/{target_index}",
                            semantic,
                        )
                    _set_usage(usage, view_usage, doc, index, "vertex", report)


def _set_usage(usage: dict, view_usage: dict, doc: dict, accessor: int, kind: str, report) -> None:
    if usage.setdefault(accessor, kind) != kind:
        report("ACCESSOR_USAGE_OVERRIDE", f"/accessors/{accessor}", f"{usage[accessor]} and {kind}")
    view = doc["accessors"][accessor].get("bufferView")
    if view is not None and view_usage.setdefault(view, kind) != kind:
        report("BUFFER_VIEW_TARGET_OVERRIDE", f"/bufferViews/{view}", f"{view_usage[view]} and {kind}")
    if view is not None and kind == "index" and "byteStride" in doc["bufferViews"][view]:
        report("MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE", f"/bufferViews/{view}", "")


def _check_unit_vectors(glb: _Glb, attributes: dict, where: str, report) -> None:
    normals, tangents = (
        glb.accessor(attributes[name]) if name in attributes else None for name in ("NORMAL", "TANGENT")
    )
    if normals is not None:
        length = np.linalg.norm(normals, axis=1)
        bad = np.abs(length - 1.0) > _UNIT_VEC3
        if bad.any():
            report(
                "ACCESSOR_VECTOR3_NON_UNIT",
                f"{where}/attributes/NORMAL",
                f"{int(bad.sum())} vectors, e.g. {length[bad][0]}",
            )
    if tangents is not None:
        bad = np.abs(np.linalg.norm(tangents[:, :3], axis=1) - 1.0) > _UNIT_VEC3
        if bad.any():
            report("ACCESSOR_VECTOR3_NON_UNIT", f"{where}/attributes/TANGENT", f"{int(bad.sum())} vectors")
        if not np.isin(tangents[:, 3], (-1.0, 1.0)).all():
            report("ACCESSOR_INVALID_SIGN", f"{where}/attributes/TANGENT", "")


def _check_indices(glb: _Glb, index: int, vertex_count: int, where: str, report) -> None:
    accessor = glb.json["accessors"][index]
    if accessor["type"] != "SCALAR" or accessor["componentType"] not in (_UBYTE, _USHORT, _UINT):
        report("MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT", where, "")
        return
    values = glb.accessor(index, normalize=False)
    if values is None:
        return
    values = values.ravel()
    restart = np.iinfo(_DTYPES[accessor["componentType"]]).max
    if (values == restart).any():
        report("ACCESSOR_INDEX_PRIMITIVE_RESTART", where + "/indices", "")
    if values.size and values.max() >= vertex_count:
        report("ACCESSOR_INDEX_OOB", where + "/indices", f"{int(values.max())} >= {vertex_count}")


def _check_influences(glb: _Glb, attributes: dict, max_joint: int, where: str, report) -> None:
    sets = sorted(int(k.split("_")[1]) for k in attributes if k.startswith("JOINTS_"))
    columns = [glb.accessor(attributes[f"{name}_{s}"], normalize=name == "WEIGHTS") for name in ("JOINTS", "WEIGHTS")
               for s in sets]  # fmt: skip
    if any(column is None for column in columns):
        return
    joints = np.concatenate(columns[: len(sets)], axis=1).astype(np.int64)
    weights = np.concatenate(columns[len(sets) :], axis=1)
    if (joints > max_joint).any():
        report("ACCESSOR_JOINTS_INDEX_OOB", where + "/attributes/JOINTS_0", f"{int(joints.max())} > {max_joint}")
    used = weights != 0
    if (weights < 0).any():
        report("ACCESSOR_WEIGHTS_NEGATIVE", where + "/attributes/WEIGHTS_0", "")
    order = np.sort(np.where(used, joints, -1 - np.arange(joints.shape[1])), axis=1)
    if (order[:, 1:] == order[:, :-1]).any():
        report("ACCESSOR_JOINTS_INDEX_DUPLICATE", where + "/attributes/JOINTS_0", "")
    # The validator sums a vertex's weights in float32, one at a time: component 0 of every
    # JOINTS_n/WEIGHTS_n set, then component 1, and so on.
    total = np.zeros(len(weights), np.float32)
    for column in np.arange(joints.shape[1]).reshape(len(sets), 4).T.ravel():
        total = (total + np.where(used[:, column], weights[:, column], 0).astype(np.float32)).astype(np.float32)
    threshold = _SUM_STEP * ((used.sum(axis=1) + 1) // 2 - 1)
    bad = np.abs(total.astype(np.float64) - 1.0) > threshold
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        detail = f"{int(bad.sum())} of {len(bad)} vertices, e.g. vertex {first} sums to {float(total[first])!r}"
        report("ACCESSOR_WEIGHTS_NON_NORMALIZED", f"{where}/attributes/WEIGHTS_0", detail)


def _ancestry(parent: dict[int, int], node: int) -> list[int]:
    """``node`` and its ancestors, up to its root (a loop, reported elsewhere, stops the walk)."""
    chain = [node]
    while chain[-1] in parent and parent[chain[-1]] not in chain:
        chain.append(parent[chain[-1]])
    return chain


def _check_skins(glb: _Glb, report) -> None:
    doc = glb.json
    parent = _parents(doc, lambda *args: None)
    in_scene = [set(_scene_nodes(doc, scene)) for scene in doc.get("scenes", [])]
    for index, skin in enumerate(doc.get("skins", [])):
        if len(set(skin["joints"])) != len(skin["joints"]):
            report("DUPLICATE_ELEMENTS", f"/skins/{index}/joints", "")
        ancestries = [_ancestry(parent, joint) for joint in skin["joints"]]
        roots = {chain[-1] for chain in ancestries}
        if len(roots) > 1:
            report("SKIN_NO_COMMON_ROOT", f"/skins/{index}", f"roots {sorted(roots)}")
        elif "skeleton" in skin and not all(skin["skeleton"] in chain for chain in ancestries):
            report("SKIN_SKELETON_INVALID", f"/skins/{index}/skeleton", str(skin["skeleton"]))
        for scene_index, nodes in enumerate(in_scene):
            drawn = any(doc["nodes"][n].get("skin") == index and "mesh" in doc["nodes"][n] for n in nodes)
            if drawn and not roots <= nodes:
                report("NODE_SKIN_NO_SCENE", f"/scenes/{scene_index}", f"skin {index}'s root not in the scene")
        if "inverseBindMatrices" in skin:
            accessor = glb.json["accessors"][skin["inverseBindMatrices"]]
            if accessor["count"] != len(skin["joints"]):
                report(
                    "INVALID_IBM_ACCESSOR_COUNT", f"/skins/{index}", f"{accessor['count']} for {len(skin['joints'])}"
                )
            if (accessor["componentType"], accessor["type"]) != (_FLOAT, "MAT4"):
                report("SKIN_IBM_INVALID_FORMAT", f"/skins/{index}", "")


_OUTPUT_TYPES = {"translation": "VEC3", "scale": "VEC3", "rotation": "VEC4", "weights": "SCALAR"}


def _check_animations(glb: _Glb, report) -> None:
    doc = glb.json
    for animation_index, animation in enumerate(doc.get("animations", [])):
        targets: dict[tuple, int] = {}
        for channel_index, channel in enumerate(animation["channels"]):
            where = f"/animations/{animation_index}/channels/{channel_index}"
            target = channel["target"]
            pointer = (target.get("extensions") or {}).get("KHR_animation_pointer", {}).get("pointer")
            key = (target.get("node"), target["path"], pointer)
            if key in targets:
                report("ANIMATION_DUPLICATE_TARGETS", where, f"same as channel {targets[key]}")
            targets.setdefault(key, channel_index)
            node = doc["nodes"][target["node"]] if "node" in target else None
            mesh = doc["meshes"][node["mesh"]] if node is not None and "mesh" in node else None
            if target["path"] == "weights" and (mesh is None or not mesh["primitives"][0].get("targets")):
                report("ANIMATION_CHANNEL_TARGET_NODE_WEIGHTS_NO_MORPHS", where, "")
            sampler = animation["samplers"][channel["sampler"]]
            _check_sampler(glb, sampler, target["path"], node, f"/animations/{animation_index}", report)


def _check_sampler(glb: _Glb, sampler: dict, path: str, node: dict | None, where: str, report) -> None:
    doc = glb.json
    source, output = doc["accessors"][sampler["input"]], doc["accessors"][sampler["output"]]
    if (source["componentType"], source["type"]) != (_FLOAT, "SCALAR"):
        report("ANIMATION_SAMPLER_INPUT_ACCESSOR_INVALID_FORMAT", where, "")
        return
    if not {"min", "max"} <= set(source):
        report("ANIMATION_SAMPLER_INPUT_ACCESSOR_WITHOUT_BOUNDS", where, f"accessor {sampler['input']}")
    times = glb.accessor(sampler["input"])
    times = np.zeros(0) if times is None else times.ravel()
    if (times < 0).any():
        report("ACCESSOR_ANIMATION_INPUT_NEGATIVE", f"/accessors/{sampler['input']}", "")
    if (np.diff(times) <= 0).any():
        report("ACCESSOR_ANIMATION_INPUT_NON_INCREASING", f"/accessors/{sampler['input']}", "")
    interpolation = sampler.get("interpolation", "LINEAR")
    per_key = 3 if interpolation == "CUBICSPLINE" else 1
    if path == "weights":
        targets = len(doc["meshes"][node["mesh"]]["primitives"][0].get("targets", [])) if node and "mesh" in node else 0
        per_key *= max(targets, 1)
    if output["count"] != per_key * source["count"]:
        report(
            "ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_COUNT", where, f"{output['count']} for {source['count']} keys"
        )
    if output["type"] != _OUTPUT_TYPES.get(path, output["type"]):
        report("ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_FORMAT", where, f"{output['type']} for {path}")
    rotations = glb.accessor(sampler["output"]) if path == "rotation" and interpolation != "CUBICSPLINE" else None
    if rotations is not None:
        length = np.linalg.norm(rotations, axis=1)
        bad = np.abs(length - 1.0) > _UNIT_VEC4
        if bad.any():
            report("ACCESSOR_ANIMATION_SAMPLER_OUTPUT_NON_NORMALIZED_QUATERNION", f"/accessors/{sampler['output']}",
                   f"{int(bad.sum())} keys")  # fmt: skip


_SIGNATURES = {"image/png": b"\x89PNG\r\n\x1a\n", "image/jpeg": b"\xff\xd8\xff"}


def _check_images(glb: _Glb, report) -> None:
    for index, image in enumerate(glb.json.get("images", [])):
        if "bufferView" not in image:
            continue
        if not isinstance(image.get("mimeType"), str):
            report("UNSATISFIED_DEPENDENCY", f"/images/{index}", f"mimeType {image.get('mimeType')!r}")
            continue
        signature = _SIGNATURES.get(image["mimeType"])
        if signature and not glb.view_bytes(image["bufferView"]).startswith(signature):
            report("IMAGE_MIME_TYPE_INVALID", f"/images/{index}", image["mimeType"])
