"""Write skinned meshes, skeletons and motions as glTF 2.0 (GLB).

``write_glb`` writes one skinned mesh (or none: a skeleton's clips) and its motions to a new
file: one node per joint (rest translation and rotation, parents before children, end sites
marked with ``extras.animlod_end_site``), a mesh node with the skin, one mesh primitive (one per
material, with the materials of a given document: :class:`FaceMaterials`)
(POSITION, NORMAL and TEXCOORD_0 when present, the other attributes the materials read,
JOINTS_0/WEIGHTS_0 and, for 8 influences, JOINTS_1/WEIGHTS_1, uint16/uint32 indices, morph
targets with their names in ``extras.targetNames``), and one LINEAR animation per motion: the
root's translation and every joint's rotation at every frame (and every joint's translation when
the motion has per-frame ``joint_translations``). What hangs from the skeleton in a given
document (props, sockets, meshes its joint nodes draw) can be copied onto the written joints:
:class:`HungNodes`.

The pieces (``add_skeleton``, ``add_skin``, ``add_animation``, ``skin_attributes``) also serve
the LoD GLB writer, which adds reduced skeletons and their clips to a whole input document.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from ..model import Motion, Skeleton, SkinnedMesh
from .glb_builder import ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER, GlbBuilder
from .gltf_document import GltfDocument
from .gltf_skin import END_SITE_EXTRA

INFLUENCES_PER_SET = 4
_TRIANGLES, _LINEAR = 4, "LINEAR"
# What of a document's root a mesh drawn with its materials needs, and what copies of its nodes
# need besides (their meshes, cameras and lights).
_MATERIAL_KEYS = ("asset", "materials", "textures", "samplers", "images", "bufferViews")
_NODE_KEYS = ("nodes", "meshes", "accessors", "cameras")
# The document-level extensions and the extensions of copied nodes a file of its own keeps: none
# of them names a node by index (an unknown one may: VRMC_node_constraint's source, MSFT_lod's ids).
STANDALONE_ROOT_EXTENSIONS = ("KHR_lights_punctual", "KHR_materials_variants", "KHR_xmp_json_ld")
STANDALONE_NODE_EXTENSIONS = (
    "KHR_lights_punctual", "KHR_xmp_json_ld", "KHR_node_visibility", "EXT_mesh_gpu_instancing",
)  # fmt: skip
_FLOAT, _BYTE, _UNSIGNED_BYTE, _SHORT, _UNSIGNED_SHORT = 5126, 5120, 5121, 5122, 5123


class FaceMaterials(NamedTuple):
    """The material of each face of a written mesh: ``indices`` (F,) into ``document``'s materials,
    -1 for none. The mesh is then drawn as one primitive per material, with the document's
    materials, textures, samplers and images, and ``vertex_attributes``: what they read per vertex
    (TANGENT, TEXCOORD_n, COLOR_n), ``(V, width)`` float32 by glTF name; a TEXCOORD_0 there stands
    for the mesh's ``uvs``."""

    document: GltfDocument
    indices: np.ndarray
    vertex_attributes: Mapping[str, np.ndarray] = MappingProxyType({})


class MeshNames(NamedTuple):
    """The names of a written skinned mesh's node and of the mesh (None: unnamed)."""

    node: str | None
    mesh: str | None


_SKINNED_MESH = MeshNames("skinned mesh", "skinned mesh")  # a mesh made, not read from a file


class HungNodes(NamedTuple):
    """What hangs from the written skeleton in ``document``: ``add(builder, joint_nodes,
    animations)`` appends copies of its nodes (with their meshes, cameras and lights, and the
    accessors, at the document's indices) under the written joint nodes, and their channels to
    the written animations (one per motion); the document's own nodes, and its meshes and
    accessors nothing written uses, are left out of the file."""

    document: GltfDocument
    add: Callable[[GlbBuilder, list[int], list[int]], None]


def write_glb(
    path: str | os.PathLike,
    skinned: SkinnedMesh | None,
    motions: Sequence[Motion] = (),
    names: Sequence[str] | None = None,
    durations: Sequence[float | None] | None = None,
    materials: FaceMaterials | None = None,
    morph_weights: Sequence[np.ndarray | None] | None = None,
    hung: HungNodes | None = None,
    mesh_names: MeshNames = _SKINNED_MESH,
    starts: Sequence[float] | None = None,
) -> None:
    """Write ``skinned`` and ``motions`` (on its skeleton) to the GLB file ``path``, atomically.

    Parameters
    ----------
    path : output file, replaced only once the whole file is written.
    skinned : the mesh; K < 4 influences are padded with zero weights to glTF's 4. None writes
        the skeleton of ``motions[0]`` and the motions only (an animation library's file).
    motions : animations on ``skinned.skeleton`` (same joint names, parents and offsets).
    names : animation names, one per motion; defaults to each motion's name, or "motion<i>".
    durations : per motion, the length of the glTF clip it was sampled from, or None (see
        :func:`add_animation`): its last frame is at the clip's end, which may fall less than a
        frame after the one before it.
    starts : per motion, the time of its first frame (:func:`add_animation`), or None: 0.
    materials : the material of each of ``skinned``'s faces, or None (no material).
    morph_weights : per motion, (T, N) the weights of ``skinned``'s N morph targets at its T
        frames, written as a channel of the mesh node, or None.
    hung : what hangs from the skeleton, copied from a document (the same as ``materials``'s).
    mesh_names : the names of ``skinned``'s node and mesh (an input's own, for a mesh read from one).

    Raises
    ------
    ValueError if a motion is on another skeleton, a duration ends before its motion's frame
    before the last, ``names``, ``durations``, ``materials`` or
    ``morph_weights`` has the wrong length or shape, ``materials`` and ``hung`` are of two
    documents, or there is neither a mesh nor a motion.
    """
    names = _animation_names(motions, names)
    if durations is not None and len(durations) != len(motions):
        raise ValueError(f"durations: {len(durations)} given for {len(motions)} motions")
    if starts is not None and len(starts) != len(motions):
        raise ValueError(f"starts: {len(starts)} given for {len(motions)} motions")
    if skinned is None and not motions:
        raise ValueError("motions: a GLB without a skinned mesh needs a motion to give its skeleton")
    skeleton = motions[0].skeleton if skinned is None else skinned.skeleton
    for index, motion in enumerate(motions):
        _check_same_skeleton(skeleton, motion, index)
    if materials is not None and (skinned is None or len(materials.indices) != skinned.face_count):
        faces = 0 if skinned is None else skinned.face_count
        raise ValueError(f"materials: {len(materials.indices)} face materials for {faces} faces")
    for name, values in ({} if materials is None else materials.vertex_attributes).items():
        if len(values) != skinned.vertex_count:
            raise ValueError(f"materials: {name} of {len(values)} vertices for {skinned.vertex_count}")
    weights = _checked_morph_weights(skinned, motions, morph_weights)
    if materials is not None and hung is not None and materials.document is not hung.document:
        raise ValueError("hung: its document is not the one of materials")
    source = materials.document if materials is not None else hung.document if hung is not None else None
    builder = GlbBuilder() if source is None else _base_of(source, hung is not None)
    dropped = len(builder.json.get("nodes", []))  # the document's own, for the copies to read
    joint_nodes = add_skeleton(builder, skeleton)
    scene_nodes = [joint_nodes[0]]
    if skinned is not None:
        skin = add_skin(builder, joint_nodes, skinned.inverse_bind)
        face_materials, surface = (None, {}) if materials is None else (materials.indices, materials.vertex_attributes)
        mesh = builder.append("meshes", _named(_mesh(builder, skinned, face_materials, surface), mesh_names.mesh))
        scene_nodes.append(builder.append("nodes", _named({"mesh": mesh, "skin": skin}, mesh_names.node)))
    animations = []
    timing = zip(durations or [None] * len(motions), starts or [0.0] * len(motions))
    for motion, name, (duration, start), track in zip(motions, names, timing, weights):
        animations.append(add_animation(builder, motion, joint_nodes, name, duration=duration, start=start))
        if track is not None:
            _add_weights_channel(builder, builder.json["animations"][animations[-1]], scene_nodes[-1], track)
    if hung is not None:
        hung.add(builder, joint_nodes, animations)
    builder.json["scenes"] = [{"nodes": scene_nodes}]
    builder.json["scene"] = 0
    if source is not None:
        _drop_first_nodes(builder.json, dropped)
        _list_extensions_used(builder.json, source)  # for prune to know what may refer to data
        builder.prune()  # the document's meshes and accessors nothing written uses
        _list_extensions_used(builder.json, source)
    builder.save(path)


def _checked_morph_weights(
    skinned: SkinnedMesh | None, motions: Sequence[Motion], morph_weights: Sequence[np.ndarray | None] | None
) -> list[np.ndarray | None]:
    """``morph_weights`` (None: one None per motion), each checked against its motion's frames and
    the mesh's targets."""
    if morph_weights is None:
        return [None] * len(motions)
    if len(morph_weights) != len(motions):
        raise ValueError(f"morph_weights: {len(morph_weights)} given for {len(motions)} motions")
    targets = 0 if skinned is None or skinned.morph_targets is None else len(skinned.morph_targets)
    for index, (motion, weights) in enumerate(zip(motions, morph_weights)):
        if weights is not None and (targets == 0 or np.shape(weights) != (motion.frame_count, targets)):
            raise ValueError(f"morph_weights[{index}]: shape {np.shape(weights)}, expected "
                             f"({motion.frame_count}, {targets}): a weight per frame and morph target")  # fmt: skip
    return list(morph_weights)


def _add_weights_channel(builder: GlbBuilder, animation: dict, node: int, weights: np.ndarray) -> None:
    """``weights`` (T, N) as a channel of ``node``'s morph weights in ``animation``, on its joint
    channels' keys."""
    times = animation["samplers"][0]["input"]
    values = np.asarray(weights).reshape(-1, 1)
    animation["samplers"].append({"input": times, "output": builder.add(values.astype(np.float32)),
                                  "interpolation": _LINEAR})  # fmt: skip
    animation["channels"].append(
        {"sampler": len(animation["samplers"]) - 1, "target": {"node": node, "path": "weights"}}
    )


def _base_of(document: GltfDocument, with_nodes: bool) -> GlbBuilder:
    """A new document holding ``document``'s materials at their indices, with their textures,
    samplers and images (embedded); ``with_nodes``: its nodes, meshes, accessors, cameras and
    lights too, for copies of its nodes to read (:func:`_drop_first_nodes` then leaves the nodes)."""
    builder = GlbBuilder.from_document(document)
    js = builder.json
    kept = _MATERIAL_KEYS + (_NODE_KEYS if with_nodes else ())
    extensions = {
        name: value for name, value in (js.get("extensions") or {}).items() if name in STANDALONE_ROOT_EXTENSIONS
    }
    for key in set(js) - set(kept):
        del js[key]
    if extensions:  # those nothing written uses are dropped at the end (_list_extensions_used)
        js["extensions"] = extensions
    js["asset"] = {**js.get("asset", {}), "generator": "animlod"}
    return builder


def _drop_first_nodes(js: dict, count: int) -> None:
    """The first ``count`` nodes out of ``js``, whose other nodes refer to none of them; the node
    indices of the scenes, nodes, skins and animations shifted down. The other nodes keep only
    the extensions of STANDALONE_NODE_EXTENSIONS (a copied node's MSFT_lod levels were among the
    dropped nodes)."""
    nodes = js.get("nodes", [])
    del nodes[:count]
    for node in nodes:
        if "children" in node:
            node["children"] = [child - count for child in node["children"]]
        if "extensions" in node:
            node["extensions"] = {k: v for k, v in node["extensions"].items() if k in STANDALONE_NODE_EXTENSIONS}
            if not node["extensions"]:
                del node["extensions"]
    for scene in js.get("scenes", []):
        scene["nodes"] = [node - count for node in scene["nodes"]]
    for skin in js.get("skins", []):
        skin["joints"] = [joint - count for joint in skin["joints"]]
        if "skeleton" in skin:
            skin["skeleton"] -= count
    for animation in js.get("animations", []):
        for channel in animation["channels"]:
            if "node" in channel["target"]:  # not a KHR_animation_pointer channel
                channel["target"]["node"] -= count


def _list_extensions_used(js: dict, document: GltfDocument) -> None:
    """``js``'s extensionsUsed and extensionsRequired: those of ``document`` that it uses (its
    document-level extensions those that something in it refers to, the others dropped)."""
    used = {"KHR_mesh_quantization"} if _quantized(js) else set()
    stack = [value for key, value in js.items() if key != "extensions"]
    while stack:
        item = stack.pop()
        if isinstance(item, dict):
            extensions = item.get("extensions")
            used.update(extensions if isinstance(extensions, dict) else ())
            stack.extend(item.values())
        elif isinstance(item, list):
            stack.extend(item)
    root = {name: value for name, value in (js.get("extensions") or {}).items() if name in used}
    js.pop("extensions", None)
    if root:
        js["extensions"] = root
    for listed in ("extensionsUsed", "extensionsRequired"):
        kept = [name for name in document.json.get(listed, []) if name in used]
        if kept:
            js[listed] = kept
        else:
            js.pop(listed, None)


def _quantized(js: dict) -> bool:
    """Whether a mesh attribute has a type of KHR_mesh_quantization's that core glTF does not
    allow (a position, normal or tangent not in float, a texture coordinate in signed or
    unnormalized integers, a morph target's anything not in float)."""
    accessors = js.get("accessors", [])
    for primitive in (p for mesh in js.get("meshes", []) for p in mesh.get("primitives", [])):
        targets = primitive.get("targets", [])
        for name, index in primitive.get("attributes", {}).items():
            accessor = accessors[index]
            kind, normalized = accessor.get("componentType"), accessor.get("normalized", False)
            texture = name.startswith("TEXCOORD_")
            if texture and (kind in (_BYTE, _SHORT) or kind in (_UNSIGNED_BYTE, _UNSIGNED_SHORT) and not normalized):
                return True
            if name in ("POSITION", "NORMAL", "TANGENT") and kind != _FLOAT:
                return True
        if any(accessors[index].get("componentType") != _FLOAT for target in targets for index in target.values()):
            return True
    return False


def add_skeleton(builder: GlbBuilder, skeleton: Skeleton, name_suffix: str = "") -> list[int]:
    """One node per joint (rest translation and rotation, children linked); the node indices.

    The root node is in no scene or children list; the caller places it.
    """
    first = len(builder.json.get("nodes", []))
    children = skeleton.children()
    for j in range(skeleton.joint_count):
        node = {
            "name": skeleton.names[j] + name_suffix,
            "translation": skeleton.offsets[j].tolist(),
            "rotation": skeleton.rest_rotations[j].tolist(),
        }
        if children[j]:
            node["children"] = [first + child for child in children[j]]
        if skeleton.end_sites[j]:
            node["extras"] = {END_SITE_EXTRA: True}
        builder.append("nodes", node)
    return list(range(first, first + skeleton.joint_count))


def add_skin(builder: GlbBuilder, joint_nodes: Sequence[int], inverse_bind: np.ndarray) -> int:
    """A skin over ``joint_nodes`` with ``inverse_bind (J, 4, 4)``; its index."""
    matrices = np.asarray(inverse_bind).transpose(0, 2, 1).reshape(len(joint_nodes), 16)  # column-major
    skin = {"inverseBindMatrices": builder.add(matrices.astype(np.float32)), "joints": list(joint_nodes)}
    skin["skeleton"] = joint_nodes[0]
    return builder.append("skins", skin)


def add_animation(
    builder: GlbBuilder,
    motion: Motion,
    joint_nodes: Sequence[int],
    name: str,
    extras: dict | None = None,
    duration: float | None = None,
    start: float = 0.0,
) -> int:
    """``motion`` as a LINEAR animation of ``joint_nodes`` (one per joint of its skeleton); its index.
    A rigid motion only: joint deformations have no TRS channels of their own (ValueError).

    ``duration``: the length of the glTF clip ``motion`` was sampled from, whose last frame is at
    its end rather than on the frame grid (:func:`~.gltf_keyframes.frame_times`: a clip of 8.275 s
    at 30 fps ends ..., 8.2667, 8.275): the last key is put there, so that the animation lasts as
    long as the clip it stands for and a player that loops each by its own length keeps them in
    step. It must come after the frame before the last (ValueError). ``start``: the time of the
    first frame (a glTF clip keyed late on its timeline is sampled from its first key,
    GltfDocument.animation_start_frame), so that the animation plays when the clip did."""
    motion.require_rigid("a glTF animation of a skeleton")
    times = start + np.arange(motion.frame_count) / motion.fps
    if duration is not None and motion.frame_count > 1:
        if not duration > times[-2]:
            raise ValueError(f"duration: {duration:g} s is not after the frame before the last ({times[-2]:g} s)")
        times[-1] = duration
    time_accessor = builder.add(times.astype(np.float32)[:, None], bounds=True)
    joint_count = motion.skeleton.joint_count
    tracks = [(0, "translation", motion.root_positions)]
    if motion.joint_translations is not None:  # bones that stretch or slide get their own tracks
        tracks += [(j, "translation", motion.joint_translations[:, j]) for j in range(1, joint_count)]
    local_rotations = sign_continuous(motion.local_rotations)
    tracks += [(j, "rotation", local_rotations[:, j]) for j in range(joint_count)]
    samplers, channels = [], []
    for joint, path, values in tracks:
        channels.append({"sampler": len(samplers), "target": {"node": joint_nodes[joint], "path": path}})
        output = builder.add(np.ascontiguousarray(values, dtype=np.float32))
        samplers.append({"input": time_accessor, "output": output, "interpolation": _LINEAR})
    animation = {"name": name, "samplers": samplers, "channels": channels}
    if extras:
        animation["extras"] = extras
    return builder.append("animations", animation)


def influence_sets(joints: np.ndarray, weights: np.ndarray) -> dict[str, np.ndarray]:
    """``joints, weights (V, K)`` as glTF's JOINTS_n (uint16) / WEIGHTS_n (float32) columns of 4,
    K padded with zero weights to a whole number of sets, in the order a primitive lists them."""
    sets = -(-joints.shape[1] // INFLUENCES_PER_SET)
    pad = ((0, 0), (0, sets * INFLUENCES_PER_SET - joints.shape[1]))
    joints = np.pad(joints, pad).astype(np.uint16)
    weights = np.pad(weights, pad).astype(np.float32)
    columns = {}
    for k in range(sets):
        taken = slice(k * INFLUENCES_PER_SET, (k + 1) * INFLUENCES_PER_SET)
        columns[f"JOINTS_{k}"] = joints[:, taken]
        columns[f"WEIGHTS_{k}"] = weights[:, taken]
    return columns


def skin_attributes(
    builder: GlbBuilder, joints: np.ndarray, weights: np.ndarray, joint_count: int, joint_dtype: type | None = None
) -> dict[str, int]:
    """JOINTS_n / WEIGHTS_n accessors for ``joints, weights (V, K)`` (:func:`influence_sets`).

    ``joint_dtype`` (uint8 or uint16) defaults to the smallest that holds ``joint_count`` joints.
    """
    if joint_dtype is None or (joint_dtype is np.uint8 and joint_count > 256):
        joint_dtype = np.uint8 if joint_count <= 256 else np.uint16
    return {
        name: builder.add(values.astype(joint_dtype) if name.startswith("JOINTS_") else values, ARRAY_BUFFER)
        for name, values in influence_sets(joints, weights).items()
    }


def index_accessor(builder: GlbBuilder, faces: np.ndarray, vertex_count: int) -> int:
    """Triangle indices as uint16 or uint32 (0xFFFF is the primitive-restart value glTF forbids)."""
    index_dtype = np.uint16 if vertex_count < 0xFFFF else np.uint32
    return builder.add(np.asarray(faces).reshape(-1, 1).astype(index_dtype), ELEMENT_ARRAY_BUFFER)


def _animation_names(motions: Sequence[Motion], names: Sequence[str] | None) -> list[str]:
    if names is None:
        return [motion.name or f"motion{index}" for index, motion in enumerate(motions)]
    if len(names) != len(motions):
        raise ValueError(f"names: {len(names)} animation names for {len(motions)} motions")
    return [str(name) for name in names]


def _check_same_skeleton(written: Skeleton, motion: Motion, index: int) -> None:
    skeleton = motion.skeleton
    same = (
        skeleton.names == written.names
        and np.array_equal(skeleton.parents, written.parents)
        and np.allclose(skeleton.offsets[1:], written.offsets[1:], rtol=1e-6, atol=1e-9)
    )
    if not same:
        raise ValueError(
            f"motion {index} ({motion.name!r}): its skeleton differs from the written one "
            "(joint names, parents or bone offsets); a GLB animation can only drive the file's own joints"
        )


def _mesh(
    builder: GlbBuilder, skinned: SkinnedMesh, face_materials: np.ndarray | None, surface: Mapping[str, np.ndarray]
) -> dict:
    """The mesh of ``skinned``: one primitive, or one per material of ``face_materials`` (F,),
    each over the vertices its faces use (a renderer skins each primitive's vertices), with the
    ``surface`` attributes of those vertices."""
    groups = np.full(skinned.face_count, -1) if face_materials is None else np.asarray(face_materials)
    materials = np.unique(groups)
    primitives = []
    for material in materials:
        faces = skinned.faces[groups == material]
        used = np.arange(skinned.vertex_count) if len(materials) == 1 else np.unique(faces)
        primitive = _primitive(builder, skinned, surface, used, np.searchsorted(used, faces))
        if material >= 0:
            primitive["material"] = int(material)
        primitives.append(primitive)
    mesh = {"primitives": primitives}
    if skinned.morph_targets is not None:
        defaults = skinned.default_morph_weights
        mesh["weights"] = [0.0] * len(skinned.morph_targets) if defaults is None else defaults.tolist()
        if skinned.morph_target_names is not None:
            mesh["extras"] = {"targetNames": list(skinned.morph_target_names)}
    return mesh


def _named(item: dict, name: str | None) -> dict:
    """``item`` (a node or mesh) with ``name`` first, where there is one."""
    return item if name is None else {"name": name, **item}


def _primitive(
    builder: GlbBuilder, skinned: SkinnedMesh, surface: Mapping[str, np.ndarray], used: np.ndarray, faces: np.ndarray
) -> dict:
    """A triangle primitive of ``skinned``'s vertices ``used`` and ``faces`` over them, with the
    ``surface`` attributes of those vertices."""
    attributes = {"POSITION": builder.add(skinned.rest_positions[used], ARRAY_BUFFER, bounds=True)}
    if skinned.normals is not None:
        attributes["NORMAL"] = builder.add(skinned.normals[used], ARRAY_BUFFER)
    if skinned.uvs is not None and "TEXCOORD_0" not in surface:
        attributes["TEXCOORD_0"] = builder.add(skinned.uvs[used], ARRAY_BUFFER)
    for name, values in surface.items():
        attributes[name] = builder.add(np.asarray(values, np.float32)[used], ARRAY_BUFFER)
    joints, weights = skinned.joints[used], skinned.weights[used]
    attributes.update(skin_attributes(builder, joints, weights, skinned.skeleton.joint_count))
    primitive = {"attributes": attributes, "indices": index_accessor(builder, faces, len(used)), "mode": _TRIANGLES}
    if skinned.morph_targets is not None:
        primitive["targets"] = [
            {"POSITION": builder.add(delta[used], ARRAY_BUFFER, bounds=True)} for delta in skinned.morph_targets
        ]
    return primitive


def sign_continuous(quaternions: np.ndarray) -> np.ndarray:
    """``(T, J, 4)`` with signs flipped so consecutive keys have a non-negative dot product.

    q and -q are the same rotation, but a viewer interpolating from q to -q' may take the long
    way round; each flip is carried forward to every later frame.
    """
    dots = np.sum(quaternions[1:] * quaternions[:-1], axis=-1)
    signs = np.cumprod(np.where(dots < 0.0, -1.0, 1.0), axis=0)
    return quaternions * np.concatenate([np.ones((1,) + signs.shape[1:]), signs])[..., None]
