"""A BVH clip of a character's skeleton, or of another humanoid's, added to its glTF document.

Clips captured or edited on a character's skeleton often come as BVH (Blender's and
MotionBuilder's exports), and capture libraries (CMU's, Bandai-Namco's) as BVH of their own
skeletons. A BVH joint's rotation is relative to the file's rest pose (every rotation zero,
each bone along its OFFSET), a glTF node's to its parent's axes with any rest rotation of its
own (bone roll), so each joint's world rotation is carried over relative to the rests:
``W(t) = G B(t) G^T S W_rest``, with ``B(t)`` the joint's world rotation in the BVH, ``W_rest``
the node's in the character's rest pose, ``G`` the turn between coordinate axes that best lays
the BVH's rest bones onto the character's (a BVH may be Z-up; where its rest pose is no pose of
the figure, its bones in the clip's frames), and ``S`` the joint's swing that lays the
character's rest bones below it onto the BVH's (identity for the same rest pose; an A-pose clip
on a T-pose rig turns the arms): every bone then points where the clip's does, whatever the two
figures' proportions. The joint above every matched one (the file's root, or the hips below a
root of the file's own) moves by its displacement from its rest position (its place in the rest
pose, the file's root on its OFFSET as Blender's importer reads it, or where that OFFSET is
zero, as in CMU's files, at the height that stands the figure on the clip's lowest point),
scaled by the ratio of the two figures' leg lengths. The character's nodes the BVH lacks keep
their rest rotation; BVH joints the character lacks, and position channels below the moving
joint, are left out and counted in the note, which also says how far the rest poses differ.

Joints correspond by the skeletons' shape where the two are alike, else by body part where
they are humanoids of two namings, else by name (:mod:`.joint_matching`, which refuses another
rig); a joint whose nearest matched ancestor differs from the character's is refused naming
the joint.
"""

from __future__ import annotations

import itertools
import os
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .. import rotations
from ..io.bvh import read_bvh
from ..io.errors import FormatError
from ..io.glb_builder import GlbBuilder
from ..io.gltf_document import GltfDocument
from ..io.gltf_write import sign_continuous
from ..model import Motion, Skeleton, spread_frames
from .joint_matching import JointMap, match_joints

# A rest pose whose bones lie farther from the character's on average, after the best turn,
# is no pose of the figure (joint orients baked into the rotations): the axes come from the clip.
NO_POSE_DEGREES = 45.0
# The 24 rotations between coordinate axes: signed permutation matrices of determinant 1.
_AXIS_TURNS = np.array([
    np.diag(signs) @ np.eye(3)[list(order)]
    for order in itertools.permutations(range(3)) for signs in itertools.product((1.0, -1.0), repeat=3)
    if np.linalg.det(np.diag(signs) @ np.eye(3)[list(order)]) > 0.0
])  # fmt: skip


def add_bvh_clip(
    builder: GlbBuilder, doc: GltfDocument, path: str | os.PathLike, joint_map: JointMap | None = None
) -> str:
    """Adds the clip of the BVH file at ``path`` to ``builder`` (the document ``doc``) as an
    animation of the nodes that match its joints (or that ``joint_map`` gives them); returns the
    note saying what was added.
    FormatError naming the file and the joint where the skeletons differ (see the module notes)."""
    motion = read_bvh(path)
    skeleton = motion.skeleton
    end_sites = np.zeros(skeleton.joint_count, bool) if skeleton.end_sites is None else skeleton.end_sites
    match = match_joints(skeleton, doc, os.fspath(path), joint_map)
    node_of = match.node_of
    into = Path(doc.path).name
    for j, node in node_of.items():
        if doc.gltf.nodes[node].matrix is not None:
            raise FormatError(os.fspath(path), f"joint {skeleton.names[j]!r}", f"{doc.node_label(node)} of {into} "
                              "has a matrix, which glTF does not animate")  # fmt: skip

    clip_world = motion.world_transforms()
    rest = skeleton.rest_world_transforms()[:, :3, 3]  # every rotation zero: a BVH's rest pose
    bones = _matched_bones(doc, skeleton, rest, node_of, match.root, os.fspath(path))
    turn, swings, pose_note = _rest_alignment(doc, motion, clip_world[..., :3, 3], bones, os.fspath(path))
    # (T, J, 3, 3) world rotations of the BVH's joints, in the character's axes.
    bvh_world = np.einsum("ab,tjbc,dc->tjad", turn, clip_world[..., :3, :3], turn)
    frame_count = motion.frame_count
    joint_of = {node: j for j, node in node_of.items()}
    world: dict[int, np.ndarray] = {}  # node -> (T, 3, 3) world rotation while the clip plays

    def world_rotation(node: int) -> np.ndarray:
        if node not in world:
            rest = _rotation(doc.rest_world_matrix(node))
            if node in joint_of:
                world[node] = bvh_world[:, joint_of[node]] @ swings[joint_of[node]] @ rest
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
    root_rest, scale = _root_rest(doc, motion, rest, clip_world[..., :3, 3], turn, node_of, match.root, bones)
    root_positions = clip_world[:, match.root, :3, 3]
    translations = _root_translations(doc, node_of[match.root], root_positions, root_rest, scale, turn)
    animate(node_of[match.root], "translation", translations)
    builder.append("animations", {"name": motion.name or Path(path).stem, "samplers": samplers, "channels": channels})

    left_out = [name for j, name in enumerate(skeleton.names) if not end_sites[j] and j not in node_of]
    notes = [f"{os.fspath(path)}: its clip added to {into} ({len(node_of)} joints)"]
    if match.note:
        notes.append(match.note)
    if left_out:
        notes.append(f"{len(left_out)} BVH joint(s) with no counterpart in {into} left out ({', '.join(left_out[:5])}"
                     f"{', ...' if len(left_out) > 5 else ''})")  # fmt: skip
    if pose_note:
        notes.append(pose_note)
    if motion.joint_translations is not None:
        notes.append(f"position channels below {skeleton.names[match.root]!r} left out")
    return "; ".join(notes)


class _Bone(NamedTuple):
    """A matched joint's bone: its nearest matched ancestor, and the bone from it in the BVH's rest
    pose and in the character's."""

    above: int
    theirs: np.ndarray
    ours: np.ndarray


def _matched_bones(
    doc: GltfDocument, skeleton: Skeleton, rest: np.ndarray, node_of: dict[int, int], root: int, path: str
) -> dict[int, _Bone]:
    """Each matched joint but ``root``, in joint order, with its :class:`_Bone` (``rest`` (J, 3):
    the BVH's rest pose). FormatError naming the first joint that hangs from another matched joint
    than in the character, or from none below ``root``."""
    bones = {}
    for j in sorted(node_of):
        if j == root:
            continue
        ancestor = int(skeleton.parents[j])
        while ancestor not in node_of:
            if ancestor == -1:
                raise FormatError(path, f"joint {skeleton.names[j]!r}", f"lies below none of the matched joints' root "
                                  f"{skeleton.names[root]!r}")  # fmt: skip
            ancestor = int(skeleton.parents[ancestor])
        node, above = node_of[j], node_of[ancestor]
        if above not in doc.ancestors(node):
            reason = f"hangs from {skeleton.names[ancestor]!r}, which is no ancestor of {doc.node_label(node)}"
            raise FormatError(path, f"joint {skeleton.names[j]!r}", reason)
        ours = doc.rest_world_matrix(node)[:3, 3] - doc.rest_world_matrix(above)[:3, 3]
        bones[j] = _Bone(ancestor, rest[j] - rest[ancestor], ours)
    return bones


def _rest_alignment(
    doc: GltfDocument, motion: Motion, clip_positions: np.ndarray, bones: dict[int, _Bone], path: str
) -> tuple[np.ndarray, dict[int, np.ndarray], str | None]:
    """``G`` (3, 3), the turn between axes that best lays the BVH's rest ``bones`` onto the
    character's (or, where the rest pose is no pose of the figure, its bones in the clip's frames
    ``clip_positions`` (T, J, 3)), each matched joint's swing ``S`` (3, 3) that lays the
    character's rest bones below it onto the BVH's turned by ``G``, and a note on how the rest
    poses differ. FormatError where no bone has a length."""
    theirs = np.array([bone.theirs for bone in bones.values()]).reshape(-1, 3)
    ours = np.array([bone.ours for bone in bones.values()]).reshape(-1, 3)
    if not (np.linalg.norm(theirs, axis=1).sum() > 0.0 and np.linalg.norm(ours, axis=1).sum() > 0.0):
        raise FormatError(path, "HIERARCHY", f"no bone between two of its joints matched to {Path(doc.path).name}'s")
    fit = _best_rotation(theirs, ours)
    lengths = np.linalg.norm(ours, axis=1)
    spread = np.average([_angle(fit @ their, our) for their, our in zip(theirs, ours)], weights=lengths)
    if spread > NO_POSE_DEGREES:
        frames = clip_positions[spread_frames(motion.frame_count, min(motion.frame_count, 64))]
        posed = frames[:, list(bones)] - frames[:, [bone.above for bone in bones.values()]]
        fit = _best_rotation(posed.reshape(-1, 3), np.tile(ours, (len(frames), 1)))
    turn = _axis_turn(fit)
    swings = {}
    for j in sorted({*bones, *(bone.above for bone in bones.values())}):  # every matched joint
        below = [(bone.ours, turn @ bone.theirs) for bone in bones.values() if bone.above == j]
        swings[j] = _best_rotation(*map(np.array, zip(*below))) if below else np.eye(3)
    angles = [_angle(turn @ bone.theirs, bone.ours) for bone in bones.values()]
    worst = int(np.argmax(angles)) if angles else 0
    note = None
    if spread > NO_POSE_DEGREES:
        note = (f"its rest pose is no pose of the figure (its bones {spread:.0f} degrees from the character's on "
                "average): the axes are taken from its frames; each bone follows the clip's direction")  # fmt: skip
    elif angles and angles[worst] > 1.0:
        name = motion.skeleton.names[list(bones)[worst]]
        note = (f"its rest pose differs from the character's by up to {angles[worst]:.0f} degrees (the bone to "
                f"{name!r}): each bone follows the clip's direction")  # fmt: skip
    return turn, swings, note


def _axis_turn(rotation: np.ndarray) -> np.ndarray:
    """The turn between coordinate axes nearest ``rotation`` (one of the 24 signed permutations
    of determinant 1): exporters write Y-up or Z-up axes, and what the best fit adds to such a turn
    is a difference of the two rest poses, which each joint's swing takes."""
    turns = _AXIS_TURNS
    return turns[int(np.argmax(np.einsum("kij,ij->k", turns, rotation)))]


def _best_rotation(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The rotation that best turns the vectors ``source`` (n, 3) onto ``target`` (n, 3): Kabsch,
    or for one vector the smallest rotation between the two directions (no twist of its own)."""
    if len(source) == 1:
        a, b = (v / max(np.linalg.norm(v), 1e-300) for v in (source[0], target[0]))
        axis, cosine = np.cross(a, b), float(np.dot(a, b))
        if cosine < -1.0 + 1e-12:  # opposite: half a turn about any perpendicular axis
            perpendicular = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
            perpendicular /= np.linalg.norm(perpendicular)
            return 2.0 * np.outer(perpendicular, perpendicular) - np.eye(3)
        cross = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
        return np.eye(3) + cross + cross @ cross / (1.0 + cosine)
    u, _, vt = np.linalg.svd(target.T @ source)
    return u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """Degrees between two vectors (0 where one is zero)."""
    lengths = np.linalg.norm(a) * np.linalg.norm(b)
    return float(np.degrees(np.arccos(np.clip(np.dot(a, b) / lengths, -1.0, 1.0)))) if lengths > 0.0 else 0.0


def _root_translations(
    doc: GltfDocument, node: int, root_positions: np.ndarray, root_rest: np.ndarray, scale: float, turn: np.ndarray
) -> np.ndarray:
    """(T, 3) translations of ``node``, the node of the BVH joint above every matched joint, in the
    frame of the node's parent: its rest position moved by the joint's displacement from its rest,
    ``root_positions`` (T, 3) - ``root_rest``, scaled and turned into the character's axes
    (:func:`_root_rest`)."""
    moved = doc.rest_world_matrix(node)[:3, 3] + scale * (root_positions - root_rest) @ turn.T
    parent = doc.parents[node]
    to_parent = np.linalg.inv(doc.rest_world_matrix(parent)) if parent != -1 else np.eye(4)
    return (np.c_[moved, np.ones(len(moved))] @ to_parent.T)[:, :3]


def _root_rest(
    doc: GltfDocument,
    motion: Motion,
    rest: np.ndarray,
    clip_positions: np.ndarray,
    turn: np.ndarray,
    node_of: dict[int, int],
    root: int,
    bones: dict[int, _Bone],
) -> tuple[np.ndarray, float]:
    """(3,) where the BVH joint ``root`` stands in the rest pose, and the scale of its moves: the
    ratio of the two legs' lengths (the matched bones from the root down to the joint lowest in
    the clip), so that feet that touch the floor in the clip touch it on the character. The rest
    pose stands the file's root on its OFFSET, or where that is zero (CMU's files give none: their
    root channels are heights above the floor) at the height that makes the root's height above
    the clip's lowest point the scaled height of its node above the character's lowest matched
    joint (``turn`` maps the file's axes onto the character's, whose up is +Y). Lengths, not the
    rest pose's heights: some files' rest pose is no pose of the figure (Bandai-Namco's lays
    every bone along its joint's x axis)."""
    joints = list(node_of)
    up = turn[1]  # the file's up direction
    heights = clip_positions[:, joints] @ up
    theirs = ours = 0.0
    joint = joints[int(np.argmin(heights.mean(axis=0)))]
    while joint != root:
        theirs += float(np.linalg.norm(bones[joint].theirs))
        ours += float(np.linalg.norm(bones[joint].ours))
        joint = bones[joint].above
    scale = ours / theirs if theirs > 0.0 and ours > 0.0 else 1.0
    if np.any(motion.skeleton.offsets[0] != 0.0):
        return rest[root], scale
    our_heights = np.array([doc.rest_world_matrix(node)[1, 3] for node in node_of.values()])
    our_height = doc.rest_world_matrix(node_of[root])[1, 3] - our_heights.min()
    return rest[root] - up * (rest[root] @ up) + up * (float(heights.min()) + our_height / scale), scale


def _rotation(matrix: np.ndarray) -> np.ndarray:
    """The rotation of a (4, 4) transform without shear: its columns made unit length."""
    linear = matrix[:3, :3]
    return linear / np.linalg.norm(linear, axis=0, keepdims=True)
