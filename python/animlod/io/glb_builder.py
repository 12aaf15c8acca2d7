"""A glTF document being written as one GLB: its JSON (plain dicts) and its binary chunk.

Either a new document, or a whole input document taken over (:meth:`GlbBuilder.from_document`):
its JSON exactly as parsed (every property, extension and extra; pygltflib's object model
drops some, so the writer works on the JSON itself), every buffer (GLB chunk, data URIs,
external .bin files) gathered into the one binary chunk, and every image with a URI embedded,
so the output stands alone wherever it is written. New data is appended as tightly packed,
4-byte aligned buffer views.
"""

from __future__ import annotations

import base64
import contextlib
import copy
import mimetypes
import os
import struct
import warnings
from pathlib import Path, PurePosixPath, PureWindowsPath
from urllib.parse import quote, unquote, urlsplit

import numpy as np

from .atomic import atomic_write
from .gltf_document import GltfDocument, image_file, uri_path
from .gltf_draco import DRACO_EXTENSION
from .gltf_meshopt import MESHOPT_EXTENSIONS
from .json_limits import finite_json_text

BYTE, UNSIGNED_BYTE, SHORT, UNSIGNED_SHORT, UNSIGNED_INT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
_COMPONENT_TYPES = {
    np.dtype("float32"): FLOAT,
    np.dtype("int8"): BYTE,
    np.dtype("uint8"): UNSIGNED_BYTE,
    np.dtype("int16"): SHORT,
    np.dtype("uint16"): UNSIGNED_SHORT,
    np.dtype("uint32"): UNSIGNED_INT,
}
_ACCESSOR_TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}
_IMAGE_TYPES = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".webp": "image/webp",
                ".ktx2": "image/ktx2", ".dds": "image/vnd-ms.dds", ".avif": "image/avif"}  # fmt: skip
# Leading bytes of the image formats glTF and its extensions embed: (offset, bytes) -> MIME type.
_IMAGE_SIGNATURES = (
    ((0, b"\x89PNG\r\n\x1a\n"), "image/png"),
    ((0, b"\xff\xd8\xff"), "image/jpeg"),
    ((8, b"WEBP"), "image/webp"),
    ((0, b"\xabKTX 20\xbb\r\n\x1a\n"), "image/ktx2"),
    ((0, b"DDS "), "image/vnd-ms.dds"),
    ((4, b"ftypavif"), "image/avif"),
)
_GLB_MAGIC, _GLB_VERSION = b"glTF", 2
# Extensions known not to refer to accessors or buffer views from places prune() does not scan
# (it scans Draco's buffer views and EXT_mesh_gpu_instancing's accessors).
_PRUNE_SAFE_EXTENSIONS = (
    "KHR_materials_", "KHR_texture_", "KHR_lights_", "KHR_mesh_quantization", "KHR_animation_pointer", "MSFT_lod",
    "KHR_xmp", "KHR_node_visibility", DRACO_EXTENSION, "EXT_mesh_gpu_instancing",
)  # fmt: skip
# Extensions known to refer to no mesh by index (KHR_animation_pointer's mesh pointers are looked
# for); an extension unknown here may (VRM 0.x's blend shapes and first-person annotations do).
_NO_MESH_REFERENCES = (*_PRUNE_SAFE_EXTENSIONS, *MESHOPT_EXTENSIONS, "EXT_texture_")
_JSON_CHUNK, _BIN_CHUNK = 0x4E4F534A, 0x004E4942


class GlbBuilder:
    """A glTF document under construction: ``json`` (dicts and lists) and ``blob`` (binary chunk)."""

    def __init__(self, document: dict | None = None, blob: bytes = b"") -> None:
        self.json = document if document is not None else {"asset": {"version": "2.0", "generator": "animlod"}}
        self.blob = bytearray(blob)
        self.overwritten: set[int] = set()  # accessors whose data overwrite() replaced
        # Images kept by a URI relative to the input document (not embedded): index -> the file
        # it names, so that :meth:`save` can refer to it from wherever the output goes.
        self.linked_images: dict[int, Path] = {}

    @classmethod
    def from_document(cls, doc: GltfDocument) -> GlbBuilder:
        """Everything of ``doc``, its buffers gathered into one binary chunk and its images embedded."""
        builder = cls(copy.deepcopy(doc.json))
        views = builder.json.get("bufferViews", [])
        for index, view in enumerate(views):
            data = doc.view_bytes(index, f"bufferView {index}")
            view["buffer"], view["byteOffset"], view["byteLength"] = 0, builder._append(data), len(data)
            # Written decoded: the output needs no meshopt decoder.
            extensions = view.pop("extensions", {})
            for name in MESHOPT_EXTENSIONS:
                extensions.pop(name, None)
            if extensions:
                view["extensions"] = extensions
        for name in MESHOPT_EXTENSIONS:
            _drop_extension(builder.json, name)
        for index, image in enumerate(builder.json.get("images", [])):
            uri = image.get("uri")
            file = None if uri is None or uri.startswith("data:") else image_file(doc.path, uri)
            found = None if uri is None else _image_bytes(doc, index, uri, file)
            if found is None:
                builder._link(doc, index, image, file)
                continue
            data, mime = found
            mime = image_type(data) or image.get("mimeType") or mime
            if mime is None:  # glTF needs the type of an embedded image: it stays as the input had it
                shown = "its data URI" if uri.startswith("data:") else repr(uri)
                warnings.warn(f"{doc.path}: image {index}: {shown} is of no image type glTF knows; "
                              "the output refers to the same file", stacklevel=2)  # fmt: skip
                builder._link(doc, index, image, file)
                continue
            del image["uri"]
            image["bufferView"] = len(views)
            views.append({"buffer": 0, "byteOffset": builder._append(data), "byteLength": len(data)})
            image["mimeType"] = mime
        if views:
            builder.json["bufferViews"] = views
        return builder

    def _link(self, doc: GltfDocument, index: int, image: dict, file: Path | None) -> None:
        """Remember the file ``image`` names when its URI is a path relative to ``doc``: ``file``,
        as :func:`image_file` found it, or where the URI points when it found none."""
        uri = image.get("uri", "")
        text = unquote(uri)
        if not uri or urlsplit(uri).scheme or PurePosixPath(text).anchor or PureWindowsPath(text).anchor:
            return  # a data URI, a URL or an absolute path: the same from anywhere
        named = file or uri_path(doc.path, uri.replace("\\", "/"))
        self.linked_images[index] = Path(os.path.abspath(named))

    def _append(self, data: bytes) -> int:
        """Appends ``data`` at the next 4-byte boundary; its offset."""
        self.blob.extend(b"\0" * (-len(self.blob) % 4))
        offset = len(self.blob)
        self.blob.extend(data)
        return offset

    def append(self, kind: str, item: dict) -> int:
        """Appends ``item`` to the top-level array ``kind`` (e.g. "nodes"); its index."""
        items = self.json.setdefault(kind, [])
        items.append(item)
        return len(items) - 1

    def add(self, values: np.ndarray, target: int | None = None, bounds: bool = False, normalized: bool = False) -> int:
        """Append ``values (count, width)`` as a tightly packed buffer view and accessor; its index.

        ``bounds`` records min and max, which glTF requires for POSITION and animation inputs;
        ``normalized`` marks integer values that stand for [0, 1] or [-1, 1].
        """
        values = np.ascontiguousarray(values)
        count, width = values.shape
        offset = self._append(values.astype(values.dtype.newbyteorder("<")).tobytes())
        view = {"buffer": 0, "byteOffset": offset, "byteLength": values.nbytes}
        if target is not None:
            view["target"] = target
        accessor = {
            "bufferView": self.append("bufferViews", view),
            "componentType": _COMPONENT_TYPES[values.dtype],
            "count": count,
            "type": _ACCESSOR_TYPES[width],
        }
        if normalized:
            accessor["normalized"] = True
        if bounds:
            accessor["min"] = values.min(axis=0).tolist()
            accessor["max"] = values.max(axis=0).tolist()
        return self.append("accessors", accessor)

    def overwrite(self, index: int, values: np.ndarray) -> bool:
        """Writes float32 ``values (count, width)`` over accessor ``index``'s own data when it is a
        float accessor of that shape with a buffer view, not sparse, and used once in the
        document: a rewritten attribute then leaves no unused accessor and data behind, and every
        index stays as it was. False (nothing written) otherwise."""
        accessors = self.json.get("accessors", [])
        accessor = accessors[index] if 0 <= index < len(accessors) else {}
        count, width = values.shape
        shape = (accessor.get("componentType"), accessor.get("type"), accessor.get("count"))
        if shape != (FLOAT, _ACCESSOR_TYPES.get(width), count) or "sparse" in accessor or "bufferView" not in accessor:
            return False
        if sum(holder[key] == index for holder, key in _accessor_references(self.json)) != 1:  # used elsewhere too
            return False
        view = self.json["bufferViews"][accessor["bufferView"]]
        start = view.get("byteOffset", 0) + accessor.get("byteOffset", 0)
        stride = view.get("byteStride", 4 * width)
        np.ndarray((count, width), "<f4", buffer=self.blob, offset=start, strides=(stride, 4))[...] = values
        if "min" in accessor or "max" in accessor:
            accessor["min"], accessor["max"] = values.min(axis=0).tolist(), values.max(axis=0).tolist()
        self.overwritten.add(index)
        return True

    def prune(self) -> None:
        """Drops meshes no node draws (all kept when an animation points at a mesh by index, through
        KHR_animation_pointer, or an extension that may refer to meshes is used); then, when no
        extension could refer to them unseen, the accessors and buffer views nothing refers to, and
        repacks the binary chunk."""
        js = self.json
        nodes = js.get("nodes", [])
        kept_meshes = sorted({node["mesh"] for node in nodes if "mesh" in node})
        may_name_meshes = any(not name.startswith(_NO_MESH_REFERENCES) for name in js.get("extensionsUsed", []))
        if _animates_meshes(js) or may_name_meshes:
            kept_meshes = list(range(len(js.get("meshes", []))))
        new_mesh = {old: new for new, old in enumerate(kept_meshes)}
        for node in nodes:
            if "mesh" in node:
                node["mesh"] = new_mesh[node["mesh"]]
        if "meshes" in js:
            js["meshes"] = [js["meshes"][old] for old in kept_meshes]
        primitives = [p for mesh in js.get("meshes", []) for p in mesh.get("primitives", [])]
        if not any(DRACO_EXTENSION in p.get("extensions", {}) for p in primitives):
            _drop_extension(js, DRACO_EXTENSION)  # the compressed meshes were the input's, now replaced
        if any(not name.startswith(_PRUNE_SAFE_EXTENSIONS) for name in js.get("extensionsUsed", [])):
            return  # read after the Draco drop: Draco no longer named is no reason to stop
        accessor_refs = list(_accessor_references(js))
        kept_accessors = sorted({holder[key] for holder, key in accessor_refs})
        new_accessor = {old: new for new, old in enumerate(kept_accessors)}
        for holder, key in accessor_refs:
            holder[key] = new_accessor[holder[key]]
        js["accessors"] = [js["accessors"][old] for old in kept_accessors]
        view_refs = [(a, "bufferView") for a in js["accessors"] if "bufferView" in a]
        for accessor in js["accessors"]:
            sparse = accessor.get("sparse", {})
            view_refs += [(sparse[part], "bufferView") for part in ("indices", "values") if part in sparse]
        view_refs += [(image, "bufferView") for image in js.get("images", []) if "bufferView" in image]
        draco = (p.get("extensions", {}).get(DRACO_EXTENSION) for m in js.get("meshes", []) for p in m["primitives"])
        view_refs += [(compressed, "bufferView") for compressed in draco if compressed and "bufferView" in compressed]
        kept_views = sorted({holder[key] for holder, key in view_refs})
        old_views, old_blob = js.get("bufferViews", []), bytes(self.blob)
        self.blob = bytearray()
        new_views = []
        for old in kept_views:
            view = dict(old_views[old])
            start = view.get("byteOffset", 0)
            view["byteOffset"] = self._append(old_blob[start : start + view["byteLength"]])
            new_views.append(view)
        new_view = {old: new for new, old in enumerate(kept_views)}
        for holder, key in view_refs:
            holder[key] = new_view[holder[key]]
        js["bufferViews"] = new_views

    def add_extension_used(self, name: str) -> None:
        used = self.json.setdefault("extensionsUsed", [])
        if name not in used:
            used.append(name)

    def to_bytes(self) -> bytes:
        """The GLB file (glTF 2.0 section 4.4): header, JSON chunk, binary chunk."""
        self.blob.extend(b"\0" * (-len(self.blob) % 4))
        if self.blob:
            self.json["buffers"] = [{"byteLength": len(self.blob)}]
        else:
            self.json.pop("buffers", None)
        text = finite_json_text(self.json, separators=(",", ":"), ensure_ascii=False).encode("utf-8")
        text += b" " * (-len(text) % 4)
        chunks = struct.pack("<II", len(text), _JSON_CHUNK) + text
        if self.blob:
            chunks += struct.pack("<II", len(self.blob), _BIN_CHUNK) + bytes(self.blob)
        return _GLB_MAGIC + struct.pack("<II", _GLB_VERSION, 12 + len(chunks)) + chunks

    def save(self, path: str | os.PathLike) -> None:
        """Writes the GLB atomically: ``path`` appears only once complete. An image kept by a
        relative URI is referred to from ``path``'s folder (written elsewhere than the input, the
        URI as the input had it named no file)."""
        folder = os.path.abspath(Path(path).parent)
        for index, linked in self.linked_images.items():
            self.json["images"][index]["uri"] = quote(Path(os.path.relpath(linked, folder)).as_posix())
        data = self.to_bytes()
        with atomic_write(path, "wb") as handle:
            handle.write(data)


def _accessor_references(js: dict):
    """(holder, key) of every accessor index the core glTF 2.0 schema places."""
    for mesh in js.get("meshes", []):
        for primitive in mesh.get("primitives", []):
            attributes = primitive.get("attributes", {})
            yield from ((attributes, name) for name in attributes)
            if "indices" in primitive:
                yield primitive, "indices"
            for target in primitive.get("targets", []):
                yield from ((target, name) for name in target)
    for skin in js.get("skins", []):
        if "inverseBindMatrices" in skin:
            yield skin, "inverseBindMatrices"
    for animation in js.get("animations", []):
        for sampler in animation.get("samplers", []):
            yield sampler, "input"
            yield sampler, "output"
    for node in js.get("nodes", []):
        instances = (node.get("extensions") or {}).get("EXT_mesh_gpu_instancing", {}).get("attributes", {})
        yield from ((instances, name) for name in instances)


def _drop_extension(js: dict, name: str) -> None:
    """``name`` out of the document's extensionsUsed and extensionsRequired."""
    for listed in ("extensionsUsed", "extensionsRequired"):
        if name in js.get(listed, []):
            js[listed].remove(name)
            if not js[listed]:
                del js[listed]


def _animates_meshes(js: dict) -> bool:
    """Whether a KHR_animation_pointer channel names a mesh (``/meshes/<index>/weights``)."""
    targets = (channel.get("target", {}) for a in js.get("animations", []) for channel in a.get("channels", []))
    pointers = ((target.get("extensions") or {}).get("KHR_animation_pointer") for target in targets)
    return any(isinstance(p, dict) and str(p.get("pointer", "")).startswith("/meshes/") for p in pointers)


def image_type(data: bytes) -> str | None:
    """The MIME type of an image by its leading bytes (PNG, JPEG, WebP, KTX2, DDS, AVIF), or None.
    Files say what they are better than their names: exporters write PNG data as ``.jpg``, and
    texture names without a suffix."""
    for (offset, signature), mime in _IMAGE_SIGNATURES:
        if data[offset : offset + len(signature)] == signature:
            return mime
    return None


def _image_bytes(doc: GltfDocument, index: int, uri: str, file: Path | None) -> tuple[bytes, str | None] | None:
    """The bytes and MIME type of an image given by a data URI or a file next to the document
    (``file``, as :func:`image_file` found it for ``uri``); None, with a warning, for a file
    that is not there. Textures left behind are common (a path on the author's machine,
    ``C:\\Users\\...\\wood.jpg``, or a file not shipped) and play no part in the levels: the
    image keeps its URI, as the input had it, instead of failing the run."""
    if uri.startswith("data:"):
        header, _, payload = uri.partition(",")
        try:
            return base64.b64decode(payload, validate=True), header[5:].split(";")[0] or None
        except ValueError as error:
            raise doc.fail(f"image {index}", f"malformed data URI ({error})") from None
    if file is not None:
        with contextlib.suppress(OSError):  # there but unreadable: kept by its URI as a missing one is
            guess = _IMAGE_TYPES.get(file.suffix.lower()) or mimetypes.guess_type(file.name)[0] or ""
            return file.read_bytes(), guess if guess.startswith("image/") else None  # not .tex's text/x-tex
    missing = uri_path(doc.path, uri.replace("\\", "/"))
    warnings.warn(f"{doc.path}: image {index}: {missing} not found; the output refers to where the input's "
                  f"{uri!r} does", stacklevel=3)  # fmt: skip
    return None
