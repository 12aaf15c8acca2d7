"""Read glTF 2.0 / GLB files into animlod's data model.

What a file becomes:

- every (mesh, skin) pair used by a node -> a :class:`SkinnedMesh` on the skin's skeleton
  (:mod:`.gltf_skin`), with one :class:`Motion` per animation that moves it;
- every mesh without a skin whose morph weights are animated -> one :class:`AnimatedMesh` per
  animation, the targets baked at ``fps`` (rest + sum_i w_i * delta_i) and placed by the node's
  world transform as that animation moves the node and its ancestors;
- every other mesh without a skin -> a one-frame :class:`AnimatedMesh`.

Placement follows what a glTF viewer shows. A skinned mesh's node transform does not affect
the skinned result (glTF 2.0, section 3.7.3.3); animlod still applies it to ``rest_positions``
so that the rest mesh lies where the skinned mesh does in its bind pose, and compensates the
inverse bind matrices (``IBM' = S(c) @ IBM @ M^-1``) so that baking stays exactly what a
viewer shows. Meshes without a skin are placed by their node's world transform.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field

import numpy as np

from .. import rotations
from ..model import AnimatedMesh, Motion, SkinnedMesh
from .gltf_document import NODE_PATHS, GltfDocument
from .gltf_keyframes import sample_keyframes
from .gltf_mesh import SINGULAR_DETERMINANT, MeshGeometry, read_mesh_geometry, transform_normals, transform_points
from .gltf_skin import SkinRig


@dataclass
class GltfScene:
    """Everything animlod reads from one glTF file.

    Attributes
    ----------
    skinned_meshes : one per (mesh, skin) pair used by a node, in node order.
    motions : the animations on the skeleton of the body, ``skinned_meshes[body]`` (empty
        without skins).
    morph_animations : meshes without a skin whose morph weights an animation drives, baked
        at ``fps`` under the node's world transform in that animation, one per (node, animation).
    static_meshes : the other meshes without a skin, one frame each, in world space.
    skinned_motions : the animations of every skinned mesh, parallel to ``skinned_meshes``.
    skinned_nodes : the node that draws each skinned mesh, parallel to ``skinned_meshes``.
    skinned_rigs : the skin of each skinned mesh as a skeleton, parallel to ``skinned_meshes``;
        their ``joint_nodes`` tell which joints of two skins are one (names may repeat in a file).
    body : the index in ``skinned_meshes`` of the character's body: the mesh whose skin lists the
        most joints the animations move, then the most joints, the first in node order among
        equals (a visor or hair may come first in the file).
    """

    skinned_meshes: list[SkinnedMesh]
    motions: list[Motion]
    morph_animations: list[AnimatedMesh]
    static_meshes: list[AnimatedMesh]
    skinned_motions: list[list[Motion]] = field(default_factory=list)
    skinned_nodes: list[int] = field(default_factory=list)
    skinned_rigs: list[SkinRig] = field(default_factory=list)
    body: int = 0


def read_gltf(
    path: str | os.PathLike | GltfDocument, fps: float | None = None, body_skin: int | str | None = None
) -> GltfScene:
    """Read every skinned mesh, motion, morph animation and static mesh of a .glb / .gltf file
    (or of a document already parsed).

    Animations are sampled at ``fps`` (None: at the rate of their keys,
    :meth:`~animlod.io.gltf_document.GltfDocument.sample_rate`) to their last key: the skeletons'
    motions from time 0, so that clips split by joint line up frame by frame (the pipelines start
    each clip at its first key, and a clip split by joint at its parts' earliest first key:
    ``Clip.start_frame``, :func:`from_first_key`), the morph
    animations from the frame at or just before their first key. ``body_skin`` picks the
    character whose mesh is :attr:`GltfScene.body` in a file of several, as :func:`read_skinned`
    picks a skin. Raises :class:`~animlod.io.FormatError` naming the file, the element and the
    reason for input it cannot read.
    """
    doc = path if isinstance(path, GltfDocument) else GltfDocument(path)
    fps = doc.sample_rate(fps)
    rigs: dict[int, SkinRig] = {}
    skinned, skinned_motions = [], []
    nodes = _skinned_mesh_nodes(doc)
    for node in nodes:
        skin = doc.gltf.nodes[node].skin
        if skin not in rigs:
            rigs[skin] = SkinRig(doc, skin)
        mesh, motions = read_skinned_node(doc, node, rigs[skin], fps)
        skinned.append(mesh)
        skinned_motions.append(motions)
    morph_animations, static_meshes = read_unskinned_meshes(doc, fps)
    candidates = nodes if body_skin is None else _using_skin(doc, nodes, body_skin)
    body = nodes.index(body_node(doc, candidates)) if nodes else 0
    return GltfScene(
        skinned_meshes=skinned,
        motions=skinned_motions[body] if skinned_motions else [],
        morph_animations=morph_animations,
        static_meshes=static_meshes,
        skinned_motions=skinned_motions,
        skinned_nodes=nodes,
        skinned_rigs=[rigs[doc.gltf.nodes[node].skin] for node in nodes],
        body=body,
    )


def read_skinned(
    path: str | os.PathLike, skin: int | str | None = None, fps: float | None = None
) -> tuple[SkinnedMesh, list[Motion]]:
    """One skinned mesh of a glTF file and its motions sampled at ``fps`` (None: at the rate of
    their keys, as :func:`read_gltf`).

    ``skin`` picks the skin by index, or by the name of a skin, a mesh or a node that draws it;
    None takes the body (as :attr:`GltfScene.body` picks it). A file without that skin raises
    FormatError naming the file and the skin asked for.
    """
    doc = GltfDocument(path)
    nodes = _skinned_mesh_nodes(doc)
    if not nodes:
        raise doc.fail("skins", "no node draws a skinned mesh (a skin names the skeleton's joints)")
    node = body_node(doc, nodes if skin is None else _using_skin(doc, nodes, skin))
    return read_skinned_node(doc, node, SkinRig(doc, doc.gltf.nodes[node].skin), doc.sample_rate(fps))


def _skinned_mesh_nodes(doc: GltfDocument) -> list[int]:
    """The first node of every distinct (mesh, skin) pair, in node order."""
    seen, nodes = set(), []
    for index, node in enumerate(doc.gltf.nodes or []):
        if node.mesh is not None and node.skin is not None and (node.mesh, node.skin) not in seen:
            doc.item("meshes", node.mesh, doc.node_label(index))
            doc.item("skins", node.skin, doc.node_label(index))
            seen.add((node.mesh, node.skin))
            nodes.append(index)
    return nodes


def body_node(doc: GltfDocument, nodes: list[int]) -> int:
    """The node of ``nodes`` that draws the character's body: the one whose skin lists the most
    joints the animations move, then the most joints, then one the scene a viewer shows draws
    (GltfDocument.in_shown_scene: a collision proxy on the body's skin that a "physics" scene
    alone lists is not the body), the first in node order among equals. A visor skinned to a few
    head joints, or hair to a hundred hair bones that only a runtime's spring simulation moves,
    comes before the body in some files; its skeleton would leave the body out."""
    moved = doc.moved_nodes()

    def size(node: int) -> tuple[int, int, bool]:
        joints = doc.gltf.skins[doc.gltf.nodes[node].skin].joints
        return sum(joint in moved for joint in joints), len(joints), doc.in_shown_scene(node)

    sizes = [size(node) for node in nodes]
    return nodes[sizes.index(max(sizes))]


def _skin_label(doc: GltfDocument, skin: int) -> str:
    name = doc.gltf.skins[skin].name
    return f"{skin} {name!r}" if name else str(skin)


def _using_skin(doc: GltfDocument, nodes: list[int], skin: int | str) -> list[int]:
    """The nodes of ``nodes`` (each drawing a skinned mesh) that use ``skin``: an index, or the name
    of a skin, a mesh or one of those nodes; FormatError naming the skins they use where none does."""
    chosen = [node for node in nodes if _uses_skin(doc, node, skin)]
    if not chosen:
        available = ", ".join(sorted({_skin_label(doc, doc.gltf.nodes[node].skin) for node in nodes})) or "none"
        raise doc.fail(f"skin {skin!r}", f"not in the file (skinned meshes use skins: {available})")
    return chosen


def _uses_skin(doc: GltfDocument, node: int, wanted: int | str) -> bool:
    drawing = doc.gltf.nodes[node]
    if isinstance(wanted, int):
        return drawing.skin == wanted
    return wanted in (doc.gltf.skins[drawing.skin].name, doc.gltf.meshes[drawing.mesh].name, drawing.name)


def read_node_motions(
    path: str | os.PathLike | GltfDocument, fps: float | None = None
) -> tuple[list[Motion], list[str]]:
    """The animations of a glTF file (or parsed document), sampled at ``fps`` (None: at the rate of
    their keys, as :func:`read_gltf`), as motions of its
    animated node tree: the skeleton of a file without skins, as animation libraries are exported
    without their mesh (:class:`~animlod.io.gltf_skin.SkinRig` without a skin); and the labels of
    animated trees left out (under no node in common with the skeleton's). Raises FormatError
    naming the file when no animation translates, turns or scales a node."""
    doc = path if isinstance(path, GltfDocument) else GltfDocument(path)
    rig = SkinRig(doc, None)
    return rig_motions(doc, rig, doc.sample_rate(fps)), rig.trees_left_out


def rig_motions(doc: GltfDocument, rig: SkinRig, fps: float) -> list[Motion]:
    """Every animation that moves one of ``rig``'s nodes (``rig.animations(doc)``), as a motion of
    its skeleton."""
    return [rig.motion(doc, animation, fps) for animation in rig.animations(doc)]


def read_skinned_node(doc: GltfDocument, node: int, rig: SkinRig, fps: float) -> tuple[SkinnedMesh, list[Motion]]:
    """The skinned mesh node ``node`` draws with ``rig`` and every animation that moves the rig."""
    mesh = skinned_mesh_of_node(doc, node, rig, read_mesh_geometry(doc, doc.gltf.nodes[node].mesh, skinned=True))
    return mesh, rig_motions(doc, rig, fps)


def skinned_mesh_of_node(
    doc: GltfDocument, node: int, rig: SkinRig, geometry: MeshGeometry, mesh_world: np.ndarray | None = None
) -> SkinnedMesh:
    """The skinned mesh node ``node`` draws with ``rig``, its rest pose in world space (see the
    module docstring), joints in skeleton order and weights normalised. ``mesh_world`` replaces
    the node's rest world transform (for a LoD node standing in for another node)."""
    mesh_index = doc.gltf.nodes[node].mesh
    slots = rig.skin_slots
    weights = _weights_of_unweighted_vertices(doc, mesh_index, geometry.weights)
    # Unused influences may carry any index (some exporters leave garbage there).
    joints = np.where(weights > 0.0, geometry.joints, 0)
    if joints.size and joints.max() >= slots:
        vertex = int(np.argmax((joints >= slots).any(axis=1)))
        reason = f"vertex {vertex} uses joint slot {int(joints[vertex].max())}, skin {rig.skin} has {slots}"
        raise doc.fail(f"mesh {mesh_index} JOINTS", reason)
    mesh_world = skinned_mesh_space(doc.rest_world_matrix(node) if mesh_world is None else mesh_world)
    inverse_bind = rig.inverse_bind.copy()
    inverse_bind[:, :3] = rig.rest_linear @ inverse_bind[:, :3]
    inverse_bind = inverse_bind @ np.linalg.inv(mesh_world)
    defaults = None if geometry.targets is None else node_weights(doc, node, geometry.default_weights)
    try:
        return SkinnedMesh(
            rest_positions=transform_points(mesh_world, geometry.positions),
            faces=geometry.faces,
            joints=rig.remap[joints],
            weights=weights,
            inverse_bind=inverse_bind,
            skeleton=rig.skeleton,
            uvs=geometry.uvs,
            normals=None if geometry.normals is None else transform_normals(mesh_world, geometry.normals),
            morph_targets=None if geometry.targets is None else geometry.targets @ mesh_world[:3, :3].T,
            morph_target_names=geometry.target_names,
            default_morph_weights=defaults,
        )
    except ValueError as error:
        raise doc.fail(f"mesh {mesh_index} with skin {rig.skin}", str(error)) from None


def skinned_mesh_space(mesh_world: np.ndarray) -> np.ndarray:
    """The space a skinned mesh is read in from its node's world transform ``mesh_world (4, 4)``:
    that transform, or the identity at zero scale. Skinning ignores the node's transform (glTF
    2.0, 3.7.3.3), so any invertible space shows the same; read_drawables takes such a mesh so."""
    return np.eye(4) if abs(np.linalg.det(mesh_world[:3, :3])) < SINGULAR_DETERMINANT else mesh_world


def _weights_of_unweighted_vertices(doc: GltfDocument, mesh_index: int, weights: np.ndarray) -> np.ndarray:
    """``weights`` with full weight on the first listed joint of every vertex whose weights are all
    zero. glTF forbids such vertices, but Blender (before 2.90) and Maya2glTF write the vertices
    no bone deforms that way; three.js and Blender's importer move them with that joint."""
    unweighted = ~(weights > 0.0).any(axis=1)
    if not unweighted.any():
        return weights
    vertex = int(np.argmax(unweighted))
    warnings.warn(
        f"{doc.path}: mesh {mesh_index} WEIGHTS: {int(unweighted.sum())} of {len(weights)} vertices (first: {vertex}) "
        "have no positive skin weight; they follow their first listed joint, as three.js and Blender do",
        stacklevel=5,
    )
    return on_first_joint_when_unweighted(weights)


def on_first_joint_when_unweighted(weights: np.ndarray) -> np.ndarray:
    """``weights (V, K)`` with full weight on the first listed joint of every row without a
    positive weight: the reading of such vertices that the levels and level 0 share."""
    unweighted = ~(weights > 0.0).any(axis=1)
    if not unweighted.any():
        return weights
    weights = weights.copy()
    weights[unweighted, 0] = 1.0
    return weights


def read_unskinned_meshes(doc: GltfDocument, fps: float | None = None) -> tuple[list[AnimatedMesh], list[AnimatedMesh]]:
    """Morph-animated meshes (one per node and animation, :attr:`GltfScene.morph_animations`,
    sampled at ``fps``, None: at the rate of their keys, from the frame at or just before the
    animation's first key, GltfDocument.animation_start_frame) and static meshes
    (:attr:`GltfScene.static_meshes`), in world space."""
    fps = doc.sample_rate(fps)
    morphs, statics = [], []
    geometries: dict[int, MeshGeometry] = {}
    for node_index, node in enumerate(doc.gltf.nodes or []):
        if node.mesh is None or node.skin is not None:
            continue
        if node.mesh not in geometries:
            geometries[node.mesh] = read_mesh_geometry(doc, node.mesh, skinned=False)
        geometry = geometries[node.mesh]
        world = doc.rest_world_matrix(node_index)
        # A mirroring transform turns counter-clockwise triangles clockwise (glTF 2.0, 3.7.4).
        faces = geometry.faces[:, ::-1] if np.linalg.det(world[:3, :3]) < 0.0 else geometry.faces
        tracks = [] if geometry.targets is None else morph_weight_tracks(doc, node_index, len(geometry.targets), fps)
        for animation, weights in tracks:
            start = doc.animation_start_frame(animation, fps)  # a late clip's held first pose left out
            worlds = _animated_world_matrices(doc, node_index, animation, fps)[start:]
            positions = geometry.positions + np.einsum("tn,nvc->tvc", weights[start:], geometry.targets)
            frames = positions @ np.swapaxes(worlds[:, :3, :3], 1, 2) + worlds[:, None, :3, 3]
            label = f"{doc.node_label(node_index)} {doc.animation_label(animation)}"
            morphs.append(_animated_mesh(doc, label, faces, frames, fps))
        if not tracks:
            positions = geometry.positions.astype(np.float64)
            if geometry.targets is not None:
                weights = node_weights(doc, node_index, geometry.default_weights)
                positions = positions + np.einsum("n,nvc->vc", weights, geometry.targets)
            frames = transform_points(world, positions)[None]
            statics.append(_animated_mesh(doc, doc.node_label(node_index), faces, frames, None))
    return morphs, statics


def _animated_world_matrices(doc: GltfDocument, node: int, animation: int, fps: float) -> np.ndarray:
    """(T, 4, 4) world transforms of node ``node`` in the frames of ``animation`` sampled at ``fps``:
    each node from the root down to it posed by the animation's translation, rotation and scale
    channels (its rest transform where it has none) and composed as a viewer composes them."""
    at = doc.animation_frame_times(animation, fps)
    channels = {target: index for index, target in enumerate(doc.channel_targets[animation]) if target[1] in NODE_PATHS}
    world = np.broadcast_to(np.eye(4), (len(at), 4, 4))
    for link in [*reversed(doc.ancestors(node)), node]:
        if not any((link, path) in channels for path in NODE_PATHS):
            world = world @ doc.rest_matrix(link)
            continue
        trs = list(doc.rest_trs(link))  # an animated node has TRS, no matrix (glTF 2.0, 3.7.3.2)
        for slot, path in enumerate(NODE_PATHS):
            if (link, path) in channels:
                trs[slot] = doc.sampled_channel(animation, channels[link, path], path, at)
        translation, rotation, scale = (np.broadcast_to(value, (len(at), value.shape[-1])) for value in trs)
        world = world @ rotations.compose_transform(translation, rotation, scale)
    return world


def node_weights(doc: GltfDocument, node: int, mesh_weights: np.ndarray) -> np.ndarray:
    """(N,) morph weights node ``node`` shows without animation: its own ``weights``, which override
    its mesh's (glTF 2.0, 3.7.2.2; pygltflib's Node drops them, the raw JSON keeps them)."""
    weights = doc.json["nodes"][node].get("weights")
    if weights is None:
        return mesh_weights
    values = np.asarray(weights, np.float64) if isinstance(weights, list) else np.empty(0)
    if values.shape != mesh_weights.shape or not np.all(np.isfinite(values)):
        reason = f"weights must be {mesh_weights.size} finite numbers, one per morph target of its mesh"
        raise doc.fail(doc.node_label(node), reason)
    return values


def from_first_key(
    doc: GltfDocument, animation: int, fps: float, motion: Motion | None, weights: np.ndarray | None
) -> tuple[Motion | None, np.ndarray | None, int]:
    """``motion`` and morph ``weights (T, N)`` of animation ``animation`` (either None), sampled at
    ``fps`` from 0, from the frame at or just before its first key
    (GltfDocument.animation_start_frame), and that frame: a clip keyed late on its timeline holds
    its first pose until then, and those frames would be driven, analysed and written for nothing."""
    start = doc.animation_start_frame(animation, fps)
    if not start:
        return motion, weights, 0
    kept = None if motion is None else motion.take_frames(np.arange(start, motion.frame_count))
    return kept, None if weights is None else weights[start:], start


def morph_weight_tracks(doc: GltfDocument, node: int, target_count: int, fps: float) -> list[tuple[int, np.ndarray]]:
    """``(animation index, weights (T, N))`` for every animation that drives the node's morph
    weights, sampled at ``fps``."""
    tracks = []
    for a, animation in enumerate(doc.gltf.animations or []):
        label = doc.animation_label(a)
        for index, (channel, target) in enumerate(zip(animation.channels or [], doc.channel_targets[a])):
            if target != (node, "weights"):
                continue
            element = f"{label} channel {index}"
            times, values, interpolation = doc.sampler_keys(a, channel.sampler, target_count, element)
            at = doc.animation_frame_times(a, fps)
            tracks.append((a, sample_keyframes(times, values, interpolation, at)))
    return tracks


def _animated_mesh(
    doc: GltfDocument, element: str, faces: np.ndarray, frames: np.ndarray, fps: float | None
) -> AnimatedMesh:
    try:
        return AnimatedMesh(faces, frames, fps=fps)
    except ValueError as error:
        raise doc.fail(element, str(error)) from None
