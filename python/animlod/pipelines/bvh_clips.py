"""A BVH clip of a character's own skeleton, added to its glTF document by joint name.

Clips captured or edited on a character's skeleton often come as BVH (Blender's and
MotionBuilder's exports). A BVH joint's rotation is relative to the file's rest pose (every
rotation zero, each bone along its OFFSET), a glTF node's to its parent's axes with any rest
rotation of its own (bone roll), so each joint's world rotation is carried over relative to the
rest: ``W(t) = G B(t) G^T W_rest``, with ``B(t)`` the joint's world rotation in the BVH,
``W_rest`` the node's in the character's rest pose, and ``G`` the rotation that best lays the
BVH's rest bones onto the character's (a BVH may be Z-up). The root moves by its displacement
from its OFFSET (its rest position, as Blender's importer reads it), scaled by the ratio of the
two skeletons' bone lengths. The character's nodes the BVH lacks keep their rest rotation; BVH
joints the character lacks, and position channels below the root, are left out and counted.

Only the same skeleton in the same rest pose is taken: every bone between two joints of the
character must lie along its rest direction within ``REST_ANGLE`` once ``G`` turns it, and a
joint's nearest named ancestor must be the same in both, or the file is refused naming the joint
(retargeting between figures or poses is not done here).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .. import rotations
from ..io.bvh import read_bvh
from ..io.errors import FormatError
from ..io.glb_builder import GlbBuilder
from ..io.gltf_document import GltfDocument
from ..io.gltf_write import sign_continuous
from ..model import Motion, Skeleton

# Largest angle between a bone's BVH rest direction (turned by G) and the character's.
REST_ANGLE = np.radians(10.0)


def add_bvh_clip(builder: GlbBuilder, doc: GltfDocument, path: str | os.PathLike, nodes_by_name: dict[str, int]) -> str:
    """Adds the clip of the BVH file at ``path`` to ``builder`` (the document ``doc``) as an
    animation of the nodes named like its joints (``nodes_by_name``: names one node alone has);
    returns the note saying what was added. FormatError naming the file and the joint where the
    skeletons differ (see the module notes)."""
    motion = read_bvh(path)
    skeleton = motion.skeleton
    end_sites = np.zeros(skeleton.joint_count, bool) if skeleton.end_sites is None else skeleton.end_sites
    joints = [j for j, name in enumerate(skeleton.names) if name in nodes_by_name and not end_sites[j]]
    into = Path(doc.path).name
    if 0 not in joints:
        reason = f"its root {skeleton.names[0]!r} is no node of {into}'s by name (another rig?)"
        raise FormatError(os.fspath(path), "ROOT", reason)
    node_of = {j: nodes_by_name[skeleton.names[j]] for j in joints}
    for j, node in node_of.items():
        if doc.gltf.nodes[node].matrix is not None:
            raise FormatError(os.fspath(path), f"joint {skeleton.names[j]!r}", f"{doc.node_label(node)} of {into} "
                              "has a matrix, which glTF does not animate")  # fmt: skip

    turn, scale = _rest_alignment(doc, motion, joints, node_of, os.fspath(path))
    # (T, J, 3, 3) world rotations of the BVH's joints, in the character's axes.
    bvh_world = motion.world_transforms()[..., :3, :3]
    bvh_world = np.einsum("ab,tjbc,dc->tjad", turn, bvh_world, turn)
    frame_count = motion.frame_count
    joint_of = {node: j for j, node in node_of.items()}
    world: dict[int, np.ndarray] = {}  # node -> (T, 3, 3) world rotation while the clip plays

    def world_rotation(node: int) -> np.ndarray:
        if node not in world:
            rest = _rotation(doc.rest_world_matrix(node))
            if node in joint_of:
                world[node] = bvh_world[:, joint_of[node]] @ rest
            elif any(ancestor in joint_of for ancestor in doc.ancestors(node)):  # its rest rotation under its parent's
                world[node] = world_rotation(doc.parents[node]) @ _rotation(doc.rest_matrix(node))
            else:
                world[node] = np.broadcast_to(rest, (frame_count, 3, 3))
        return world[node]

    times = builder.add((np.arange(frame_count) / motion.fps).astype(np.float32)[:, None], bounds=True)
    samplers, channels = [], []

    def animate(node: int, path_name: str, values: np.ndarray) -> None:
        samplers.append({"input": times, "output": builder.add(values.astype(np.float32)), "interpolation": "LINEAR"})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": path_name}})

    for node in node_of.values():
        parent = doc.parents[node]
        parent_world = world_rotation(parent) if parent != -1 else np.eye(3)
        local = np.swapaxes(parent_world, -1, -2) @ world_rotation(node)
        animate(node, "rotation", sign_continuous(rotations.from_matrix(local)[:, None])[:, 0])
    root = node_of[0]
    rest_position = doc.rest_world_matrix(root)[:3, 3]
    moved = rest_position + scale * (motion.root_positions - skeleton.offsets[0]) @ turn.T
    parent_matrix = doc.rest_world_matrix(doc.parents[root]) if doc.parents[root] != -1 else np.eye(4)
    local_positions = (np.c_[moved, np.ones(frame_count)] @ np.linalg.inv(parent_matrix).T)[:, :3]
    animate(root, "translation", local_positions)
    builder.append("animations", {"name": motion.name or Path(path).stem, "samplers": samplers, "channels": channels})

    left_out = [name for j, name in enumerate(skeleton.names) if not end_sites[j] and j not in node_of]
    notes = [f"{os.fspath(path)}: its clip added to {into} ({len(node_of)} joints)"]
    if left_out:
        notes.append(f"{len(left_out)} joint(s) {into} has not left out ({', '.join(left_out[:5])}"
                     f"{', ...' if len(left_out) > 5 else ''})")  # fmt: skip
    if motion.joint_translations is not None:
        notes.append("position channels below the root left out")
    return "; ".join(notes)


def _rest_alignment(
    doc: GltfDocument, motion: Motion, joints: list[int], node_of: dict[int, int], path: str
) -> tuple[np.ndarray, float]:
    """``G`` (3, 3), the rotation that best turns the BVH's rest bones onto the character's
    (Kabsch), and the ratio of their lengths; FormatError naming the first joint whose bone
    points elsewhere or hangs from another named joint."""
    skeleton = motion.skeleton
    bvh_rest = _rest_positions(skeleton)
    named = set(joints)
    pairs = []
    for j in joints[1:]:
        ancestor = int(skeleton.parents[j])
        while ancestor not in named:
            ancestor = int(skeleton.parents[ancestor])
        node, above = node_of[j], node_of[ancestor]
        if above not in doc.ancestors(node):
            reason = f"hangs from {skeleton.names[ancestor]!r}, which is no ancestor of {doc.node_label(node)}"
            raise FormatError(path, f"joint {skeleton.names[j]!r}", reason)
        ours = doc.rest_world_matrix(node)[:3, 3] - doc.rest_world_matrix(above)[:3, 3]
        pairs.append((j, bvh_rest[j] - bvh_rest[ancestor], ours))
    theirs = np.array([pair[1] for pair in pairs]).reshape(-1, 3)
    ours = np.array([pair[2] for pair in pairs]).reshape(-1, 3)
    lengths = np.linalg.norm(theirs, axis=1), np.linalg.norm(ours, axis=1)
    if not len(pairs) or lengths[0].sum() <= 0.0 or lengths[1].sum() <= 0.0:
        raise FormatError(path, "HIERARCHY", f"no bone between two joints of {Path(doc.path).name}'s by name")
    u, _, vt = np.linalg.svd(ours.T @ theirs)
    turn = u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
    for (j, their_bone, our_bone), their_length, our_length in zip(pairs, *lengths):
        if their_length <= 0.0 or our_length <= 0.0:
            continue
        cosine = float(np.dot(turn @ their_bone, our_bone) / (their_length * our_length))
        if cosine < np.cos(REST_ANGLE):
            angle = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0)))
            label = doc.node_label(node_of[j])
            reason = (f"its rest bone points {angle:.0f} degrees away from the character's ({label}): another rest "
                      "pose or figure (retarget the clip to this character first)")  # fmt: skip
            raise FormatError(path, f"joint {skeleton.names[j]!r}", reason)
    return turn, float(lengths[1].sum() / lengths[0].sum())


def _rest_positions(skeleton: Skeleton) -> np.ndarray:
    """(J, 3) world positions of the joints with every rotation zero (a BVH's rest pose)."""
    positions = np.zeros((skeleton.joint_count, 3))
    positions[0] = skeleton.offsets[0]
    for joint in range(1, skeleton.joint_count):
        positions[joint] = positions[skeleton.parents[joint]] + skeleton.offsets[joint]
    return positions


def _rotation(matrix: np.ndarray) -> np.ndarray:
    """The rotation of a (4, 4) transform without shear: its columns made unit length."""
    linear = matrix[:3, :3]
    return linear / np.linalg.norm(linear, axis=0, keepdims=True)
