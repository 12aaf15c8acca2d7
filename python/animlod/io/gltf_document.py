"""Checked access to a loaded glTF 2.0 document: buffers, accessors and the node tree.

This module splits a GLB into its chunks, parses the JSON with bounded nesting and has it
decoded into pygltflib's object model with every value's JSON type checked (gltf_decode.py);
then it turns accessors into numpy arrays and checks every reference on the way, so that a
broken file fails with :class:`FormatError` naming the file, the element and the reason
instead of an IndexError or a silently wrong array.
"""

from __future__ import annotations

import base64
import os
import re
import struct
import warnings
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np
import pygltflib

from .. import rotations
from .errors import FormatError
from .gltf_decode import decode_gltf, is_whole_number, labels_as_text
from .gltf_draco import DRACO_EXTENSION, decode_draco, draco_elements, draco_sources
from .gltf_keyframes import (
    INTERPOLATIONS,
    MIN_SAMPLE_RATE,
    frame_count,
    frame_times,
    key_sample_rate,
    sample_keyframes,
)
from .gltf_meshopt import MESHOPT_EXTENSIONS, decode_meshopt_view, meshopt_extension
from .gltf_references import LIGHTS_EXTENSION, index_references
from .json_limits import load_json

_GLB_MAGIC = b"glTF"
_GLB_HEADER_BYTES = 12
_GLB_JSON_CHUNK = 0x4E4F534A  # "JSON"
_GLB_BIN_CHUNK = 0x004E4942  # "BIN\0"
_DATA_URI_BASE64 = ";base64,"
INSTANCING_EXTENSION = "EXT_mesh_gpu_instancing"
LOD_EXTENSION = "MSFT_lod"
# Node extras key of the (mesh level x motion level) grid of level nodes that character chains
# write beside MSFT_lod: grid[g][m] lists the node drawing geometry level g at motion level m.
GRID_EXTRA = "animlod_grid"
# Required extensions animlod reads: those that leave geometry, skins and animation readable as
# plain glTF (quantized attributes are ordinary normalised or integer accessors), Draco's, decoded
# into its accessors (gltf_draco.py), and meshopt's, decoded into its buffer views
# (gltf_meshopt.py), and GPU instancing, whose per-instance transforms leave each mesh as it is
# (level nodes repeat them, gltf_lod.py); any other required extension changes what the buffers
# mean and is refused.
_READABLE_EXTENSIONS = (
    "KHR_mesh_quantization", "KHR_materials_", "KHR_texture_", "EXT_texture_", "KHR_lights_", DRACO_EXTENSION,
    *MESHOPT_EXTENSIONS, INSTANCING_EXTENSION,
)  # fmt: skip


COMPONENT_DTYPES = {
    5120: np.dtype("<i1"),
    5121: np.dtype("<u1"),
    5122: np.dtype("<i2"),
    5123: np.dtype("<u2"),
    5125: np.dtype("<u4"),
    5126: np.dtype("<f4"),
}
# Normalised integers map to [0, 1] (unsigned) or [-1, 1] (signed), glTF 2.0 section 3.11.
_NORMALIZED_DIVISORS = {5120: 127.0, 5121: 255.0, 5122: 32767.0, 5123: 65535.0}
_TYPE_WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
# Sparse indices are unsigned: UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT (glTF 2.0 section 3.6.2.3).
_SPARSE_INDEX_COMPONENTS = (5121, 5123, 5125)
# bufferView.byteStride is a multiple of 4 no larger than 252 (glTF 2.0 section 3.6.2.4).
_MAX_BYTE_STRIDE = 252
_MAX_ACCESSOR_COUNT = 2**32 - 1
# An accessor without a bufferView is zeros (plus sparse values), and a meshopt-compressed buffer
# view decodes to count x byteStride bytes; either may take at most this many times the bytes
# of the file and its buffers (+1 MiB).
_ZERO_FILL_FACTOR = 16
# Most frames an animation is sampled to by default: 100,000 is 55 minutes at 30 fps. A file whose
# keys run longer is refused (naming the animation and its duration) rather than sampled: a
# few kilobytes with a key at 30,000 s would otherwise become 900,001 frames. Raise it per
# document (GltfDocument(max_animation_frames=...)) or with ANIMLOD_MAX_ANIMATION_FRAMES.
MAX_ANIMATION_FRAMES = 100_000
# Top-level glTF properties that are arrays of objects (glTF 2.0 section 5.17).
_TOP_LEVEL_ARRAYS = (
    "accessors", "animations", "buffers", "bufferViews", "cameras", "images", "materials", "meshes", "nodes",
    "samplers", "scenes", "skins", "textures", "extensionsUsed", "extensionsRequired",
)  # fmt: skip
NODE_PATHS = ("translation", "rotation", "scale")  # the channel paths that move a node
_CHANNEL_PATHS = (*NODE_PATHS, "weights")
# KHR_animation_pointer: a channel of path "pointer" animates the property its JSON pointer
# names; those of a node's TRS or weights are read as that node's channels.
POINTER_EXTENSION = "KHR_animation_pointer"
NODE_POINTER = re.compile(r"/nodes/(\d+)/(translation|rotation|scale|weights)")
# A pointer at a property of a listed object: its list (None: KHR_lights_punctual's lights) and index.
_POINTER_TARGET = re.compile(r"/(?:(materials|meshes|cameras|textures|images|samplers|skins|nodes|accessors)"
                             r"|extensions/KHR_lights_punctual/lights)/(\d+)/")  # fmt: skip
# Top-level arrays whose singular is not the name without its last letter.
_IRREGULAR_SINGULARS = {"meshes": "mesh"}

# Relative tolerance under which a node's scale counts as uniform (exporters leave float noise
# such as 1.0000009 on scales that are meant to be 1).
UNIFORM_SCALE_TOLERANCE = 1e-4


class GltfDocument:
    """A parsed glTF file with its buffers loaded, and checked accessors into it.

    Attributes
    ----------
    path : the file, for error messages.
    gltf : the pygltflib document.
    json : the document's JSON as parsed, every property kept (pygltflib drops some, such as a
        node's morph ``weights``); what whole-document writers start from.
    parents : (N,) int, parent node of every node, -1 for nodes at the top of the tree.
    channel_targets : per animation, per channel, the (node, path) it animates (a
        KHR_animation_pointer channel resolved; ``(None, "pointer")`` when it animates no node).
    """

    def __init__(
        self, path: str | os.PathLike, max_animation_frames: int | None = None, data: bytes | None = None
    ) -> None:
        """``data``: the file's bytes, given instead of read from ``path`` (a document assembled in
        memory, whose messages still name ``path``)."""
        self.path = os.fspath(path)
        self.max_animation_frames = _frame_limit(max_animation_frames)
        self._size = None if data is None else len(data)
        self.gltf, self.json = _parse(self.path, data)
        self._buffers: dict[int, bytes] = {}
        self._accessors: dict[int, np.ndarray] = {}
        self._draco_meshes: dict[int, Any] = {}  # decoded per compressed buffer view
        self._decoded_views: dict[int, bytes] = {}  # EXT_meshopt_compression's
        self._draco = draco_sources(self.gltf, self.fail)
        self.parents = self._node_parents()
        self._check_scenes_and_channels()
        self._check_references()

    def fail(self, element: str, reason: str) -> FormatError:
        """The error to raise for ``element`` of this file."""
        return FormatError(self.path, element, reason)

    def item(self, kind: str, index: Any, referrer: str) -> Any:
        """``gltf.<kind>[index]`` (``lights``: KHR_lights_punctual's), or FormatError naming
        ``referrer`` when the index is invalid."""
        items = self._lights() if kind == "lights" else getattr(self.gltf, kind) or []
        if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(items):
            singular = _IRREGULAR_SINGULARS.get(kind, kind[:-1])
            raise self.fail(referrer, f"refers to {singular} {index!r}, but the file has {len(items)} {kind}")
        return items[index]

    # ---- accessors -------------------------------------------------------------------------

    def accessor(self, index: Any, referrer: str) -> np.ndarray:
        """The elements of accessor ``index`` as a read-only ``(count, width)`` array (cached).

        Float and normalised-integer accessors come back as float32 (checked finite), other
        integer accessors in their own dtype. Sparse substitutions are applied.
        """
        accessor = self.item("accessors", index, referrer)
        if index not in self._accessors:
            self._accessors[index] = self._decode_accessor(index, accessor, f"accessor {index} ({referrer})")
        return self._accessors[index]

    def _decode_accessor(self, index: int, accessor: pygltflib.Accessor, element: str) -> np.ndarray:
        component = accessor.componentType
        if component not in COMPONENT_DTYPES:
            raise self.fail(element, f"unknown componentType {component!r}")
        if accessor.type not in _TYPE_WIDTHS:
            raise self.fail(element, f"type {accessor.type!r} is not supported here")
        count = accessor.count
        # Elements are addressed by unsigned 32-bit indices, which bounds what a file can mean.
        if not isinstance(count, int) or isinstance(count, bool) or not 0 <= count <= _MAX_ACCESSOR_COUNT:
            raise self.fail(element, f"invalid count {count!r}")
        width = _TYPE_WIDTHS[accessor.type]
        dtype = COMPONENT_DTYPES[component]
        if accessor.bufferView is None and index in self._draco:
            values = self._draco_elements(index, count, width, dtype)
        elif accessor.bufferView is None:
            # All zeros unless sparse says otherwise: nothing in the file backs the elements, so
            # their number is bounded by what the file holds elsewhere (a sparse morph target is
            # as long as its POSITION accessor, whose bytes are in a buffer).
            limit = _ZERO_FILL_FACTOR * (self._file_bytes() + 2**20)
            if count * width * dtype.itemsize > limit:
                reason = f"count {count} without a bufferView needs {count * width * dtype.itemsize} bytes of zeros"
                raise self.fail(element, f"{reason}, more than the file can justify ({limit})")
            values = np.zeros((count, width), dtype)
        else:
            values = self._strided_elements(accessor, count, width, dtype, element)
        if accessor.sparse is not None:
            self._apply_sparse(accessor.sparse, values, width, dtype, element)
        if accessor.normalized and component in _NORMALIZED_DIVISORS:
            values = np.maximum(values / np.float32(_NORMALIZED_DIVISORS[component]), np.float32(-1.0))
        if values.dtype.kind == "f":
            values = values.astype(np.float32)
            finite = np.isfinite(values)
            if not finite.all():
                bad = int(np.argmax(~finite.all(axis=1)))
                raise self.fail(element, f"non-finite value at element {bad}")
        values.flags.writeable = False
        return values

    def _draco_elements(self, index: int, count: int, width: int, dtype: np.dtype) -> np.ndarray:
        """Accessor ``index``'s elements decoded from its primitive's Draco buffer view."""
        source = self._draco[index]
        if source.view not in self._draco_meshes:
            data = self.view_bytes(source.view, source.element)
            self._draco_meshes[source.view] = decode_draco(data, source.element, self.fail)
        return draco_elements(self._draco_meshes[source.view], source, count, width, dtype, self.fail)

    def view_bytes(self, view_index: Any, referrer: str) -> memoryview:
        """The bytes of buffer view ``view_index``, decoded where a meshopt extension compresses
        them; FormatError naming ``referrer`` or the view if they cannot be had."""
        view = self.item("bufferViews", view_index, referrer)
        element = f"bufferView {view_index}"
        meshopt = meshopt_extension(view.extensions)
        if meshopt is None:
            return self._buffer_range(view.buffer, view.byteOffset, view.byteLength, element)
        if view_index not in self._decoded_views:
            name, extension = meshopt
            where = extension if isinstance(extension, dict) else {}
            element = f"{element} {name}"
            start, length = where.get("byteOffset"), where.get("byteLength")
            compressed = self._buffer_range(where.get("buffer"), start, length, element)
            limit = _ZERO_FILL_FACTOR * (self._file_bytes() + 2**20)
            self._decoded_views[view_index] = decode_meshopt_view(extension, compressed, element, self.fail, limit)
        return memoryview(self._decoded_views[view_index])

    def _buffer_range(self, buffer: Any, offset: Any, length: Any, element: str) -> memoryview:
        """``length`` bytes at ``offset`` of buffer ``buffer`` (checked to lie inside it)."""
        data = self.buffer_bytes(buffer, element)
        offset = self._whole_number(offset, "byteOffset", element)
        length = self._whole_number(length, "byteLength", element)
        if offset + length > len(data):
            reason = f"bytes [{offset}, {offset + length}) lie outside buffer {buffer} of {len(data)} bytes"
            raise self.fail(element, f"{reason} (truncated file?)")
        return memoryview(data)[offset : offset + length]

    def _strided_elements(
        self, accessor: pygltflib.Accessor, count: int, width: int, dtype: np.dtype, element: str
    ) -> np.ndarray:
        view_index = accessor.bufferView
        data = self.view_bytes(view_index, element)
        view, view_length = self.gltf.bufferViews[view_index], len(data)
        element_bytes = dtype.itemsize * width
        stride = view.byteStride
        if stride is None:
            stride = element_bytes
        # A stride below the element size would read elements that overlap.
        elif not (isinstance(stride, int) and element_bytes <= stride <= _MAX_BYTE_STRIDE and stride % 4 == 0):
            reason = (
                f"byteStride {stride!r} must be a multiple of 4 from {element_bytes} (the element size of "
                f"{element}) to {_MAX_BYTE_STRIDE}"
            )
            raise self.fail(f"bufferView {view_index}", reason)
        start = self._whole_number(accessor.byteOffset, "byteOffset", element)
        needed = start + stride * (count - 1) + element_bytes if count else 0
        if needed > view_length:
            raise self.fail(element, f"needs {needed} bytes but bufferView {view_index} has {view_length}")
        if count == 0:
            return np.zeros((0, width), dtype)
        window = np.frombuffer(data, np.uint8, needed - start, start)
        rows = np.lib.stride_tricks.as_strided(window, (count, element_bytes), (stride, 1))
        return rows.copy().view(dtype).reshape(count, width)

    def _apply_sparse(
        self, sparse: pygltflib.Sparse, values: np.ndarray, width: int, dtype: np.dtype, element: str
    ) -> None:
        if sparse.indices is None or sparse.values is None:
            raise self.fail(f"{element} sparse", "needs both indices and values")
        substitutes = self._whole_number(sparse.count, "sparse count", element)
        index_element = f"{element} sparse indices"
        if sparse.indices.componentType not in _SPARSE_INDEX_COMPONENTS:
            reason = f"componentType {sparse.indices.componentType!r} is not one of {_SPARSE_INDEX_COMPONENTS}"
            raise self.fail(index_element, reason)
        index_dtype = COMPONENT_DTYPES[sparse.indices.componentType]
        indices = self._sparse_part(sparse.indices, substitutes, 1, index_dtype, index_element)
        new_values = self._sparse_part(sparse.values, substitutes, width, dtype, f"{element} sparse values")
        rows = indices[:, 0].astype(np.int64)  # unsigned, so only the upper bound can be crossed
        if rows.size and rows.max() >= values.shape[0]:
            raise self.fail(index_element, f"index {int(rows.max())} outside [0, {values.shape[0]})")
        values[rows] = new_values

    def _sparse_part(self, part: Any, count: int, width: int, dtype: np.dtype, element: str) -> np.ndarray:
        data = self.view_bytes(part.bufferView, element)
        start = self._whole_number(part.byteOffset, "byteOffset", element)
        length = count * width * dtype.itemsize
        if start + length > len(data):
            reason = f"needs bytes up to {start + length}, bufferView {part.bufferView} has {len(data)}"
            raise self.fail(element, reason)
        return np.frombuffer(data, dtype, count * width, start).reshape(count, width)

    def _file_bytes(self) -> int:
        """Size of the file and of the external buffer files it names: what bounds its accessors
        (declared byteLengths are not trusted)."""
        total = os.path.getsize(self.path) if self._size is None else self._size
        for buffer in self.gltf.buffers or []:
            if isinstance(buffer.uri, str) and not buffer.uri.startswith("data:"):
                external = uri_path(self.path, buffer.uri)
                total += external.stat().st_size if external.is_file() else 0
        return total

    def _whole_number(self, value: Any, name: str, element: str) -> int:
        """A byteOffset, byteLength or count of ``element``: 0 when absent, else a whole number >= 0."""
        if value is None:
            return 0
        if not is_whole_number(value):
            raise self.fail(element, f"{name} {value!r} is not a whole number >= 0")
        return value

    def buffer_bytes(self, index: Any, referrer: str) -> bytes:
        """The bytes of buffer ``index`` (cached); FormatError naming ``referrer`` if it cannot be read."""
        buffer = self.item("buffers", index, referrer)
        if index not in self._buffers:
            self._buffers[index] = self._buffer_bytes(index, buffer)
        return self._buffers[index]

    def _buffer_bytes(self, index: int, buffer: pygltflib.Buffer) -> bytes:
        element = f"buffer {index}"
        if buffer.uri is None:
            blob = self.gltf.binary_blob()
            if blob is None:
                raise self.fail(element, "has no uri and the file has no GLB binary chunk")
            data = bytes(blob)
        elif buffer.uri.startswith("data:"):
            try:
                data = base64.b64decode(buffer.uri.split(_DATA_URI_BASE64, 1)[1], validate=True)
            except (IndexError, ValueError) as error:  # binascii.Error, or non-ASCII text
                raise self.fail(element, f"malformed base64 data URI ({error})") from None
        else:
            external = uri_path(self.path, buffer.uri)
            try:
                data = external.read_bytes()
            except OSError as error:
                raise self.fail(element, f"cannot read {external} ({error.strerror})") from None
        if buffer.byteLength is not None and len(data) < buffer.byteLength:
            raise self.fail(element, f"holds {len(data)} bytes, byteLength says {buffer.byteLength} (truncated file?)")
        return data

    # ---- nodes ------------------------------------------------------------------------------

    def _node_parents(self) -> np.ndarray:
        nodes = self.gltf.nodes or []
        parents = np.full(len(nodes), -1, dtype=np.int64)
        for index, node in enumerate(nodes):
            for child in node.children or []:
                self.item("nodes", child, f"node {index} children")
                if parents[child] != -1 or child == index:
                    raise self.fail(f"node {child}", "has more than one parent (the node graph must be a tree)")
                parents[child] = index
        for index in range(len(nodes)):  # a cycle never reaches a top node
            seen, node = 0, index
            while node != -1:
                node, seen = parents[node], seen + 1
                if seen > len(nodes):
                    raise self.fail(f"node {index}", "lies on a cycle of children")
        return parents

    def _check_scenes_and_channels(self) -> None:
        """The default scene, the scenes' root nodes and every animation channel's target refer to
        things the file has (a channel on node 9999 or a scene past the list is an error); the
        targets are resolved into ``channel_targets``."""
        gltf = self.gltf
        if gltf.scene is not None:
            self.item("scenes", gltf.scene, "scene")
        for index, scene in enumerate(gltf.scenes or []):
            for node in scene.nodes or []:
                self.item("nodes", node, f"scene {index} nodes")
        self.channel_targets = [
            [self._channel_target(a, c, channel) for c, channel in enumerate(animation.channels or [])]
            for a, animation in enumerate(gltf.animations or [])
        ]

    def _lights(self) -> list:
        """The document's KHR_lights_punctual lights (none where it has no such list)."""
        extension = (self.json.get("extensions") or {}).get(LIGHTS_EXTENSION)
        lights = extension.get("lights") if isinstance(extension, dict) else None
        return lights if isinstance(lights, list) else []

    def _check_references(self) -> None:
        """Every other index of the file refers to something it has (gltf_references.py)."""
        for kind, index, referrer in index_references(self):
            self.item(kind, index, referrer)

    def _channel_target(self, a: int, c: int, channel: pygltflib.AnimationChannel) -> tuple[int | None, str]:
        """The (node, path) channel ``c`` of animation ``a`` animates: its target's, or for a
        KHR_animation_pointer channel the node TRS or weights its pointer names, else (None, "pointer")
        for a property of anything else (a material's colour, a light), which nothing here reads."""
        element = f"animation {a} channel {c} target"
        if channel.target is None:
            raise self.fail(f"animation {a} channel {c}", "has no target")
        if channel.target.path == "pointer":
            extension = (channel.target.extensions or {}).get(POINTER_EXTENSION)
            pointer = extension.get("pointer") if isinstance(extension, dict) else None
            if not isinstance(pointer, str):
                raise self.fail(element, f"path 'pointer' needs a {POINTER_EXTENSION} pointer string")
            match = NODE_POINTER.fullmatch(pointer)
            if match is None:
                target = _POINTER_TARGET.match(pointer)  # an object of the document: it must exist
                if target is not None:
                    self.item(target.group(1) or "lights", int(target.group(2)), f"{element} pointer")
                return None, "pointer"
            node = int(match.group(1))
            self.item("nodes", node, f"{element} pointer")
            return node, match.group(2)
        if channel.target.node is not None:
            self.item("nodes", channel.target.node, element)
        if channel.target.path not in _CHANNEL_PATHS:
            reason = f"path {channel.target.path!r} is not one of {', '.join(_CHANNEL_PATHS)}, or 'pointer'"
            raise self.fail(element, reason)
        return channel.target.node, channel.target.path

    def moved_nodes(self) -> set[int]:
        """The nodes an animation channel translates, turns or scales (a "weights" channel morphs a
        mesh and moves no node)."""
        return {node for targets in self.channel_targets for node, path in targets if path in NODE_PATHS}

    def idle_weight_channels_note(self) -> str | None:
        """Names the animation channels that drive the morph weights of a node whose mesh has no
        morph target (or of a node without a mesh), which glTF does not allow and which change
        nothing: Blender writes them when it applies modifiers to a mesh with shape keys, which
        drops the keys its clip animates. None when the document has none."""
        idle = []
        for a, targets in enumerate(self.channel_targets):
            for c, (node, path) in enumerate(targets):
                if path != "weights" or node is None:
                    continue
                mesh = self.gltf.nodes[node].mesh
                primitives = self.gltf.meshes[mesh].primitives if mesh is not None else []
                if not any(primitive.targets for primitive in primitives):
                    idle.append(f"{self.animation_label(a)} channel {c} ({self.node_label(node)})")
        if not idle:
            return None
        return (f"morph weights animated on a mesh without morph targets, which change nothing (as where an exporter "
                f"that applied modifiers dropped the shape keys they drove): {', '.join(idle)}")  # fmt: skip

    def alternate_nodes(self) -> set[int]:
        """Nodes that stand in for another node at other levels of detail: the ids of its MSFT_lod
        chain and the nodes of animlod's level grid. They are that node drawn otherwise, not
        meshes or bones of their own (a level node plays its base node's channels)."""
        alternates = set()
        for index, node in enumerate(self.json.get("nodes", [])):
            ids = list(((node.get("extensions") or {}).get(LOD_EXTENSION) or {}).get("ids") or [])
            extras = node.get("extras")
            grid = extras.get(GRID_EXTRA) or [] if isinstance(extras, dict) else []
            ids += [other for row in grid if isinstance(row, list) for other in row]
            alternates.update(other for other in ids if isinstance(other, int) and other != index)
        return alternates

    def node_label(self, index: int) -> str:
        """``node 5 'Hips'`` for messages."""
        name = self.gltf.nodes[index].name
        return f"node {index} {name!r}" if name else f"node {index}"

    def ancestors(self, index: int) -> list[int]:
        """Ancestors of node ``index``, nearest first."""
        chain = []
        node = self.parents[index]
        while node != -1:
            chain.append(int(node))
            node = self.parents[node]
        return chain

    def in_shown_scene(self, index: int) -> bool:
        """Whether node ``index`` is drawn in the scene a viewer shows: the default ``scene``, else
        the first, under one of its root nodes (a collision proxy listed by a "physics" scene
        alone is not); every node is, in a file without scenes."""
        scenes = self.gltf.scenes or []
        if not scenes:
            return True
        roots = set(scenes[self.gltf.scene if self.gltf.scene is not None else 0].nodes or [])
        return index in roots or any(a in roots for a in self.ancestors(index))

    def rest_trs(self, index: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rest ``translation (3,)``, ``rotation (4,)`` and ``scale (3,)`` of node ``index``.

        A ``matrix`` is decomposed (a mirroring one with a negative x scale); shear cannot be
        expressed as TRS and raises.
        """
        node = self.gltf.nodes[index]
        if node.matrix is not None:
            return self._decompose(index)
        translation = np.asarray(node.translation if node.translation is not None else (0.0, 0.0, 0.0), np.float64)
        rotation = np.asarray(node.rotation if node.rotation is not None else (0.0, 0.0, 0.0, 1.0), np.float64)
        scale = np.asarray(node.scale if node.scale is not None else (1.0, 1.0, 1.0), np.float64)
        if translation.shape != (3,) or rotation.shape != (4,) or scale.shape != (3,):
            raise self.fail(self.node_label(index), "translation, rotation or scale has the wrong length")
        if not (np.all(np.isfinite(translation)) and np.all(np.isfinite(rotation)) and np.all(np.isfinite(scale))):
            raise self.fail(self.node_label(index), "non-finite translation, rotation or scale")
        if np.linalg.norm(rotation) == 0.0:
            raise self.fail(self.node_label(index), "zero rotation quaternion")
        return translation, rotations.normalize(rotation), scale

    def _decompose(self, index: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        matrix = self.rest_matrix(index)
        linear = matrix[:3, :3]
        scale = np.linalg.norm(linear, axis=0)
        if np.any(scale == 0.0):
            raise self.fail(self.node_label(index), "matrix is singular")
        if np.linalg.det(linear) < 0.0:  # mirrored: a negative x scale and a proper rotation
            scale[0] = -scale[0]
        rotation = linear / scale
        if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-4):
            raise self.fail(self.node_label(index), "matrix has shear, not translation-rotation-scale")
        return matrix[:3, 3].copy(), rotations.from_matrix(rotation), scale

    def rest_matrix(self, index: int) -> np.ndarray:
        """Local rest transform ``(4, 4)`` of node ``index`` (a ``matrix`` is taken as it is)."""
        matrix = self.gltf.nodes[index].matrix
        if matrix is not None:
            matrix = np.asarray(matrix, np.float64)
            if matrix.shape != (16,) or not np.all(np.isfinite(matrix)):
                raise self.fail(self.node_label(index), "matrix must be 16 finite numbers")
            matrix = matrix.reshape(4, 4).T  # glTF stores column-major
            if not affine_rows(matrix[None])[0]:  # glTF asks for a matrix made of TRS
                raise self.fail(self.node_label(index), f"matrix {last_row_fault(matrix)}")
            return matrix
        translation, rotation, scale = self.rest_trs(index)
        return rotations.compose_transform(translation, rotation, scale)

    def rest_world_matrix(self, index: int) -> np.ndarray:
        """World rest transform ``(4, 4)`` of node ``index`` (its ancestors included)."""
        world = self.rest_matrix(index)
        for ancestor in self.ancestors(index):
            world = self.rest_matrix(ancestor) @ world
        return world

    def uniform_scale(self, index: int, scale: np.ndarray, element: str) -> float | None:
        """The common value of a uniform ``scale (3,)``, None when it is not uniform or mirrors (a
        negative component, as 3ds Max and Maya write mirrored bones); FormatError when a component
        is zero (a flattened node)."""
        if not np.all(scale != 0.0):
            reason = f"scale {np.round(scale, 6).tolist()} of {self.node_label(index)} has a zero component"
            raise self.fail(element, f"{reason}; skeletons take no flattened joint")
        if np.any(scale < 0.0):
            return None
        value = float(np.mean(scale))
        return value if np.max(np.abs(scale - value)) <= UNIFORM_SCALE_TOLERANCE * value else None

    # ---- animations -------------------------------------------------------------------------

    def animation_label(self, index: int) -> str:
        """``animation 'Run'`` (or ``animation 3`` when unnamed) for messages."""
        name = self.gltf.animations[index].name
        return f"animation {name!r}" if name else f"animation {index}"

    def animation_duration(self, index: int) -> float:
        """The last key time over the samplers that animation ``index``'s channels use: the clip
        length a viewer plays (from 0). A sampler no channel uses (exporters leave them behind)
        sets nothing: one of 10 s beside a 1.25 s clip made its levels hold still for 8.75 s."""
        return float(max((times.max(initial=0.0) for times in self._key_times(index)), default=0.0))

    def animation_start(self, index: int) -> float:
        """The first key time over the samplers that animation ``index``'s channels use. Before it
        every channel holds its first key (glTF clamps to the keys' range), so a clip keyed late on
        a timeline (Blender keeps an action's frame numbers unless told to slide it to 0) shows
        one pose until then."""
        return float(min((times.min(initial=np.inf) for times in self._key_times(index)), default=0.0))

    def animation_start_frame(self, index: int, fps: float) -> int:
        """The frame at ``fps`` at or just before animation ``index``'s first key
        (:meth:`animation_start`): the frames before it show that key's pose, so the clips start
        there (frame k at ``(animation_start_frame + k) / fps``)."""
        last = frame_count(self.animation_duration(index), fps) - 1
        return int(np.clip(np.floor(self.animation_start(index) * fps), 0, last))

    def sample_rate(self, fps: float | None = None) -> float:
        """``fps``, or where it is None the rate at which the document's clips are sampled: the
        highest of its clips' key rates (:func:`~.gltf_keyframes.key_sample_rate`), within 30 to
        240 fps. Clips played together share one rate: a clip keyed at 60 fps keeps its keys,
        beside it a 30 fps clip is sampled at 60; one keyed at 24 fps or more sparsely at 30."""
        if fps is not None:
            return fps
        rates = [MIN_SAMPLE_RATE]
        for index in range(len(self.gltf.animations or [])):
            try:
                rates.append(key_sample_rate(self._key_times(index)))
            except FormatError:  # refused by whatever reads that clip, not by the rate of the others
                continue
        return max(rates)

    def _key_times(self, index: int) -> list[np.ndarray]:
        """The key times of each sampler that animation ``index``'s channels use."""
        label = self.animation_label(index)
        animation = self.gltf.animations[index]
        used = {channel.sampler for channel in animation.channels or []}
        return [
            self.accessor(sampler.input, f"{label} sampler {k} input")
            for k, sampler in enumerate(animation.samplers or [])
            if k in used
        ]

    def animation_frame_times(self, index: int, fps: float) -> np.ndarray:
        """Sample times ``(T,)`` at ``fps`` from 0 to the animation's duration, the last one at
        the duration itself (:func:`~.gltf_keyframes.frame_times`)."""
        label = self.animation_label(index)
        duration = self.animation_duration(index)
        count = frame_count(duration, fps)
        if count > self.max_animation_frames:
            reason = (
                f"lasts {duration:g} s: {count} frames at {fps:g} fps, more than the limit of "
                f"{self.max_animation_frames} (ANIMLOD_MAX_ANIMATION_FRAMES raises it)"
            )
            raise self.fail(label, reason)
        return frame_times(duration, fps)

    def sampler_keys(
        self, animation_index: int, sampler_index: Any, width: int, element: str
    ) -> tuple[np.ndarray, np.ndarray, str]:
        """Key ``times (N,)``, values and interpolation of one animation sampler.

        Values are ``(N, width)``, or ``(N, 3, width)`` (in-tangent, value, out-tangent) for
        CUBICSPLINE; ``width`` is 3 or 4 for node paths and the morph target count for weights.
        """
        samplers = self.gltf.animations[animation_index].samplers or []
        if not isinstance(sampler_index, int) or not 0 <= sampler_index < len(samplers):
            raise self.fail(element, f"refers to sampler {sampler_index!r}, the animation has {len(samplers)}")
        sampler = samplers[sampler_index]
        interpolation = sampler.interpolation or "LINEAR"
        if interpolation not in INTERPOLATIONS:
            raise self.fail(element, f"unknown interpolation {interpolation!r}")
        times = self.accessor(sampler.input, f"{element} input")
        if times.shape[1] != 1 or times.dtype.kind != "f" or times.shape[0] == 0:
            raise self.fail(element, "input must be a non-empty float SCALAR accessor")
        times = times[:, 0]
        steps = np.diff(times)
        if np.any(steps <= 0.0):
            key = int(np.argmax(steps <= 0.0)) + 1
            raise self.fail(element, f"key times are not strictly increasing (at key {key})")
        output = self.accessor(sampler.output, f"{element} output")
        count = times.shape[0]
        per_key = 3 if interpolation == "CUBICSPLINE" else 1
        if output.size != count * per_key * width:
            raise self.fail(element, f"output holds {output.size} numbers, {count} keys x {per_key} x {width} expected")
        return times, output.reshape((count, 3, width) if per_key == 3 else (count, width)), interpolation

    def sampled_channel(self, animation_index: int, channel_index: int, path: str, at: np.ndarray) -> np.ndarray:
        """Channel ``channel_index`` of animation ``animation_index``, which sets a node's ``path``
        (translation, rotation or scale), sampled at the times ``at``: ``(T, 3)`` or ``(T, 4)``."""
        element = f"{self.animation_label(animation_index)} channel {channel_index}"
        sampler = self.gltf.animations[animation_index].channels[channel_index].sampler
        width = 4 if path == "rotation" else 3
        times, values, interpolation = self.sampler_keys(animation_index, sampler, width, element)
        try:
            return sample_keyframes(times, values, interpolation, at, rotation=path == "rotation")
        except ValueError as error:  # a zero or non-finite quaternion among the keys
            raise self.fail(element, str(error)) from None


def _parse(path: str, data: bytes | None = None) -> tuple[pygltflib.GLTF2, dict]:
    """pygltflib's document for a .glb or .gltf file (or its bytes, ``data``) and its raw JSON;
    FormatError for anything else."""
    if data is None:
        try:
            data = Path(path).read_bytes()
        except OSError as error:
            raise FormatError(path, "file", f"cannot read ({error.strerror})") from None
    if not data:
        raise FormatError(path, "file", "empty file")
    glb = data[:4] == _GLB_MAGIC
    json_chunk, binary_chunk = _glb_chunks(path, data) if glb else (data, None)
    if not glb and not re.match(rb"(?:\xef\xbb\xbf)?\s*\{", data):  # a BVH or an OBJ, say: not a syntax error at line 1
        raise FormatError(path, "file", "not a glTF file: neither GLB (magic 'glTF') nor a JSON object")
    # Parsed with bounded nesting (json.loads recurses per level) and checked for the shape the
    # object model would otherwise bend ("nodes": {} is not a list). The object model shares
    # nothing with the raw JSON kept for the writers (decode_gltf copies what it keeps).
    element = "GLB JSON chunk" if glb else "JSON"
    raw = load_json(path, _utf8(path, json_chunk, element), element)
    _check_top_level(path, raw)
    gltf = decode_gltf(path, raw)
    labels_as_text(raw)
    if binary_chunk is not None:
        gltf.set_binary_blob(binary_chunk)
    unsupported = [name for name in gltf.extensionsRequired or [] if not name.startswith(_READABLE_EXTENSIONS)]
    if unsupported:
        raise FormatError(path, "extensionsRequired", f"needs {', '.join(unsupported)}, which animlod cannot read")
    return gltf, raw


# A last row off (0, 0, 0, 1) by more than this (its first three entries times the translation's
# length: their share of w for points that far out) is no rounding: skinning or a node would
# divide positions by a w that is not 1.
_AFFINE_TOLERANCE = 1e-4


def affine_rows(matrices: np.ndarray) -> np.ndarray:
    """``(N,) bool``: whether each of ``matrices (N, 4, 4)`` (row-major, as read) is affine, its
    last row (0, 0, 0, 1) to rounding. A matrix written row-major into glTF's column-major
    storage has its translation there."""
    reach = np.maximum(1.0, np.linalg.norm(matrices[:, :3, 3], axis=-1))
    tilt = np.abs(matrices[:, 3, :3]).max(axis=-1) * reach
    return (tilt <= _AFFINE_TOLERANCE) & (np.abs(matrices[:, 3, 3] - 1.0) <= _AFFINE_TOLERANCE)


def last_row_fault(matrix: np.ndarray) -> str:
    """What is wrong with a ``(4, 4)`` matrix :func:`affine_rows` refuses, for an error message."""
    row = ", ".join(f"{v:.6g}" for v in matrix[3])
    return f"has a last row of ({row}), not (0, 0, 0, 1); written row-major instead of column-major?"


def document_json(path: str | os.PathLike) -> dict:
    """The JSON of a .glb or .gltf file, read without a GLB's binary chunk (what an asset holds,
    told cheaply); FormatError naming the file for what is not a glTF document."""
    path = os.fspath(path)
    try:
        with open(path, "rb") as handle:
            head = handle.read(_GLB_HEADER_BYTES + 8)
            if head[:4] != _GLB_MAGIC:
                data, element = head + handle.read(), "JSON"
            else:
                data, element = handle.read(_glb_json_chunk_length(path, head)), "GLB JSON chunk"
    except OSError as error:
        raise FormatError(path, "file", f"cannot read ({error.strerror})") from None
    document = load_json(path, _utf8(path, data, element), element)
    _check_top_level(path, document)
    return document


def uri_path(document: str | os.PathLike, uri: str) -> Path:
    """The file a buffer's URI names: relative to the document, percent-encoded."""
    return Path(document).parent / unquote(uri)


def image_file(document: str | os.PathLike, uri: str) -> Path | None:
    """The file an image's URI names (see :func:`uri_path`), None if there is none. A URI's
    separator is '/', but Windows exporters write backslashes (``.\\textures\\wood.png``)."""
    for text in dict.fromkeys((uri, uri.replace("\\", "/"))):
        if (path := uri_path(document, text)).is_file():
            return path
    return None


def _utf8(path: str, data: bytes, element: str) -> bytes:
    """``data`` as UTF-8: JSON that is not UTF-8 is read as Latin-1, with a warning. assimp's glTF
    exporter writes names in Latin-1 ("Terraind\xe6k" of its OBJ test set); every byte is a
    Latin-1 character, so such a document parses with its names as they were most likely meant."""
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as error:
        warnings.warn(f"{path}: {element}: not UTF-8 text (byte {error.start}); read as Latin-1", stacklevel=4)
        return data.decode("latin-1").encode("utf-8")
    return data


def _frame_limit(limit: int | None) -> int:
    """The sampling limit: ``limit``, else ANIMLOD_MAX_ANIMATION_FRAMES, else MAX_ANIMATION_FRAMES."""
    if limit is None:
        text = os.environ.get("ANIMLOD_MAX_ANIMATION_FRAMES", "")
        if not text:
            return MAX_ANIMATION_FRAMES
        if not text.isdigit() or int(text) < 1:
            raise ValueError(f"ANIMLOD_MAX_ANIMATION_FRAMES: expected a whole number >= 1, got {text!r}")
        return int(text)
    if isinstance(limit, bool) or not isinstance(limit, int) or limit < 1:
        raise ValueError(f"max_animation_frames: expected a whole number >= 1, got {limit!r}")
    return limit


_UPGRADE_ADVICE = "convert it to glTF 2.0 first: gltf-pipeline, for one, upgrades glTF 0.8 and 1.0 files"


def _check_top_level(path: str, document: Any) -> None:
    """The JSON is an object whose arrays of objects are arrays, and whose scene is an index."""
    if not isinstance(document, dict):
        raise FormatError(path, "JSON", f"the document is a {type(document).__name__}, not an object")
    # Checked first: a glTF 1.0 document has objects where 2.0 has arrays, which would be named
    # as the fault otherwise.
    asset = document.get("asset")
    version = asset.get("version") if isinstance(asset, dict) else None
    if not (isinstance(version, str) and version.startswith("2.")):
        reason = "has no version (glTF 2.0 requires one)" if version is None else f"glTF version {version!r} is not 2.x"
        # Before 1.0 the version was a number (collada2gltf's 0.8, Qt 3D's examples), and
        # collada2gltf wrote 1.0 as the integer 1 (Cesium's CesiumMilkTruck).
        number = isinstance(version, (int, float)) and not isinstance(version, bool)
        if (number and 0 <= version < 2) or (isinstance(version, str) and version.startswith(("0.", "1."))):
            reason += f"; {_UPGRADE_ADVICE}"
        raise FormatError(path, "asset", reason)
    for key in _TOP_LEVEL_ARRAYS:
        if key in document and not isinstance(document[key], list):
            raise FormatError(path, key, f"must be an array, got {type(document[key]).__name__}")
    scene = document.get("scene")
    if scene is not None and (isinstance(scene, bool) or not isinstance(scene, int)):
        raise FormatError(path, "scene", f"must be an index, got {scene!r}")


def _glb_json_chunk_length(path: str, head: bytes) -> int:
    """Check a GLB's header and that its first chunk is the JSON chunk, from the file's first 20
    bytes (``head``); return that chunk's declared length."""
    if len(head) < _GLB_HEADER_BYTES + 8:
        raise FormatError(path, "GLB header", f"file is truncated ({len(head)} bytes)")
    version = struct.unpack_from("<I", head, 4)[0]
    if version != 2:
        advice = f": a glTF 1.0 binary file; {_UPGRADE_ADVICE}" if version == 1 else ""
        raise FormatError(path, "GLB header", f"container version {version} is not 2{advice}")
    chunk_length, chunk_type = struct.unpack_from("<II", head, _GLB_HEADER_BYTES)
    if chunk_type != _GLB_JSON_CHUNK:
        raise FormatError(path, f"GLB chunk at byte {_GLB_HEADER_BYTES}", "the first chunk must be the JSON chunk")
    return chunk_length


def _glb_chunks(path: str, data: bytes) -> tuple[bytes, bytes | None]:
    """Check the GLB header and chunk table; return the JSON chunk's bytes and the first BIN
    chunk's (None without one). Chunks of other types are skipped (glTF 2.0 section 4.4.3)."""
    _glb_json_chunk_length(path, data[: _GLB_HEADER_BYTES + 8])
    length = struct.unpack_from("<I", data, 8)[0]
    if length > len(data):
        raise FormatError(path, "GLB header", f"file is truncated: header says {length} bytes, file has {len(data)}")
    offset = _GLB_HEADER_BYTES
    json_chunk = binary_chunk = None
    while offset < length:
        if offset + 8 > length:
            raise FormatError(path, f"GLB chunk at byte {offset}", "chunk header is truncated")
        chunk_length, chunk_type = struct.unpack_from("<II", data, offset)
        if offset + 8 + chunk_length > length:
            raise FormatError(
                path, f"GLB chunk at byte {offset}", f"declares {chunk_length} bytes, only {length - offset - 8} remain"
            )
        chunk = data[offset + 8 : offset + 8 + chunk_length]
        if json_chunk is None:  # the first chunk, JSON as _glb_json_chunk_length checked
            json_chunk = chunk
        elif chunk_type == _GLB_BIN_CHUNK and binary_chunk is None:
            binary_chunk = chunk
        offset += 8 + chunk_length
    if json_chunk is None:
        raise FormatError(path, "GLB", "no JSON chunk")
    return json_chunk, binary_chunk
