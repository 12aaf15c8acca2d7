"""Geometry of a glTF mesh: its triangle primitives, each whole, and merged into one vertex set.

Each triangle primitive is read with every vertex attribute and morph target it has
(:class:`PrimitiveGeometry`, node-local space); the primitives of a mesh are then concatenated,
their indices offset, with a primitive index per face (:class:`MeshGeometry`). Points and lines
primitives are listed, not read: animlod leaves them as they are. Merged attributes only some
primitives have (NORMAL, TEXCOORD_0) are dropped rather than invented; skinning sets
JOINTS_0/WEIGHTS_0 and, for 8 influences, JOINTS_1/WEIGHTS_1 are required on every primitive of
a skinned mesh.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np
import pygltflib

from .gltf_document import GltfDocument

TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN = 4, 5, 6
_TRIANGLE_MODES = (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN)
_INFLUENCE_SETS = (0, 1)
# A transform whose 3x3 part has a smaller determinant has no inverse (a node at zero scale).
SINGULAR_DETERMINANT = 1e-30
# Widths glTF 2.0 allows for the attributes animlod interprets (section 3.7.2.1); others
# (custom _ATTRIBUTES) are carried with their accessor's own width.
_ATTRIBUTE_WIDTHS = {"POSITION": 3, "NORMAL": 3, "TANGENT": 4}


@dataclass
class PrimitiveGeometry:
    """One triangle primitive as stored, decoded.

    Attributes
    ----------
    index : the primitive's index in ``mesh.primitives``.
    attributes : every vertex attribute by glTF name, ``(n, width)``: float32 (normalised
        integers decoded to [0, 1] or [-1, 1]), integer arrays for JOINTS_n.
    faces : (m, 3) int64 counter-clockwise triangles (strips and fans converted), local indices.
    targets : per morph target, its attributes by name (``POSITION``, ``NORMAL``, ``TANGENT``
        deltas), ``(n, width)`` float32.
    """

    index: int
    attributes: dict[str, np.ndarray]
    faces: np.ndarray
    targets: list[dict[str, np.ndarray]] = field(default_factory=list)

    @property
    def vertex_count(self) -> int:
        return int(self.attributes["POSITION"].shape[0])


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
    target_names : N names from ``mesh.extras.targetNames`` (or, as UniVRM writes them, the first
        triangle primitive's ``extras.targetNames``), or None.
    default_weights : (N,) morph weights of the mesh, or None.
    face_groups : (M,) int32 position in ``primitives`` of the primitive of each face.
    primitives : the triangle primitives, in mesh order; their vertices follow one another.
    other_primitives : indices of the points and lines primitives, which were not read.
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
    face_groups: np.ndarray | None = None
    primitives: list[PrimitiveGeometry] = field(default_factory=list)
    other_primitives: list[int] = field(default_factory=list)

    @property
    def vertex_starts(self) -> np.ndarray:
        """(P + 1,) first vertex of each primitive in the merged arrays, then V."""
        return np.cumsum([0] + [primitive.vertex_count for primitive in self.primitives])


def read_mesh_geometry(doc: GltfDocument, mesh_index: int, skinned: bool) -> MeshGeometry:
    """All triangle primitives of mesh ``mesh_index`` merged; ``skinned`` requires skin weights."""
    element = f"mesh {mesh_index}"
    mesh = doc.item("meshes", mesh_index, element)
    if not mesh.primitives:
        raise doc.fail(element, "has no primitives")
    parts, others = [], []
    for k, primitive in enumerate(mesh.primitives):
        mode = TRIANGLES if primitive.mode is None else primitive.mode
        if mode in _TRIANGLE_MODES:
            parts.append(_read_primitive(doc, f"{element} primitive {k}", k, primitive, skinned))
        elif mode in range(4):
            others.append(k)
        else:
            raise doc.fail(f"{element} primitive {k}", f"unknown mode {mode!r}")
    if not parts:
        raise doc.fail(element, "has no triangle primitive (only points or lines)")
    target_counts = sorted({len(part.targets) for part in parts})
    if len(target_counts) > 1:
        raise doc.fail(element, f"primitives have different numbers of morph targets {target_counts}")
    target_count = target_counts[0]
    starts = np.cumsum([0] + [part.vertex_count for part in parts])
    names = _target_names(mesh.extras, target_count)
    if names is None:  # UniVRM puts them on each primitive
        names = _target_names(mesh.primitives[parts[0].index].extras, target_count)
    defaults = np.asarray(mesh.weights if mesh.weights else np.zeros(target_count), np.float64)
    if defaults.shape != (target_count,):
        raise doc.fail(element, f"has {defaults.size} default weights for {target_count} morph targets")
    influence_sets = [s for s in _INFLUENCE_SETS if any(f"JOINTS_{s}" in part.attributes for part in parts)]
    return MeshGeometry(
        positions=np.concatenate([part.attributes["POSITION"] for part in parts]),
        faces=np.concatenate([part.faces + start for part, start in zip(parts, starts)]),
        normals=_concatenate_if_all([part.attributes.get("NORMAL") for part in parts]),
        uvs=_concatenate_if_all([part.attributes.get("TEXCOORD_0") for part in parts]),
        joints=_influences(parts, "JOINTS", influence_sets) if skinned else None,
        weights=_influences(parts, "WEIGHTS", influence_sets) if skinned else None,
        targets=_position_deltas(parts, target_count),
        target_names=names,
        default_weights=defaults if target_count else None,
        face_groups=np.concatenate([np.full(len(part.faces), k, np.int32) for k, part in enumerate(parts)]),
        primitives=parts,
        other_primitives=others,
    )


def _target_names(extras: object, target_count: int) -> list[str] | None:
    """``extras.targetNames`` when it names each of the ``target_count`` morph targets."""
    names = extras.get("targetNames") if isinstance(extras, dict) else None
    return [str(name) for name in names] if isinstance(names, list) and len(names) == target_count > 0 else None


def transform_points(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points ``(..., 3)`` under the affine ``matrix (4, 4)``."""
    return points @ matrix[:3, :3].T + matrix[:3, 3]


def transform_normals(matrix: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Normals ``(V, 3)`` under the inverse transpose of ``matrix``'s linear part, renormalised."""
    turned = normals @ np.linalg.inv(matrix[:3, :3])
    length = np.linalg.norm(turned, axis=1, keepdims=True)
    return turned / np.where(length > 0.0, length, 1.0)  # a zero normal stays zero


def transform_tangents(matrix: np.ndarray, tangents: np.ndarray) -> np.ndarray:
    """glTF tangents ``(V, 4)`` under ``matrix``'s linear part: xyz turned with the surface and
    renormalised, w (the bitangent's side) flipped where the matrix mirrors."""
    linear = matrix[:3, :3]
    turned = tangents[:, :3] @ linear.T
    length = np.linalg.norm(turned, axis=1, keepdims=True)
    side = tangents[:, 3:] * np.sign(np.linalg.det(linear))
    return np.concatenate([turned / np.where(length > 0.0, length, 1.0), side], axis=1).astype(np.float32)


def _read_primitive(
    doc: GltfDocument, element: str, index: int, primitive: pygltflib.Primitive, skinned: bool
) -> PrimitiveGeometry:
    attribute_names = [name for name, value in vars(primitive.attributes).items() if value is not None]
    if "POSITION" not in attribute_names:
        raise doc.fail(element, "has no POSITION attribute")
    count = doc.accessor(primitive.attributes.POSITION, f"{element} POSITION").shape[0]
    attributes = {name: _attribute(doc, primitive.attributes, name, count, element) for name in attribute_names}
    if skinned and ("JOINTS_0" not in attributes or "WEIGHTS_0" not in attributes):
        raise doc.fail(element, "a skinned mesh primitive needs JOINTS_0 and WEIGHTS_0")
    for s in _INFLUENCE_SETS:
        if (f"JOINTS_{s}" in attributes) != (f"WEIGHTS_{s}" in attributes):
            raise doc.fail(element, f"has only one of JOINTS_{s} and WEIGHTS_{s}")
    return _referenced_only(
        PrimitiveGeometry(
            index=index,
            attributes=attributes,
            faces=_primitive_faces(doc, primitive, count, element),
            targets=_morph_targets(doc, primitive, count, element),
        )
    )


def _referenced_only(primitive: PrimitiveGeometry) -> PrimitiveGeometry:
    """The primitive without the vertices its triangles do not use. Exporters that share one
    vertex buffer among a mesh's primitives (UniVRM's VRM avatars: one per material) give each
    primitive every vertex of the mesh; kept, they were skinned, posed and welded once per
    primitive (an 8-primitive Soldier took twice as long to simplify)."""
    used = np.zeros(primitive.vertex_count, bool)
    used[primitive.faces] = True
    if used.all():
        return primitive
    new_index = np.cumsum(used) - 1
    return PrimitiveGeometry(
        index=primitive.index,
        attributes={name: values[used] for name, values in primitive.attributes.items()},
        faces=new_index[primitive.faces],
        targets=[{name: delta[used] for name, delta in target.items()} for target in primitive.targets],
    )


def _attribute(doc: GltfDocument, attributes, name: str, vertex_count: int, element: str) -> np.ndarray:
    """Vertex attribute ``name`` as ``(V, width)``, checked against what glTF allows for it."""
    values = doc.accessor(getattr(attributes, name), f"{element} {name}")
    where = f"{element} {name}"
    width = _ATTRIBUTE_WIDTHS.get(name)
    if name.startswith("TEXCOORD_") and values.shape[1] == 3:
        # glTF's texture coordinates are VEC2, but assimp's exporter writes a source's (u, v, w)
        # as they were (its Collada and OBJ test models): u and v are what a renderer samples.
        warnings.warn(f"{doc.path}: {where}: VEC3, which glTF does not allow; the levels keep u and v", stacklevel=5)
        values = values[:, :2]
    if name.startswith("TEXCOORD_"):
        width = 2
    elif name.startswith(("JOINTS_", "WEIGHTS_", "COLOR_")):
        width = values.shape[1] if name.startswith("COLOR_") and values.shape[1] in (3, 4) else 4
    if width is not None and values.shape[1] != width:
        raise doc.fail(where, f"expected width {width}, got {values.shape[1]}")
    if name.startswith("JOINTS_") and values.dtype.kind == "f":
        raise doc.fail(where, f"expected unsigned integers, got {values.dtype}")
    if len(values) != vertex_count:
        raise doc.fail(where, f"has {len(values)} elements, POSITION has {vertex_count}")
    return values


def _morph_targets(doc: GltfDocument, primitive: pygltflib.Primitive, count: int, element: str) -> list[dict]:
    """Per target, its deltas by attribute name (``POSITION``, ``NORMAL``, ``TANGENT``)."""
    targets = []
    for t, target in enumerate(primitive.targets or []):
        items = target.items() if isinstance(target, dict) else vars(target).items()
        deltas = {}
        for name, index in items:
            if index is None:
                continue
            delta = doc.accessor(index, f"{element} target {t} {name}")
            width = 3 if name in ("POSITION", "NORMAL", "TANGENT") else delta.shape[1]
            if delta.shape != (count, width):
                raise doc.fail(f"{element} target {t} {name}", f"expected {count} VEC{width}, got shape {delta.shape}")
            # KHR_mesh_quantization stores deltas as plain BYTE or SHORT too, in the units the
            # node's scale turns into positions, as its POSITION.
            deltas[name] = delta.astype(np.float32, copy=False)
        targets.append(deltas)
    return targets


def _primitive_faces(doc: GltfDocument, primitive: pygltflib.Primitive, vertex_count: int, element: str) -> np.ndarray:
    """Triangles ``(M, 3)`` of a TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive (glTF 2.0, 3.7.2.1)."""
    mode = TRIANGLES if primitive.mode is None else primitive.mode
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
    if mode == TRIANGLES:
        if indices.size % 3:
            raise doc.fail(f"{element} indices", f"{indices.size} indices do not make whole triangles")
        return indices.reshape(-1, 3)
    i = np.arange(max(indices.size - 2, 0))
    if mode == TRIANGLE_STRIP:  # every other triangle swaps two corners to stay counter-clockwise
        odd = i % 2
        return np.stack([indices[i], indices[i + 1 + odd], indices[i + 2 - odd]], axis=1)
    return np.stack([indices[i + 1], indices[i + 2], np.full_like(i, indices[0] if indices.size else 0)], axis=1)


def _concatenate_if_all(parts: list[np.ndarray | None]) -> np.ndarray | None:
    return None if any(part is None for part in parts) else np.concatenate(parts)


def _influences(parts: list[PrimitiveGeometry], kind: str, sets: list[int]) -> np.ndarray | None:
    """JOINTS or WEIGHTS columns of the influence sets any primitive has, merged; a primitive
    without a set gets zero weights there (4 influences padded to 8)."""
    if not sets:
        return None

    # Joint slots stay integers: float padding would turn the merged JOINTS into floats.
    padding = np.uint8 if kind == "JOINTS" else np.float32

    def columns(part: PrimitiveGeometry, s: int) -> np.ndarray:
        values = part.attributes.get(f"{kind}_{s}")
        return np.zeros((part.vertex_count, 4), padding) if values is None else values

    return np.concatenate([np.concatenate([columns(part, s) for s in sets], axis=1) for part in parts])


def _position_deltas(parts: list[PrimitiveGeometry], target_count: int) -> np.ndarray | None:
    """(N, V, 3) POSITION deltas of every target (zeros where a target has none)."""
    if not target_count:
        return None
    # Filled in place: a face's targets are most of its memory, which stacking, joining and
    # casting copied three times.
    deltas = np.zeros((target_count, sum(part.vertex_count for part in parts), 3), np.float32)
    start = 0
    for part in parts:
        for t, target in enumerate(part.targets):
            if "POSITION" in target:
                deltas[t, start : start + part.vertex_count] = target["POSITION"]
        start += part.vertex_count
    return deltas
