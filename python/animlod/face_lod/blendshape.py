"""Levels of detail of blendshape faces (glTF morph targets, or a neutral face and expressions).

A blendshape face is ``neutral + sum_i w_i(t) delta_i``. Each target plays the part a region
plays in seeds/004: a unit of animation that can be skipped when it matters little. Per level:

- **ranking**: a target's contribution is the largest displacement it ever causes, the largest
  weight the animation gives it times its largest vertex delta (asset units); a target the
  animation never drives counts at weight 1, as when there is no animation (a rig's targets are
  often driven at run time: live capture, a state machine); targets are ranked by it, ties by
  index;
- **geometry**: one AQEM run over the neutral face and every target at that weight, with
  region importance from regions grown from the targets' motion (moving 1, static lower), every
  target's deltas carried through the collapses as attributes; vertices are placed on the
  collapsed edge (``placement="on_edge"``) so that a vertex and its deltas describe one point;
- **pruning**: a level drops the targets whose contribution is no more than its geometric error
  (the Hausdorff distance between its neutral mesh and the full one): what they add is below
  what the simplification already lost, as the lattice reduction of the region-animated face
  (Figure 6). A target that moves no vertex but turns normals or tangents (a wrinkle's shading)
  has no displacement to judge and is kept. The coarsest level keeps no target ("when the model
  is far enough, no animation is needed", Section 4.2.1). Explicit fractions of kept targets per
  level replace the rule.

Shapes: ``V`` vertices, ``M`` faces, ``N`` targets, ``T`` animation frames.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..aqem import simplify_animated
from ..model import AnimatedMesh, spread_frames
from .grow import GrowOptions, grow_regions, motion_of_targets
from .measure import measured_frames
from .regions import FaceRegions


@dataclass
class BlendshapeFace:
    """A neutral mesh, its morph targets and an animation of their weights.

    Attributes
    ----------
    neutral : (V, 3) float32 positions.
    faces : (M, 3) int32.
    targets : (N, V, 3) float32 position deltas.
    names : N target names.
    weights : (T, N) float64 target weights per animation frame.
    fps : frames per second of ``weights``.
    uvs : (V, 2) float32 or None.
    """

    neutral: np.ndarray
    faces: np.ndarray
    targets: np.ndarray
    names: list[str]
    weights: np.ndarray
    fps: float = 30.0
    uvs: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.neutral = np.ascontiguousarray(self.neutral, dtype=np.float32)
        vertex_count = len(self.neutral)
        if self.neutral.shape != (vertex_count, 3):
            raise ValueError(f"blendshape face: neutral of shape {self.neutral.shape}, expected (V, 3)")
        self.faces = AnimatedMesh(self.faces, self.neutral[None]).faces
        names = [str(name) for name in self.names]
        targets = []
        for index, target in enumerate(self.targets):  # O(N), each checked whole
            target = np.asarray(target, dtype=np.float32)
            if target.shape != (vertex_count, 3):
                name = names[index] if index < len(names) else ""
                raise ValueError(
                    f"morph target {index} {name!r} has shape {target.shape}: expected ({vertex_count}, 3), "
                    f"one delta per vertex of its mesh"
                )
            targets.append(target)
        self.targets = np.stack(targets) if targets else np.zeros((0, vertex_count, 3), np.float32)
        self.names = names
        if len(self.names) != len(self.targets):
            raise ValueError(f"blendshape face: {len(self.names)} names for {len(self.targets)} targets")
        if not np.all(np.isfinite(self.targets)):
            index = int(np.argwhere(~np.isfinite(self.targets))[0, 0])
            raise ValueError(f"morph target {index} {self.names[index]!r}: non-finite delta")
        self.weights = np.asarray(self.weights, dtype=np.float64)
        if self.weights.ndim != 2 or self.weights.shape[1] != len(self.targets) or len(self.weights) == 0:
            raise ValueError(
                f"blendshape face: weights of shape {self.weights.shape}, expected (T, {len(self.targets)}) with T >= 1"
            )
        if not np.all(np.isfinite(self.weights)):
            frame = int(np.argwhere(~np.isfinite(self.weights))[0, 0])
            raise ValueError(f"blendshape face: animation frame {frame} has a non-finite weight")
        if self.uvs is not None:
            self.uvs = np.ascontiguousarray(self.uvs, dtype=np.float32)
            if self.uvs.shape != (vertex_count, 2):
                raise ValueError(f"blendshape face: uvs of shape {self.uvs.shape}, expected ({vertex_count}, 2)")

    @property
    def target_count(self) -> int:
        return int(len(self.targets))

    @property
    def vertex_count(self) -> int:
        return int(len(self.neutral))

    def reach_weights(self) -> np.ndarray:
        """(N,) the weight each target is judged at: the largest absolute weight the animation
        gives it, or 1 for a target the animation never drives (see the module notes)."""
        largest = np.abs(self.weights).max(axis=0)
        return np.where(largest > 0.0, largest, 1.0)

    def frames(self, weights: np.ndarray | None = None) -> AnimatedMesh:
        """The face blended with ``weights (T, N)`` (the animation when None)."""
        weights = self.weights if weights is None else np.asarray(weights, dtype=np.float64)
        blended = self.neutral[None] + np.tensordot(weights, self.targets, axes=(1, 0))
        return AnimatedMesh(self.faces, blended, fps=self.fps)


@dataclass
class BlendshapeLevel:
    """One level of a blendshape face.

    Attributes
    ----------
    faces : (M', 3) int32.
    neutral : (V', 3) float32.
    targets : (N', V', 3) float32 deltas of the kept targets.
    kept_targets : (N',) int64 index of each kept target in the input.
    kept_vertices : (V',) int32 input vertex of each vertex.
    uvs : (V', 2) float32 or None.
    aqem_error : AQEM's error, asset units (0 at level 0).
    geometric_error : Hausdorff distance between the level's neutral mesh and the input's,
        asset units; targets contributing no more than this are pruned.
    """

    faces: np.ndarray
    neutral: np.ndarray
    targets: np.ndarray
    kept_targets: np.ndarray
    kept_vertices: np.ndarray
    uvs: np.ndarray | None
    aqem_error: float
    geometric_error: float = 0.0

    @property
    def triangle_count(self) -> int:
        return int(len(self.faces))

    def frame(self, weights: np.ndarray) -> np.ndarray:
        """(V', 3) float32 positions for the input's ``weights (N,)`` (pruned targets ignored)."""
        kept = np.asarray(weights, dtype=np.float32)[self.kept_targets]
        if kept.size == 0:
            return self.neutral
        return self.neutral + (kept @ self.targets.reshape(len(kept), -1)).reshape(-1, 3)

    def frames(self, weights: np.ndarray) -> AnimatedMesh:
        """The level over ``weights (T, N)`` of the input's targets."""
        kept = np.asarray(weights, dtype=np.float64)[:, self.kept_targets]
        return AnimatedMesh(self.faces, self.neutral[None] + np.tensordot(kept, self.targets, axes=(1, 0)))


@dataclass
class BlendshapeLodOptions:
    """How :func:`build_blendshape_lod` builds the levels.

    Attributes
    ----------
    ratios : triangle fractions of the levels after the input (level 0).
    face_counts : the same as counts; replaces ``ratios``.
    target_fractions : per level (the input included) the fraction of targets kept, most
        important first, rounded up; replaces the error rule.
    animate_coarsest : keep the error rule at the coarsest level too, instead of no target.
    grow : how regions are grown from the targets' motion for the importance weights (None:
        every vertex has importance 1).
    """

    ratios: Sequence[float] = (0.5, 0.25, 0.1)
    face_counts: Sequence[int] | None = None
    target_fractions: Sequence[float] | None = None
    animate_coarsest: bool = False
    grow: GrowOptions | None = field(default_factory=GrowOptions)


def target_contributions(face: BlendshapeFace) -> np.ndarray:
    """(N,) the largest displacement (asset units) each target causes: its reach weight
    (:meth:`BlendshapeFace.reach_weights`) times its largest vertex delta."""
    largest_delta = np.linalg.norm(face.targets, axis=2).max(axis=1, initial=0.0)
    return face.reach_weights() * largest_delta


def rank_targets(face: BlendshapeFace) -> np.ndarray:
    """(N,) target indices, most important first (ties: lower index first)."""
    return np.lexsort((np.arange(face.target_count), -target_contributions(face)))


def target_regions(face: BlendshapeFace, options: GrowOptions | None = None) -> FaceRegions:
    """Regions grown from the targets' motion (each region a set of vertices that the same
    targets move alike), groups "moving" and "static"."""
    return grow_regions(motion_of_targets(face.targets, face.reach_weights()), face.faces, options)


def build_blendshape_lod(face: BlendshapeFace, options: BlendshapeLodOptions | None = None) -> list[BlendshapeLevel]:
    """Levels of ``face``, the input first: each with no more triangles and no more targets.
    A level has fewer triangles than the one before unless the face is too small for its ratio
    (a level keeps one triangle at least) or AQEM finds no legal collapse left.

    Raises ValueError for fractions of the wrong length or outside [0, 1] and whatever AQEM
    rejects (naming the element).
    """
    options = options or BlendshapeLodOptions()
    if options.face_counts is not None:
        sizes = {"target_face_counts": checked_face_counts(options.face_counts, len(face.faces))}
    else:  # the core rounds ratios to triangle counts, one at least, as for glTF faces
        sizes = {"target_ratios": list(options.ratios)}
    [requested] = sizes.values()
    check_fractions(options.target_fractions, len(requested) + 1)
    everything = np.arange(face.target_count)
    identity = np.arange(face.vertex_count, dtype=np.int32)
    levels = [BlendshapeLevel(face.faces, face.neutral, face.targets, everything, identity, face.uvs, 0.0, 0.0)]
    if not requested:
        return levels
    importance = None
    if options.grow is not None and face.target_count and np.any(face.targets):
        importance = target_regions(face, options.grow).vertex_importance()
    levels += _simplified_levels(face, sizes, importance)
    prune_levels(face, levels, options)
    return levels


def checked_face_counts(counts: Sequence[int], triangle_count: int) -> list[int]:
    """``counts`` as ints; ValueError naming the first outside [1, ``triangle_count``]."""
    for count in counts:
        if not 1 <= count <= triangle_count:
            bounds = f"[1, {triangle_count}] (the face has {triangle_count} triangles)"
            raise ValueError(f"face counts: {count} outside {bounds}")
    return [int(count) for count in counts]


def check_fractions(fractions: Sequence[float] | None, level_count: int | None = None) -> None:
    """ValueError unless ``fractions`` is None or one value in [0, 1] per level (any number of
    them when ``level_count`` is None)."""
    if fractions is None:
        return
    if level_count is not None and len(fractions) != level_count:
        raise ValueError(f"target fractions: {len(fractions)} given for {level_count} levels")
    for index, fraction in enumerate(fractions):
        if not 0.0 <= fraction <= 1.0:
            raise ValueError(f"target fraction of level {index}: {fraction} is outside [0, 1]")


def prune_levels(
    face: BlendshapeFace,
    levels: list[BlendshapeLevel],
    options: BlendshapeLodOptions,
    shading_only: np.ndarray | None = None,
) -> None:
    """Set every simplified level's ``geometric_error`` (Hausdorff distance of its neutral mesh to
    the input's) and keep, in ``kept_targets`` and ``targets``, the targets the rule of the module
    notes (or ``options.target_fractions``) keeps; the rule keeps the ``shading_only`` ones (a
    (N,) mask of targets that turn normals or tangents without moving a vertex). ``levels[0]`` is
    the input and keeps them all; the others must still hold every target."""
    from ..metrics import hausdorff_distance

    check_fractions(options.target_fractions, len(levels))
    everything = np.arange(face.target_count)
    order, contributions = rank_targets(face), target_contributions(face)
    always = np.zeros(face.target_count, bool) if shading_only is None else np.asarray(shading_only, bool)
    full = AnimatedMesh(face.faces, face.neutral[None])
    for index, level in enumerate(levels[1:], start=1):
        rest = AnimatedMesh(level.faces, level.neutral[None])
        level.geometric_error = hausdorff_distance(full, rest, samples=5000)
        if options.target_fractions is not None:
            kept = np.sort(order[: int(np.ceil(options.target_fractions[index] * face.target_count - 1e-9))])
        elif index == len(levels) - 1 and not options.animate_coarsest:
            kept = everything[:0]
        else:
            kept = everything[(contributions > level.geometric_error) | always]
        level.kept_targets = kept
        level.targets = np.ascontiguousarray(level.targets[kept])


def _simplified_levels(
    face: BlendshapeFace, sizes: dict[str, list], importance: np.ndarray | None
) -> list[BlendshapeLevel]:
    """One AQEM run over the neutral face and every target at its reach weight, carrying UVs
    (attributes: copies with other UVs form seams) and every target's deltas (position
    attributes); one level per size (``sizes``: ``target_ratios`` or ``target_face_counts``, as
    :func:`animlod.simplify_animated` takes them), every target still attached."""
    reach = face.reach_weights()
    frames = np.concatenate([face.neutral[None], face.neutral[None] + reach[:, None, None] * face.targets])
    result = simplify_animated(
        AnimatedMesh(face.faces, frames),
        importance=importance,
        attributes=face.uvs,
        position_attributes=face.targets.transpose(1, 0, 2).reshape(face.vertex_count, -1),
        placement="on_edge",
        record_positions=False,
        **sizes,
    )
    levels = []
    for level in result.levels:
        kept = len(level.kept_vertices)
        carried = level.position_attributes
        carried = np.zeros((kept, 0), np.float32) if carried is None else carried
        deltas = carried.reshape(kept, face.target_count, 3).transpose(1, 0, 2)
        levels.append(
            BlendshapeLevel(
                faces=level.mesh.faces,
                neutral=level.mesh.frames[0],
                targets=np.ascontiguousarray(deltas),
                kept_targets=np.arange(face.target_count),
                kept_vertices=level.kept_vertices,
                uvs=level.attributes if face.uvs is not None else None,
                aqem_error=level.error,
                geometric_error=0.0,
            )
        )
    return levels


@dataclass
class BlendshapeMeasurement:
    """One row of the blendshape table: size, targets, time per frame to blend, error."""

    level: int
    triangles: int
    vertices: int
    targets: int
    max_frame_seconds: float
    median_frame_seconds: float
    hausdorff: float
    hausdorff_units: float


# Frames whose blends are timed per level: enough for a median and a largest time. Timing every
# frame of a 3,000-frame clip of a 41k-vertex head with 52 targets (3 repeats, 4 levels) took
# `animlod face` from 20 to 50 s (README, Facial LoD).
TIMED_FRAMES = 240


def measure_blendshape_lod(
    face: BlendshapeFace, levels: Sequence[BlendshapeLevel], repeats: int = 5, max_frames: int = 60,
    samples: int = 20000, timed_frames: int = TIMED_FRAMES,
) -> list[BlendshapeMeasurement]:  # fmt: skip
    """Per level: the largest (and median) time to blend one frame over ``timed_frames`` evenly
    spaced frames of the animation (0: every frame; numpy, the fastest of ``repeats`` runs per
    frame) and the largest symmetric Hausdorff
    distance to the full face over ``max_frames`` evenly spaced frames and each target's
    peak-weight frame (:func:`~animlod.face_lod.measure.measured_frames`), and over a pose of each
    target the animation never drives at weight 1 (it is ranked and pruned at that weight, as rigs
    drive such targets at run time: :meth:`BlendshapeFace.reach_weights`), relative to its
    bounding-box diagonal. A level that is the input itself (its arrays, every target) is not
    measured: its error is 0 (measuring it gave float rounding, 5e-10 of face-poses' size, at a
    quarter of the measuring time)."""
    from ..metrics import frame_hausdorff

    undriven = np.eye(face.target_count)[np.abs(face.weights).max(axis=0) == 0.0]
    weights = np.concatenate([face.weights[measured_frames(face.weights, max_frames)], undriven])
    reference = face.frames(weights)
    timed = face.weights if timed_frames <= 0 else face.weights[spread_frames(len(face.weights), timed_frames)]
    # The levels take turns within each repeat, so that a spell of load on the machine slows
    # every level's runs alike rather than one level's (the ratios between levels are the point).
    best = np.full((len(levels), len(timed)), np.inf)
    for _ in range(repeats):  # O(repeats x levels x timed frames) blends, each vectorised
        for index, level in enumerate(levels):
            for frame, row in enumerate(timed):
                start = time.perf_counter()
                level.frame(row)
                best[index, frame] = min(best[index, frame], time.perf_counter() - start)
    rows = []
    for index, level in enumerate(levels):
        relative = units = 0.0
        if not _is_the_input(level, face):
            error = frame_hausdorff(reference, level.frames(weights), samples=samples)
            worst = int(np.argmax(error.hausdorff))
            relative, units = float(error.relative_hausdorff[worst]), float(error.hausdorff[worst])
        rows.append(
            BlendshapeMeasurement(
                level=index,
                triangles=level.triangle_count,
                vertices=len(level.neutral),
                targets=len(level.kept_targets),
                max_frame_seconds=float(best[index].max()),
                median_frame_seconds=float(np.median(best[index])),
                hausdorff=relative,
                hausdorff_units=units,
            )
        )
    return rows


def _is_the_input(level: BlendshapeLevel, face: BlendshapeFace) -> bool:
    """Whether ``level`` draws ``face`` itself: its very arrays and every target."""
    whole = len(level.kept_targets) == face.target_count
    return whole and level.faces is face.faces and level.neutral is face.neutral and level.targets is face.targets


def one_at_a_time(target_count: int, frames_each: int = 15) -> np.ndarray:
    """(T, N) weights that raise every target from 0 to 1 and back in turn (for faces given as
    poses, which have no animation of their own)."""
    per = max(3, frames_each)
    envelope = 0.5 - 0.5 * np.cos(2.0 * np.pi * np.arange(per) / (per - 1))  # sin^2, exact 0 at the ends
    weights = np.zeros((per * max(target_count, 1), target_count))
    for index in range(target_count):  # O(N) rows
        weights[index * per : (index + 1) * per, index] = envelope
    return weights
