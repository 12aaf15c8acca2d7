"""The skinned meshes of a glTF on one skeleton as one mesh: a character in parts (BrainStem's
pieces, Soldier's visor, VRoid's hair, a head with its own blendshapes beside a body without),
for writers that take one skinned mesh per file (`animlod motion`'s level GLBs).

Each part lies on the body's skeleton as :mod:`.skin_parts` places it; bones of a part's own
that move in its clips join that skeleton. Morph targets join by name: a target some parts name
moves those parts' vertices and leaves the others', so one weight drives it everywhere, as
engines drive a face's and its teeth's "jawOpen" together. A part without normals gets smooth
ones where other parts have them; the attributes the materials read (texture coordinates, colours,
tangents) join as :mod:`.surface_attributes` says.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..io.gltf_document import GltfDocument
from ..io.gltf_mesh import MeshGeometry, read_mesh_geometry
from ..io.gltf_read import GltfScene, morph_weight_tracks, read_skinned_node, skinned_mesh_space
from ..io.gltf_skin import SkinRig
from ..model import Motion, SkinnedMesh, morphed
from ..motion_lod.clips import join_clips
from ..normals import vertex_normals
from .skin_parts import JointKeys, hanging_rig, joined_rig, moved_onto, placement_on
from .surface_attributes import joined_surface, node_surface


@dataclass
class WholeSkin:
    """The skinned meshes on one skeleton as one mesh (:func:`whole_skin`).

    Attributes
    ----------
    mesh : the joined mesh, the body's vertices and faces first.
    motions : its animations, sampled.
    animations : the animation each motion is (its index in the document).
    face_materials : (F,) each face's material (index in the document's materials, -1 for none).
    surface : the attributes the materials read besides normals (texture coordinates, colours,
        tangents: :mod:`.surface_attributes`), (V, width) float32 by glTF name.
    left_out : each skinned mesh of the document not in it, its node's label and why
        (``node 7 'Body2' (on another skeleton)``).
    part_nodes : the nodes whose meshes it joins, the body's first.
    rig : the skeleton's rig (the body's, with the bones of parts that join it).
    morph_weights : per animation that drives a part's morph weights (its index in the document),
        (T, N) the joined targets' weights at the animation's sampled frames; a target no part's
        channel drives keeps its default, and the first part's channel drives a shared one.
    """

    mesh: SkinnedMesh
    motions: list[Motion]
    animations: list[int]
    face_materials: np.ndarray
    surface: dict[str, np.ndarray]
    left_out: list[str]
    part_nodes: list[int]
    morph_weights: dict[int, np.ndarray]
    rig: SkinRig


def whole_skin(doc: GltfDocument, scene: GltfScene, note: Callable[[str], None], fps: float) -> WholeSkin:
    """The body of ``scene`` (``scene.body``) with every other skinned mesh on its skeleton joined
    to it, with its motions (sampled at ``fps``). Meshes stay out that lie on other joints, are
    bound in another pose, whose morph targets lack names where the others' have them, or that
    only a scene a viewer does not show draws where the body is in the one it shows
    (GltfDocument.in_shown_scene). A part's joints match the body's by node (a part whose skin
    lists bones of its own alone meets it at the joint they hang from, skin_parts.hanging_rig);
    bones of its own that move in its clips join the skeleton, the body read again with them, and
    ``note`` names them. Morph targets join by name
    (:func:`_joined_targets`), each part keeping the shape of its default weights."""
    body, motions, rig, body_node = (scene.skinned_meshes[scene.body], scene.skinned_motions[scene.body],
                                     scene.skinned_rigs[scene.body], scene.skinned_nodes[scene.body])  # fmt: skip
    parts, part_nodes, vertex_spaces = [body], [body_node], [skinned_mesh_space(doc.rest_world_matrix(body_node))]
    left_out = []
    body_shown = doc.in_shown_scene(body_node)  # a body in another scene only: every part stays in
    for index, mesh in enumerate(scene.skinned_meshes):
        if index == scene.body:
            continue
        node, part_rig = scene.skinned_nodes[index], scene.skinned_rigs[index]
        if body_shown and not doc.in_shown_scene(node):  # the level GLBs have the body's scene alone
            left_out.append(f"{doc.node_label(node)} (in no scene a viewer shows)")
            continue
        if not _targets_join(parts, mesh):
            left_out.append(f"{doc.node_label(node)} (unnamed morph targets beside named ones)")
            continue
        clips = scene.skinned_motions[index]
        hung = hanging_rig(doc, part_rig, set(rig.joint_nodes))
        if hung is not None:  # its skin lists bones of its own alone, hung from one of the skeleton's joints
            part_rig = hung
            mesh, clips = read_skinned_node(doc, node, hung, fps)
        keys = JointKeys(rig.joint_nodes, part_rig.joint_nodes)
        placement = placement_on(body, mesh, keys, join_clips(clips)[0] if clips else None)
        with_bones = joined_rig(doc, rig, body, part_rig, mesh) if placement is None else None
        if with_bones is not None:  # the joined skeleton keeps every joint's index: placed parts stay valid
            own = with_bones.extra_joints[len(rig.extra_joints) :]
            note(f"{doc.path}: {doc.node_label(node)} has joints of its own that move in its clips "
                 f"({', '.join(map(doc.node_label, own))}); they join the skeleton of "
                 f"{doc.node_label(body_node)}")  # fmt: skip
            rig = with_bones
            body, motions = read_skinned_node(doc, body_node, rig, fps)
            placement = placement_on(body, mesh, JointKeys(rig.joint_nodes, part_rig.joint_nodes))
        if placement is not None:
            parts.append(moved_onto(mesh, body, placement))
            part_nodes.append(node)
            vertex_spaces.append(placement.transform @ skinned_mesh_space(doc.rest_world_matrix(node)))
        elif set(part_rig.joint_nodes).isdisjoint(rig.joint_nodes):  # a second character
            left_out.append(f"{doc.node_label(node)} (on another skeleton)")
        else:
            left_out.append(f"{doc.node_label(node)} (on other joints or bound in another pose)")
    parts[0] = body
    meshes = [doc.gltf.nodes[node].mesh for node in part_nodes]
    geometries = [read_mesh_geometry(doc, mesh, skinned=True) for mesh in meshes]
    materials = np.concatenate([_face_materials(doc, mesh, geometry) for mesh, geometry in zip(meshes, geometries)])
    surfaces = [node_surface(geometry, space) for geometry, space in zip(geometries, vertex_spaces)]
    surface = joined_surface([(attributes, part.vertex_count) for attributes, part in zip(surfaces, parts)])
    if len(parts) == 1:
        count = 0 if body.morph_targets is None else len(body.morph_targets)
        defaults = np.zeros(count) if body.default_morph_weights is None else body.default_morph_weights
        tracks = _weight_tracks(doc, part_nodes, [list(range(count))], defaults, fps)
        return WholeSkin(body, motions, rig.animations(doc), materials, surface, left_out, part_nodes, tracks, rig)
    influences = max(part.joints.shape[1] for part in parts)
    starts = np.cumsum([0] + [part.vertex_count for part in parts])

    def padded(values: np.ndarray) -> np.ndarray:
        return np.pad(values, ((0, 0), (0, influences - values.shape[1])))

    def joined(attribute: str, missing: Callable[[SkinnedMesh], np.ndarray]) -> np.ndarray | None:
        """An attribute of the parts as one mesh's, ``missing(part)`` for a part without it; None
        where no part has it."""
        values = [getattr(part, attribute) for part in parts]
        if all(value is None for value in values):
            return None
        return np.concatenate([missing(part) if value is None else value for part, value in zip(parts, values)])

    targets, target_names, defaults, shapes, places = _joined_targets(parts)
    whole = SkinnedMesh(
        rest_positions=np.concatenate(shapes).astype(np.float32),
        faces=np.concatenate([part.faces + start for part, start in zip(parts, starts)]),
        joints=np.concatenate([padded(part.joints) for part in parts]),
        weights=np.concatenate([padded(part.weights) for part in parts]),
        inverse_bind=body.inverse_bind,
        skeleton=body.skeleton,
        uvs=joined("uvs", lambda part: np.zeros((part.vertex_count, 2), np.float32)),  # an untextured part
        normals=joined("normals", lambda part: vertex_normals(part.rest_positions, part.faces)),
        morph_targets=targets,
        morph_target_names=target_names,
        default_morph_weights=defaults,
    )
    tracks = {} if defaults is None else _weight_tracks(doc, part_nodes, places, defaults, fps)
    return WholeSkin(whole, motions, rig.animations(doc), materials, surface, left_out, part_nodes, tracks, rig)


def _weight_tracks(
    doc: GltfDocument, nodes: list[int], places: list[list[int]], defaults: np.ndarray, fps: float
) -> dict[int, np.ndarray]:
    """WholeSkin.morph_weights of the parts drawn by ``nodes``, whose targets are the joined
    mesh's ``places``."""
    tracks: dict[int, np.ndarray] = {}
    for node, targets in reversed(list(zip(nodes, places))):  # the first part's channel written last
        if not targets:
            continue
        for animation, weights in morph_weight_tracks(doc, node, len(targets), fps):
            track = tracks.setdefault(animation, np.tile(defaults, (len(weights), 1)))
            track[:, targets] = weights
    return tracks


def _face_materials(doc: GltfDocument, mesh: int, geometry: MeshGeometry) -> np.ndarray:
    """(F,) the material of each face of mesh ``mesh`` as read (``geometry``: its triangle
    primitives in order), -1 for a primitive without one."""
    primitives = doc.gltf.meshes[mesh].primitives
    of_part = [-1 if primitives[part.index].material is None else primitives[part.index].material
               for part in geometry.primitives]  # fmt: skip
    return np.asarray(of_part, np.int64)[geometry.face_groups]


def _target_keys(mesh: SkinnedMesh) -> list[tuple[str | None, int]]:
    """What identifies each morph target of ``mesh`` across meshes: its name and how many before it
    bear that name (names may repeat), or no name and its index where the mesh names none."""
    if mesh.morph_targets is None:
        return []
    if mesh.morph_target_names is None:
        return [(None, index) for index in range(len(mesh.morph_targets))]
    seen: dict[str, int] = {}
    keys = []
    for name in mesh.morph_target_names:
        keys.append((name, seen.get(name, 0)))
        seen[name] = keys[-1][1] + 1
    return keys


def _targets_join(parts: list[SkinnedMesh], mesh: SkinnedMesh) -> bool:
    """Whether ``mesh``'s morph targets can join those of ``parts``: all named or all unnamed."""
    named = {part.morph_target_names is not None for part in parts + [mesh] if part.morph_targets is not None}
    return len(named) <= 1


def _joined_targets(
    parts: list[SkinnedMesh],
) -> tuple[np.ndarray | None, list[str] | None, np.ndarray | None, list[np.ndarray], list[list[int]]]:
    """The parts' morph targets as one mesh's, (N, V, 3) with their names (None where unnamed) and
    default weights: one target per key (:func:`_target_keys`) of any part, no offset on the parts
    without it, at the default weight of the first part that has it. Then each part's bind shape
    with the difference of its own defaults from those folded in, so that every part shows its own
    default shape; last, where each part's targets are among the joined ones."""
    keys = [_target_keys(part) for part in parts]
    union = list(dict.fromkeys(key for part_keys in keys for key in part_keys))
    shapes = [part.rest_positions for part in parts]
    place = {key: index for index, key in enumerate(union)}
    places = [[place[key] for key in part_keys] for part_keys in keys]
    if not union:
        return None, None, None, shapes, places
    targets = np.zeros((len(union), sum(part.vertex_count for part in parts), 3), np.float32)
    defaults = np.full(len(union), np.nan)
    start = 0
    for k, (part, part_places) in enumerate(zip(parts, places)):
        if part_places:
            targets[part_places, start : start + part.vertex_count] = part.morph_targets
            own = np.zeros(len(part_places)) if part.default_morph_weights is None else part.default_morph_weights
            unset = np.isnan(defaults[part_places])
            defaults[np.asarray(part_places)[unset]] = own[unset]
            if np.any(own != defaults[part_places]):
                shapes[k] = morphed(part.rest_positions, part.morph_targets, own - defaults[part_places])
        start += part.vertex_count
    names = None if union[0][0] is None else [name for name, _ in union]
    return targets, names, defaults, shapes, places
