"""Which node of a character each joint of a BVH clip drives.

Exporters name one skeleton's joints differently (CMU's ASF conversions say ``LeftHip`` and
``LeftKnee`` where the cgspeed BVH files and the rigs made from them say ``LeftUpLeg`` and
``LeftLeg``; Mixamo adds a ``mixamorig:`` namespace), and one name can mean two joints: CMU's
``LeftShoulder`` is the upper arm, a cgspeed rig's is the collar. So where the two skeletons
have the same shape (the rooted tree of the BVH's joints, with or without its end sites, and
that of the skins' joints), joints correspond by their place in it: children of one shape are
told apart by name, then by side (left or right in the name), then by their order in the files,
which the note then says. Humanoids of two namings correspond by body part
(:mod:`.humanoid_roles`: CMU's ``LeftShoulder`` onto Mixamo's ``LeftArm``). Other skeletons
correspond by name, exactly or up to case, separators and namespace. Where none of these tells,
the user's table does (:class:`JointMap`), and only its entries are matched.
"""

from __future__ import annotations

import json
import os
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..io.errors import FormatError
from ..io.gltf_document import GltfDocument
from ..model import Skeleton
from .humanoid_roles import MIN_ROLES, roles_of
from .joint_names import normalized_name, side, unique_index


@dataclass(frozen=True)
class JointMatch:
    """``node_of``: the character's node each BVH joint drives (end sites left out), ``root``:
    the BVH joint above all of them, whose node takes the clip's translation; ``note``: how they
    were matched where names alone would not say it, else None."""

    node_of: dict[int, int]
    note: str | None
    root: int = 0


@dataclass(frozen=True)
class JointMap:
    """A table of the node each BVH joint drives, where no rule finds it (a rig of unnamed or
    unusual joints): ``nodes`` maps a joint's name to a node's name or index; ``path`` is the
    table's file, named in messages."""

    path: str
    nodes: dict[str, str | int]


def read_joint_map(path: str | os.PathLike) -> JointMap:
    """The JSON object of ``path`` ({"BVH joint": "node name" or node index, ...}); FormatError
    naming the file and the entry that is not one."""
    where = os.fspath(path)
    try:
        table = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise FormatError(where, "JSON", f"no joint map: {error}") from None
    if not isinstance(table, dict) or not table:
        raise FormatError(where, "JSON", 'a joint map is an object {"BVH joint": "node name" or node index, ...}')
    for joint, node in table.items():
        if isinstance(node, bool) or not isinstance(node, str | int) or (isinstance(node, int) and node < 0):
            raise FormatError(where, repr(joint), f"maps to {node!r}: a node's name or index is expected")
    return JointMap(where, table)


@dataclass(frozen=True)
class _Tree:
    """A rooted tree of ids (BVH joints or glTF nodes): ``order`` parents first, ``parent`` of
    each id (-1 for the root), ``names`` of each."""

    order: list[int]
    parent: dict[int, int]
    names: dict[int, str]

    def children(self) -> dict[int, list[int]]:
        result: dict[int, list[int]] = defaultdict(list)
        for item in self.order[1:]:
            result[self.parent[item]].append(item)
        return result


def match_joints(skeleton: Skeleton, doc: GltfDocument, path: str, joint_map: JointMap | None = None) -> JointMatch:
    """The character's node of each joint of ``skeleton`` (the BVH file ``path``'s) in ``doc``
    (see the module notes, or ``joint_map``'s entries alone where given); joints that match no
    node are left out of ``node_of``. FormatError naming the file where the root matches no node,
    or where names alone match fewer than half of the smaller skeleton's joints (another rig:
    what little matched would move a few joints of another figure, some of them named alike for
    other places), or naming the joint map's entry that names no joint or node."""
    end_sites = np.zeros(skeleton.joint_count, bool) if skeleton.end_sites is None else skeleton.end_sites
    if joint_map is not None:
        return _match_by_map(skeleton, doc, end_sites, joint_map, path)
    skin_joints = {int(j) for skin in doc.gltf.skins or [] for j in skin.joints or []}
    ours = _tree_of(doc, skin_joints)
    if ours is not None:
        for with_end_sites in (True, False):
            kept = [j for j in range(skeleton.joint_count) if with_end_sites or not end_sites[j]]
            theirs = _Tree(kept, {j: int(skeleton.parents[j]) for j in kept}, dict(enumerate(skeleton.names)))
            paired = _pair_by_shape(theirs, ours)
            if paired is not None:
                pairs, in_file_order = paired
                return JointMatch({j: n for j, n in pairs.items() if not end_sites[j]},
                                  _shape_note(skeleton, doc, pairs, end_sites, in_file_order))  # fmt: skip
    into = Path(doc.path).name
    by_role = _match_by_role(skeleton, doc, end_sites, skin_joints)
    if by_role is not None:
        return by_role
    match = _match_by_name(skeleton, doc, end_sites)
    if 0 not in match.node_of:
        reason = (f"its root {skeleton.names[0]!r} matches no node of {into}'s, by shape, body part or name "
                  "(another rig? a joint map, --joint-map, pairs the joints)")  # fmt: skip
        raise FormatError(path, "ROOT", reason)
    joint_count = int(np.count_nonzero(~end_sites))
    node_count = len(skin_joints or doc.gltf.nodes or [])
    if len(match.node_of) < 0.5 * min(joint_count, node_count):
        names = ", ".join(skeleton.names[j] for j in list(match.node_of)[:5])
        reason = (f"only {len(match.node_of)} of its {joint_count} joints match a node of {into}'s by name "
                  f"({names}{', ...' if len(match.node_of) > 5 else ''}), and the skeletons differ in shape: "
                  "another rig (a joint map, --joint-map, pairs the joints)")  # fmt: skip
        raise FormatError(path, "HIERARCHY", reason)
    return match


def named_nodes(doc: GltfDocument) -> dict[str, int]:
    """Node index by name, for the names one node alone has."""
    return unique_index([node.name or "" for node in doc.gltf.nodes or []])


def _tree_of(doc: GltfDocument, joints: set[int]) -> _Tree | None:
    """The nodes ``joints`` as a tree (each under its nearest ancestor among them), or None
    where they form several trees or none."""
    parent = {n: next((a for a in doc.ancestors(n) if a in joints), -1) for n in joints}
    roots = [n for n, p in parent.items() if p == -1]
    if len(roots) != 1:
        return None
    order = sorted(joints, key=lambda n: (len(doc.ancestors(n)), n))
    return _Tree(order, parent, {n: doc.gltf.nodes[n].name or "" for n in joints})


def _shapes(tree: _Tree, table: dict[tuple[int, ...], int]) -> dict[int, int]:
    """Each id's subtree shape as a number, equal for subtrees of the same shape (children in
    any order) in every tree numbered through the same ``table``."""
    children = tree.children()
    shape: dict[int, int] = {}
    for item in reversed(tree.order):
        key = tuple(sorted(shape[child] for child in children.get(item, [])))
        shape[item] = table.setdefault(key, len(table))
    return shape


def _pair_by_shape(theirs: _Tree, ours: _Tree) -> tuple[dict[int, int], int] | None:
    """Each id of ``theirs`` paired with the one in the same place of ``ours``, and how many
    pairs only the files' order told apart; None where the trees differ in shape."""
    table: dict[tuple[int, ...], int] = {}
    their_shape, our_shape = _shapes(theirs, table), _shapes(ours, table)
    if their_shape[theirs.order[0]] != our_shape[ours.order[0]]:
        return None
    their_children, our_children = theirs.children(), ours.children()
    pairs = {theirs.order[0]: ours.order[0]}
    in_file_order = 0
    pending = [theirs.order[0]]
    while pending:
        item = pending.pop()
        groups: dict[int, tuple[list[int], list[int]]] = defaultdict(lambda: ([], []))
        for child in their_children.get(item, []):
            groups[their_shape[child]][0].append(child)
        for child in our_children.get(pairs[item], []):
            groups[our_shape[child]][1].append(child)
        for group_theirs, group_ours in groups.values():
            siblings, guessed = _pair_siblings(group_theirs, group_ours, theirs.names, ours.names)
            pairs.update(siblings)
            in_file_order += guessed
            pending.extend(group_theirs)
    return pairs, in_file_order


def _pair_siblings(
    theirs: list[int], ours: list[int], their_names: dict[int, str], our_names: dict[int, str]
) -> tuple[dict[int, int], int]:
    """Siblings of one shape paired by name, then by side, then in order; also how many of the
    pairs the order alone made (0 where one pair is left)."""
    pairs: dict[int, int] = {}
    for key in (normalized_name, side):
        our_once = unique_index([key(our_names[i]) for i in ours])
        for k, t in unique_index([key(their_names[i]) for i in theirs]).items():
            if k in our_once:
                pairs[theirs[t]] = ours[our_once[k]]
        theirs = [i for i in theirs if i not in pairs]
        taken = set(pairs.values())
        ours = [i for i in ours if i not in taken]
    pairs.update(zip(theirs, ours))
    return pairs, len(theirs) if len(theirs) > 1 else 0


def _shape_note(
    skeleton: Skeleton, doc: GltfDocument, pairs: dict[int, int], end_sites: np.ndarray, in_file_order: int
) -> str | None:
    renamed = [(skeleton.names[j], doc.gltf.nodes[n].name or "") for j, n in pairs.items() if not end_sites[j]]
    renamed = [(a, b) for a, b in renamed if normalized_name(a) != normalized_name(b)]
    if not renamed and not in_file_order:
        return None
    details = []
    if renamed:
        examples = ", ".join(f"{a!r} -> {b!r}" for a, b in renamed[:3])
        details.append(f"{len(renamed)} to nodes of other names ({examples}{', ...' if len(renamed) > 3 else ''})")
    if in_file_order:
        details.append(f"{in_file_order} alike in shape, name and side paired in the files' order")
    return "joints matched by the two skeletons' shape: " + "; ".join(details)


def _match_by_map(
    skeleton: Skeleton, doc: GltfDocument, end_sites: np.ndarray, joint_map: JointMap, path: str
) -> JointMatch:
    """The joint map's pairs, each checked; the topmost mapped joint takes the translation."""
    joints = {name: j for j, name in enumerate(skeleton.names) if not end_sites[j]}
    nodes = doc.gltf.nodes or []
    by_name = named_nodes(doc)
    into = Path(doc.path).name
    node_of: dict[int, int] = {}
    for joint, node in joint_map.nodes.items():
        if joint not in joints:
            raise FormatError(joint_map.path, repr(joint), f"is no joint of {Path(path).name} (end sites take none)")
        index = node if isinstance(node, int) else by_name.get(node, -1)
        if not 0 <= index < len(nodes):
            raise FormatError(joint_map.path, repr(joint), f"maps to {node!r}, no node of {into}'s (or one of several)")
        if index in node_of.values():
            raise FormatError(
                joint_map.path, repr(joint), f"maps to {doc.node_label(index)}, which another joint drives"
            )
        node_of[joints[joint]] = index
    note = f"joints matched by the joint map {Path(joint_map.path).name}"
    return JointMatch(dict(sorted(node_of.items())), note, root=min(node_of))


def _match_by_role(
    skeleton: Skeleton, doc: GltfDocument, end_sites: np.ndarray, skin_joints: set[int]
) -> JointMatch | None:
    """Joints matched by the body part their two namings give them (:mod:`.humanoid_roles`),
    where the skeletons are humanoids of two namings that share ``MIN_ROLES`` parts, hips among them."""
    theirs = roles_of(["" if end else name for name, end in zip(skeleton.names, end_sites)])
    nodes = doc.gltf.nodes or []
    ours = roles_of([(node.name or "") if not skin_joints or n in skin_joints else "" for n, node in enumerate(nodes)])
    if theirs is None or ours is None or theirs[0] == ours[0]:
        return None
    shared = [role for role in theirs[1] if role in ours[1]]
    if len(shared) < MIN_ROLES or "hips" not in shared:
        return None
    node_of = {theirs[1][role]: ours[1][role] for role in shared}
    pairs = ", ".join(f"{skeleton.names[j]!r} -> {nodes[n].name!r}" for j, n in list(node_of.items())[:3])
    note = f"joints matched by body part, {theirs[0]}'s naming onto {ours[0]}'s ({pairs}, ...)"
    return JointMatch(dict(sorted(node_of.items())), note, root=theirs[1]["hips"])


def _match_by_name(skeleton: Skeleton, doc: GltfDocument, end_sites: np.ndarray) -> JointMatch:
    """Joints matched to the nodes of their name, else of their normalized name (each name one
    node's and one joint's alone)."""
    nodes = doc.gltf.nodes or []
    exact = named_nodes(doc)
    loose = unique_index([normalized_name(node.name) if node.name else "" for node in nodes])
    joints = [j for j in range(skeleton.joint_count) if not end_sites[j]]
    their_loose = [normalized_name(skeleton.names[j]) for j in joints]
    once = unique_index(their_loose)
    node_of = {j: exact[skeleton.names[j]] for j in joints if skeleton.names[j] in exact}
    taken = set(node_of.values())
    loosely = []
    for j, name in zip(joints, their_loose):
        if j not in node_of and name in loose and name in once and loose[name] not in taken:
            node_of[j] = loose[name]
            loosely.append(f"{skeleton.names[j]!r} -> {nodes[loose[name]].name!r}")
    note = None
    if loosely:
        note = (f"{len(loosely)} joint(s) matched by name up to case, separators and namespace "
                f"({', '.join(loosely[:3])}{', ...' if len(loosely) > 3 else ''})")  # fmt: skip
    return JointMatch(dict(sorted(node_of.items())), note)
