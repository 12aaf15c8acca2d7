"""Simplification of deforming and skinned meshes with AQEM (Yang et al. 2019), run in the C++ core.

``simplify_animated`` collapses edges once for all frames of an :class:`~animlod.model.AnimatedMesh`
(one connectivity), placing every new vertex optimally in every frame (Eq. 5) and ordering the
collapses by the animated quadric cost weighted by motion features (Eq. 6). One run returns
several levels and the ordered collapse record. ``simplify_skinned`` does the same over the
rest pose and the baked poses of given motions, and returns skinned levels whose merged skin
weights still drive them. ``motion_features`` exposes the feature extraction on its own.

Shapes: ``F`` frames, ``V`` vertices, ``M`` faces, ``K`` skin influences, ``C`` collapses.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from . import _core
from .model import AnimatedMesh, Motion, SkinnedMesh

DEFAULT_MIN_ANGLE_CHANGE = math.radians(1.0)


@dataclass
class MotionFeatures:
    """Motion features of a deforming mesh (paper section "Rotation connected graph").

    Attributes
    ----------
    edges : (E, 2) int32 undirected edges, lower vertex first, sorted.
    angle_change : (E,) float32 g_i, the largest change of the edge's dihedral angle between
        consecutive frames, radians (0 on boundary edges).
    connected : (E,) bool, edges that join a feature.
    threshold : the THR used, radians.
    vertex_feature : (V,) int32 feature index per vertex, -1 outside every feature.
    feature_sizes : (C,) int32 vertex count of each feature.
    vertex_weights : (V,) float32 weight of Eq. 6: the feature's vertex count, 1 outside.
    """

    edges: np.ndarray
    angle_change: np.ndarray
    connected: np.ndarray
    threshold: float
    vertex_feature: np.ndarray
    feature_sizes: np.ndarray
    vertex_weights: np.ndarray


@dataclass
class SimplifiedLevel:
    """One level of detail of a deforming mesh.

    Attributes
    ----------
    mesh : the simplified sequence, (F, V', 3) frames and (M', 3) faces.
    kept_vertices : (V',) int32 index in the input of every kept vertex, ascending.
    vertex_map : (V,) int32 input vertex -> kept vertex it merged into (-1 for vertices that
        ``repair=True`` dropped).
    error : asset units, the largest collapse error so far (see ``CollapseRecord.error``).
    target_face_count : the face count asked for; ``mesh`` has at most that many if ``reached``.
    reached : False when ``max_error`` (or no legal collapse left) stopped the run first.
    collapse_count : this level is the first ``collapse_count`` entries of the collapse record.
    attributes : (V', A) float32 carried per-vertex attributes, or None.
    skin_joints, skin_weights : (V', K) skin influences, or None. Rows of vertices made by a
        collapse are merged: sorted by decreasing weight, summing to 1; other rows are the input's.
    """

    mesh: AnimatedMesh
    kept_vertices: np.ndarray
    vertex_map: np.ndarray
    error: float
    target_face_count: int
    reached: bool
    collapse_count: int
    attributes: np.ndarray | None = None
    skin_joints: np.ndarray | None = None
    skin_weights: np.ndarray | None = None


@dataclass
class CollapseRecord:
    """Every collapse in order: vertex ``removed[i]`` merged into ``kept[i]`` (input indices).

    Attributes
    ----------
    removed, kept : (C,) int32.
    positions : (C, F, 3) float32 new positions of the kept vertex in every frame.
    cost : (C,) float64 weighted cost of Eq. 6.
    error : (C,) float64 asset units: RMS distance of the new vertex to the planes of its merged
        quadric, over those planes and the frames used.
    """

    removed: np.ndarray
    kept: np.ndarray
    positions: np.ndarray
    cost: np.ndarray
    error: np.ndarray


@dataclass
class SimplifyResult:
    """Levels (finest first), the collapse record, the frames whose quadrics were used and the
    vertex weights (V,) of Eq. 6."""

    levels: list[SimplifiedLevel]
    collapses: CollapseRecord
    frames_used: np.ndarray
    vertex_weights: np.ndarray


@dataclass
class SkinnedLevel:
    """One level of a skinned mesh: ``mesh`` skins with merged weights; ``error`` is the AQEM
    error and ``skinning_error`` the largest distance (asset units, over the given poses and
    kept vertices) between re-skinned positions and the positions AQEM chose."""

    mesh: SkinnedMesh
    kept_vertices: np.ndarray
    vertex_map: np.ndarray
    error: float
    skinning_error: float
    target_face_count: int
    reached: bool


def motion_features(
    mesh: AnimatedMesh,
    *,
    feature_threshold: float = 0.0,
    min_angle_change: float = DEFAULT_MIN_ANGLE_CHANGE,
    boundary_is_feature: bool = True,
) -> MotionFeatures:
    """Find the motion features of ``mesh`` over all its frames.

    Parameters
    ----------
    mesh : the deforming mesh.
    feature_threshold : radians; 0 selects an adaptive THR, the mean of g_i over the interior
        edges (the paper averages over all edges; boundary edges are features anyway).
    min_angle_change : radians; g_i must also exceed this floor (paper: 1 degree).
    boundary_is_feature : count boundary edges as connected, as the paper does.

    Raises ValueError naming the element on bad connectivity (see ``simplify_animated``).
    """
    found = _core.motion_features(
        mesh.frames,
        mesh.faces,
        feature_threshold=feature_threshold,
        min_angle_change=min_angle_change,
        boundary_is_feature=boundary_is_feature,
    )
    return MotionFeatures(**found)


def simplify_animated(
    mesh: AnimatedMesh,
    target_ratios: Sequence[float] = (0.5,),
    *,
    target_face_counts: Sequence[int] | None = None,
    max_error: float = math.inf,
    use_motion_features: bool = True,
    feature_threshold: float = 0.0,
    min_angle_change: float = DEFAULT_MIN_ANGLE_CHANGE,
    boundary_is_feature: bool = True,
    boundary_quadrics: bool = True,
    check_inversion: bool = True,
    strict_inversion: bool = False,
    max_frames: int = 0,
    frame_subset: Sequence[int] | None = None,
    locked_vertices: Sequence[int] | np.ndarray | None = None,
    importance: np.ndarray | None = None,
    attributes: np.ndarray | None = None,
    skin_joints: np.ndarray | None = None,
    skin_weights: np.ndarray | None = None,
    repair: bool = False,
    progress: Callable[[int, int], None] | None = None,
    placement: str = "optimal",
) -> SimplifyResult:
    """Simplify a deforming mesh over all its frames with AQEM; several levels from one run.

    Parameters
    ----------
    mesh : (F, V, 3) frames and (M, 3) faces; manifold, no degenerate or duplicate faces.
    target_ratios : level sizes as fractions of M in (0, 1].
    target_face_counts : level sizes as face counts in [4, M]; replaces ``target_ratios``.
    max_error : asset units; the run stops before a collapse whose error (an RMS plane distance,
        see ``CollapseRecord.error``) exceeds it.
    use_motion_features, feature_threshold, min_angle_change, boundary_is_feature : the
        weights of Eq. 6 (see :func:`motion_features`); off gives every vertex weight 1.
    boundary_quadrics : planes perpendicular to open borders keep their shape.
    check_inversion : reject collapses that invert a face by Eq. 7, summed over every frame
        (also those outside the quadrics' frames); ``strict_inversion`` rejects an inversion in
        any single frame and is ignored when ``check_inversion`` is False.
    max_frames : quadrics over K frames chosen by farthest-point sampling of the poses (0: all).
    frame_subset : explicit frames for the quadrics; replaces ``max_frames``.
    locked_vertices : indices of vertices that are never removed nor moved.
    importance : (V,) float32 > 0, multiplies each vertex's weight (e.g. face regions).
    attributes : (V, A) float32 per-vertex data interpolated along collapses (e.g. UVs).
    skin_joints, skin_weights : (V, K) int32 / float32 skin influences, merged along collapses
        (union, blended, the K largest kept, renormalised); the levels carry them.
    repair : first drop faces that repeat a vertex, duplicate faces and unreferenced vertices,
        and split non-manifold vertices (see :func:`repair_mesh`), instead of raising; edges
        shared by three or more faces still raise. ``kept_vertices``, ``vertex_map`` and the
        collapse record then refer to the input's vertices.
    progress : ``progress(done, total)`` called now and then from the simplifier.
    placement : ``"optimal"``, the paper's Eq. 5 in every frame, or ``"on_edge"``, one point of
        the collapsed edge for all frames (the vertex keeps one identity, so UVs and skin
        weights stay consistent with its positions; a little more error).

    Returns
    -------
    SimplifyResult with one level per target, finest first.

    Raises
    ------
    ValueError naming the element: non-finite position, index out of range, degenerate or
    duplicate face, non-manifold edge or vertex, unreferenced vertex, target out of range.
    """
    original_vertex_count = mesh.vertex_count
    kept_input = None
    if repair:
        mesh, kept_input = repair_mesh(mesh)
    locked = None
    if locked_vertices is not None:
        locked = np.zeros(original_vertex_count, dtype=bool)
        locked[np.asarray(locked_vertices, dtype=np.int64)] = True
    locked = _per_vertex(locked, bool, kept_input)
    importance = _per_vertex(importance, np.float32, kept_input)
    attributes = _per_vertex(attributes, np.float32, kept_input)
    skin_joints = _per_vertex(skin_joints, np.int32, kept_input)
    skin_weights = _per_vertex(skin_weights, np.float32, kept_input)
    raw = _core.simplify_animated(
        mesh.frames,
        mesh.faces,
        target_ratios=list(target_ratios),
        target_face_counts=list(target_face_counts or []),
        max_error=max_error,
        use_motion_features=use_motion_features,
        feature_threshold=feature_threshold,
        min_angle_change=min_angle_change,
        boundary_is_feature=boundary_is_feature,
        boundary_quadrics=boundary_quadrics,
        check_inversion=check_inversion,
        strict_inversion=strict_inversion,
        max_frames=max_frames,
        frame_subset=list(frame_subset or []),
        locked=locked,
        importance=importance,
        attributes=attributes,
        skin_joints=skin_joints,
        skin_weights=skin_weights,
        progress=progress,
        placement=placement,
    )
    return _result_in_input_indices(raw, mesh.fps, kept_input, original_vertex_count)


def simplify_skinned(
    skinned: SkinnedMesh,
    motions: Sequence[Motion],
    target_ratios: Sequence[float] = (0.5,),
    **options: object,
) -> list[SkinnedLevel]:
    """Simplify a skinned mesh over its rest pose and the baked poses of ``motions``.

    UVs and morph targets are interpolated along collapses; skin weights are merged (union of
    influences, blended, the K largest kept and renormalised). Normals are dropped (they no
    longer match the simplified surface; recompute them). The rest positions of a level are its
    AQEM positions in the rest pose, so re-skinning them with the merged weights reproduces
    the poses; ``skinning_error`` says how closely.

    Parameters
    ----------
    skinned : the mesh to simplify.
    motions : clips whose poses the levels must fit; their skeleton must match ``skinned``.
    target_ratios : level sizes as fractions of the face count.
    **options : any keyword argument of :func:`simplify_animated` except ``attributes`` and
        ``repair``; ``placement`` defaults to ``"on_edge"`` here, so that the merged weights
        and the positions describe the same point.

    Returns
    -------
    One SkinnedLevel per target, finest first.
    """
    if "attributes" in options or "repair" in options:
        raise ValueError("simplify_skinned: attributes come from the SkinnedMesh (uvs, morph targets); repair it first")
    baked = [skinned.bake(motion).frames for motion in motions]
    poses = AnimatedMesh(skinned.faces, np.concatenate([skinned.rest_positions[None], *baked], axis=0))
    uv_count = 0 if skinned.uvs is None else 2
    morph_count = 0 if skinned.morph_targets is None else skinned.morph_targets.shape[0]
    columns = [np.zeros((skinned.vertex_count, 0), np.float32)]
    if uv_count:
        columns.append(skinned.uvs)
    if morph_count:
        columns.append(skinned.morph_targets.transpose(1, 0, 2).reshape(skinned.vertex_count, 3 * morph_count))
    result = simplify_animated(
        poses,
        target_ratios,
        attributes=np.concatenate(columns, axis=1),
        skin_joints=skinned.joints,
        skin_weights=skinned.weights,
        **{"placement": "on_edge", **options},
    )
    # Frame 0 is the rest pose, then each motion's poses in order.
    starts = np.cumsum([1] + [len(frames) for frames in baked])
    levels = []
    for level in result.levels:
        carried = level.attributes
        simplified = SkinnedMesh(
            rest_positions=level.mesh.frames[0],
            faces=level.mesh.faces,
            joints=level.skin_joints,
            weights=level.skin_weights,
            inverse_bind=skinned.inverse_bind,
            skeleton=skinned.skeleton,
            uvs=carried[:, :uv_count] if uv_count else None,
            morph_targets=carried[:, uv_count:].reshape(-1, morph_count, 3).transpose(1, 0, 2) if morph_count else None,
            morph_target_names=skinned.morph_target_names if morph_count else None,
        )
        skinning_error = 0.0
        for motion, start in zip(motions, starts):
            reskinned = simplified.bake(motion).frames
            chosen = level.mesh.frames[start : start + motion.frame_count]
            skinning_error = max(skinning_error, _largest_distance(reskinned, chosen))
        levels.append(
            SkinnedLevel(
                mesh=simplified,
                kept_vertices=level.kept_vertices,
                vertex_map=level.vertex_map,
                error=level.error,
                skinning_error=skinning_error,
                target_face_count=level.target_face_count,
                reached=level.reached,
            )
        )
    return levels


def repair_mesh(mesh: AnimatedMesh) -> tuple[AnimatedMesh, np.ndarray]:
    """Make a mesh acceptable to the simplifier where that is unambiguous.

    Drops faces that repeat a vertex and duplicate faces (the first copy stays), drops vertices
    no face references, and splits every non-manifold vertex (faces forming separate fans
    joined only at the vertex, a "bow tie") into one vertex per fan. Edges shared by three or
    more faces are left for the simplifier to report.

    Returns the repaired mesh and ``(V',) int32`` the input index of each of its vertices
    (split vertices appear once per fan).
    """
    faces = mesh.faces
    distinct = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    faces = faces[distinct]
    _, first = np.unique(np.sort(faces, axis=1), axis=0, return_index=True)
    faces = faces[np.sort(first)]
    fan = _corner_fans(faces)
    # One output vertex per (input vertex, fan), numbered in input-vertex order.
    keys, corner_vertex = np.unique(np.stack([faces.ravel(), fan], axis=1), axis=0, return_inverse=True)
    kept_input = keys[:, 0].astype(np.int32)
    repaired = AnimatedMesh(corner_vertex.reshape(-1, 3).astype(np.int32), mesh.frames[:, kept_input], fps=mesh.fps)
    return repaired, kept_input


def _corner_fans(faces: np.ndarray) -> np.ndarray:
    """(3M,) label of each face corner: corners of one vertex share a label when their faces
    are joined through edges around that vertex (label propagation, vectorised)."""
    corner_count = faces.size
    corners = np.arange(corner_count).reshape(-1, 3)
    # Each face side a -> b, with the corners of a and b in that face.
    starts, ends = faces.ravel(), faces[:, [1, 2, 0]].ravel()
    start_corner, end_corner = corners.ravel(), corners[:, [1, 2, 0]].ravel()
    low, high = np.minimum(starts, ends), np.maximum(starts, ends)
    order = np.lexsort((high, low))
    same = (low[order][1:] == low[order][:-1]) & (high[order][1:] == high[order][:-1])
    first, second = order[:-1][same], order[1:][same]
    # Across a shared edge the side runs a -> b in one face and b -> a in the other (or the same
    # way when orientation is inconsistent); join corners of equal vertices either way.
    straight = starts[first] == starts[second]
    pairs = np.concatenate(
        [
            np.stack([start_corner[first], np.where(straight, start_corner[second], end_corner[second])], axis=1),
            np.stack([end_corner[first], np.where(straight, end_corner[second], start_corner[second])], axis=1),
        ]
    )
    label = np.arange(corner_count)
    while True:
        smaller = np.minimum(label[pairs[:, 0]], label[pairs[:, 1]])
        updated = label.copy()
        np.minimum.at(updated, pairs[:, 0], smaller)
        np.minimum.at(updated, pairs[:, 1], smaller)
        updated = updated[updated]  # pointer jumping: follow labels to their own labels
        if np.array_equal(updated, label):
            return label
        label = updated


def _per_vertex(values: np.ndarray | None, dtype: type, kept_input: np.ndarray | None) -> np.ndarray | None:
    """Per-vertex input as ``dtype``, following a repair's vertex selection when there was one."""
    if values is None:
        return None
    values = np.asarray(values, dtype=dtype)
    return values if kept_input is None else values[kept_input]


def _largest_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance between corresponding points of two (..., 3) arrays."""
    return float(np.sqrt(np.max(np.sum((a.astype(np.float64) - b) ** 2, axis=-1)))) if a.size else 0.0


def _result_in_input_indices(
    raw: dict, fps: float | None, kept_input: np.ndarray | None, vertex_count: int
) -> SimplifyResult:
    """Wrap the core's dictionaries; after a repair, map vertex indices back to the input
    (``kept_input[i]`` is the input vertex of repaired vertex i; a split vertex maps to one of
    its copies)."""
    levels = []
    for level in raw["levels"]:
        vertex_map, kept_vertices = level["vertex_map"], level["kept_vertices"]
        if kept_input is not None:
            vertex_map = np.full(vertex_count, -1, dtype=np.int32)
            vertex_map[kept_input] = level["vertex_map"]
            kept_vertices = kept_input[kept_vertices]
        levels.append(
            SimplifiedLevel(
                mesh=AnimatedMesh(level["faces"], level["positions"], fps=fps),
                kept_vertices=kept_vertices,
                vertex_map=vertex_map,
                error=float(level["error"]),
                target_face_count=int(level["target_face_count"]),
                reached=bool(level["reached"]),
                collapse_count=int(level["collapse_count"]),
                attributes=level["attributes"] if level["attributes"].shape[1] else None,
                skin_joints=level["skin_joints"] if level["skin_joints"].shape[0] else None,
                skin_weights=level["skin_weights"] if level["skin_weights"].shape[0] else None,
            )
        )
    collapses = raw["collapses"]
    if kept_input is not None:
        collapses = {**collapses, "removed": kept_input[collapses["removed"]], "kept": kept_input[collapses["kept"]]}
    return SimplifyResult(
        levels=levels,
        collapses=CollapseRecord(**collapses),
        frames_used=raw["frames_used"],
        vertex_weights=raw["vertex_weights"],
    )
