"""A skinned glTF character in, the paper's full chain out: geometry levels times motion levels.

Section 3 of the motion LoD paper pairs a mesh level with a skeleton level per character.
Here every skinned drawable gets AQEM geometry levels (as :func:`simplify_document` builds
them) and every skin gets motion levels: the clips of all its animations are analysed as one
(so one reduced skeleton serves them all), joints are frozen level by level, each clip is
re-fitted with SLSQP, and the weights of frozen joints move to their kept ancestors (seeds/000,
Sections 4-5). A skin whose clips scale a joint keeps every joint, with the input's clips, at
every level: the re-fit is rigid. Level i of the written chain combines geometry level i with
motion level i (or the coarsest one a small skeleton has); every other combination is written
too (``extras.animlod_grid`` on the base node lists them by geometry level, then motion level)
so that a benchmark can walk the whole grid.

A skin whose joints belong to a larger skin's (a helmet or visor on the head), or hang from
them (hair bones, listed with the head or alone), bound in the same pose, is a part
(:mod:`.skin_parts`): it plays that skin's motion levels, on its reduced skeletons, and the
chains of one skeleton switch at one distance. Its own bones that move in its clips join that
skin's skeleton first. Motion level m >= 1 adds, per skin, a reduced
skeleton as joint nodes of its own, a skin over them and one animation per input clip
(``extras.animlod = {"clip", "motion_level", "skins"}``, the input skins that play it; named
``<clip>@motion<m>``, or ``<clip>@skin<s>@motion<m>`` where several skeletons have motion levels);
a level node at motion level m uses that skin, so any glTF engine can play it. Nodes hung from the
input's joints (props, sockets) are copied onto each level's skeleton, and each level clip also
plays what its input clip moves besides the skeleton (morph weights; :mod:`.attachments`).

The meshes no clip skins (a sword in a hand, a hat a joint's node draws, a prop beside the
character, a skinned mesh whose joints no clip moves) get levels of their own, as
:func:`simplify_document` gives them: an MSFT_lod chain on each node that draws one, switched by
its own size and error, and on each copy of it on a motion level's skeleton.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io.errors import FormatError
from ..io.glb_builder import GlbBuilder
from ..io.gltf_document import GRID_EXTRA, GltfDocument
from ..io.gltf_drawable import Clip, Drawable, on_rig, read_drawables
from ..io.gltf_lod import (
    LevelInfo,
    PrimitiveArrays,
    add_level_mesh,
    add_level_node,
    attach_chain,
    drive_level_nodes,
    hidden_level_notes,
    level_node_name,
    screen_coverages,
    unchained,
)
from ..io.gltf_skin import SkinRig
from ..io.gltf_write import add_animation, add_skeleton, add_skin, influence_sets
from ..io.stored_weights import normalise_stored_weights
from ..metrics import hausdorff_distances
from ..model import Motion, SkinnedMesh, spread_frames
from ..motion_lod import MotionLodChain, build_motion_chain, joint_floor
from ..motion_lod.chain import MotionLevel
from ..motion_lod.clips import join_clips
from ..motion_lod.frozen import FrozenLevel
from ..motion_lod.skin_measure import analyze_skinned_motion, hidden_note, without_skin_tips
from ..motion_lod.skin_transfer import key_bind_pose, transfer_skin
from .attachments import (
    add_level_attachments,
    carry_other_channels,
    copy_level_chains,
    find_attachments,
    posed_by_level_clips,
)
from .clip_import import document_with_clips
from .drawable_levels import (
    DrawableLevel,
    DrawableLevels,
    DrawableSettings,
    measure_samples,
    simplify_drawable,
    split_empty,
)
from .lod_document import DEFAULT_RATIOS, DrawableReport, add_drawable_chain, drawable_report, empty_drawables_note
from .skin_parts import JointKeys, Placement, hanging_rig, joined_rig, moved_onto, placement_on


@dataclass
class CharacterLevel:
    """One level of a character's chain: its geometry and motion levels and measured error."""

    level: int
    mesh_level: int
    motion_level: int
    faces: int
    joints: int
    error: float  # asset units: max over measured frames of every clip of the Hausdorff distance
    relative_error: float
    coverage: float


@dataclass
class CharacterReport:
    """The result of :func:`build_character`: one chain per skinned drawable that its clips move,
    and the levels of the other drawables (``others``: props, static meshes)."""

    source: Path
    output: Path
    chains: dict[str, list[CharacterLevel]]
    motion_seconds: float
    geometry_seconds: float
    notes: list[str] = field(default_factory=list)
    others: list[DrawableReport] = field(default_factory=list)


def build_character(
    source: str | os.PathLike,
    output: str | os.PathLike,
    ratios: Sequence[float] = DEFAULT_RATIOS,
    *,
    solver: str = "slsqp",
    workers: int = 0,
    clips: Sequence[str] = (),
    joint_map: str | os.PathLike | None = None,
    settings: DrawableSettings | None = None,
    progress: Callable[[str], None] | None = None,
    **keywords: object,
) -> CharacterReport:
    """Build geometry x motion levels of every skinned drawable of ``source`` into one LoD GLB,
    and levels of their own of the drawables no clip skins (props, static meshes).

    Parameters
    ----------
    source, output : the input glTF and the LoD GLB to write (atomically).
    ratios : face ratios of geometry levels 1, 2, ...; motion levels are as many (joint counts
        spread down to the fewest the skeleton allows, see :func:`animlod.build_motion_chain`).
    solver, workers : the motion re-fit (``"slsqp"``, the paper's SQP, or ``"newton"``), and the
        threads of the motion analysis and re-fit (0: every core; the levels are the same).
    clips : glTF files of clips on the same rig (an animation library without the mesh), added to
        the character's own by node name (:mod:`.clip_import`).
    joint_map : a JSON table of the character's node each BVH clip's joint drives, where the
        skeletons' shape, body parts and names do not tell (:func:`.joint_matching.read_joint_map`).
    settings, **keywords : a :class:`~animlod.pipelines.DrawableSettings` and/or its fields and
        AQEM options by name, as for :func:`animlod.pipelines.simplify_document`.

    Raises
    ------
    FormatError when the file has no skinned mesh with an animation, or cannot be read.
    """
    say = progress or (lambda _line: None)
    settings = DrawableSettings.resolve(settings, keywords)
    notes: list[str] = []
    doc = document_with_clips(source, clips, notes.append, joint_map)
    fps = doc.sample_rate(settings.fps)
    all_drawables = read_drawables(doc, fps)
    chained = {d.label: d for d in all_drawables if unchained(doc, d.nodes) != d.nodes}
    if chained:
        notes.append("kept with the MSFT_lod chains they have: "
                     + ", ".join(f"{d.label} (nodes {d.nodes})" for d in chained.values()))  # fmt: skip
    drawables = [d for d in all_drawables if d.skinned is not None and d.label not in chained]
    animated = [d for d in drawables if any(clip.motion is not None for clip in d.clips)]
    if not animated:
        reason = "no skinned mesh with an animation: a character chain needs both"
        if any(d.skinned is not None for d in chained.values()):
            raise FormatError(doc.path, "skins", "every skinned mesh's node has an MSFT_lod chain already, "
                              "nothing to build a character chain of")  # fmt: skip
        if any(d.skinned is not None for d in all_drawables):  # a rig in its bind pose, as Mixamo's "with skin"
            raise FormatError(doc.path, "skins", f"{reason}; its skinned meshes have no clip: add clips with --clips "
                              "(glTF or BVH files), or `animlod simplify` gives mesh levels alone")  # fmt: skip
        if all_drawables or not doc.gltf.animations:
            raise FormatError(doc.path, "skins", f"{reason} (`animlod simplify` gives mesh levels alone)")
        raise FormatError(doc.path, "skins", f"{reason} (it draws no mesh: `animlod motion` takes its clips)")
    levels_wanted = len(ratios) + 1
    started = time.perf_counter()
    joints_of = {d.skin_index: set(doc.gltf.skins[d.skin_index].joints) for d in animated}
    played_clips = {d.skin_index: _joined_clips(d) for d in animated}
    roles = _assign_skeletons(doc, animated, joints_of, played_clips, notes, fps)
    chain_of, parts, owners, sharing = roles.chain_of, roles.parts, roles.owners, roles.sharing
    animated = [roles.current(d) for d in animated]
    motion_chains: dict[int, _SkinMotion] = {}
    for skin, drawable in owners.items():
        clips, joined, spans = played_clips[skin]
        scaling = joined.deforming_joint()
        if scaling is not None:
            notes.append(
                f"skin {skin}: joint {scaling!r} scales in its clips, and motion LoD re-fits rigid motions only; "
                "the skin keeps every joint at every level"
            )
            motion_chains[skin] = _SkinMotion(None, list(zip(clips, spans)), drawable.rig, joined)
            continue
        # Measured as every skin that plays these levels sees it (skin_measure.py; a visor or a
        # head of its own too): leaf joints by their skin's points, joints that move no skin and
        # hold no attachment not at all. The levels drop the points.
        players = [d for d in animated if chain_of[d.skin_index] == skin]
        skins = [_played(d.skinned, parts.get(d.skin_index)) for d in players]
        attached = [attachment.joint for attachment in find_attachments(doc, drawable.rig)]
        tipped, analysis, trial_measure = analyze_skinned_motion(joined, skins, attached, workers=workers, clips=spans)
        hidden = hidden_note(analysis, joined)
        if hidden:
            notes.append(f"skin {skin}: {hidden}")
        # As many motion levels as geometry levels, or as the skeleton has joints that can freeze.
        floor = joint_floor(tipped, analysis)
        levels = min(levels_wanted, floor.possible_levels)
        owner = sharing.get(skin)
        if owner is not None and joints_of[skin] < joints_of[owner]:  # bound in another pose: its joints stay
            levels = 1
            notes.append(
                f"skin {skin}: its joints belong to skin {owner}, bound in another pose; it keeps them at every level"
            )
        elif owner is not None:
            notes.append(
                f"skin {skin}: shares joints with skin {owner} but cannot play its motion levels (bound in another "
                f"pose, or weighted to joints below none of skin {owner}'s); its own levels may part from them"
            )
        elif levels < levels_wanted:
            notes.append(
                f"skin {skin}: {levels} motion level(s) for {levels_wanted} geometry levels ({floor.total} joints, "
                f"at least {floor.fewest} kept: {floor.explain()})"
            )
        say(f"skin {skin}: {levels} motion levels over {len(clips)} clips")
        chain = build_motion_chain(
            tipped, levels=levels, solver=solver, workers=workers, analysis=analysis, trial_measure=trial_measure,
            on_choice=lambda chosen, total, s=skin: say(f"skin {s}: joints of {chosen} of {total} motion levels "
                                                        "chosen (trial re-fits)"),
            on_level=lambda index, joints, s=skin: say(f"skin {s}: re-fitting motion level {index} ({joints} joints)")
            if index > 0 else None,
        )  # fmt: skip
        chain = without_skin_tips(chain, joined)
        motion_chains[skin] = _SkinMotion(chain, list(zip(clips, spans)), drawable.rig, joined)
    motion_seconds = time.perf_counter() - started
    started = time.perf_counter()
    geometry = {}
    for drawable in animated:
        say(f"{drawable.label}: geometry levels of {len(drawable.geometry.faces)} triangles")
        # The chain's diagonal is measured below (_measure_chain); the geometry levels alone are not.
        geometry[drawable.label] = simplify_drawable(drawable, ratios, settings, measure=False, progress=say)
    moved = {drawable.label for drawable in animated}
    others = [d for d in all_drawables if d.label not in moved and d.label not in chained]
    others, empty = split_empty(others, settings.measured_frames)
    other_levels = []
    for drawable in others:
        say(f"{drawable.label}: levels of {len(drawable.geometry.faces)} triangles (no clip skins it)")
        other_levels.append(simplify_drawable(drawable, ratios, settings, progress=say))
    geometry_seconds = time.perf_counter() - started

    builder = GlbBuilder.from_document(doc)
    # Before the motion levels: the copies of what hangs from the joints copy these chains.
    other_reports = [drawable_report(d, levels, ratios, settings) for d, levels in zip(others, other_levels)]
    for drawable, levels, report in zip(others, other_levels, other_reports):
        add_drawable_chain(builder, doc, drawable, levels, report)
    # Where several skeletons have motion levels, one input clip has a level clip on each: their
    # names and extras say whose skeleton each poses.
    leveled = [skin for skin, motion in motion_chains.items() if motion.reduced_levels]
    motion_nodes = {
        skin: _add_motion_levels(builder, doc, motion, _players(chain_of, skin), len(leveled) > 1)
        for skin, motion in motion_chains.items()
    }
    motion_nodes = {skin: motion_nodes[owner] for skin, owner in chain_of.items()}
    motion_chains = {skin: motion_chains[owner] for skin, owner in chain_of.items()}
    chains, grids = {}, {}
    level_skins: dict[tuple[tuple[int, ...], bytes], int] = {}
    for drawable in animated:
        motion = motion_chains[drawable.skin_index]
        levels = geometry[drawable.label]
        say(f"{drawable.label}: writing the grid, measuring the chain")
        part = parts.get(drawable.skin_index)
        grid = _write_grid(builder, doc, drawable, levels, motion, motion_nodes[drawable.skin_index], part, level_skins)
        report = _measure_chain(drawable, levels, motion, settings.measured_frames, part)
        coverages = screen_coverages(
            [level.error for level in report], levels.size, settings.pixel_error, settings.viewport_px
        )
        for level, coverage in zip(report, coverages):
            level.coverage = coverage
            level.relative_error = level.error / levels.size if levels.size > 0 else 0.0
        chains[drawable.label], grids[drawable.label] = report, grid
        notes += [f"{drawable.label}: {note}" for note in levels.notes]
        weights_note = normalise_stored_weights(builder, doc, drawable)
        if weights_note:
            notes.append(f"{drawable.label}: {weights_note}")
    for skin in set(chain_of.values()):
        members = [d for d in animated if chain_of[d.skin_index] == skin]
        _switch_together([chains[d.label] for d in members], [geometry[d.label].size for d in members])
    for drawable in animated:
        _attach(builder, drawable, chains[drawable.label], grids[drawable.label])
        chain = chains[drawable.label]
        hidden = hidden_level_notes([level.relative_error for level in chain], [level.coverage for level in chain])
        notes += [f"{drawable.label}: {note}" for note in hidden]
    if empty:
        notes.append(empty_drawables_note(empty))
    builder.save(output)
    return CharacterReport(Path(source), Path(output), chains, motion_seconds, geometry_seconds, notes, other_reports)


@dataclass
class _SkinMotion:
    """A skin's motion chain (None when its clips scale joints: the input's skeleton and clips
    serve every level), the clips (with their frames in the joined motion), the rig and the
    joined motion the chain reduces."""

    chain: MotionLodChain | None
    clips: list[tuple[Clip, slice]]
    rig: SkinRig
    joined: Motion

    @property
    def reduced_levels(self) -> list[MotionLevel]:
        """Motion levels 1, 2, ... (level 0 is the input's skeleton and clips)."""
        return [] if self.chain is None else self.chain.levels[1:]

    @property
    def joint_count(self) -> int:
        """Joints of motion level 0 (end sites not counted)."""
        return int(np.count_nonzero(~self.joined.skeleton.end_sites))


@dataclass
class _Roles:
    """Which skin plays which skin's motion levels (:func:`_assign_skeletons`)."""

    chain_of: dict[int, int] = field(default_factory=dict)  # skin -> the skin whose levels it plays
    parts: dict[int, _Part] = field(default_factory=dict)  # skin -> its place on that skin's skeleton
    owners: dict[int, Drawable] = field(default_factory=dict)  # the skins with levels of their own
    sharing: dict[int, int] = field(default_factory=dict)  # owner -> an owner it shares joints with
    # Drawables read again on their skin's rig joined with a part's own bones, by label.
    rejoined: dict[str, Drawable] = field(default_factory=dict)

    def current(self, drawable: Drawable) -> Drawable:
        """``drawable`` as its chain plays it: on a joined rig where a part's bones joined it."""
        return self.rejoined.get(drawable.label, drawable)


def _assign_skeletons(
    doc: GltfDocument,
    animated: list[Drawable],
    joints_of: dict[int, set[int]],
    played_clips: dict[int, tuple[list[Clip], Motion, list[slice]]],
    notes: list[str],
    fps: float,
) -> _Roles:
    """Larger skeletons first: a skin over the joints of one before it (exporters may give every
    mesh a skin of its own over the same joints) plays its motion levels, and so does a skin whose
    joints belong to a larger skin's (a helmet bound to the head) or hang from them (VRoid's hair
    bones below the head): freezing its joints on their own, or keeping them while the body
    freezes them, would tear it from the body. Bones of its own that hold their bind pose move its
    vertices with the body's joint above them; bones that move (a cape's, swinging hair) join the
    body's skeleton (:func:`_join`). Every other skin has levels of its own. Notes say which is
    which; ``joints_of`` and ``played_clips`` follow the joined skeletons."""
    roles = _Roles()
    for drawable in sorted(animated, key=lambda d: -len(joints_of[d.skin_index])):
        skin = drawable.skin_index
        if skin in roles.chain_of:
            continue
        # One skeleton per level serves twins (a copy each would animate the skeleton once per mesh).
        twin = next((o for o, d in roles.owners.items() if d.rig.joint_nodes == drawable.rig.joint_nodes), None)
        if twin is not None:
            roles.chain_of[skin] = twin
            notes.append(f"skin {skin}: the joints of skin {twin}; it plays the same motion levels")
            continue
        owner = next((other for other in roles.owners if joints_of[skin] & joints_of[other]), None)
        alone = drawable
        if owner is None:  # its bones may hang from an owner's joint in the node tree
            owner, drawable = _hanging_from(doc, roles, drawable, joints_of, fps)
        clips = played_clips[skin] if drawable is alone else _joined_clips(drawable)
        placement = None if owner is None else _placement(roles.owners[owner], drawable, clips[1])
        relation = None
        if placement is None and owner is not None and _join(doc, roles, owner, drawable, animated, fps):
            own = sorted(set(drawable.rig.joint_nodes) - joints_of[owner])
            relation = f"its own joints ({', '.join(doc.node_label(node) for node in own)}) move in its clips and join"
            joints_of[owner] = set(roles.owners[owner].rig.joint_nodes)
            played_clips[owner] = _joined_clips(roles.owners[owner])
            placement = _placement(roles.owners[owner], drawable)
        if placement is not None:
            if drawable is not alone:
                roles.rejoined[drawable.label], played_clips[skin] = drawable, clips
            roles.chain_of[skin] = owner
            roles.parts[skin] = _Part(roles.owners[owner].skinned, placement)
            if relation is None:
                relation = (
                    "its joints belong to" if joints_of[skin] < joints_of[owner] else "its joints hang from those of"
                )
            notes.append(f"skin {skin}: {relation} skin {owner}; it plays that skin's motion levels")
            continue
        roles.chain_of[skin], roles.owners[skin] = skin, alone
        if owner is not None and drawable is alone:
            roles.sharing[skin] = owner
    return roles


def _hanging_from(
    doc: GltfDocument, roles: _Roles, drawable: Drawable, joints_of: dict[int, set[int]], fps: float
) -> tuple[int | None, Drawable]:
    """The owner whose joint ``drawable``'s bones hang from in the node tree (its skin lists none
    of that owner's joints), with ``drawable`` read again on its rig with that joint
    (skin_parts.hanging_rig); (None, ``drawable``) where they hang from none."""
    for owner in roles.owners:
        rig = hanging_rig(doc, drawable.rig, joints_of[owner])
        if rig is not None:
            return owner, on_rig(doc, drawable, rig, fps)
    return None, drawable


def _placement(owner: Drawable, part: Drawable, motion: Motion | None = None) -> Placement | None:
    """Where ``part`` lies on ``owner``'s skeleton (skin_parts.placement_on), joints matched by node."""
    keys = JointKeys(owner.rig.joint_nodes, part.rig.joint_nodes)
    return placement_on(owner.skinned, part.skinned, keys, motion)


def _join(doc: GltfDocument, roles: _Roles, owner: int, part: Drawable, animated: list[Drawable], fps: float) -> bool:
    """Adds ``part``'s own bones, those ``owner``'s skin lacks, to the skeleton of every drawable
    that plays ``owner``'s levels on a skin of its own kind (the owner's meshes and twins: read
    again, ``roles.rejoined``; parts placed on it move onto the joined skeleton), so that the part
    plays them too. False, and nothing changed, where some of them cannot take those bones (bound
    in another pose than the part; skin_parts.joined_rig)."""
    members = [
        roles.current(d)
        for d in animated
        if roles.chain_of.get(d.skin_index) == owner and d.skin_index not in roles.parts
    ]
    rigs = {}
    for member in members:
        if member.skin_index not in rigs:
            rig = joined_rig(doc, member.rig, member.skinned, part.rig, part.skinned)
            if rig is None:
                return False
            rigs[member.skin_index] = rig
    for member in members:
        roles.rejoined[member.label] = on_rig(doc, member, rigs[member.skin_index], fps)
    roles.owners[owner] = roles.rejoined[roles.owners[owner].label]
    for skin, placed in roles.parts.items():
        if roles.chain_of[skin] == owner:  # the joined skeleton keeps every joint's index
            placed.first = roles.owners[owner].skinned
    return True


@dataclass
class _Part:
    """A skinned drawable that plays the motion levels of a skin over more of its joints (a visor
    on the head): that skin's mesh, and where the drawable lies on its skeleton (skin_parts.py)."""

    first: SkinnedMesh
    placement: Placement


def _joined_clips(drawable: Drawable) -> tuple[list[Clip], Motion, list[slice]]:
    """The drawable's clips that move its skeleton, and their motions one after another (with
    each one's frames in it)."""
    clips = [clip for clip in drawable.clips if clip.motion is not None]
    joined, spans = join_clips([clip.motion for clip in clips])
    return clips, joined, spans


def _played(skinned: SkinnedMesh, part: _Part | None) -> SkinnedMesh:
    """``skinned`` on the skeleton whose motion levels it plays."""
    return skinned if part is None else moved_onto(skinned, part.first, part.placement)


def _players(chain_of: dict[int, int], skin: int) -> list[int]:
    """The skins that play ``skin``'s motion levels: ``skin`` first, then its parts and twins."""
    return [skin, *sorted(other for other, owner in chain_of.items() if owner == skin and other != skin)]


@dataclass
class _MotionLevelNodes:
    """What one motion level adds to the document for one skin: the joint nodes of its reduced
    skeleton (None at level 0, which keeps the input's joints) and its joint count."""

    joint_nodes: list[int] | None
    joints: int


def _add_motion_levels(
    builder: GlbBuilder, doc: GltfDocument, motion: _SkinMotion, skins: list[int], several: bool
) -> list[_MotionLevelNodes]:
    """Reduced skeletons and re-fitted clips of motion levels 1, 2, ... (level 0 is the input's),
    with what hangs from the skeleton and the clips' other channels (:mod:`.attachments`).
    ``skins``: the input skins that play these levels (``skins[0]`` the one whose skeleton they
    reduce, then parts and twins), listed in each clip's extras; ``several``: other skeletons have
    motion levels too, so the names of the clips and copies say ``@skin<s>`` before ``@motion<m>``."""
    nodes = [_MotionLevelNodes(None, motion.joint_count)]
    attachments = find_attachments(doc, motion.rig)
    posing = posed_by_level_clips(doc, motion.rig, attachments)
    for m, level in enumerate(motion.reduced_levels, start=1):
        suffix = (f"@skin{skins[0]}" if several else "") + f"@motion{m}"
        joint_nodes = add_skeleton(builder, level.motion.skeleton)
        copies = add_level_attachments(builder, doc, motion.rig, attachments, motion.joined, level, joint_nodes, suffix)
        for clip, span in motion.clips:
            name = f"{clip.name or f'animation {clip.index}'}{suffix}"
            extras = {"animlod": {"clip": clip.index, "motion_level": m, "skins": list(skins)}}
            clip_motion = level.motion.take_frames(np.arange(span.start, span.stop))
            duration, start = doc.animation_duration(clip.index), clip.start_frame / clip_motion.fps
            animation = add_animation(builder, clip_motion, joint_nodes, name, extras, duration, start)
            carry_other_channels(builder, doc, posing, clip.index, animation, copies)
        copy_level_chains(builder, doc, copies, suffix, m)
        nodes.append(_MotionLevelNodes(joint_nodes, level.report.joint_count))
    return nodes


def _write_grid(
    builder: GlbBuilder,
    doc: GltfDocument,
    drawable: Drawable,
    levels: DrawableLevels,
    motion: _SkinMotion,
    motion_nodes: list[_MotionLevelNodes],
    part: _Part | None,
    level_skins: dict[tuple[tuple[int, ...], bytes], int],
) -> list[list[list[int]]]:
    """Every (geometry g, motion m) combination of ``drawable`` as level nodes, one per base
    node; returns ``grid[g][m]`` -> those nodes ((0, 0) is the base nodes themselves). A ``part``
    is bound to its owner's reduced skeletons at motion levels m >= 1. ``level_skins``: the reduced
    skins written so far, by joint nodes and inverse binds (shared across drawables)."""
    geometry: list[DrawableLevel | None] = [None, *levels.levels]  # geometry level 0 is the input
    frozen = [None] + [level.frozen for level in motion.reduced_levels]  # motion level 0 freezes nothing
    played = [_played(drawable.skinned if level is None else level.skinned, part) for level in geometry]
    to_bind = drawable.world if part is None else part.placement.transform @ drawable.world
    skins = [drawable.skin_index]
    for m in range(1, len(frozen)):  # a reduced skin's inverse binds do not depend on the geometry
        reduced = transfer_skin(played[0], frozen[m])
        # One skin per reduced skeleton and binds: a part shares its owner's, so that a runtime
        # poses that skeleton once for both.
        key = (tuple(motion_nodes[m].joint_nodes), reduced.inverse_bind.astype(np.float32).tobytes())
        if key not in level_skins:
            level_skins[key] = add_skin(builder, motion_nodes[m].joint_nodes, reduced.inverse_bind)
        skins.append(level_skins[key])
    mesh_name = doc.gltf.meshes[drawable.mesh_index].name or f"mesh{drawable.mesh_index}"
    grid = [[list(drawable.nodes) for _ in frozen] for _ in geometry]
    for g, level in enumerate(geometry):
        for m, frozen_level in enumerate(frozen):
            if g == 0 and m == 0:
                continue
            primitives = _input_primitives(drawable) if level is None else level.primitives
            skinned = drawable.skinned if level is None else level.skinned
            if frozen_level is not None:
                primitives = _reposed(played[g], to_bind, frozen_level, primitives)
            mesh = add_level_mesh(
                builder, drawable.mesh_index, primitives, drawable.geometry.other_primitives, f"{mesh_name}_G{g}M{m}"
            )
            info = LevelInfo(-1, 0.0, skinned.face_count, g, m, motion_nodes[m].joints)
            grid[g][m] = [add_level_node(builder, base, mesh, skins[m], info) for base in drawable.nodes]
    return grid


def _input_primitives(drawable: Drawable) -> list[PrimitiveArrays]:
    """The input's triangle primitives as level primitives (every vertex, in order)."""
    starts = drawable.geometry.vertex_starts
    return [
        PrimitiveArrays(p.index, dict(p.attributes), p.faces, list(p.targets), np.arange(starts[k], starts[k + 1]))
        for k, p in enumerate(drawable.geometry.primitives)
    ]


def _reposed(
    skinned: SkinnedMesh, to_bind: np.ndarray, frozen: FrozenLevel, primitives: list[PrimitiveArrays]
) -> list[PrimitiveArrays]:
    """``primitives`` bound to a motion level's reduced skin: positions and directions re-posed
    into the key posture of the frozen joints (in the space of ``skinned``'s rest pose and inverse
    binds, which ``to_bind`` (4, 4) maps the primitives' node-local space to), skin weights moved to
    the kept joints (:func:`transfer_skin`)."""
    reduced = transfer_skin(skinned, frozen)
    matrices = key_bind_pose(skinned, frozen) @ skinned.inverse_bind  # (J, 4, 4) rest -> key posture
    blended = np.einsum("vk,vkij->vij", skinned.weights, matrices[skinned.joints])[:, :3, :3]
    to_bind_directions = np.linalg.inv(to_bind[:3, :3]).T  # the inverse transpose
    out = []
    for primitive in primitives:
        vertices = primitive.vertices
        attributes = {k: v for k, v in primitive.attributes.items() if not k.startswith(("JOINTS_", "WEIGHTS_"))}
        attributes["POSITION"] = reduced.rest_positions[vertices]
        for name in ("NORMAL", "TANGENT"):
            if name in attributes:
                turned = np.einsum("vij,vj->vi", blended[vertices], attributes[name][:, :3] @ to_bind_directions.T)
                length = np.linalg.norm(turned, axis=1, keepdims=True)
                values = attributes[name].copy()
                values[:, :3] = turned / np.where(length > 0.0, length, 1.0)
                attributes[name] = values.astype(np.float32)
        attributes.update(influence_sets(reduced.joints[vertices], reduced.weights[vertices]))
        targets = [dict(target) for target in primitive.targets]
        if skinned.morph_targets is not None:  # world-space deltas, like the positions
            for t, target in enumerate(targets):
                if "POSITION" in target:
                    target["POSITION"] = skinned.morph_targets[t][vertices].astype(np.float32)
        out.append(PrimitiveArrays(primitive.source, attributes, primitive.faces, targets, vertices))
    return out


def _measure_chain(
    drawable: Drawable,
    levels: DrawableLevels,
    motion: _SkinMotion,
    measured_frames: int,
    part: _Part | None,
) -> list[CharacterLevel]:
    """The chain's levels (geometry level i with motion level i, or the coarsest motion level
    there is), each measured as it is written: the level's skin played with its clips (the
    input's at motion level 0, the re-fitted ones on the reduced skin above) against the input's
    clips, max Hausdorff distance. A ``part`` plays its owner's clips on its owner's skeleton."""
    chain = []  # (geometry level, motion level index, motion level or None, the skin it plays)
    for i in range(1, len(levels.levels) + 1):
        m = min(i, len(motion.reduced_levels))  # a small skeleton runs out of motion levels first
        level = levels.levels[i - 1]
        motion_level = motion.reduced_levels[m - 1] if m > 0 else None
        played = _played(level.skinned, part)
        chain.append(
            (level, m, motion_level, played if motion_level is None else transfer_skin(played, motion_level.frozen))
        )
    errors = [0.0] * len(chain)
    input_skin = _played(drawable.skinned, part)
    for clip, span in motion.clips:
        frames = spread_frames(clip.frame_count, measured_frames)
        weights = _morph_weights(clip, drawable, frames)
        clip_frames = clip.motion.take_frames(frames)
        original = input_skin.bake(clip_frames, weights)
        posed = [
            skin.bake(
                clip_frames if motion_level is None else motion_level.motion.take_frames(span.start + frames), weights
            )
            for _, _, motion_level, skin in chain
        ]
        errors = hausdorff_distances(original, posed, measure_samples(drawable), at_least=errors)
    report = [CharacterLevel(0, 0, 0, len(drawable.geometry.faces), motion.joint_count, 0.0, 0.0, 0.0)]
    for i, ((level, m, motion_level, _), error) in enumerate(zip(chain, errors), start=1):
        joints = motion.joint_count if motion_level is None else motion_level.report.joint_count
        report.append(CharacterLevel(i, i, m, level.simplified.mesh.face_count, joints, error, 0.0, 0.0))
    return report


def _switch_together(reports: list[list[CharacterLevel]], sizes: list[float]) -> None:
    """Coverages that switch the chains of one skeleton (a body, its clothes and visor) at the same
    distances, the farthest any of them asks for, so that a glTF engine never draws two of them
    at different motion levels. An engine compares a node's own projected size with its
    coverages, and a mesh of size s covers s / d at distance d (in some unit of the viewport):
    level i of every chain ends at distance D_i = max over chains of s / c_i, at coverage s / D_i."""
    if len(reports) < 2 or min(sizes) <= 0.0 or len({len(report) for report in reports}) != 1:
        return
    for i in range(len(reports[0]) - 1):  # the last coverage is 0: the coarsest level never ends
        ends = [size / report[i].coverage if report[i].coverage > 0.0 else np.inf
                for report, size in zip(reports, sizes)]  # fmt: skip
        for report, size in zip(reports, sizes):
            report[i].coverage = min(1.0, size / max(ends))


def _morph_weights(clip: Clip, drawable: Drawable, frames: np.ndarray) -> np.ndarray | None:
    """The morph weights of ``drawable`` at ``frames`` of ``clip``, or None (its default weights).
    ``clip`` is the skeleton's, read with another drawable (its owner, or another mesh on its
    skin: ReadyPlayerMe's teeth beside the head); the drawable's own clip of that animation holds
    its weights, for its own targets."""
    own = next((c for c in drawable.clips if c.index == clip.index and c.frame_count == clip.frame_count), None)
    return None if own is None or own.morph_weights is None else own.morph_weights[frames]


def _attach(builder: GlbBuilder, drawable: Drawable, report: list[CharacterLevel], grid: list) -> None:
    """The chain (diagonal of the grid) on every base node, with the grid beside it."""
    for index, base in enumerate(drawable.nodes):
        chain_nodes = [grid[level.mesh_level][level.motion_level][index] for level in report[1:]]
        base_name = builder.json["nodes"][base].get("name", f"node{base}")
        for level, node in zip(report[1:], chain_nodes):
            info = builder.json["nodes"][node]["extras"]["animlod"]
            info.update(level=level.level, error=level.error)
            builder.json["nodes"][node]["name"] = level_node_name(base_name, LevelInfo(**info))
        attach_chain(
            builder,
            base,
            chain_nodes,
            [level.coverage for level in report],
            LevelInfo(0, 0.0, report[0].faces, 0, 0, report[0].joints),
        )
        extras = builder.json["nodes"][base]["extras"]
        extras[GRID_EXTRA] = [[cells[index] for cells in row] for row in grid]
        grid_only = [cells[index] for row in grid for cells in row if cells[index] not in (base, *chain_nodes)]
        drive_level_nodes(builder, base, grid_only)
