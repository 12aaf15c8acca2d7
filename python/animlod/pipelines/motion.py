"""The motion LoD pipeline: a BVH or a glTF clip in, one BVH (and GLB) per level out.

Joint elimination and re-fit (the motion LoD paper, Sections 4-6) through
:func:`animlod.build_motion_chain`; ``animlod motion`` and the batch runner's ``motion`` job
call :func:`build_motion_levels`.
"""

from __future__ import annotations

import errno
import hashlib
import os
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from ..io.atomic import LONGEST_NAME, check_writable_folder, staged_files
from ..io.bvh import BvhLayout
from ..io.detect import input_kind, input_stem
from ..io.errors import FormatError
from ..model import Motion, SkinnedMesh
from ..motion_lod.analysis import TRANSLATION_TOLERANCE, MotionAnalysis, check_analysis_options
from ..motion_lod.chain import (
    SOLVERS,
    JointFloor,
    MotionLevel,
    MotionLodChain,
    TrialMeasure,
    check_level_request,
    resolve_solver,
)
from ..motion_lod.ranking import DEFAULT_RANKING
from ..options import MotionRefitOptions
from .result import AssetResult, LevelRow, Progress

if TYPE_CHECKING:
    from ..io.gltf_write import FaceMaterials
    from .motion_level_files import LevelContent


@dataclass
class MotionReport:
    """What :func:`build_motion_levels` did.

    chain : the analysis and the levels, finest first (level 0 keeps every joint).
    files : per level, the files written (relative to the output folder): a BVH per clip, and for
        a glTF input a GLB with every clip (the skinned mesh on the level's joints, or the skeleton
        alone without a skin).
    manifest : the level chooser's manifest (``<stem>_motion_lod.json``).
    faces : triangles of the skinned mesh (None for a BVH).
    motion : the clip simplified (several clips merged into one, or one after another: see ``notes``).
    floor : the fewest joints the skeleton allows and why (:func:`animlod.motion_lod.chain.joint_floor`).
    notes : what the user should know (clips merged, nothing could freeze).
    skin_errors : for a skinned glTF, per level, the skin's largest distance from the input's in
        each frame (asset units; :func:`skin_distances`); None otherwise.
    skin_seconds : wall seconds spent measuring ``skin_errors``.
    """

    chain: MotionLodChain
    files: list[list[Path]]
    manifest: Path
    faces: int | None
    motion: Motion
    floor: JointFloor
    notes: list[str]
    skin_errors: list[np.ndarray] | None = None
    skin_seconds: float = 0.0


def build_motion_levels(
    source: str | os.PathLike,
    output: str | os.PathLike,
    levels: int | None = None,
    *,
    joints: Sequence[int] | None = None,
    lock: Sequence[str] = (),
    ranking: str = DEFAULT_RANKING,
    solver: str = SOLVERS[0],
    penalty: bool = False,
    workers: int = 0,
    translation_tolerance: float = TRANSLATION_TOLERANCE,
    weights: Sequence[float] = (0.2, 0.4, 0.4),
    max_frames: int = 600,
    clip: int | str | None = None,
    clips: Sequence[str] = (),
    joint_map: str | os.PathLike | None = None,
    body_skin: int | str | None = None,
    on_level: Callable[[int, int, int, int], Callable[[float], None] | None] | None = None,
    on_choice: Callable[[int, int], None] | None = None,
    on_measure: Callable[[int, int], None] | None = None,
    on_note: Callable[[str], None] | None = None,
) -> MotionReport:
    """Motion levels of ``source`` (a .bvh, or a .glb/.gltf with animations: of a skinned mesh, or
    of a node tree without skins) written into the folder ``output`` as ``<stem>_lod<i>.bvh``
    (``<stem>_lod<i>_<clip>.bvh`` for each of several clips) and ``.glb`` with every clip, the skin
    moved onto the kept joints or the skeleton alone, plus ``<stem>_motion_lod.json``, each file
    atomically.

    Parameters
    ----------
    levels : number of levels from every joint down to the fewest possible (the paper's 100 .. 8 %
        where the skeleton allows); None: 8, or as many as the skeleton allows.
    joints : joint counts of the levels instead of ``levels``.
    lock : names of joints never to freeze.
    ranking : which joints freeze first (:data:`animlod.motion_lod.ranking.RANKINGS`).
    solver, penalty : the re-fit (``"slsqp"`` in the core, ``"slsqp-python"``, ``"newton"``);
        bone lengths are equality constraints with the SLSQP solvers unless ``penalty``.
    workers : threads of the motion analysis and the core's solve (0: every core), or processes of
        the Python solvers.
    translation_tolerance : fraction of a bone's length above which a translating joint never freezes.
    weights : (alpha, beta, gamma) of the distance, string and angle errors (Eq. 5).
    max_frames : frames the motion analysis looks at, at most.
    clip : which animation of a glTF input, by index or name; None: all of them, as one motion when
        each moves other joints (one animation per joint node), else one after another, so that
        each level has one skeleton for every clip.
    clips : glTF files of clips on the same rig, added to a glTF input's own by node name
        (:mod:`.clip_import`).
    joint_map : a JSON table of the character's node each BVH clip's joint drives, where the
        skeletons' shape, body parts and names do not tell (:func:`.joint_matching.read_joint_map`).
    body_skin : in a glTF of several characters, the one whose motion to simplify: its skin by
        index, or the name of its skin, mesh or node; None: the body whose skin lists the most joints
        (:attr:`animlod.io.gltf.GltfScene.body`). The skinned meshes on other skeletons are left
        out of the level files, named in a note.
    on_level : called with (level index, joint count, frame count, number of levels) as each
        level starts; may return a callback taking the frames done.
    on_choice : called with (levels chosen, levels to choose) while the "refit" ranking's trial
        re-fits choose the joints, before the first level.
    on_measure : called with (frames measured, frames) while the levels' skins are measured
        against the input's, after the last level (a skinned glTF only).
    on_note : called with each note as it arises (also kept in the report).

    Raises FormatError for unreadable input or a glTF without animations of a skeleton;
    ValueError naming the option for bad options and impossible level requests.
    """
    from ..motion_lod.chain import build_motion_chain
    from ..motion_lod.objective import Weights
    from ..motion_lod.skin_measure import hidden_note, without_skin_tips

    check_motion_options(
        levels=levels, joints=joints, ranking=ranking, solver=solver, penalty=penalty, workers=workers,
        translation_tolerance=translation_tolerance, weights=weights, max_frames=max_frames,
    )  # fmt: skip
    folder, stem = Path(output), input_stem(source)
    manifest = Path(f"{stem}_motion_lod.json")
    if (folder / manifest).is_dir():  # found before the work, not after it
        raise IsADirectoryError(errno.EISDIR, "Is a directory", os.fspath(folder / manifest))
    check_writable_folder(folder)
    notes: list[str] = []

    def note(text: str) -> None:
        notes.append(text)
        if on_note is not None:
            on_note(text)

    motion, played, skin, materials, layout, content = _read_input(source, clip, clips, joint_map, body_skin, note)
    if layout is not None and len(layout.roots) > 1:
        note(f"{os.fspath(source)}: its {len(layout.roots)} ROOTs ({', '.join(layout.roots)}) are joints below "
             f"one ROOT of its own, {motion.skeleton.names[0]!r}, at the origin, in every level")  # fmt: skip
    spans = [clip.frames for clip in played] if len(played) > 1 else None
    tipped, analysis, trial_measure, counts, floor = _plan_levels(
        motion, skin, spans, levels, joints, lock, max_frames, translation_tolerance, ranking, workers
    )
    hidden = hidden_note(analysis, motion)
    if hidden:
        note(f"{os.fspath(source)}: {hidden}")
    if floor.possible_levels == 1:
        note(
            f"{os.fspath(source)}: nothing can freeze ({floor.total} joint{'s' if floor.total != 1 else ''}, "
            f"all kept: {floor.explain()}); "
            "writing one level, the input's motion"
        )
    chain = build_motion_chain(
        tipped,
        counts,
        weights=Weights(*weights),
        solver=solver,
        slsqp_options=_refit_options(solver, penalty),
        workers=workers,
        on_level=(lambda index, count: on_level(index, count, motion.frame_count, len(counts))) if on_level else None,
        analysis=analysis,
        on_choice=on_choice,
        trial_measure=trial_measure,
    )
    chain = without_skin_tips(chain, motion, skin)

    from ..io.bvh import write_bvh
    from ..io.manifest import write_lod_manifest

    # A BVH's levels keep its channel layout: each joint's rotation order as the input writes it.
    orders = layout.rotation_orders if layout is not None else "ZXY"
    last_level = f"{stem}_lod{len(chain.levels) - 1}.bvh"  # the longest level part
    suffixes = _clip_suffixes([clip.name for clip in played], LONGEST_NAME - len(last_level.encode()))
    gltf_input = input_kind(source) == "gltf"
    measuring = time.perf_counter()
    skin_errors = None if skin is None else skin_distances(skin, motion, chain.levels, on_measure)
    skin_seconds = time.perf_counter() - measuring
    files, rows = [], []
    with staged_files(folder) as staged:  # no level reaches the folder unless every file is written
        for index, level in enumerate(chain.levels):
            names = []
            level_clips = [level.motion.take_frames(clip.frames) for clip in played]
            for clip_motion, suffix in zip(level_clips, suffixes):
                names.append(Path(f"{stem}_lod{index}{suffix}.bvh"))
                write_bvh(staged / names[-1], clip_motion, rotation_order=orders)
            if gltf_input:  # every clip in one GLB per level
                from ..io.gltf import write_glb

                names.append(Path(f"{stem}_lod{index}.glb"))
                clip_names, durations = [clip.name for clip in played], [clip.duration for clip in played]
                weights, starts = [clip.morph_weights for clip in played], [clip.start for clip in played]
                hung = content.on_level(motion, level, played)
                write_glb(staged / names[-1], level.skin, level_clips, clip_names, durations, materials, weights, hung,
                          content.mesh_names, starts)  # fmt: skip
            files.append(names)
            rows.append(_manifest_row(level, index, names, played, skin_errors))
        # The runtime's level chooser: each level's largest joint position error in asset units
        # (and the skin's largest distance, for a skinned glTF).
        write_lod_manifest(staged / manifest, "motion", rows)
    earlier = _earlier_level_files(folder, stem, {name.name for names in files for name in names})
    if earlier:
        note(f"{folder}: holds level files this run did not write, of an earlier run with other levels or "
             f"clips: {', '.join(earlier)} (the manifest {manifest} names this run's)")  # fmt: skip
    faces = None if skin is None else int(skin.faces.shape[0])
    return MotionReport(chain, files, manifest, faces, motion, floor, notes, skin_errors, skin_seconds)


def _manifest_row(
    level: MotionLevel, index: int, names: list[Path], played: list[PlayedClip], skin_errors: list | None
) -> dict:
    """A level's row of the manifest: its files, joints and largest error (and per clip, for several)."""
    row = {"files": [name.as_posix() for name in names], "joints": level.report.joint_count,
           "error": level.report.max_error}  # fmt: skip
    if skin_errors is not None:  # what a runtime drawing the skin sees
        row["skin_error"] = float(skin_errors[index].max())
    if len(played) > 1:  # a runtime may pick each clip's level by its own error
        row["clips"] = []
        for clip in played:
            span = clip.frames
            row["clips"].append({"name": clip.name, "error": float(level.report.frame_errors[span].max())})
            if skin_errors is not None:
                row["clips"][-1]["skin_error"] = float(skin_errors[index][span].max())
    return row


def _earlier_level_files(folder: Path, stem: str, written: set[str]) -> list[str]:
    """Level files of ``stem`` in ``folder`` that this run did not write (an earlier run's with
    more levels or other clips), by name."""
    pattern = re.compile(rf"{re.escape(stem)}_lod\d+(_.+)?\.(bvh|glb)")
    return sorted(path.name for path in folder.iterdir() if pattern.fullmatch(path.name) and path.name not in written)


class PlayedClip(NamedTuple):
    """A clip of the simplified motion: its name, its frames in the motion, and for a glTF clip
    its length in seconds (its last key, where its last frame is sampled), the
    weights its channels give the skinned mesh's morph targets at its frames (T, N), if any,
    the document's animation it is (None for several joined into one) and the time of its first
    frame (a clip keyed late on its timeline starts at its first key, not at 0)."""

    name: str
    frames: slice
    duration: float | None = None
    morph_weights: np.ndarray | None = None
    animation: int | None = None
    start: float = 0.0


class _Input(NamedTuple):
    """What :func:`_read_input` reads: the motion to simplify, the clips it is made of, for a
    skinned glTF its skin and materials, for a BVH its layout, and for a glTF what its level
    files carry besides (:class:`.motion_level_files.LevelContent`)."""

    motion: Motion
    played: list[PlayedClip]
    skin: SkinnedMesh | None = None
    materials: FaceMaterials | None = None
    layout: BvhLayout | None = None
    content: LevelContent | None = None


# Vertex-frames times levels measured between two progress calls of skin_distances (about half a
# second on two cores).
_MEASURED_PER_STEP = 1 << 26


def skin_distances(
    skin: SkinnedMesh,
    motion: Motion,
    levels: Sequence[MotionLevel],
    progress: Callable[[int, int], None] | None = None,
) -> list[np.ndarray]:
    """Per level, (T,) the largest distance, in each frame of ``motion``, of a vertex of the
    level's skin played with the level's motion from where ``motion`` puts it on the input ``skin``.
    ``progress`` is called with (frames measured, T) as the frames are measured, a step at a time."""
    step = max(1, _MEASURED_PER_STEP // max(1, skin.vertex_count * len(levels)))
    out = np.empty((len(levels), motion.frame_count))
    for start in range(0, motion.frame_count, step):
        frames = slice(start, min(start + step, motion.frame_count))
        played = [(level.skin, level.motion.take_frames(frames)) for level in levels]
        out[:, frames] = skin.distance_maxima(motion.take_frames(frames), played)
        if progress is not None:
            progress(frames.stop, motion.frame_count)
    return list(out)


def _read_input(
    source: str | os.PathLike,
    clip: int | str | None,
    clip_files: Sequence[str],
    joint_map: str | os.PathLike | None,
    body_skin: int | str | None,
    note: Callable[[str], None],
) -> _Input:
    """The motion to simplify, the clips it is made of (each one's name and frames in it), for a
    skinned glTF its skin (None for a glTF without skins: the animated node tree is the skeleton),
    for a BVH its layout, and what hangs from a glTF's skeleton. ``clip_files`` add to a glTF's
    clips (BVH ones matched by ``joint_map``)."""
    path = os.fspath(source)
    kind = input_kind(source)
    if (clip_files or joint_map is not None) and kind != "gltf":
        option = "clips" if clip_files else "joint_map"
        raise ValueError(f"{option}: adds glTF clips to a glTF input, not to a {kind} input")
    if clip is not None and kind != "gltf":
        raise ValueError(f"clip: picks one of a glTF input's animations; a {kind} file holds one clip")
    if body_skin is not None and kind != "gltf":
        raise ValueError(f"skin: picks one of a glTF input's characters; a {kind} file holds one skeleton")
    if kind == "bvh":
        from ..io.bvh import read_bvh_with_layout

        motion, layout = read_bvh_with_layout(source)
        return _Input(motion, [PlayedClip(motion.name, slice(None))], layout=layout)
    if kind != "gltf":
        raise FormatError(path, "file", f"a {kind} input has no skeleton; motion LoD needs a .bvh or an animated glTF")
    from ..io.gltf import read_gltf
    from ..io.gltf_read import from_first_key, rig_motions
    from ..io.gltf_skin import SkinRig
    from ..io.gltf_write import FaceMaterials, MeshNames
    from .attachments import find_attachments
    from .clip_import import document_with_clips
    from .motion_level_files import LevelContent, left_out_of_level_files, level_mesh_names, poses_nothing
    from .whole_skin import whole_skin

    document = document_with_clips(source, clip_files, note, joint_map)
    fps = document.sample_rate()
    scene = read_gltf(document, fps, body_skin)
    if scene.skinned_meshes:
        whole = whole_skin(document, scene, note, fps)
        skin, motions, animations, left_out = whole.mesh, whole.motions, whole.animations, whole.left_out
        rig = whole.rig
        materials, morph_weights = FaceMaterials(document, whole.face_materials, whole.surface), whole.morph_weights
        if skin.vertex_count > scene.skinned_meshes[scene.body].vertex_count:
            note(f"{path}: the skinned meshes on its skeleton are written as one mesh in each level's GLB")
        if left_out:
            note(f"{path}: skinned mesh{'es' if len(left_out) > 1 else ''} not in the levels' GLBs: "
                 f"{', '.join(left_out)} (`--skin` picks another character; `animlod character` takes every "
                 "skin)")  # fmt: skip
        if not motions:
            raise FormatError(path, "animations", "the skinned mesh has no animation to simplify: add clips with "
                              "--clips (glTF or BVH files)")  # fmt: skip
        joined_nodes, mesh_names = set(whole.part_nodes), level_mesh_names(document, whole.part_nodes)
    else:  # an animation library exported without its mesh
        rig, skin, materials, morph_weights = SkinRig(document, None), None, None, {}
        motions, animations, other_trees = (
            rig_motions(document, rig, fps),
            rig.animations(document),
            rig.trees_left_out,
        )
        skeleton, joined_nodes, mesh_names = motions[0].skeleton, set(), MeshNames(None, None)  # no mesh to name
        note(f"{path}: no skinned mesh; the skeleton is its animated node tree ({skeleton.joint_count} joints "
             f"from {skeleton.names[0]!r}), and each level's GLB holds the skeleton, its clips and what hangs from "
             "it")  # fmt: skip
        if other_trees:
            note(f"{path}: animated nodes under no node in common with the skeleton's left out: "
                 f"{', '.join(other_trees)}")  # fmt: skip
    attachments = find_attachments(document, rig)
    content = LevelContent(document, rig, attachments, mesh_names)
    unwritten = left_out_of_level_files(document, rig, joined_nodes, attachments)
    if unwritten:
        whole_document = " (`animlod character` keeps the whole document)" if skin is not None else ""
        note(f"{path}: the levels' GLBs hold the skeleton, its clips, the skinned mesh if any with its materials, "
             f"and what hangs from the joints; not {unwritten}{whole_document}")  # fmt: skip
    names = [motion.name or f"animation{index}" for index, motion in enumerate(motions)]
    durations = [document.animation_duration(animation) for animation in animations]
    still = [index for index in range(len(document.gltf.animations)) if index not in animations]
    if still:  # a prop's spin, a blink of morph weights alone
        labels = ", ".join(document.animation_label(index) for index in still)
        note(f"{path}: {labels} move{'s' if len(still) == 1 else ''} no joint of the skeleton: not in the levels")
    if clip is None:
        from ..motion_lod.clips import join_clips, merge_split_clips

        merged = merge_split_clips(motions)
        if merged is not None:
            note(f"{path}: its {len(motions)} animations each move other joints: simplifying them as one motion "
                 "(use --clip to take one)")  # fmt: skip
            if poses_nothing(document, rig):
                note(f"{path}: the channels of its animations that pose no joint (morph weights, what hangs from the "
                     "joints, KHR_animation_pointer) are not in the levels' GLBs (the animations are joined into one "
                     "motion)")  # fmt: skip
            # The parts of one motion start together, at the earliest first key: a late one's held
            # first pose would be analysed, re-fitted and written for nothing.
            start = min(document.animation_start_frame(animation, fps) for animation in animations)
            if start:
                merged = merged.take_frames(np.arange(start, merged.frame_count))
            played = PlayedClip(merged.name, slice(None), max(durations), start=start / fps)
            return _Input(_rigid(path, motions, range(len(motions)), merged), [played], skin, materials, None, content)
        # A clip that scales a joint cannot be re-fitted; the others still make levels.
        rigid = [index for index, motion in enumerate(motions) if motion.deforming_joint() is None]
        scaling = [names[index] for index in range(len(motions)) if index not in rigid]
        if scaling and rigid:
            note(f"{path}: {', '.join(map(repr, scaling))} scale{'s' if len(scaling) == 1 else ''} joints and "
                 "motion LoD re-fits rigid motions only: left out of the levels")  # fmt: skip
        if len(rigid) > 1:
            note(f"{path}: its {len(rigid)} animations simplified together, one skeleton per level for all of "
                 "them (use --clip to take one)")  # fmt: skip
            keyed = [from_first_key(document, animations[i], fps, motions[i], morph_weights.get(animations[i]))
                     for i in rigid]  # fmt: skip
            joined, spans = join_clips([motion for motion, _, _ in keyed])
            played = [PlayedClip(names[index], span, durations[index], weights, animations[index], start / fps)
                      for index, span, (_, weights, start) in zip(rigid, spans, keyed)]  # fmt: skip
            return _Input(joined, played, skin, materials, None, content)
        clip = rigid[0] if rigid else 0
    listed = ", ".join(f"{i}: {name!r}" for i, name in enumerate(names))
    if isinstance(clip, str):
        if clip not in names:
            moves_no_joint = any(document.gltf.animations[index].name == clip for index in still)
            reason = "moves no joint of the skeleton" if moves_no_joint else "is not in the file"
            raise FormatError(path, "clip", f"the animation named {clip!r} {reason}; those that move it: {listed}")
        clip = names.index(clip)
    if not 0 <= clip < len(motions):
        raise FormatError(path, "clip", f"the file has {len(motions)} animations that move the skeleton ({listed}), "
                                        f"got index {clip}")  # fmt: skip
    animation = animations[clip]
    motion, weights, start = from_first_key(document, animation, fps, motions[clip], morph_weights.get(animation))
    played = [PlayedClip(names[clip], slice(None), durations[clip], weights, animation, start / fps)]
    return _Input(_rigid(path, motions, range(clip, clip + 1), motion), played, skin, materials, None, content)


def _clip_suffixes(names: list[str], room: int = LONGEST_NAME) -> list[str]:
    """File name suffixes of the clips' BVH files: none for one clip, else ``_<name>`` with what a
    file name should not hold as ``_`` (``Armature|Walk`` -> ``_Armature_Walk``), ``_<name>_<index>``
    where names repeat. A suffix longer than ``room`` bytes of UTF-8 keeps the start of the name
    that fits, cut between characters, and the first 8 hex digits of the whole name's SHA-1
    (``_<start>_<hash>``, ``_<start>_<hash>_<index>`` where names repeat), so that the file name
    fits and differs from the other clips'."""
    if len(names) == 1:
        return [""]
    safe = [re.sub(r"[^\w.-]+", "_", name).strip("_.") or "animation" for name in names]
    repeated = {name for name in safe if safe.count(name) > 1}
    suffixes = []
    for index, (name, original) in enumerate(zip(safe, names)):
        numbered = f"_{index}" if name in repeated else ""
        suffix = f"_{name}{numbered}"
        if len(suffix.encode()) > room:
            tail = f"_{hashlib.sha1(original.encode(errors='surrogatepass')).hexdigest()[:8]}{numbered}"
            fits = max(0, room - len(tail.encode()) - 1)
            start = name.encode()[:fits].decode(errors="ignore").rstrip("_.")  # a cut character dropped
            suffix = f"_{start}{tail}" if start else tail
        suffixes.append(suffix)
    return suffixes


def _rigid(path: str, motions: list[Motion], used: range, motion: Motion) -> Motion:
    """``motion``, made of ``motions[used]``, when none of those scales a joint; FormatError otherwise."""
    for index in used:
        joint = motions[index].deforming_joint()
        if joint is not None:
            element = f"animation {motions[index].name!r}" if motions[index].name else f"animation {index}"
            reason = f"joint {joint!r} scales; motion LoD re-fits rigid motions only (animlod simplify takes it)"
            raise FormatError(path, element, reason)
    return motion


def check_motion_options(
    *,
    levels: int | None,
    joints: Sequence[int] | None,
    ranking: str,
    solver: str,
    penalty: bool,
    workers: int,
    translation_tolerance: float,
    weights: Sequence[float],
    max_frames: int,
) -> None:
    """Refuse, naming the option, values of :func:`build_motion_levels`'s options it cannot take
    whatever the clip (each checked by the code that uses it): both ``levels`` and ``joints``, a
    level request, a ranking, solver, weight or analysis option out of range. A batch checks its
    manifest with it before anything runs; whether the skeleton allows the levels only the clip
    can tell."""
    from ..motion_lod.objective import Weights

    if levels is not None and joints is not None:
        raise ValueError("levels and joints: give one of them, not both")
    if levels is not None or joints is not None:
        check_level_request(levels if joints is None else list(joints))
    check_analysis_options(max_frames, translation_tolerance, ranking, workers)
    resolve_solver(solver, _refit_options(solver, penalty))
    if len(weights) != 3:
        raise ValueError(f"weights: expected (alpha, beta, gamma), got {len(weights)} values")
    Weights(*weights)


def _refit_options(solver: str, penalty: bool) -> MotionRefitOptions:
    """Bone lengths as equality constraints with the SLSQP solvers unless ``penalty``."""
    return MotionRefitOptions(hard_constraints=solver != "newton" and not penalty)


def _plan_levels(
    motion: Motion,
    skin: SkinnedMesh | None,
    spans: list[slice] | None,
    levels: int | None,
    joints: Sequence[int] | None,
    lock: Sequence[str],
    max_frames: int,
    translation_tolerance: float,
    ranking: str,
    workers: int,
) -> tuple[Motion, MotionAnalysis, TrialMeasure | None, list[int], JointFloor]:
    """The motion the chain is built on (with the skin's tips, skin_measure.py, for a skinned input),
    its analysis (over each clip's frames, ``spans``, of several; measured as the skin sees it),
    the refit ranking's trial measure (the skin's, or None: the joints'), the joint counts of the
    levels and the joint floor (ValueError on a bad request)."""
    from ..motion_lod.analysis import analyze_motion
    from ..motion_lod.chain import joint_floor, level_joint_counts
    from ..motion_lod.skin_measure import analyze_skinned_motion

    options = dict(
        locked=lock,
        max_frames=max_frames,
        translation_tolerance=translation_tolerance,
        ranking=ranking,
        workers=workers,
        clips=spans,
    )
    if skin is None:
        tipped, analysis, measure = motion, analyze_motion(motion, **options), None
    else:
        tipped, analysis, measure = analyze_skinned_motion(motion, [skin], **options)
    floor = joint_floor(tipped, analysis)
    if joints:
        counts = level_joint_counts(tipped, analysis, list(joints))
    elif floor.possible_levels == 1:  # every joint stays: one level, in a note
        counts = [floor.total]
    else:
        counts = level_joint_counts(tipped, analysis, levels if levels is not None else min(8, floor.possible_levels))
    return tipped, analysis, measure, counts, floor


def motion_asset(
    source: str | os.PathLike,
    output: str | os.PathLike,
    *,
    progress: Progress | None = None,
    **options: object,
) -> AssetResult:
    """The batch job of :func:`build_motion_levels`: its files in the folder ``output`` and one
    row per level (joints, max joint position error in asset units and over the figure size,
    the level's re-fit seconds). ``options`` are the keyword arguments of :func:`build_motion_levels`.
    """
    started = time.perf_counter()

    def on_level(index: int, count: int, frames: int, levels: int) -> None:
        if progress is not None:
            progress(index / levels, f"level {index}: {count} joints, {frames} frames")

    options.setdefault("workers", 1)  # a batch spreads its work over assets, one core each
    report = build_motion_levels(source, output, on_level=on_level, **options)  # type: ignore[arg-type]
    folder = Path(output)
    size = report.chain.figure_size
    rows = [
        LevelRow(index, "", report.faces, level.report.joint_count, level.report.max_error,
                 level.report.max_error / size if size > 0 else None, level.report.seconds)
        for index, level in enumerate(report.chain.levels)
    ]  # fmt: skip
    outputs = [folder / name for names in report.files for name in names] + [folder / report.manifest]
    failures = sum(len(level.report.failures) for level in report.chain.levels)
    notes = report.notes + ([f"{failures} frames needed a second solve"] if failures else [])
    return AssetResult("motion", os.fspath(source), outputs, rows, time.perf_counter() - started, notes)
