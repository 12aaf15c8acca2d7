"""The data model every part of animlod shares (DESIGN.md, "Data model").

Shapes: ``F`` frames, ``V`` vertices, ``M`` faces, ``J`` joints, ``T`` motion frames, ``K`` skin
influences per vertex. Positions are float32, indices int32, quaternions (x, y, z, w), matrices
(4, 4) acting on column vectors. Units are the asset's own; nothing is rescaled.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from . import _core, rotations

# Joint deformations this close (on any matrix entry) count as equal when naming the joint that
# deforms: float32 keys and rotations leave ~1e-7 between joints a scale carries into alike.
_DEFORMATION_NOISE = 1e-5


def joint_depths(parents: np.ndarray) -> np.ndarray:
    """Number of ancestors of every joint, ``(J,) int64`` (parents in topological order)."""
    depth = np.zeros(parents.size, dtype=np.int64)
    for joint in range(1, parents.size):  # O(J): parents come first
        depth[joint] = depth[parents[joint]] + 1
    return depth


def spread_frames(frame_count: int, count: int) -> np.ndarray:
    """(<= count,) int frame indices spread evenly over [0, frame_count), both ends included."""
    return np.unique(np.linspace(0, frame_count - 1, min(count, frame_count)).round().astype(np.int64))


def _require(condition: bool, what: str) -> None:
    if not condition:
        raise ValueError(what)


def check_finite(name: str, array: np.ndarray) -> None:
    """ValueError naming ``name`` and the index of the first non-finite value of ``array``."""
    if not np.all(np.isfinite(array)):
        bad = np.argwhere(~np.isfinite(array))[0]
        raise ValueError(f"{name}: non-finite value at index {tuple(int(i) for i in bad)}")


def whole_number(name: str, value: object, minimum: int) -> int:
    """``value`` as an int when it is a whole number (Python's or numpy's, not a bool) of at
    least ``minimum``; otherwise a ValueError naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise ValueError(f"{name}: expected a whole number >= {minimum}, got {value!r}")
    return int(value)


def whole_indices(name: str, values: object, item: str, low: int, high: int) -> np.ndarray:
    """``values`` as int32 indices in [``low``, ``high``); ValueError naming ``name`` and the
    ``item`` (row) holding one that is not a whole number or lies outside. Checked before the
    cast to int32, which would wrap 2**32 + 2 to 2 and truncate 1.9 to 1 silently."""
    given = np.asarray(values)
    integral = given.dtype.kind in "iuf" or given.dtype == np.bool_
    _require(integral, f"{name}: expected integer indices, got dtype {given.dtype}")
    if not given.size:
        return np.ascontiguousarray(given, dtype=np.int32)
    rows = given.reshape(len(given), -1) if given.ndim else given.reshape(1, 1)

    def fail(bad: np.ndarray, what: str) -> None:
        row = int(np.argmax(bad.any(axis=1)))
        shown = rows[row].tolist() if rows.shape[1] > 1 else rows[row, 0].item()
        raise ValueError(f"{name}: {item} {row} {shown} has an index {what}")

    if given.dtype.kind == "f":
        wide = rows.astype(np.float64)
        bad = ~np.isfinite(wide) | (wide != np.round(wide))
        if bad.any():
            fail(bad, "that is not a whole number")
    if rows.min() < low or rows.max() >= high:
        fail((rows < low) | (rows >= high), f"outside [{low}, {high})")
    return np.ascontiguousarray(given, dtype=np.int32)


def checked_faces(faces: np.ndarray, vertex_count: int) -> np.ndarray:
    """``faces`` as (M, 3) int32 indices below ``vertex_count`` (:func:`whole_indices`)."""
    given = np.asarray(faces)
    _require(given.ndim == 2 and given.shape[1] == 3, f"faces: expected shape (M, 3), got {given.shape}")
    return whole_indices("faces", given, "face", 0, vertex_count)


@dataclass
class AnimatedMesh:
    """A deforming mesh with fixed connectivity.

    Attributes
    ----------
    faces : (M, 3) int32, counter-clockwise front faces.
    frames : (F, V, 3) float32 positions per frame.
    fps : frames per second, or None when the frames are not a time sequence (e.g. poses).
    """

    faces: np.ndarray
    frames: np.ndarray
    fps: float | None = None

    def __post_init__(self) -> None:
        self.frames = np.ascontiguousarray(self.frames, dtype=np.float32)
        _require(
            self.frames.ndim == 3 and self.frames.shape[2] == 3 and self.frames.shape[0] >= 1,
            f"frames: expected shape (F, V, 3) with F >= 1, got {self.frames.shape}",
        )
        check_finite("frames", self.frames)
        self.faces = checked_faces(self.faces, self.frames.shape[1])
        _require(self.fps is None or self.fps > 0.0 and np.isfinite(self.fps), f"fps: expected > 0, got {self.fps}")

    @property
    def frame_count(self) -> int:
        return int(self.frames.shape[0])

    @property
    def vertex_count(self) -> int:
        return int(self.frames.shape[1])

    @property
    def face_count(self) -> int:
        return int(self.faces.shape[0])


@dataclass
class Skeleton:
    """A joint hierarchy in topological order (``parents[j] < j``, ``parents[root] == -1``).

    Attributes
    ----------
    names : J joint names, unique.
    parents : (J,) int32 parent index per joint, -1 for the root (joint 0).
    offsets : (J, 3) float64 translation of each joint in its parent's frame (the root's
        offset is its rest position).
    rest_rotations : (J, 4) float64 local rotation of each joint in the rest pose.
    end_sites : (J,) bool, True for leaf markers that carry no rotation of their own (BVH
        "End Site"); they give leaf bones a length and direction.
    """

    names: list[str]
    parents: np.ndarray
    offsets: np.ndarray
    rest_rotations: np.ndarray | None = None
    end_sites: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.names = [str(n) for n in self.names]
        joint_count = len(self.names)
        _require(joint_count >= 1, "skeleton: needs at least one joint")
        _require(len(set(self.names)) == joint_count, "skeleton: joint names must be unique")
        self.parents = whole_indices("parents", self.parents, "joint", -1, joint_count)
        self.offsets = np.asarray(self.offsets, dtype=np.float64)
        _require(
            self.parents.shape == (joint_count,), f"parents: expected shape ({joint_count},), got {self.parents.shape}"
        )
        _require(
            self.offsets.shape == (joint_count, 3),
            f"offsets: expected shape ({joint_count}, 3), got {self.offsets.shape}",
        )
        _require(self.parents[0] == -1, "parents: joint 0 must be the root (parent -1)")
        later = np.nonzero(self.parents[1:] >= np.arange(1, joint_count))[0]
        _require(
            later.size == 0,
            f"parents: joint {later[0] + 1 if later.size else 0} has a parent that does not come before it",
        )
        _require(bool(np.all(self.parents[1:] >= 0)), "parents: only joint 0 may have no parent")
        check_finite("offsets", self.offsets)
        if self.rest_rotations is None:
            self.rest_rotations = rotations.identity((joint_count,))
        self.rest_rotations = np.asarray(self.rest_rotations, dtype=np.float64)
        shape = self.rest_rotations.shape
        _require(shape == (joint_count, 4), f"rest_rotations: expected shape ({joint_count}, 4), got {shape}")
        self.rest_rotations = rotations.normalize(self.rest_rotations, "rest_rotations")
        self.end_sites = np.zeros(joint_count, bool) if self.end_sites is None else np.asarray(self.end_sites, bool)
        _require(self.end_sites.shape == (joint_count,), f"end_sites: expected shape ({joint_count},)")
        has_children = np.zeros(joint_count, bool)
        has_children[self.parents[1:]] = True
        _require(not np.any(self.end_sites & has_children), "end_sites: an end site must be a leaf")

    @property
    def joint_count(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        """Index of the joint called ``name``; ValueError naming the joint if there is none."""
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(f"skeleton has no joint named {name!r}") from None

    def children(self) -> list[list[int]]:
        """Child joint indices of every joint."""
        result: list[list[int]] = [[] for _ in self.names]
        for joint, parent in enumerate(self.parents[1:], start=1):
            result[parent].append(joint)
        return result

    def rest_motion(self, frame_count: int = 1, fps: float = 30.0) -> Motion:
        """The skeleton held in its rest pose (root at its offset) for ``frame_count`` frames."""
        return Motion(
            self,
            np.repeat(self.offsets[None, 0], frame_count, axis=0),
            np.repeat(self.rest_rotations[None], frame_count, axis=0),
            fps=fps,
        )

    def rest_world_transforms(self) -> np.ndarray:
        """World transforms ``(J, 4, 4)`` of the rest pose (root at its offset)."""
        return self.rest_motion(1, fps=1.0).world_transforms()[0]


@dataclass
class Motion:
    """Skeletal motion: root translation and every joint's local rotation per frame.

    The local transform of joint j at frame t is ``T(offsets[j]) @ R(local_rotations[t, j])``,
    except the root, whose translation is ``root_positions[t]``.

    Attributes
    ----------
    skeleton : the joint hierarchy.
    root_positions : (T, 3) float64 world position of the root per frame.
    local_rotations : (T, J, 4) float64 local joint rotations (x, y, z, w) per frame.
    fps : frames per second.
    name : clip name ("" when the source has none).
    joint_translations : (T, J, 3) float64 or None. Per-frame local translations that replace
        ``offsets`` for non-root joints (BVH position channels on non-root joints); column 0
        is ignored, the root uses ``root_positions``. None when the offsets hold in every frame.
    joint_deformations : (T, J, 3, 3) float64 or None. What a joint's world transform does
        beyond its rigid frame, in that frame: ``world_linear = R_world @ D`` (glTF's animated
        scale, and the shear a parent's non-uniform scale gives a turned child). Only skinning
        (:meth:`skin_matrices`) applies it; joint positions and rotations are the rigid ones.
        None for a rigid motion, the only kind motion LoD re-fits (:meth:`require_rigid`).
    """

    skeleton: Skeleton
    root_positions: np.ndarray
    local_rotations: np.ndarray
    fps: float
    name: str = ""
    joint_translations: np.ndarray | None = None
    joint_deformations: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.root_positions = np.asarray(self.root_positions, dtype=np.float64)
        local = np.asarray(self.local_rotations, dtype=np.float64)
        frame_count = self.root_positions.shape[0] if self.root_positions.ndim == 2 else -1
        _require(
            self.root_positions.ndim == 2 and self.root_positions.shape[1] == 3 and frame_count >= 1,
            f"root_positions: expected shape (T, 3) with T >= 1, got {self.root_positions.shape}",
        )
        expected = (frame_count, self.skeleton.joint_count, 4)
        _require(local.shape == expected, f"local_rotations: expected shape {expected}, got {local.shape}")
        check_finite("root_positions", self.root_positions)
        check_finite("local_rotations", local)
        self.local_rotations = rotations.normalize(local, "local_rotations")
        _require(self.fps > 0 and np.isfinite(self.fps), f"fps: must be positive, got {self.fps}")
        if self.joint_translations is not None:
            self.joint_translations = np.asarray(self.joint_translations, dtype=np.float64)
            _require(
                self.joint_translations.shape == expected[:2] + (3,),
                f"joint_translations: expected shape {expected[:2] + (3,)}, got {self.joint_translations.shape}",
            )
            check_finite("joint_translations", self.joint_translations)
        if self.joint_deformations is not None:
            self.joint_deformations = np.asarray(self.joint_deformations, dtype=np.float64)
            _require(
                self.joint_deformations.shape == expected[:2] + (3, 3),
                f"joint_deformations: expected shape {expected[:2] + (3, 3)}, got {self.joint_deformations.shape}",
            )
            check_finite("joint_deformations", self.joint_deformations)

    @property
    def frame_count(self) -> int:
        return int(self.root_positions.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return (self.frame_count - 1) / self.fps

    def local_translations(self) -> np.ndarray:
        """Local translation of every joint per frame ``(T, J, 3)``, a new array: the offsets (or
        ``joint_translations`` where given), with column 0 the root position."""
        if self.joint_translations is None:
            translations = np.broadcast_to(self.skeleton.offsets, self.local_rotations.shape[:2] + (3,)).copy()
        else:
            translations = self.joint_translations.copy()
        translations[:, 0] = self.root_positions
        return translations

    def take_frames(self, frames: np.ndarray | slice) -> Motion:
        """The motion at ``frames`` (indices into this motion, or a slice), same skeleton, name
        and fps."""
        translations = None if self.joint_translations is None else self.joint_translations[frames]
        deformations = None if self.joint_deformations is None else self.joint_deformations[frames]
        return Motion(
            self.skeleton,
            self.root_positions[frames],
            self.local_rotations[frames],
            self.fps,
            self.name,
            translations,
            deformations,
        )

    @staticmethod
    def concatenate(motions: list[Motion], name: str) -> Motion:
        """The motions one after another as one, on the first one's skeleton and fps (the
        caller's to check they share them)."""
        translations = deformations = None
        if any(motion.joint_translations is not None for motion in motions):
            translations = np.concatenate([motion.local_translations() for motion in motions])
        if any(motion.joint_deformations is not None for motion in motions):
            deformations = np.concatenate([motion.local_deformations() for motion in motions])
        return Motion(
            motions[0].skeleton,
            np.concatenate([motion.root_positions for motion in motions]),
            np.concatenate([motion.local_rotations for motion in motions]),
            motions[0].fps,
            name,
            translations,
            deformations,
        )

    def local_deformations(self) -> np.ndarray:
        """``joint_deformations`` ``(T, J, 3, 3)``, identities for a rigid motion; a new array."""
        if self.joint_deformations is None:
            return np.broadcast_to(np.eye(3), self.local_rotations.shape[:2] + (3, 3)).copy()
        return self.joint_deformations.copy()

    def deforming_joint(self) -> str | None:
        """The joint that starts the deformation: the one whose deformation strays furthest from
        what its parent's gives it, the shallowest of those that float noise alone tells apart;
        None for a rigid motion."""
        if self.joint_deformations is None:
            return None
        # A parent's scale carries into every joint below it: by the world deviation alone, a
        # scaled root ties with all its descendants and float noise named one of them.
        deformations = self.joint_deformations
        parents = self.skeleton.parents[1:]
        turns = rotations.to_matrix(self.local_rotations[:, 1:])  # a joint's rigid frame in its parent's
        inherited = np.broadcast_to(np.eye(3), deformations.shape).copy()
        inherited[:, 1:] = np.swapaxes(turns, -1, -2) @ deformations[:, parents] @ turns
        deviation = np.abs(deformations - inherited).max(axis=(0, 2, 3))
        depths = joint_depths(self.skeleton.parents)
        largest = np.flatnonzero(deviation >= deviation.max() - _DEFORMATION_NOISE)
        return self.skeleton.names[int(largest[np.argmin(depths[largest])])]

    def require_rigid(self, what: str) -> None:
        """ValueError saying that ``what`` takes rigid motions only, when joints of this one deform."""
        joint = self.deforming_joint()
        if joint is not None:
            label = repr(self.name) if self.name else "(unnamed)"
            raise ValueError(f"motion {label}: joint {joint!r} scales; {what} takes rigid motions only")

    def world_transforms(self) -> np.ndarray:
        """Forward kinematics: world transforms ``(T, J, 4, 4)`` of every joint (float64, in the
        core: pose.hpp's clip_forward_kinematics)."""
        return _core.clip_forward_kinematics(self.skeleton.parents, self.local_translations(), self.local_rotations)

    def world_positions(self) -> np.ndarray:
        """World positions ``(T, J, 3)`` of every joint."""
        return self.world_transforms()[..., :3, 3]

    def skin_matrices(self, inverse_bind: np.ndarray) -> np.ndarray:
        """Skinning matrices ``world @ inverse_bind``, ``(T, J, 4, 4)``; ``world`` includes the
        joint deformations. ``inverse_bind`` is ``(J, 4, 4)``, one finite matrix per joint of the
        skeleton; any other shape (a lone ``(4, 4)``, which numpy would broadcast, too) or a
        non-finite value is a ValueError naming ``inverse_bind``."""
        inverse_bind = np.asarray(inverse_bind, dtype=np.float64)
        expected = (self.skeleton.joint_count, 4, 4)
        _require(inverse_bind.shape == expected, f"inverse_bind: expected shape {expected}, got {inverse_bind.shape}")
        check_finite("inverse_bind", inverse_bind)
        world = self.world_transforms()
        if self.joint_deformations is not None:
            world[..., :3, :3] = world[..., :3, :3] @ self.joint_deformations
        return world @ inverse_bind


@dataclass
class SkinnedMesh:
    """A mesh bound to a skeleton with linear blend skinning.

    Attributes
    ----------
    rest_positions : (V, 3) float32 bind-pose positions.
    faces : (M, 3) int32.
    joints : (V, K) int32 joint index per influence, K = 4 by default (8 allowed).
    weights : (V, K) float32, normalised to sum 1 per vertex and sorted by decreasing weight.
    inverse_bind : (J, 4, 4) float64 inverse bind matrices.
    skeleton : the joint hierarchy the indices in ``joints`` refer to.
    uvs : (V, 2) float32 or None.
    normals : (V, 3) float32 or None.
    morph_targets : (N, V, 3) float32 position deltas or None.
    morph_target_names : N names, or None.
    default_morph_weights : (N,) float64 weights the morph targets show where no animation drives
        them (glTF's mesh or node ``weights``), or None: all 0.
    """

    rest_positions: np.ndarray
    faces: np.ndarray
    joints: np.ndarray
    weights: np.ndarray
    inverse_bind: np.ndarray
    skeleton: Skeleton
    uvs: np.ndarray | None = None
    normals: np.ndarray | None = None
    morph_targets: np.ndarray | None = None
    morph_target_names: list[str] | None = field(default=None)
    default_morph_weights: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.rest_positions = np.ascontiguousarray(self.rest_positions, dtype=np.float32)
        vertex_count = self.rest_positions.shape[0]
        _require(
            self.rest_positions.shape == (vertex_count, 3),
            f"rest_positions: expected (V, 3), got {self.rest_positions.shape}",
        )
        check_finite("rest_positions", self.rest_positions)
        self.faces = checked_faces(self.faces, vertex_count)
        self.joints = np.asarray(self.joints)
        weights = np.asarray(self.weights, dtype=np.float64)
        _require(
            self.joints.ndim == 2 and self.joints.shape[0] == vertex_count,
            f"joints: expected (V, K), got {self.joints.shape}",
        )
        _require(weights.shape == self.joints.shape, f"weights: expected {self.joints.shape}, got {weights.shape}")
        _require(
            self.joints.shape[1] in (1, 2, 3, 4, 8),
            f"joints: K must be 1-4 or 8 influences, got {self.joints.shape[1]}",
        )
        check_finite("weights", weights)
        joint_count = self.skeleton.joint_count
        self.joints = whole_indices("joints", self.joints, "vertex", 0, joint_count)
        _require(bool(np.all(weights >= 0.0)), "weights: negative skin weight")
        self.joints, self.weights = normalize_skin_weights(self.joints, weights)
        self.inverse_bind = np.asarray(self.inverse_bind, dtype=np.float64)
        _require(
            self.inverse_bind.shape == (joint_count, 4, 4),
            f"inverse_bind: expected ({joint_count}, 4, 4), got {self.inverse_bind.shape}",
        )
        check_finite("inverse_bind", self.inverse_bind)
        if self.uvs is not None:
            self.uvs = np.ascontiguousarray(self.uvs, dtype=np.float32)
            _require(self.uvs.shape == (vertex_count, 2), f"uvs: expected ({vertex_count}, 2), got {self.uvs.shape}")
            check_finite("uvs", self.uvs)
        if self.normals is not None:
            self.normals = np.ascontiguousarray(self.normals, dtype=np.float32)
            _require(
                self.normals.shape == (vertex_count, 3),
                f"normals: expected ({vertex_count}, 3), got {self.normals.shape}",
            )
            check_finite("normals", self.normals)
        if self.morph_targets is not None:
            self.morph_targets = np.ascontiguousarray(self.morph_targets, dtype=np.float32)
            _require(
                self.morph_targets.ndim == 3 and self.morph_targets.shape[1:] == (vertex_count, 3),
                f"morph_targets: expected (N, {vertex_count}, 3), got {self.morph_targets.shape}",
            )
            check_finite("morph_targets", self.morph_targets)
        if self.default_morph_weights is not None:
            self.default_morph_weights = np.asarray(self.default_morph_weights, np.float64)
            target_count = 0 if self.morph_targets is None else len(self.morph_targets)
            _require(
                self.default_morph_weights.shape == (target_count,),
                f"default_morph_weights: expected ({target_count},), got {self.default_morph_weights.shape}",
            )
            check_finite("default_morph_weights", self.default_morph_weights)

    @property
    def vertex_count(self) -> int:
        return int(self.rest_positions.shape[0])

    @property
    def face_count(self) -> int:
        return int(self.faces.shape[0])

    def bake(self, motion: Motion, morph_weights: np.ndarray | None = None) -> AnimatedMesh:
        """Linear blend skinning of every frame of ``motion`` in the C++ core.

        ``morph_weights (T, N)`` finite, one row per frame of ``motion`` and one column per morph
        target (N = 0 for a skin without targets), blends the morph targets into the rest pose of
        each frame first, as glTF does (morphing before skinning); None keeps the rest pose with
        ``default_morph_weights``. Another shape or a non-finite weight is a ValueError naming
        ``morph_weights``.
        """
        from ._core import bake_lbs

        if morph_weights is not None:
            morph_weights = np.asarray(morph_weights, np.float64)
            target_count = 0 if self.morph_targets is None else len(self.morph_targets)
            expected = (motion.frame_count, target_count)
            _require(
                morph_weights.shape == expected, f"morph_weights: expected shape {expected}, got {morph_weights.shape}"
            )
            check_finite("morph_weights", morph_weights)
        if morph_weights is None or self.morph_targets is None:
            return AnimatedMesh(self.faces, bake_lbs(*self._lbs_inputs(motion)), fps=motion.fps)
        matrices = self._skin_matrices(motion)
        frames = np.empty((motion.frame_count, self.vertex_count, 3), np.float32)
        for t in range(motion.frame_count):  # O(T) calls, each a whole frame in C++
            rest = morphed(self.rest_positions, self.morph_targets, morph_weights[t])
            frames[t] = bake_lbs(rest, self.joints, self.weights, matrices[t : t + 1])[0]
        return AnimatedMesh(self.faces, frames, fps=motion.fps)

    def distance_maxima(self, motion: Motion, others: Sequence[tuple[SkinnedMesh, Motion]]) -> np.ndarray:
        """(N, T) float32: in each frame of ``motion``, the largest distance between where this
        skin played with ``motion`` and each of the N ``(skin, motion)`` pairs ``others`` (the
        same vertices and frame count; another skeleton or weights: reduced skins) put a vertex,
        all at their default morph weights. Equal to the maxima of the distances between the
        :meth:`bake` results, computed in the core without storing the frames (a long clip of a
        dense mesh would take gigabytes per skin)."""
        return _core.skin_distance_maxima(
            self._lbs_inputs(motion), [skin._lbs_inputs(played) for skin, played in others]
        )

    def _lbs_inputs(self, motion: Motion) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """What the core's skinning takes to play ``motion`` on this skin at its default morph weights."""
        return self.default_shape(), self.joints, self.weights, self._skin_matrices(motion)

    def _skin_matrices(self, motion: Motion) -> np.ndarray:
        """(T, J, 4, 4) float32 skinning matrices of ``motion`` on this skin's skeleton."""
        if motion.skeleton.joint_count != self.skeleton.joint_count:
            raise ValueError(
                f"motion has {motion.skeleton.joint_count} joints, the skin's skeleton {self.skeleton.joint_count}"
            )
        return motion.skin_matrices(self.inverse_bind).astype(np.float32)

    def default_shape(self) -> np.ndarray:
        """(V, 3) float32 bind shape with the morph targets at their default weights: what the
        skeleton poses where no animation drives the weights."""
        return morphed(self.rest_positions, self.morph_targets, self.default_morph_weights)

    def rest_pose(self) -> np.ndarray:
        """(V, 3) float32 positions skinned by the skeleton's rest pose: what a viewer shows with no
        animation. ``rest_positions`` (the bind shape) can differ from it in pose and in scale (a
        centimetre mesh under a 0.01 armature, positions quantized with the scale folded into the
        inverse bind matrices)."""
        return self.bake(self.skeleton.rest_motion(1)).frames[0]

    def rest_pose_morph_targets(self) -> np.ndarray | None:
        """(N, V, 3) float32 morph deltas as they move :meth:`rest_pose` (glTF morphs before it
        skins: each vertex's deltas through its blended skinning matrix of the rest pose), or None."""
        if self.morph_targets is None:
            return None
        matrices = self.skeleton.rest_motion(1).skin_matrices(self.inverse_bind)[0, :, :3, :3]  # (J, 3, 3)
        blended = np.einsum("vk,vkij->vij", self.weights, matrices[self.joints])
        return np.einsum("vij,nvj->nvi", blended, self.morph_targets).astype(np.float32)


def morphed(
    bind: np.ndarray, targets: np.ndarray | None, weights: np.ndarray | None, count: int | None = None
) -> np.ndarray:
    """float32: the shape ``bind`` (V, 3) with its morph ``targets`` (N, V, 3) at ``weights`` (N,)
    (None: all 0), (V, 3); with ``count``, (count, V, 3), one shape per frame for ``weights``
    (count, N) or (N,)."""
    shape = (1 if count is None else count,) + bind.shape
    if weights is None or not np.any(weights):
        shapes = np.broadcast_to(bind, shape).astype(np.float32)
    else:
        blended = bind.astype(np.float64) + np.einsum("...n,nvc->...vc", weights, targets)
        shapes = np.broadcast_to(blended, shape).astype(np.float32)
    return shapes[0] if count is None else shapes


def normalize_skin_weights(joints: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge a vertex's influences of one joint, sort them by decreasing weight and normalise them
    to sum 1 per vertex.

    Influences of one joint add up, as a skinning shader adds them; glTF forbids a joint twice in
    a vertex's influences, and exporters write it. A vertex with all-zero weights is an error (it
    would not move with any joint). Returns ``joints (V, K) int32`` and ``weights (V, K) float32``.
    """
    weights = np.asarray(weights, dtype=np.float64)
    totals = weights.sum(axis=1)
    if np.any(totals <= 0.0):
        vertex = int(np.argmax(totals <= 0.0))
        raise ValueError(f"weights: vertex {vertex} has no positive skin weight")
    joints = np.asarray(joints)
    weights = merge_repeated_influences(joints, weights)
    order = np.argsort(-weights, axis=1, kind="stable")
    weights = np.take_along_axis(weights, order, axis=1) / totals[:, None]
    joints = np.take_along_axis(joints, order, axis=1)
    # Unused influences point at joint 0 with weight 0, as glTF allows.
    joints = np.where(weights > 0.0, joints, 0)
    return np.ascontiguousarray(joints, dtype=np.int32), np.ascontiguousarray(weights, dtype=np.float32)


def merge_repeated_influences(joints: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(V, K) float64 ``weights`` with the influences of a joint listed twice for a vertex added
    into its first slot (in slot order) and the later slots zero; the slots' order stays."""
    weights = np.array(weights, dtype=np.float64)
    for later in range(1, weights.shape[1]):
        for first in range(later):
            repeat = joints[:, later] == joints[:, first]
            weights[repeat, first] += weights[repeat, later]
            weights[repeat, later] = 0.0
    return weights


@dataclass
class LodLevel:
    """One level of a chain: what is drawn, how it moves, and its error in asset units.

    Attributes
    ----------
    mesh : the level's geometry (a skinned mesh, a deforming or static mesh), or None for a
        motion-only level.
    skeleton : the skeleton the level animates (fewer joints at motion levels), or None.
    motions : the level's clips on ``skeleton``.
    error : asset units; what the level gets wrong against level 0 (the max-over-frames
        surface distance for geometry, the largest joint error for motion).
    screen_coverage : the MSFT_screencoverage where the level starts to be used (fraction of the
        viewport height the object covers), or None where the level is chosen from its error.
    mesh_level, motion_level : the geometry and motion levels this level combines.
    """

    mesh: AnimatedMesh | SkinnedMesh | None
    skeleton: Skeleton | None
    motions: list[Motion]
    error: float
    screen_coverage: float | None = None
    mesh_level: int = 0
    motion_level: int = 0


@dataclass
class LodChain:
    """Levels from finest (index 0) to coarsest: what every technique returns or converts to,
    what the LoD GLB holds (:func:`animlod.io.read_lod_chains`), what runtimes consume.

    ``name`` names what the chain draws (the glTF node, or the technique's input).
    """

    levels: list[LodLevel] = field(default_factory=list)
    name: str = ""

    def level_for(self, screen_error_budget: float, distance: float, focal_length_px: float) -> int:
        """Coarsest level whose error, projected to pixels at ``distance``, is within the budget.

        ``error / distance * focal_length_px`` is the level's error on screen in pixels; level 0
        is used when no level fits. The rule is the core's runtime selector's
        (``lod_selector.hpp``, ``level_for_error``), so Python and engines pick alike; a
        character that moves should keep a ``_core.LodSelector`` for its hysteresis.
        """
        for name, value in (("distance", distance), ("focal_length_px", focal_length_px)):
            if not value > 0.0 or not np.isfinite(value):  # NaN compares false: every level would fit
                raise ValueError(f"{name}: must be positive, got {value}")
        if not screen_error_budget >= 0.0:
            raise ValueError(f"screen_error_budget: must be a number >= 0, got {screen_error_budget}")
        errors = np.array([level.error for level in self.levels], dtype=np.float32)
        return int(_core.level_for_error(errors, distance, focal_length_px, screen_error_budget))
