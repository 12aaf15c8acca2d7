"""LoD chains in glTF 2.0: the LoD GLB.

The input document stays whole and level 0 is its own mesh node, untouched but for skin weights
that break glTF's unit sum (:mod:`.stored_weights`, which the pipelines apply). Lower levels are
nodes listed by the base node's MSFT_lod extension (in no scene and no children list, so that
any viewer shows level 0), with the base node's transform and skin, and their own meshes whose
primitives keep the input primitives' materials and attribute sets:

- ``base.extensions.MSFT_lod = {"ids": [n1, ..., nL]}``, finest first;
- ``base.extras.MSFT_screencoverage = [c0, ..., cL]``: level i is used while the object covers
  at least ``c_i`` of the viewport height; ``cL = 0``;
- ``extras.animlod = {"level", "error", "triangles", "mesh_level", "motion_level", "joints"}`` on
  every node of the chain (``error`` in asset units; ``joints``: the skeleton's joints at that
  motion level, alike on every skin that plays it).

Motion levels (fewer joints, see :mod:`animlod.pipelines.character`) add a reduced skeleton as
its own joint nodes, a skin over them, and one animation per input clip with
``extras.animlod = {"clip": <input animation index>, "motion_level": m, "skins": [<input skins
that play it>]}`` (named ``<clip>@motion<m>``, or ``<clip>@skin<s>@motion<m>`` in a file where
several skeletons have motion levels); every combination of
geometry and motion level is a node, listed by ``base.extras.animlod_grid[g][m]``.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field

import numpy as np

from ..model import AnimatedMesh, LodChain, LodLevel
from .glb_builder import ARRAY_BUFFER, GlbBuilder
from .gltf_document import (
    COMPONENT_DTYPES,
    INSTANCING_EXTENSION,
    LOD_EXTENSION,
    NODE_POINTER,
    POINTER_EXTENSION,
    GltfDocument,
)
from .gltf_draco import DRACO_EXTENSION
from .gltf_mesh import read_mesh_geometry, transform_points
from .gltf_read import skinned_mesh_of_node
from .gltf_skin import SkinRig
from .gltf_write import index_accessor

COVERAGE_EXTRA = "MSFT_screencoverage"
ANIMLOD_EXTRA = "animlod"
_NODE_TRANSFORM = ("matrix", "translation", "rotation", "scale")


@dataclass
class PrimitiveArrays:
    """One triangle primitive of a level mesh, ready to write.

    Attributes
    ----------
    source : index of the input primitive it replaces (material, mode and extras come from it).
    attributes : glTF attribute name -> (n, width) array: float32, or unsigned integers for
        JOINTS_n.
    faces : (m, 3) triangles over the n vertices.
    targets : per morph target, attribute name -> (n, 3) float32 deltas.
    vertices : (n,) index of each vertex in the level it was cut from (not written).
    """

    source: int
    attributes: dict[str, np.ndarray]
    faces: np.ndarray
    targets: list[dict[str, np.ndarray]] = field(default_factory=list)
    vertices: np.ndarray | None = None


@dataclass
class LevelInfo:
    """What ``extras.animlod`` records on a node of a chain."""

    level: int
    error: float
    triangles: int
    mesh_level: int
    motion_level: int = 0
    joints: int = 0

    def extras(self) -> dict:
        return {
            "level": self.level,
            "error": float(self.error),
            "triangles": int(self.triangles),
            "mesh_level": self.mesh_level,
            "motion_level": self.motion_level,
            "joints": self.joints,
        }


# Attributes a level writes in the component type of the input's (normalised or plain integers,
# as quantised exports store texture coordinates, colours and feature IDs); positions,
# directions, morph deltas and skin weights are rebuilt by the levels and stay float.
_INPUT_TYPED = ("TEXCOORD_", "COLOR_", "_")


def add_level_mesh(
    builder: GlbBuilder, mesh_index: int, primitives: list[PrimitiveArrays], shared: list[int], name: str
) -> int:
    """A new mesh like input mesh ``mesh_index`` with the triangle primitives ``primitives`` and
    the input primitives ``shared`` (points and lines) as they are, in the input's order. Returns
    its index."""
    source = builder.json["meshes"][mesh_index]
    mesh = {key: copy.deepcopy(value) for key, value in source.items() if key != "primitives"}
    mesh["name"] = name
    placed = [(k, copy.deepcopy(source["primitives"][k])) for k in shared]
    for arrays in primitives:
        primitive = {
            key: copy.deepcopy(value)
            for key, value in source["primitives"][arrays.source].items()
            if key not in ("attributes", "indices", "targets", "mode")
        }
        extensions = primitive.pop("extensions", {})
        extensions.pop(DRACO_EXTENSION, None)  # the level's data is its own, uncompressed
        if extensions:
            primitive["extensions"] = extensions
        vertex_count = len(arrays.attributes["POSITION"])
        inputs = source["primitives"][arrays.source].get("attributes", {})
        primitive["attributes"] = {}
        for attribute, values in arrays.attributes.items():
            like = builder.json["accessors"][inputs[attribute]] if attribute in inputs else {}
            stored, normalized = _storable(values, like if attribute.startswith(_INPUT_TYPED) else {})
            primitive["attributes"][attribute] = builder.add(
                stored, ARRAY_BUFFER, bounds=attribute == "POSITION", normalized=normalized
            )
        primitive["indices"] = index_accessor(builder, arrays.faces, vertex_count)
        primitive["mode"] = 4
        if arrays.targets:
            primitive["targets"] = [
                {
                    name: builder.add(_storable(delta, {})[0], ARRAY_BUFFER, bounds=name == "POSITION")
                    for name, delta in t.items()
                }
                for t in arrays.targets
            ]
        placed.append((arrays.source, primitive))
    mesh["primitives"] = [primitive for _, primitive in sorted(placed, key=lambda item: item[0])]
    return builder.append("meshes", mesh)


def add_level_node(builder: GlbBuilder, base: int, mesh: int, skin: int | None, info: LevelInfo) -> int:
    """A node drawing ``mesh`` (with ``skin``) where node ``base`` is; in no scene. Its index."""
    base_node = builder.json["nodes"][base]
    node = {key: copy.deepcopy(base_node[key]) for key in _NODE_TRANSFORM if key in base_node}
    instances = base_node.get("extensions", {}).get(INSTANCING_EXTENSION)
    if instances is not None:  # every instance draws the level too
        node["extensions"] = {INSTANCING_EXTENSION: copy.deepcopy(instances)}
    node["name"] = level_node_name(base_node.get("name", f"node{base}"), info)
    node["mesh"] = mesh
    # A node's morph weights override its mesh's (glTF 2.0, 3.7.2.2): a level that kept every target
    # shows the base node's shape only with them. A level with other targets keeps its mesh's.
    primitives = builder.json["meshes"][mesh].get("primitives") or [{}]
    if "weights" in base_node and len(primitives[0].get("targets", [])) == len(base_node["weights"]):
        node["weights"] = copy.deepcopy(base_node["weights"])
    if skin is not None:
        node["skin"] = skin
    node["extras"] = {ANIMLOD_EXTRA: info.extras()}
    return builder.append("nodes", node)


def level_node_name(base_name: str, info: LevelInfo) -> str:
    """``<base>_LOD<i>`` for level i of a chain, ``<base>_G<g>M<m>`` for a grid-only node (level -1)."""
    if info.level >= 0:
        return f"{base_name}_LOD{info.level}"
    return f"{base_name}_G{info.mesh_level}M{info.motion_level}"


def attach_chain(
    builder: GlbBuilder, base: int, level_nodes: list[int], coverages: list[float], base_info: LevelInfo
) -> None:
    """Makes node ``base`` the top of a chain: MSFT_lod ids, screen coverages (one per level,
    ``len(level_nodes) + 1`` decreasing values ending at 0), its own animlod extras, and the
    level nodes driven by its clips (:func:`drive_level_nodes`)."""
    if len(coverages) != len(level_nodes) + 1:
        raise ValueError(f"coverages: {len(coverages)} values for {len(level_nodes) + 1} levels")
    node = builder.json["nodes"][base]
    node.setdefault("extensions", {})[LOD_EXTENSION] = {"ids": list(level_nodes)}
    extras = node_extras(node)
    extras[COVERAGE_EXTRA] = [float(c) for c in coverages]
    extras[ANIMLOD_EXTRA] = base_info.extras()
    node["extras"] = extras
    builder.add_extension_used(LOD_EXTENSION)
    drive_level_nodes(builder, base, level_nodes)


def node_extras(node: dict) -> dict:
    """A copy of ``node``'s extras as an object animlod can add its keys to. glTF allows any JSON
    value there; one that is not an object is kept beside ours as ``original_extras``."""
    extras = node.get("extras")
    if not isinstance(extras, dict):
        return {} if extras is None else {"original_extras": extras}
    return dict(extras)


def has_lod_chain(node: dict) -> bool:
    """Whether ``node`` (its JSON) is the base of an MSFT_lod chain."""
    return LOD_EXTENSION in (node.get("extensions") or {})


def unchained(doc: GltfDocument, nodes: list[int]) -> list[int]:
    """Those of ``nodes`` that are not the base of an MSFT_lod chain in ``doc``: an input's own
    chain (an artist's levels, or animlod's output simplified again) stays as it is, since a new
    chain would replace its ids and leave its level nodes in no chain."""
    return [node for node in nodes if not has_lod_chain(doc.json["nodes"][node])]


def drive_level_nodes(builder: GlbBuilder, base: int, level_nodes: list[int]) -> None:
    """Every clip's channel that moves node ``base`` (its translation, rotation or scale) or sets its
    morph weights also drives ``level_nodes`` through the same sampler; morph weights only those
    whose meshes have as many targets. A channel animates one node and a level is a node of its own:
    without this, a viewer that switches to a coarser level shows it at rest (a flamingo that stops
    flapping, a truck whose wheels stop turning at a distance)."""
    targets = _morph_target_count(builder, base)
    weighted = [node for node in level_nodes if targets and _morph_target_count(builder, node) == targets]
    for animation in builder.json.get("animations", []) if level_nodes else []:
        channels = animation.get("channels", [])
        for channel in list(channels):
            target = _node_target(channel.get("target", {}))
            if target is None or target[0] != base:
                continue
            driven = weighted if target[1] == "weights" else level_nodes
            channels.extend({"sampler": channel["sampler"], "target": {"node": n, "path": target[1]}} for n in driven)


def _morph_target_count(builder: GlbBuilder, node: int) -> int:
    """Morph targets of the mesh node ``node`` draws (every primitive of a mesh has as many)."""
    mesh = builder.json["nodes"][node].get("mesh")
    primitives = builder.json["meshes"][mesh].get("primitives") if mesh is not None else None
    return len(primitives[0].get("targets", [])) if primitives else 0


def _node_target(target: dict) -> tuple[int, str] | None:
    """The (node, path) a channel target animates, by node and path or by a KHR_animation_pointer
    at ``/nodes/<n>/<path>``; None for anything else (a material's colour, a light)."""
    path = target.get("path")
    if path != "pointer":
        return (target["node"], path) if target.get("node") is not None else None
    pointer = (target.get("extensions") or {}).get(POINTER_EXTENSION, {}).get("pointer", "")
    match = NODE_POINTER.fullmatch(pointer) if isinstance(pointer, str) else None
    return (int(match.group(1)), match.group(2)) if match else None


# A level whose coverage range is narrower than 1% of where it ends is all but never shown.
_HIDDEN_RANGE = 0.99


def screen_coverages(
    errors: list[float], size: float, pixel_error: float = 1.0, viewport_px: float = 1080.0
) -> list[float]:
    """MSFT_screencoverage thresholds from each level's error (asset units).

    An object of ``size`` covering a fraction ``c`` of a viewport ``viewport_px`` pixels high
    shows an error ``e`` as ``e / size * c * viewport_px`` pixels, so level i + 1 is good enough
    once ``c <= pixel_error * size / (e_(i+1) * viewport_px)``: that is where level i ends.
    The values are clamped to [0, 1] and made non-increasing; the last is 0.
    """
    thresholds = []
    for error in errors[1:]:
        limit = 1.0 if error <= 0.0 else pixel_error * size / (error * viewport_px)
        thresholds.append(min(1.0, limit, thresholds[-1] if thresholds else 1.0))
    return [*thresholds, 0.0]


def hidden_level_notes(errors: list[float], coverages: list[float]) -> list[str]:
    """A note for each level 1, 2, ... that a runtime (all but) never shows: its range of screen
    coverage, from where the level before it ends to where it ends, is under 1% of its end. Either
    the next level's error is within the pixel error even where the object fills the viewport (both
    coverages are 1), or the next level measured about the same error or less (the coverages follow
    the next level's error and never increase). ``errors`` (in the units the notes show) and
    ``coverages`` per level, level 0 first (see :func:`screen_coverages`)."""
    notes = []
    for level in range(1, len(coverages) - 1):
        if coverages[level] < _HIDDEN_RANGE * coverages[level - 1]:
            continue
        if coverages[level] >= 1.0:
            why = f"level {level + 1}'s error ({errors[level + 1]:.3g}) is within the pixel error even at full screen"
        else:
            why = (f"level {level + 1} measured about the same error or less "
                   f"({errors[level + 1]:.3g} against {errors[level]:.3g})")  # fmt: skip
        notes.append(f"level {level} is (all but) never shown: {why}, so a runtime goes from level {level - 1} to "
                     f"level {level + 1} at screen coverage {coverages[level]:.3g}")  # fmt: skip
    return notes


def lod_ids(doc: GltfDocument, base: int) -> list[int] | None:
    """The level nodes node ``base``'s MSFT_lod lists, None when it has none. FormatError naming
    the element unless they are indices of other nodes, each once."""
    lod = doc.json["nodes"][base].get("extensions", {}).get(LOD_EXTENSION)
    if lod is None:
        return None
    element = f"{doc.node_label(base)} {LOD_EXTENSION}"
    ids = lod.get("ids") if isinstance(lod, dict) else None
    if not isinstance(ids, list):
        raise doc.fail(element, "has no list of level node ids")
    for index in ids:
        doc.item("nodes", index, element)
    repeated = next((index for index in ids if index == base or ids.count(index) > 1), None)
    if repeated is not None:
        reason = "the node itself" if repeated == base else f"node {repeated} twice"
        raise doc.fail(element, f"lists {reason}: each level is another node")
    return ids


def lod_coverages(doc: GltfDocument, base: int, ids: list[int]) -> list[float | None]:
    """The MSFT_screencoverage of node ``base``'s chain of ``ids``, one a level (None each where it
    has none). FormatError naming the element unless they are as many finite numbers >= 0, none
    above the one before (level i is used while the object covers at least c_i), as the crowd's
    loader requires."""
    extras = doc.json["nodes"][base].get("extras")
    coverages = (extras if isinstance(extras, dict) else {}).get(COVERAGE_EXTRA)
    if coverages is None:
        return [None] * (len(ids) + 1)
    element = f"{doc.node_label(base)} extras {COVERAGE_EXTRA}"
    if not isinstance(coverages, list) or len(coverages) != len(ids) + 1:
        raise doc.fail(element, f"needs {len(ids) + 1} values")
    for level, value in enumerate(coverages):
        if isinstance(value, bool) or not isinstance(value, int | float) or not 0.0 <= value < float("inf"):
            raise doc.fail(element, f"level {level}: {value!r} is not a finite number >= 0")
        if level and value > coverages[level - 1]:
            raise doc.fail(element, f"level {level}: {value} is above level {level - 1}'s {coverages[level - 1]}")
    return [float(value) for value in coverages]


def read_lod_chains(path: str | os.PathLike, fps: float | None = None) -> list[LodChain]:
    """Every chain of a LoD GLB (one per node with MSFT_lod), levels finest first.

    A level's mesh is a world-space :class:`~animlod.model.SkinnedMesh` with the clips that
    move its skin (a reduced skeleton's own clips at motion levels, sampled at ``fps``; None: at
    the rate of their keys, :meth:`~.gltf_document.GltfDocument.sample_rate`), or a one-frame
    :class:`~animlod.model.AnimatedMesh`; its error and coverage come from the extras.
    A file without MSFT_lod has no chains. Raises FormatError naming the element.
    """
    doc = GltfDocument(path)
    fps = doc.sample_rate(fps)
    rigs: dict[int, SkinRig] = {}
    chains = []
    for base, node in enumerate(doc.json.get("nodes", [])):
        ids = lod_ids(doc, base)
        if ids is None:
            continue
        coverages = lod_coverages(doc, base, ids)
        parent = doc.parents[base]
        parent_world = doc.rest_world_matrix(parent) if parent >= 0 else np.eye(4)
        levels = []
        for node_index, coverage in zip([base, *ids], coverages):
            world = parent_world @ doc.rest_matrix(node_index)
            levels.append(_read_level(doc, node_index, world, rigs, fps, coverage))
        chains.append(LodChain(levels, name=node.get("name", f"node {base}")))
    return chains


def _read_level(
    doc: GltfDocument, index: int, world: np.ndarray, rigs: dict, fps: float, coverage: float | None
) -> LodLevel:
    node = doc.gltf.nodes[index]
    label = doc.node_label(index)
    extras = node.extras.get(ANIMLOD_EXTRA, {}) if isinstance(node.extras, dict) else {}
    info = extras if isinstance(extras, dict) else {}
    if node.mesh is None:
        raise doc.fail(label, "is a level of a LoD chain but draws no mesh")
    error = float(info.get("error", 0.0))
    mesh_level, motion_level = int(info.get("mesh_level", 0)), int(info.get("motion_level", 0))
    if node.skin is None:
        geometry = read_mesh_geometry(doc, node.mesh, skinned=False)
        mesh = AnimatedMesh(geometry.faces, transform_points(world, geometry.positions)[None])
        return LodLevel(mesh, None, [], error, coverage, mesh_level, motion_level)
    if node.skin not in rigs:
        rigs[node.skin] = SkinRig(doc, node.skin)
    rig = rigs[node.skin]
    geometry = read_mesh_geometry(doc, node.mesh, skinned=True)
    mesh = skinned_mesh_of_node(doc, index, rig, geometry, world)
    motions = [rig.motion(doc, animation, fps) for animation in range(len(doc.gltf.animations or []))]
    motions = [motion for motion in motions if motion is not None]
    return LodLevel(mesh, rig.skeleton, motions, error, coverage, mesh_level, motion_level)


def _storable(values: np.ndarray, like: dict) -> tuple[np.ndarray, bool]:
    """``values`` to write, and whether they are normalised: in the integer component type of
    the input accessor ``like`` if it has one (rounded, normalised ones scaled), else float32;
    integer arrays (JOINTS_n) in the smallest unsigned type."""
    values = np.asarray(values)
    if values.dtype.kind in "iu":
        return values.astype(np.uint8 if values.max(initial=0) < 256 else np.uint16), False
    dtype = COMPONENT_DTYPES.get(like.get("componentType"))
    if dtype is None or dtype.kind == "f":
        return values.astype(np.float32), False
    normalized = bool(like.get("normalized", False))
    limits = np.iinfo(dtype)
    if normalized:  # [0, 1] or [-1, 1] to the type's range (glTF 2.0 section 3.11)
        values = values * limits.max
        lowest = -limits.max if limits.min < 0 else 0
    else:
        lowest = limits.min
    return np.clip(np.rint(values), lowest, limits.max).astype(dtype), normalized
