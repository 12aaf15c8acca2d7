"""A skinned rig's motion measured as its skin sees it (Eqs. 1-5 on the points that matter).

The paper measures a joint by the points below it: Eq. 1's bones to its children, the re-fit's
joint positions (Eq. 5) and the levels' errors. On a skinned rig that misjudges two kinds of joint.

- A leaf joint that carries skin. A BVH leaf ends in an End Site; a glTF skeleton's leaf joints
  have nothing below them (Blender's head, toes and weapon bones), so turning one moved no point:
  Eq. 1 gave it importance 0 and the re-fit saw no error in freezing it, so it froze first
  whatever skin it carried (Castle Game Engine's knight lost its head's motion at the first
  level, 8 % of its size on the skin for a joint error of 1e-6). :func:`with_skin_tips` gives it
  two end sites where its skin is: the weighted centroid moved one standard deviation along each
  of the two main axes of the skin around the joint (weighted principal axes, in its bind
  frame). Two points off one line fix the joint's rotation, swing and twist, and their
  displacement is the skin's. They are markers (MotionAnalysis.markers): they count in Eq. 1 and
  in every error, belong to no level and are not re-fitted (a kept leaf keeps its own rotation,
  which places them; as SLSQP variables they took 1.7x the CPU time of Soldier.glb's 4 levels
  for about the same errors).
- A joint that moves no skin: a rig's IK targets and controls. Its position cost as much as any
  joint's, and a translating one could never freeze (the knight: 18 of 50 joints, 6 translating).
  :func:`measured_by_skin` hides it (MotionAnalysis.hidden): it freezes first, translating or
  not, and counts in no error.

The default ranking (refit_choice.py) keeps, at each level, the proposal whose trial re-fit
leaves the lowest error; :func:`skin_trial_measure` makes that error the skin's mean distance
rather than the joints'. :func:`without_skin_tips` then takes the tips out of the chain, whose
levels have the input's joints and errors measured as the skin sees them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from .. import rotations
from ..model import Motion, Skeleton, SkinnedMesh
from .analysis import MotionAnalysis, analyze_motion
from .chain import MotionLodChain, TrialMeasure, build_motion_chain
from .frozen import FrozenLevel
from .skin_transfer import transfer_skin

TIPS_PER_JOINT = 2


def with_skin_tips(motion: Motion, skins: list[SkinnedMesh]) -> Motion:
    """``motion`` with end sites on the skin of every leaf joint that ``skins`` weigh (after its
    joints, in joint order; names ``<joint>_tip0``, ``<joint>_tip1`` made unique); ``motion``
    itself where no leaf joint carries skin."""
    skeleton = motion.skeleton
    tips = _tip_offsets(skeleton, skins)
    if not tips:
        return motion
    owners = np.repeat(sorted(tips), TIPS_PER_JOINT)
    offsets = np.concatenate([tips[j] for j in sorted(tips)])
    taken = set(skeleton.names)
    names = []
    for joint, k in zip(owners, np.tile(np.arange(TIPS_PER_JOINT), len(tips))):
        name = f"{skeleton.names[joint]}_tip{k}"
        while name in taken:
            name += "_"
        taken.add(name)
        names.append(name)
    added = len(names)
    tipped = Skeleton(
        skeleton.names + names,
        np.concatenate([skeleton.parents, owners]),
        np.concatenate([skeleton.offsets, offsets]),
        np.concatenate([skeleton.rest_rotations, rotations.identity((added,))]),
        np.concatenate([skeleton.end_sites, np.ones(added, bool)]),
    )
    frames = motion.frame_count
    local = np.concatenate([motion.local_rotations, rotations.identity((frames, added))], axis=1)
    translations = None
    if motion.joint_translations is not None:
        held = np.broadcast_to(offsets, (frames, added, 3))
        translations = np.concatenate([motion.joint_translations, held], axis=1)
    deformations = None
    if motion.joint_deformations is not None:
        identity = np.broadcast_to(np.eye(3), (frames, added, 3, 3))
        deformations = np.concatenate([motion.joint_deformations, identity], axis=1)
    return Motion(tipped, motion.root_positions, local, motion.fps, motion.name, translations, deformations)


def _tip_offsets(skeleton: Skeleton, skins: list[SkinnedMesh]) -> dict[int, np.ndarray]:
    """``{leaf joint: (2, 3) tip offsets in its frame}`` for the leaf joints the skins weigh."""
    leaves = _joint_weights(skeleton, skins) > 0.0  # checks the skins' skeletons too
    # Leaves only: tips on every skinned joint, or on those of one child (to see an inner joint's
    # twist, which moves no child), moved bench_skin_measure.py's levels both ways at 1.5-3x the
    # CPU time (Monster's first level 11% -> 6% of the diagonal, soldier1's 2.2% -> 11%).
    leaves[skeleton.parents[1:]] = False
    leaves &= ~skeleton.end_sites
    leaves[0] = False
    total = np.zeros(skeleton.joint_count)
    first = np.zeros((skeleton.joint_count, 3))
    second = np.zeros((skeleton.joint_count, 3, 3))
    for skin in skins:
        weights = skin.weights.astype(np.float64)
        used = weights > 0.0
        vertices, slots = np.nonzero(used & leaves[skin.joints])
        joints = skin.joints[vertices, slots]
        # Each vertex in the bind frame of each leaf joint it follows: inverse_bind @ v.
        rest = np.c_[skin.rest_positions[vertices].astype(np.float64), np.ones(vertices.size)]
        local = np.einsum("nij,nj->ni", skin.inverse_bind[joints], rest)[:, :3]
        w = weights[vertices, slots]
        np.add.at(total, joints, w)
        np.add.at(first, joints, w[:, None] * local)
        np.add.at(second, joints, w[:, None, None] * local[:, :, None] * local[:, None, :])
    tips = {}
    for joint in np.flatnonzero(total > 0.0):  # O(leaf joints) 3x3 eigenproblems
        centroid = first[joint] / total[joint]
        covariance = second[joint] / total[joint] - np.outer(centroid, centroid)
        variances, axes = np.linalg.eigh(covariance)  # ascending
        spread = np.sqrt(np.maximum(variances[::-1][:TIPS_PER_JOINT], 0.0))
        tips[int(joint)] = centroid + (axes[:, ::-1][:, :TIPS_PER_JOINT] * spread).T
    return tips


def measured_by_skin(
    analysis: MotionAnalysis, motion: Motion, skins: list[SkinnedMesh], attached: Sequence[int] = ()
) -> MotionAnalysis:
    """``analysis`` of :func:`with_skin_tips` of ``motion``, measured as the skins see it: the tips
    are markers, and the joints that move no skin are hidden: no skin on them or below them, nor
    on their parent (whose end bone such a joint would be), and no node hung from them or below
    them (``attached``: joint indices, a character's props). Those are a rig's IK targets and
    controls (Castle Game Engine's knight: 18 of 50 joints, 6 of them translating); they freeze
    first, translating or not, and count in no error. A locked joint is never hidden."""
    skeleton = motion.skeleton
    carries = _joint_weights(skeleton, skins) > 0.0
    carries[list(attached)] = True
    below = carries.copy()
    for joint in range(skeleton.joint_count - 1, 0, -1):  # O(J): children before parents
        below[skeleton.parents[joint]] |= below[joint]
    hidden = [
        j
        for j in range(1, skeleton.joint_count)
        if not below[j] and not carries[skeleton.parents[j]] and j not in analysis.locked
    ]
    joints = [j for j in hidden if not skeleton.end_sites[j]]  # an end site goes with its joint
    return dataclasses.replace(
        analysis,
        markers=list(range(skeleton.joint_count, analysis.key_frames.size)),
        hidden=hidden,
        priority=joints + [j for j in analysis.priority if j not in hidden],
    )


def hidden_note(analysis: MotionAnalysis, motion: Motion) -> str | None:
    """What the summary says of the hidden joints (``measured_by_skin``), or None without any."""
    skeleton = motion.skeleton
    names = [skeleton.names[j] for j in analysis.hidden if not skeleton.end_sites[j]]
    if not names:
        return None
    shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
    count = "1 joint moves" if len(names) == 1 else f"{len(names)} joints move"
    return f"{count} no skin ({shown}): frozen first, counted in no error"


def _joint_weights(skeleton: Skeleton, skins: list[SkinnedMesh]) -> np.ndarray:
    """(J,) the summed skin weight of every joint over ``skins``."""
    total = np.zeros(skeleton.joint_count)
    for skin in skins:
        if skin.skeleton.names != skeleton.names:
            raise ValueError("skin: its skeleton's joint names differ from the motion's")
        np.add.at(total, skin.joints.ravel(), skin.weights.ravel().astype(np.float64))
    return total


class SkinnedAnalysis(NamedTuple):
    """What a skinned rig's chain is built from (:func:`analyze_skinned_motion`)."""

    motion: Motion  # the rig's motion with its skin tips (with_skin_tips)
    analysis: MotionAnalysis  # its analysis measured as the skins see it (measured_by_skin)
    trial_measure: TrialMeasure  # the refit ranking's trial score on the skins (skin_trial_measure)


def analyze_skinned_motion(
    motion: Motion, skins: list[SkinnedMesh], attached: Sequence[int] = (), **options: object
) -> SkinnedAnalysis:
    """The motion a skinned rig's chain is built on (``motion`` with :func:`with_skin_tips`), its
    :func:`analyze_motion` (``options``) measured as ``skins`` see it (:func:`measured_by_skin`)
    and the trial measure that chooses its levels' joints by the skins (:func:`skin_trial_measure`)."""
    tipped = with_skin_tips(motion, skins)
    analysis = measured_by_skin(analyze_motion(tipped, **options), motion, skins, attached)  # type: ignore[arg-type]
    return SkinnedAnalysis(tipped, analysis, skin_trial_measure(motion, skins))


def skin_trial_measure(motion: Motion, skins: list[SkinnedMesh]) -> TrialMeasure:
    """The refit ranking's trial score for a rig skinned by ``skins`` (on ``motion``'s joints; the
    levels scored may be of :func:`with_skin_tips` of it): the mean distance of the skins' vertices
    over the trial frames from where ``motion`` puts them, each skin moved onto the level's kept
    joints (:func:`transfer_skin`) and played with the trial's re-fitted motion.

    The joints' mean error, the default score, is a proxy for the skin's: on Soldier.glb's second
    and third levels it chose joints whose skin moved 20 % and 16 % more on average over every frame,
    and no level of bench/bench_skin_measure.py's files moved more by the skin's score.
    """
    count = motion.skeleton.joint_count
    originals: dict[bytes, list[np.ndarray]] = {}  # the ranking scores every proposal on the same frames

    def measure(level: FrozenLevel, refitted: Motion, frames: np.ndarray) -> float:
        key = frames.tobytes()
        if key not in originals:
            played = motion.take_frames(frames)
            originals[key] = [skin.bake(played).frames for skin in skins]
        untipped = _first_points(level, motion.skeleton, count)
        distances = [
            np.linalg.norm(transfer_skin(skin, untipped).bake(refitted).frames - original, axis=-1)
            for skin, original in zip(skins, originals[key])
        ]
        return float(sum(d.sum() for d in distances) / sum(d.size for d in distances))

    return measure


def build_skinned_motion_chain(
    motion: Motion,
    skin: SkinnedMesh,
    levels: int | Sequence[int] = 8,
    attached: Sequence[int] = (),
    locked: Sequence[str] = (),
    **options: object,
) -> MotionLodChain:
    """:func:`~animlod.motion_lod.chain.build_motion_chain` of ``motion`` measured as ``skin``
    sees it, as ``animlod character`` and ``animlod motion`` build it: the levels on ``motion``'s
    joints, each with its skin. ``options`` go to ``build_motion_chain`` (not ``analysis``)."""
    tipped, analysis, measure = analyze_skinned_motion(motion, [skin], attached, locked=locked)
    chain = build_motion_chain(tipped, levels, analysis=analysis, trial_measure=measure, **options)
    return without_skin_tips(chain, motion, skin)


def without_skin_tips(chain: MotionLodChain, motion: Motion, skin: SkinnedMesh | None = None) -> MotionLodChain:
    """``chain``, built on :func:`with_skin_tips` of ``motion`` with :func:`measured_by_skin`,
    on ``motion``'s joints: the frozen splits, the re-fitted positions and the analysis without
    the tips (the levels' skeletons never had them), the reports (errors measured on the tips
    too) as they are, and each level's skin ``skin`` moved onto its kept joints
    (:func:`transfer_skin`) when given."""
    count = motion.skeleton.joint_count
    levels = []
    for level in chain.levels:
        frozen = _first_points(level.frozen, motion.skeleton, count)
        skin_of_level = None if skin is None else transfer_skin(skin, frozen)
        levels.append(
            dataclasses.replace(level, frozen=frozen, positions=level.positions[:, :count], skin=skin_of_level)
        )
    analysis = dataclasses.replace(
        chain.analysis,
        key_frames=chain.analysis.key_frames[:count],
        importance=chain.analysis.importance[:count],
        markers=[],
    )
    return MotionLodChain(analysis, levels)


def _first_points(level: FrozenLevel, skeleton: Skeleton, count: int) -> FrozenLevel:
    """``level`` on its first ``count`` points (the tips come after them and hang from them)."""
    arrays = {
        field.name: getattr(level, field.name)[:count]
        for field in dataclasses.fields(level)
        if isinstance(getattr(level, field.name), np.ndarray)
    }
    return dataclasses.replace(level, skeleton=skeleton, **arrays)
