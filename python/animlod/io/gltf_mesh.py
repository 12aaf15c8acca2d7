"""Geometry of a glTF mesh: its triangle primitives merged into one vertex set.

Each primitive is read into a :class:`MeshGeometry` (node-local space) and the primitives of a
mesh are concatenated, their indices offset. Attributes only some primitives have (NORMAL,
TEXCOORD_0) are dropped rather than invented; skinning sets JOINTS_0/WEIGHTS_0 and, for 8
influences, JOINTS_1/WEIGHTS_1 are required on every primitive of a skinned mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pygltflib

from .gltf_document import GltfDocument

_TRIANGLES, _TRIANGLE_STRIP, _TRIANGLE_FAN = 4, 5, 6
_INFLUENCE_SETS = (0, 1)


@dataclass
class MeshGeometry:
    """Vertices and triangles of a glTF mesh in its node's local space.

    Attributes
    ----------
    positions : (V, 3) float32.
    faces : (M, 3) int64 triangles, counter-clockwise.
    normals : (V, 3) or None (None unless every primitive has NORMAL).
    uvs : (V, 2) or None (TEXCOORD_0).
    joints : (V, K) skin joint slots (indices into ``skin.joints``), K = 4 or 8; None unskinned.
    weights : (V, K) skin weights as stored (not yet normalised), or None.
    targets : (N, V, 3) morph target position deltas, or None.
    target_names : N names from ``mesh.extras.targetNames``, or None.
    default_weights : (N,) morph weights of the mesh, or None.
    """

    positions: np.ndarray
    faces: np.ndarray
    normals: np.ndarray | None
    uvs: np.ndarray | None
    joints: np.ndarray | None
    weights: np.ndarray | None
    targets: np.ndarray | None
    target_names: list[str] | None = None
    default_weights: np.ndarray | None = None


def read_mesh_geometry(doc: GltfDocument, mesh_index: int, skinned: bool) -> MeshGeometry:
    """All triangle primitives of mesh ``mesh_index`` merged; ``skinned`` requires skin weights."""
    element = f"mesh {mesh_index}"
    mesh = doc.item("meshes", mesh_index, element)
    if not mesh.primitives:
        raise doc.fail(element, "has no primitives")
    parts = [_read_primitive(doc, f"{element} primitive {k}", p, skinned) for k, p in enumerate(mesh.primitives)]
    target_counts = sorted({len(part.targets) for part in parts})
    if len(target_counts) > 1:
        raise doc.fail(element, f"primitives have different numbers of morph targets {target_counts}")
    target_count = target_counts[0]
    starts = np.cumsum([0] + [len(part.positions) for part in parts])
    names = mesh.extras.get("targetNames") if isinstance(mesh.extras, dict) else None
    names_fit = isinstance(names, list) and len(names) == target_count > 0
    defaults = np.asarray(mesh.weights if mesh.weights else np.zeros(target_count), np.float64)
    if defaults.shape != (target_count,):
        raise doc.fail(element, f"has {defaults.size} default weights for {target_count} morph targets")
    return MeshGeometry(
        positions=np.concatenate([part.positions for part in parts]),
        faces=np.concatenate([part.faces + start for part, start in zip(parts, starts)]),
        normals=_concatenate_if_all([part.normals for part in parts]),
        uvs=_concatenate_if_all([part.uvs for part in parts]),
        joints=_concatenate_padded([part.joints for part in parts]) if skinned else None,
        weights=_concatenate_padded([part.weights for part in parts]) if skinned else None,
        targets=np.concatenate([part.targets for part in parts], axis=1) if target_count else None,
        target_names=[str(n) for n in names] if names_fit else None,
        default_weights=defaults if target_count else None,
    )


def transform_points(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points ``(..., 3)`` under the affine ``matrix (4, 4)``."""
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def transform_normals(matrix: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Normals ``(V, 3)`` under the inverse transpose of ``matrix``'s linear part, renormalised."""
    turned = normals @ np.linalg.inv(matrix[:3, :3])
    length = np.linalg.norm(turned, axis=1, keepdims=True)
    return turned / np.where(length > 0.0, length, 1.0)  # a zero normal stays zero


def _read_primitive(doc: GltfDocument, element: str, primitive: pygltflib.Primitive, skinned: bool) -> MeshGeometry:
    attributes = primitive.attributes
    positions = _attribute(doc, attributes, "POSITION", 3, element, required=True)
    count = len(positions)
    joints = weights = None
    if skinned:
        sets = [s for s in _INFLUENCE_SETS if getattr(attributes, f"JOINTS_{s}", None) is not None]
        if 0 not in sets:
            raise doc.fail(element, "a skinned mesh primitive needs JOINTS_0 and WEIGHTS_0")
        joints = np.concatenate(
            [_attribute(doc, attributes, f"JOINTS_{s}", 4, element, required=True, integer=True) for s in sets], axis=1
        )
        weights = np.concatenate(
            [_attribute(doc, attributes, f"WEIGHTS_{s}", 4, element, required=True) for s in sets], axis=1
        )
    return MeshGeometry(
        positions=positions,
        faces=_primitive_faces(doc, primitive, count, element),
        normals=_attribute(doc, attributes, "NORMAL", 3, element),
        uvs=_attribute(doc, attributes, "TEXCOORD_0", 2, element),
        joints=joints,
        weights=weights,
        targets=_morph_targets(doc, primitive, count, element),
    )


def _attribute(
    doc: GltfDocument, attributes, name: str, width: int, element: str, required: bool = False, integer: bool = False
) -> np.ndarray | None:
    """Vertex attribute ``name`` as ``(V, width)``; None when absent and not ``required``."""
    index = getattr(attributes, name, None)
    if index is None:
        if required:
            raise doc.fail(element, f"has no {name} attribute")
        return None
    values = doc.accessor(index, f"{element} {name}")
    if values.shape[1] != width or (integer and values.dtype.kind == "f"):
        kind = "integer " if integer else ""
        raise doc.fail(f"{element} {name}", f"expected {kind}width {width}, got {values.dtype} width {values.shape[1]}")
    vertex_count = doc.gltf.accessors[attributes.POSITION].count
    if len(values) != vertex_count:
        raise doc.fail(f"{element} {name}", f"has {len(values)} elements, POSITION has {vertex_count}")
    return values


def _morph_targets(doc: GltfDocument, primitive: pygltflib.Primitive, count: int, element: str) -> np.ndarray:
    """Position deltas ``(N, V, 3)`` of the primitive's targets (zeros for a target without POSITION)."""
    targets = np.zeros((len(primitive.targets or []), count, 3), np.float32)
    for t, target in enumerate(primitive.targets or []):
        index = target.get("POSITION") if isinstance(target, dict) else getattr(target, "POSITION", None)
        if index is not None:
            delta = doc.accessor(index, f"{element} target {t} POSITION")
            if delta.shape != (count, 3):
                raise doc.fail(f"{element} target {t} POSITION", f"expected {count} VEC3, got shape {delta.shape}")
            targets[t] = delta
    return targets


def _primitive_faces(doc: GltfDocument, primitive: pygltflib.Primitive, vertex_count: int, element: str) -> np.ndarray:
    """Triangles ``(M, 3)`` of a TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive (glTF 2.0, 3.7.2.1)."""
    mode = _TRIANGLES if primitive.mode is None else primitive.mode
    if mode not in (_TRIANGLES, _TRIANGLE_STRIP, _TRIANGLE_FAN):
        raise doc.fail(element, f"mode {mode} (points or lines) is not a triangle mesh")
    if primitive.indices is None:
        indices = np.arange(vertex_count, dtype=np.int64)
    else:
        raw = doc.accessor(primitive.indices, f"{element} indices")
        if raw.shape[1] != 1 or raw.dtype.kind == "f":
            raise doc.fail(f"{element} indices", "must be an unsigned integer SCALAR accessor")
        indices = raw[:, 0].astype(np.int64)
    if indices.size and indices.max() >= vertex_count:
        at = int(np.argmax(indices >= vertex_count))
        reason = f"index {int(indices[at])} at position {at} is outside [0, {vertex_count})"
        raise doc.fail(f"{element} indices", reason)
    if mode == _TRIANGLES:
        if indices.size % 3:
            raise doc.fail(f"{element} indices", f"{indices.size} indices do not make whole triangles")
        return indices.reshape(-1, 3)
    i = np.arange(max(indices.size - 2, 0))
    if mode == _TRIANGLE_STRIP:  # every other triangle swaps two corners to stay counter-clockwise
        odd = i % 2
        return np.stack([indices[i], indices[i + 1 + odd], indices[i + 2 - odd]], axis=1)
    return np.stack([indices[i + 1], indices[i + 2], np.full_like(i, indices[0] if indices.size else 0)], axis=1)


def _concatenate_if_all(parts: list[np.ndarray | None]) -> np.ndarray | None:
    return None if any(part is None for part in parts) else np.concatenate(parts)


def _concatenate_padded(parts: list[np.ndarray]) -> np.ndarray:
    """Influence columns of all primitives, padded with zeros to the widest (4 or 8)."""
    width = max(part.shape[1] for part in parts)
    return np.concatenate([np.pad(part, ((0, 0), (0, width - part.shape[1]))) for part in parts])
