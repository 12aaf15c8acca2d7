"""EXT_meshopt_compression and KHR_meshopt_compression: buffer views stored compressed by
meshoptimizer's codecs (gltfpack writes them, usually with KHR_mesh_quantization), decoded with
meshoptimizer's Python package. The KHR extension adds version 1 of the vertex codec, which the
decoder reads from the data's header, and a colour filter, which the package does not decode.

The extension on a buffer view names where the compressed bytes are (its own buffer, byte offset
and length), how many elements of which stride they decode to, the codec (``mode``: vertex
attributes, triangle indices or an index sequence) and a filter that then turns the decoded
integers into normals, quaternions or floats. The decoded bytes take the place of the view's own
data, which lives in a fallback buffer with no bytes or duplicates them uncompressed.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .gltf_decode import is_whole_number

MESHOPT_EXTENSIONS = ("EXT_meshopt_compression", "KHR_meshopt_compression")
# Builds the error to raise from (element, reason): the document's FormatError.
Fail = Callable[[str, str], Exception]
_MODES = ("ATTRIBUTES", "TRIANGLES", "INDICES")
_FILTERS = ("NONE", "OCTAHEDRAL", "QUATERNION", "EXPONENTIAL")


def meshopt_extension(extensions: object) -> tuple[str, object] | None:
    """(name, value) of the meshopt extension among a buffer view's ``extensions``, if any."""
    if not isinstance(extensions, dict):
        return None
    return next(((name, extensions[name]) for name in MESHOPT_EXTENSIONS if name in extensions), None)


def decode_meshopt_view(extension: object, compressed: bytes, element: str, fail: Fail, limit: int) -> bytes:
    """The ``count * byteStride`` bytes that a buffer view's meshopt ``extension`` (``element``
    names both) decodes to, from its ``compressed`` bytes; ``fail``'s error for a malformed
    extension or data, or for more than ``limit`` bytes (a few bytes of zeros can claim gigabytes)."""
    import meshoptimizer  # only files that use the extension need it

    if not isinstance(extension, dict):
        raise fail(element, "must be an object")
    count, stride = extension.get("count"), extension.get("byteStride")
    mode, filter_name = extension.get("mode"), extension.get("filter", "NONE")
    if not (is_whole_number(count) and is_whole_number(stride) and 0 < stride <= 256):
        raise fail(element, "needs a count and a byteStride in (0, 256]")
    if filter_name == "COLOR":
        raise fail(element, "filter 'COLOR' is not decoded by the meshoptimizer package animlod uses")
    if mode not in _MODES or filter_name not in _FILTERS:
        raise fail(element, f"mode {mode!r} or filter {filter_name!r} is not defined")
    if count * stride > limit:
        reason = f"claims {count} x {stride} bytes, more than the file can justify ({limit})"
        raise fail(element, reason)
    if (mode == "ATTRIBUTES" and stride % 4) or (mode != "ATTRIBUTES" and stride not in (2, 4)):
        raise fail(element, f"byteStride {stride} does not suit mode {mode}")
    decode = {
        "ATTRIBUTES": meshoptimizer.decode_vertex_buffer,
        "TRIANGLES": meshoptimizer.decode_index_buffer,
        "INDICES": meshoptimizer.decode_index_sequence,
    }[mode]
    try:
        decoded = np.asarray(decode(count, stride, bytes(compressed))).tobytes()[: count * stride]
        if filter_name != "NONE":
            apply = {
                "OCTAHEDRAL": meshoptimizer.decode_filter_oct,
                "QUATERNION": meshoptimizer.decode_filter_quat,
                "EXPONENTIAL": meshoptimizer.decode_filter_exp,
            }[filter_name]
            decoded = np.asarray(apply(np.frombuffer(decoded, np.uint8).copy(), count, stride)).tobytes()
    except (ValueError, RuntimeError) as error:
        raise fail(element, f"the data does not decode ({error})") from None
    if len(decoded) != count * stride:
        raise fail(element, f"decodes to {len(decoded)} bytes, not {count} x {stride}")
    return decoded
