"""A glTF skin as an animlod skeleton, and its animations as motions.

A file without skins (an animation library exported without its mesh) gives its animated node
tree instead: the nodes its animations move and every node below one that draws nothing (end
sites, helper bones) and holds no prop (a keyless node over a mesh, as animlod's level files hang
a prop from a frozen joint's kept ancestor), with an identity inverse bind.

The skin's joints are put in topological order (parents first; an order that already is
topological is kept, so JOINTS_0 of such files need no remapping). Every joint and every
ancestor of one takes part in posing: the armature above the root joint (glTF viewers apply
it, so baking must too) and any non-joint node between two joints. A pose composes world
rotations and positions through that node tree; a joint's motion rotation is then its world
rotation relative to its parent joint's, and the root's position is its world position.
Joints that form several trees (several root bones under one armature) get the lowest node
above all of them as an extra root joint.

Scale: glTF nodes may scale, animlod skeletons are rigid. A uniform rest scale ``c``
accumulated down the tree scales the bone offsets below it, and ``diag(c, c, c, 1)`` moves into
the joint's inverse bind matrix (``W = W_rigid @ S(c)``, so ``W @ IBM = W_rigid @ (S(c) @ IBM)``).
A non-uniform rest scale (a node stretched along one axis) poses the full transforms, and what
each joint's world transform does beyond ``S(c)`` at rest, ``rest_shape``, moves into the
inverse bind too. An animation that scales nodes of the tree (squash and stretch, parts shrunk to
nothing), or turns a joint under a non-uniformly scaled one (a shear), poses the full transforms:
the joints' rigid frames move with the scaled offsets, and the rest of each joint's world
transform becomes the motion's ``joint_deformations``
(``W = W_rigid @ D @ rest_shape @ S(c)``), which skinning applies and motion LoD refuses;
``D`` within 1e-3 of the identity in every frame is float noise (3ds Max's Biped scales) and
leaves the motion rigid.
A mirrored node (a negative scale, as 3ds Max and Maya write mirrored bones) counts as
non-uniform, and the rotations below it are mirrored too (``F @ R @ F``, :func:`_mirrored`), so
that the mirroring stays in ``rest_shape`` and the motion stays rigid.
"""

from __future__ import annotations

import heapq
from collections.abc import Sequence

import numpy as np

from .. import rotations
from ..model import Motion, Skeleton
from .gltf_document import (
    LIGHTS_EXTENSION,
    NODE_PATHS,
    UNIFORM_SCALE_TOLERANCE,
    GltfDocument,
    affine_rows,
    last_row_fault,
)
from .gltf_keyframes import sample_keyframes

# Animated bone offsets within this fraction of the skeleton's largest rest offset of their
# rest value count as held, so the motion needs no per-frame joint translations.
_HELD_TRANSLATION_TOLERANCE = 1e-4
# Below this relative volume (|det| over the product of the column lengths) a 3x3 part counts as
# singular: its inverse would amplify float32 noise by more than a million.
_SINGULAR_VOLUME = 1e-6
# A joint whose deformation relative to its rest shape stays this close to the identity in every
# frame (a stretched leaf, a stretched joint whose children do not turn) leaves the motion rigid.
# 3ds Max's Biped writes every node's scale off 1 by up to ~1.5e-4 on each axis, and glTF turns
# that into shears of ~2e-4 under turning joints (assimp's MotionCaptureROM.ase, exported to
# glTF): float noise, which refused the file's motion LoD at 1e-6; a real stretch is far above.
_RIGID_DEFORMATION_TOLERANCE = 1e-3
# Node extras key marking a joint as an end site (a BVH "End Site": a leaf without rotation);
# animlod writes it and reads it back, other tools ignore it.
END_SITE_EXTRA = "animlod_end_site"


class SkinRig:
    """Skin ``skin`` of a document (None: its animated node tree) as a skeleton, with what is
    needed to pose it.

    Attributes
    ----------
    skeleton : the joints in topological order, rest offsets and rotations from the nodes.
        When the skin's joints form several trees, their lowest common ancestor node joins
        the skeleton as its root (no vertex is bound to it, its inverse bind is identity).
        ``extra_joints`` (nodes below the skin's joints, with ``extra_binds`` (E, 4, 4) in the
        skin's bind space) join it too: the bones of another skin that plays this one's skeleton
        (pipelines/skin_parts.py); no vertex of this skin is bound to them.
    skin_slots : S, the number of joints the skin lists (JOINTS_0 indexes them).
    remap : (J,) skeleton joint of each skin slot, then of the extra joints and the added common
        root if any.
    scales : (J,) accumulated uniform scale of each joint's node at rest (non-uniform nodes count 1).
    rest_shape : (J, 3, 3) what each joint's rest world transform does beyond its rotation and
        ``scales`` (a non-uniform rest scale), in the joint's frame; None when every node is uniform.
    inverse_bind : (J, 4, 4) the skin's inverse bind matrices in skeleton order, as stored.
    trees_left_out : without a skin, the first node of each animated tree under no node in common
        with the skeleton's (a weapon animated beside the character), for messages.
    """

    def __init__(
        self,
        doc: GltfDocument,
        skin: int | None,
        extra_joints: Sequence[int] = (),
        extra_binds: np.ndarray | None = None,
    ) -> None:
        self.skin = skin
        self.element = "animated nodes" if skin is None else f"skin {skin}"
        self.trees_left_out: list[str] = []
        joint_nodes = self._joint_nodes(doc)
        self.skin_slots = len(joint_nodes)
        self.extra_joints = list(extra_joints)
        self.extra_binds = np.zeros((0, 4, 4)) if extra_binds is None else np.asarray(extra_binds, np.float64)
        joint_nodes += self.extra_joints
        joint_nodes += self._common_root(doc, joint_nodes)
        parent_slots = self._parent_slots(doc, joint_nodes)
        order = _topological_order(parent_slots)
        self.joint_nodes = [joint_nodes[slot] for slot in order]
        self.remap = np.empty(len(order), np.int64)
        self.remap[order] = np.arange(len(order))
        parents = np.array([-1 if parent_slots[slot] < 0 else self.remap[parent_slots[slot]] for slot in order])
        self._parents = parents
        # Every joint and ancestor, parents first (depth order).
        tree = {n for joint in joint_nodes for n in [joint, *doc.ancestors(joint)]}
        self._nodes = sorted(tree, key=lambda n: len(doc.ancestors(n)))
        self._node_parents = {n: int(doc.parents[n]) for n in self._nodes}
        self.rest_translation, self.rest_rotation, self._rest_scale = {}, {}, {}
        self._local_scale, self._world_scale = {}, {}
        self._mirror: dict[int, np.ndarray] = {}  # (3,) signs of the scales down to each node at rest
        uniform = True
        for node in self._nodes:
            translation, rotation, scale = doc.rest_trs(node)
            self.rest_translation[node], self.rest_rotation[node] = translation[None], rotation[None]
            self._rest_scale[node] = scale[None]
            common = doc.uniform_scale(node, scale, self.element)
            uniform &= common is not None
            self._local_scale[node] = 1.0 if common is None else common
            self._world_scale[node] = self._local_scale[node] * self._world_scale.get(self._node_parents[node], 1.0)
            self._mirror[node] = np.sign(scale) * self._mirror.get(self._node_parents[node], np.ones(3))
        self.scales = np.array([self._world_scale[n] for n in self.joint_nodes])
        self.inverse_bind = self._inverse_bind(doc, len(order))[order]
        positions, world_rotations, rest_shape = self._pose(
            self.rest_translation, self.rest_rotation, frames=1, scales=None if uniform else self._rest_scale
        )
        self.rest_shape = None if uniform else rest_shape[0]
        offsets = self._offsets(positions, world_rotations)[0]
        self._translation_tolerance = _HELD_TRANSLATION_TOLERANCE * max(np.abs(offsets[1:]).max(initial=0.0), 1e-12)
        names = _unique_names(doc, self.joint_nodes)
        try:
            self.skeleton = Skeleton(
                names, parents, offsets, self._local_rotations(world_rotations)[0], end_sites=self._end_sites(doc)
            )
        except ValueError as error:
            raise doc.fail(self.element, str(error)) from None

    @property
    def rest_linear(self) -> np.ndarray:
        """(J, 3, 3) what each joint's rest world transform does beyond its rotation, in the joint's
        frame: ``rest_shape @ S(c)``, ``S(c)`` alone when every node is uniform. The inverse binds
        fold it in (the rigid skeleton's joints do not carry it), and so does a node hung from a joint."""
        scale = self.scales[:, None, None] * np.eye(3)
        return scale if self.rest_shape is None else self.rest_shape @ scale

    def animations(self, doc: GltfDocument) -> list[int]:
        """The animations of ``doc`` that move one of its nodes (:meth:`motion` gives a motion for each)."""
        return [
            index
            for index, targets in enumerate(doc.channel_targets)
            if any(self._moves(*target) for target in targets)
        ]

    def _moves(self, node: int, path: str) -> bool:
        return node in self.rest_translation and path in NODE_PATHS

    def motion(self, doc: GltfDocument, animation_index: int, fps: float) -> Motion | None:
        """Animation ``animation_index`` sampled at ``fps`` on this skeleton; None if it moves none of its nodes.

        Channels missing for a node keep its rest TRS. Animated translations of non-root bones
        become per-frame ``joint_translations`` (None when every bone keeps its rest offset).
        """
        animation = doc.gltf.animations[animation_index]
        label = doc.animation_label(animation_index)
        channels = [
            (index, channel.sampler, node, path)
            for index, (channel, (node, path)) in enumerate(
                zip(animation.channels or [], doc.channel_targets[animation_index])
            )
            if self._moves(node, path)
        ]
        if not channels:
            return None
        at = doc.animation_frame_times(animation_index, fps)
        translations, local_rotations = dict(self.rest_translation), dict(self.rest_rotation)
        scales = dict(self._rest_scale)
        scaled = self.rest_shape is not None
        for index, sampler, node, path in channels:
            if path == "scale":  # its keys, not only its samples, tell float noise from a stretch
                times, values, interpolation = doc.sampler_keys(animation_index, sampler, 3, f"{label} channel {index}")
                scales[node] = sample_keyframes(times, values, interpolation, at)
                scaled |= self._scale_moves(node, values)
            elif path == "translation":
                translations[node] = doc.sampled_channel(animation_index, index, path, at)
            else:
                local_rotations[node] = doc.sampled_channel(animation_index, index, path, at)
        # Scale keys within float noise of the rest scale leave the motion rigid.
        positions, world_rotations, deformations = self._pose(
            translations, local_rotations, frames=len(at), scales=scales if scaled else None
        )
        if self.rest_shape is not None:  # the rest shape is in the inverse binds already
            deformations = deformations @ np.linalg.inv(self.rest_shape)
            if np.abs(deformations - np.eye(3)).max() <= _RIGID_DEFORMATION_TOLERANCE:
                deformations = None
        offsets = self._offsets(positions, world_rotations)
        bones_move = np.abs(offsets[:, 1:] - self.skeleton.offsets[1:]).max(initial=0.0) > self._translation_tolerance
        try:
            return Motion(
                self.skeleton,
                offsets[:, 0],
                self._local_rotations(world_rotations),
                fps=fps,
                name=animation.name or "",
                joint_translations=offsets if bones_move else None,
                joint_deformations=deformations,
            )
        except ValueError as error:
            raise doc.fail(label, str(error)) from None

    def _end_sites(self, doc: GltfDocument) -> np.ndarray:
        extras = [doc.gltf.nodes[n].extras for n in self.joint_nodes]
        return np.array([isinstance(e, dict) and e.get(END_SITE_EXTRA) is True for e in extras])

    def _joint_nodes(self, doc: GltfDocument) -> list[int]:
        if self.skin is None:
            nodes, self.trees_left_out = _animated_tree(doc)
            return nodes
        joints = list(doc.gltf.skins[self.skin].joints or [])
        if not joints:
            raise doc.fail(self.element, "has no joints")
        for slot, node in enumerate(joints):
            doc.item("nodes", node, f"{self.element} joint {slot}")
        if len(set(joints)) != len(joints):
            raise doc.fail(self.element, "lists a node twice among its joints")
        return joints

    def _common_root(self, doc: GltfDocument, joint_nodes: list[int]) -> list[int]:
        """``[lowest common ancestor]`` of the joints' top nodes when there are several, else ``[]``."""
        joints = set(joint_nodes)
        roots = [node for node in joint_nodes if joints.isdisjoint(doc.ancestors(node))]
        if len(roots) == 1:
            return []
        shared = set.intersection(*({root, *doc.ancestors(root)} for root in roots))
        if not shared:
            raise doc.fail(self.element, _separate_trees(doc, roots))
        return [max(shared, key=lambda node: len(doc.ancestors(node)))]  # the deepest shared node

    def _parent_slots(self, doc: GltfDocument, joint_nodes: list[int]) -> list[int]:
        """Slot of each joint's nearest joint ancestor, -1 for the root."""
        slot_of = {node: slot for slot, node in enumerate(joint_nodes)}
        return [next((slot_of[a] for a in doc.ancestors(node) if a in slot_of), -1) for node in joint_nodes]

    def _inverse_bind(self, doc: GltfDocument, joint_count: int) -> np.ndarray:
        """Inverse bind matrices ``(J, 4, 4)`` in slot order: the skin's (identity when absent), the
        extra joints', then identity for an added common root (and for an animated node tree, which
        has no skin)."""
        matrices = np.broadcast_to(np.eye(4), (joint_count, 4, 4)).copy()
        matrices[self.skin_slots : self.skin_slots + len(self.extra_binds)] = self.extra_binds
        if self.skin is None or doc.gltf.skins[self.skin].inverseBindMatrices is None:
            return matrices
        skin = doc.gltf.skins[self.skin]
        stored = doc.accessor(skin.inverseBindMatrices, f"{self.element} inverseBindMatrices")
        count = self.skin_slots
        if stored.shape != (count, 16) or stored.dtype.kind != "f":
            got = f"{stored.shape[0]} of width {stored.shape[1]}"
            raise doc.fail(self.element, f"inverseBindMatrices must be {count} float MAT4, got {got}")
        matrices[:count] = stored.reshape(count, 4, 4).transpose(0, 2, 1)  # glTF is column-major
        projective = np.flatnonzero(~affine_rows(matrices[:count]))
        if projective.size:  # a row-major write puts the translation there: skinning ran on w != 1
            slot = int(projective[0])
            reason = f"inverse bind matrix of joint {slot} ({doc.node_label(skin.joints[slot])}) "
            raise doc.fail(f"{self.element} inverseBindMatrices", reason + last_row_fault(matrices[slot]))
        # Skinning and re-skinning invert these; a singular one must be named here, not fail
        # later as a bare "Singular matrix". Volume of the columns relative to their lengths:
        # 1 for a rotation-scale, 0 for a flattened matrix.
        linear = matrices[:count, :3, :3]
        lengths = np.prod(np.linalg.norm(linear, axis=1), axis=1)
        volume = np.abs(np.linalg.det(linear)) / np.where(lengths > 0.0, lengths, 1.0)
        singular = np.flatnonzero((lengths == 0.0) | (volume < _SINGULAR_VOLUME))
        if singular.size:
            slot = int(singular[0])
            reason = f"inverse bind matrix of joint {slot} ({doc.node_label(doc.gltf.skins[self.skin].joints[slot])}) "
            raise doc.fail(f"{self.element} inverseBindMatrices", reason + "is singular (cannot be inverted)")
        return matrices

    def _pose(
        self, translations: dict, local_rotations: dict, frames: int, scales: dict | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """World positions ``(T, J, 3)``, rotations ``(T, J, 4)`` and deformations ``(T, J, 3, 3)``
        (None without ``scales``) of the joints, T = ``frames``.

        ``translations[node] (T or 1, 3)`` and ``local_rotations[node] (T or 1, 4)`` give the
        local transform of every node of the tree. A node's position is its parent's plus the
        parent's accumulated scale times its translation turned by the parent's rotation. With
        ``scales[node] (T or 1, 3)``, the parent's full linear part ``L`` (rotations and scales
        down the tree) takes the place of that scale and rotation, and a joint's deformation is
        ``R_world^T @ L / c``, ``c`` its accumulated rest scale (in the inverse bind already).
        """
        position, rotation, linear = {}, {}, {}
        for node in self._nodes:
            parent = self._node_parents[node]
            if scales is not None:
                own = rotations.to_matrix(local_rotations[node]) * scales[node][:, None, :]  # R @ diag(s)
                linear[node] = own if parent < 0 else linear[parent] @ own
            if parent < 0:
                position[node], rotation[node] = translations[node], local_rotations[node]
                continue
            if scales is None:
                turned = self._world_scale[parent] * rotations.rotate(rotation[parent], translations[node])
            else:
                turned = (linear[parent] @ translations[node][..., None])[..., 0]
            position[node] = position[parent] + turned
            turned_rotation = _mirrored(local_rotations[node], self._mirror[parent])
            rotation[node] = rotations.multiply(rotation[parent], turned_rotation)
        world_rotations = self._per_joint(rotation, frames)
        if scales is None:
            return self._per_joint(position, frames), world_rotations, None
        linears = np.stack([np.broadcast_to(linear[n], (frames, 3, 3)) for n in self.joint_nodes], axis=1)
        unturned = np.swapaxes(rotations.to_matrix(world_rotations), -1, -2) @ linears
        return self._per_joint(position, frames), world_rotations, unturned / self.scales[:, None, None]

    def _per_joint(self, values: dict, frames: int) -> np.ndarray:
        """``(T, J, C)`` from per-node ``(T or 1, C)`` arrays."""
        return np.stack([np.broadcast_to(values[n], (frames, values[n].shape[1])) for n in self.joint_nodes], axis=1)

    def _offsets(self, positions: np.ndarray, world_rotations: np.ndarray) -> np.ndarray:
        """Joint translations ``(T, J, 3)`` in the parent joint's rigid frame (the root's in the world)."""
        offsets = positions.copy()
        parents = self._parents[1:]
        offsets[:, 1:] = rotations.rotate(
            rotations.conjugate(world_rotations[:, parents]), positions[:, 1:] - positions[:, parents]
        )
        return offsets

    def _local_rotations(self, world_rotations: np.ndarray) -> np.ndarray:
        """Joint rotations ``(T, J, 4)`` relative to the parent joint's world rotation."""
        local = world_rotations.copy()
        parents = self._parents[1:]
        local[:, 1:] = rotations.multiply(rotations.conjugate(world_rotations[:, parents]), world_rotations[:, 1:])
        return local

    def _scale_moves(self, node: int, values: np.ndarray) -> bool:
        """Whether a scale channel's keys leave the node's rest scale by more than float noise."""
        keys = values[:, 1] if values.ndim == 3 else values  # CUBICSPLINE: the values between tangents
        rest = self._rest_scale[node]
        return float(np.abs(keys - rest).max()) > UNIFORM_SCALE_TOLERANCE * float(np.abs(rest).max())


def _animated_tree(doc: GltfDocument) -> tuple[list[int], list[str]]:
    """The nodes an animation translates, turns or scales, but cameras and lights (the scene's, not
    the skeleton's), meshes that only scale and the lower levels of MSFT_lod chains, and every
    node below one that draws nothing and,
    unless it holds one of those, holds nothing that draws (an end site or a bone without keys),
    in node order; and the labels of the top nodes of trees left out. Animated nodes under no
    common node (a weapon animated beside the character, a second character) are several trees:
    the one of the most nodes is the skeleton."""
    nodes = doc.gltf.nodes or []
    staging = {
        index
        for index, node in enumerate(nodes)
        if node.camera is not None or LIGHTS_EXTENSION in (node.extensions or {})
    }
    moved = doc.moved_nodes() - staging - doc.alternate_nodes()  # a level node plays its base's channels
    # A mesh that only scales, with nothing moving below it (a blinking light), is a prop on its
    # parent, not a bone: a rigid skeleton has none that scales.
    turned = {node for targets in doc.channel_targets for node, path in targets if path in ("translation", "rotation")}
    carried_moves = {ancestor for node in moved for ancestor in doc.ancestors(node)}
    moved -= {node for node in moved - turned - carried_moves if nodes[node].mesh is not None}
    if not moved:
        raise doc.fail(
            "animations", "no skin, and no animation translates, turns or scales a node: no skeleton to read"
        )
    # A keyless node whose subtree draws and moves nothing holds a prop (or a camera): not a bone.
    drawing = {index for index, node in enumerate(nodes) if node.mesh is not None} | staging
    holds = {ancestor for index in drawing - moved for ancestor in doc.ancestors(index)}
    carries = {ancestor for index in moved for ancestor in doc.ancestors(index)}
    tree = [
        index
        for index in range(len(nodes))
        if index in moved
        or (
            index not in drawing
            and (index in carries or index not in holds)
            and not moved.isdisjoint(doc.ancestors(index))
        )
    ]
    trees: dict[int, list[int]] = {}  # by the top node of the scene tree each lies in
    for index in tree:
        trees.setdefault([index, *doc.ancestors(index)][-1], []).append(index)
    kept = max(trees.values(), key=len)  # the first of the largest
    left_out = [members[0] for members in trees.values() if members is not kept]
    return kept, [doc.node_label(node) for node in left_out]


def _separate_trees(doc: GltfDocument, roots: list[int]) -> str:
    """Why joints whose top joints ``roots`` share no node cannot be one skeleton, naming the node
    trees they are in: an exporter that leaves one joint out of the armature's children (Blender's
    flattened deform bones) reads as that joint, the child of no node, beside the armature holding
    the rest."""
    trees: dict[int, list[int]] = {}
    for root in roots:
        trees.setdefault(([root, *doc.ancestors(root)])[-1], []).append(root)
    parts = []
    for top, members in trees.items():
        if members == [top]:
            parts.append(f"{doc.node_label(top)}, the child of no node")
            continue
        shown = ", ".join(doc.node_label(member) for member in members[:3]) + (", ..." if len(members) > 3 else "")
        parts.append(f"{len(members)} under {doc.node_label(top)} ({shown})")
    return f"joints form {len(trees)} node trees with no node in common: {'; '.join(parts)}; one root is needed"


def _mirrored(rotation: np.ndarray, signs: np.ndarray) -> np.ndarray:
    """Quaternions ``(..., 4)`` of ``F @ R @ F``, F = diag(``signs``) the mirroring above a node: a
    rotation again. Under a mirrored parent, ``L_parent @ R = Q_parent @ (F R F) @ F`` keeps the
    mirroring F (with the scale) in the rest shape and the rigid frames turning."""
    if np.all(signs > 0.0):
        return rotation
    # F R(a, t) F = R(det(F) F a, t): the axis mirrored, and reversed by an odd mirroring.
    factors = np.append(np.prod(signs) * signs, 1.0)
    return rotation * factors


def _topological_order(parent_slots: list[int]) -> list[int]:
    """Skin slots ordered parents first; an order that already is topological stays as it is.

    Kahn's algorithm, taking the smallest ready slot each time.
    """
    children: list[list[int]] = [[] for _ in parent_slots]
    for slot, parent in enumerate(parent_slots):
        if parent >= 0:
            children[parent].append(slot)
    ready = [slot for slot, parent in enumerate(parent_slots) if parent < 0]
    order = []
    while ready:
        slot = heapq.heappop(ready)
        order.append(slot)
        for child in children[slot]:
            heapq.heappush(ready, child)
    return order


def _unique_names(doc: GltfDocument, nodes: list[int]) -> list[str]:
    """Node names (``node<i>`` when unnamed), with ``#<node>`` appended where names repeat."""
    names = [doc.gltf.nodes[n].name or f"node{n}" for n in nodes]
    repeated = {name for name in names if names.count(name) > 1}
    return [f"{name}#{node}" if name in repeated else name for name, node in zip(names, nodes)]
