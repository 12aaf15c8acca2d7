"""AQEM (Yang et al. 2019): simplification of deforming and skinned meshes, run in the C++ core.

``simplify_animated`` collapses edges once for all frames of an :class:`~animlod.model.AnimatedMesh`
(one connectivity), placing every new vertex optimally in every frame (Eq. 5) and ordering the
collapses by the animated quadric cost weighted by motion features (Eq. 6). One run returns
several levels and the ordered collapse record. Any indexed triangle mesh is accepted: seam
copies are welded and the seams kept, degenerate and repeated faces dropped, non-manifold spots
cut into stitched manifold pieces (``SimplifyResult.preparation`` says what was done).
``simplify_skinned`` does the same over the rest pose and the baked poses of given motions, and
returns skinned levels whose merged skin weights still drive them. ``motion_features`` exposes
the feature extraction on its own.

Shapes: ``F`` frames, ``V`` vertices, ``M`` faces, ``K`` skin influences, ``C`` collapses.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from . import _core
from .model import AnimatedMesh, LodChain, LodLevel, Motion, SkinnedMesh, whole_indices
from .options import AqemOptions, MotionFeatureOptions, resolve_options


@dataclass
class MotionFeatures:
    """Motion features of a deforming mesh (paper section "Rotation connected graph").

    Attributes
    ----------
    edges : (E, 2) int32 undirected edges, lower vertex first, sorted.
    angle_change : (E,) float32 g_i, the largest change of the edge's dihedral angle between
        consecutive frames, radians (0 on boundary edges).
    connected : (E,) bool, edges that join a feature.
    threshold : the threshold used, radians (on ``amplitude`` for the amplitude weighting, on
        ``angle_change`` for the paper's).
    vertex_feature : (V,) int32 feature index per vertex, -1 outside every feature.
    feature_sizes : (C,) int32 vertex count of each feature.
    vertex_weights : (V,) float32 weight of Eq. 6 (see :func:`motion_features`), 1 outside features.
    amplitude : (E,) float32 a_i, the range of the edge's dihedral angle over all frames, radians
        (0 on boundary edges).
    """

    edges: np.ndarray
    angle_change: np.ndarray
    connected: np.ndarray
    threshold: float
    vertex_feature: np.ndarray
    feature_sizes: np.ndarray
    vertex_weights: np.ndarray
    amplitude: np.ndarray


@dataclass
class SimplifiedLevel:
    """One level of detail of a deforming mesh.

    Attributes
    ----------
    mesh : the simplified sequence, (F, V', 3) frames and (M', 3) faces (corners in input order).
    face_sources : (M',) int32 input face of every face (its primitive or material).
    kept_vertices : (V',) int32 index in the input of every kept vertex, ascending.
    vertex_map : (V,) int32 input vertex -> kept vertex it merged into (-1 for vertices no face
        references, vertices of dropped faces only, and vertices of a piece that collapsed away).
    error : asset units, the largest collapse error so far (see ``CollapseRecord.error``).
    target_face_count : the face count asked for; ``mesh`` has at most that many if ``reached``.
    reached : False when ``max_error`` (or no legal collapse left) stopped the run first.
    stopped_by_max_error : not ``reached`` because the next collapse's error exceeds
        ``max_error`` (False: no legal collapse was left, or the level was reached).
    collapse_count : this level is the first ``collapse_count`` entries of the collapse record.
    attributes : (V', A) float32 carried per-vertex attributes, or None.
    position_attributes : (V', B) float32 carried position-following attributes, or None.
    skin_joints, skin_weights : (V', K) skin influences, or None. Rows of vertices made by a
        collapse are merged: sorted by decreasing weight, summing to 1; other rows are the input's.
    """

    mesh: AnimatedMesh
    face_sources: np.ndarray
    kept_vertices: np.ndarray
    vertex_map: np.ndarray
    error: float
    target_face_count: int
    reached: bool
    collapse_count: int
    stopped_by_max_error: bool = False
    attributes: np.ndarray | None = None
    position_attributes: np.ndarray | None = None
    skin_joints: np.ndarray | None = None
    skin_weights: np.ndarray | None = None


@dataclass
class Preparation:
    """What the simplifier did to the input before simplifying (counts).

    degenerate_faces, duplicate_faces : dropped faces (two corners at one welded position; the
        same corners as an earlier face).
    mirrored_faces : faces with the corners of an earlier face in the reverse turn (two-sided
        sheets): simplified with that face and written on every level as its reverse, on the
        same vertices (they count in the levels' faces and targets, not in ``face_count``).
    welded_vertices : vertices welded onto a lower-numbered copy (UV-seam or flat-shading copies).
    seam_vertices : welded positions whose copies keep different attributes (seams kept).
    split_vertices : copies made to cut non-manifold edges and vertices; they stay in place.
    unreferenced_vertices : vertices no face uses.
    face_count : the faces simplified (ratios refer to it).
    """

    degenerate_faces: int
    duplicate_faces: int
    mirrored_faces: int
    welded_vertices: int
    seam_vertices: int
    split_vertices: int
    unreferenced_vertices: int
    face_count: int


@dataclass
class PhaseSeconds:
    """Wall-clock seconds of one simplification's phases, in the order they run: where its time
    goes. The core's own phases; converting the input and the result to numpy is not included.

    preparation : checks, weld, dropped faces and cuts. motion_features : Eq. 6's features
        (0 when off). connectivity : the collapse engine's OpenMesh connectivity and
        per-point state, while the faces' quadrics are summed beside it. quadrics : what the
        points' quadrics take beyond that (the rest of the faces', the border and seam
        sides'). ranking : the costs of every collapsible edge (each collapse pass's, or the
        greedy order's first). choosing : collapse passes ordering their candidates by cost
        and choosing their collapses. collapsing : collapse attempts (the greedy order's
        re-keying included). levels : the levels' meshes and arrays.
    """

    preparation: float
    motion_features: float
    connectivity: float
    quadrics: float
    ranking: float
    choosing: float
    collapsing: float
    levels: float

    @property
    def total(self) -> float:
        return sum(vars(self).values())


@dataclass
class CollapseRecord:
    """Every collapse in order: vertex ``removed[i]`` merged into ``kept[i]`` (input indices; for
    welded copies, the lowest input index at that position).

    Attributes
    ----------
    removed, kept : (C,) int32.
    positions : (C, F, 3) float32 new positions of the kept vertex in every frame; (0, F, 3)
        when ``record_positions`` is off.
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
    """Levels (finest first), the collapse record, the frames whose quadrics were used, the
    vertex weights (V,) of Eq. 6, what preparing the input did and the phases' seconds."""

    levels: list[SimplifiedLevel]
    collapses: CollapseRecord
    frames_used: np.ndarray
    vertex_weights: np.ndarray
    preparation: Preparation
    seconds: PhaseSeconds

    def lod_chain(self, original: AnimatedMesh, name: str = "") -> LodChain:
        """The levels as a :class:`~animlod.model.LodChain`, ``original`` as level 0; each
        level's error is its AQEM error (asset units, see ``SimplifiedLevel.error``)."""
        levels = [LodLevel(original, None, [], 0.0)]
        levels += [LodLevel(level.mesh, None, [], level.error, mesh_level=i) for i, level in enumerate(self.levels, 1)]
        return LodChain(levels, name)


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
    mesh: AnimatedMesh, options: MotionFeatureOptions | None = None, **option_fields: object
) -> MotionFeatures:
    """Find the motion features of ``mesh`` over all its frames and their weights (Eq. 6).

    Parameters
    ----------
    mesh : the deforming mesh.
    options, **option_fields : a :class:`~animlod.MotionFeatureOptions` and/or its fields by
        name: ``feature_threshold`` (radians; 0 selects the weighting's adaptive threshold),
        ``min_angle_change`` (the 1-degree floor), ``boundary_is_feature``,
        ``feature_weighting``, ``max_feature_weight``, ``noise_mads``. ``"amplitude"``
        weighting (default): an edge's motion is the range a_i of its dihedral angle over all
        frames (independent of the frame rate), the adaptive threshold is T = median +
        ``noise_mads`` * MAD of the interior edges' a_i (so capture noise and ordinary
        deformation find nothing), and a vertex weighs 1 + (``max_feature_weight`` - 1) *
        clamp((a - T) / T, 0, 1) with a its largest edge amplitude: bounded, and exactly 1 where
        nothing moves above T. ``"paper"``: Eq. 6 as published: g_i, the largest change between
        consecutive frames, THR = the mean of g_i over the interior edges, and every vertex of a
        feature of w vertices weighs w.

    Raises ValueError naming the element on bad connectivity (see ``simplify_animated``), the
    option for an unknown option or a bad value.
    """
    resolved = resolve_options(MotionFeatureOptions, options, option_fields)
    return MotionFeatures(**_core.motion_features(mesh.frames, mesh.faces, resolved))


def simplify_animated(
    mesh: AnimatedMesh,
    target_ratios: Sequence[float] | None = None,
    options: AqemOptions | None = None,
    *,
    locked_vertices: Sequence[int] | np.ndarray | None = None,
    guarded_vertices: Sequence[int] | np.ndarray | None = None,
    importance: np.ndarray | None = None,
    attributes: np.ndarray | None = None,
    position_attributes: np.ndarray | None = None,
    skin_joints: np.ndarray | None = None,
    skin_weights: np.ndarray | None = None,
    face_groups: np.ndarray | None = None,
    progress: Callable[[int, int], None] | None = None,
    **option_fields: object,
) -> SimplifyResult:
    """Simplify a deforming mesh over all its frames with AQEM; several levels from one run.

    Parameters
    ----------
    mesh : (F, V, 3) frames and (M, 3) faces, any topology (see the module docstring).
    target_ratios : level sizes as fractions in (0, 1] of the faces left after dropping
        degenerate and repeated ones (``AqemOptions.target_ratios``; default one level at 0.5).
    options, **option_fields : an :class:`~animlod.AqemOptions` and/or its fields by name (also
        those of its ``motion_features``); ``help(animlod.AqemOptions)`` describes each:
        ``target_face_counts`` (replaces ``target_ratios``; a level no legal collapse can reach
        holds the smallest mesh reached, with ``reached`` False), ``max_error`` (asset units;
        stop before a collapse whose error, an RMS plane distance, exceeds it),
        ``use_motion_features`` and the weights of Eq. 6 (see :func:`motion_features`:
        ``"amplitude"`` by default, ``"paper"`` the published rule), ``boundary_quadrics``,
        ``tip_quadrics`` (needle tips cost their displacement; off: the paper's quadrics),
        ``check_inversion`` and ``fold_limit`` (Eq. 7 summed over every frame, and no fold
        deeper than ``fold_limit`` opposite-edge lengths in any frame: 1 by default, 0 for no flip
        at all, ``math.inf`` for Eq. 7 alone), ``max_frames`` and ``frame_subset`` (the frames of
        the quadrics), ``placement`` (``"optimal"``: Eq. 5 in every frame; ``"on_edge"``: one
        point of the collapsed edge for all frames, so that UVs and skin weights stay consistent
        with its positions), ``weld`` (weld copies of a position; off, seams are open borders)
        and ``record_positions`` (off: ``collapses.positions`` stays empty, which saves 12 bytes per
        collapse and frame).
    locked_vertices : indices of vertices that are never removed nor moved.
    guarded_vertices : indices of vertices kept like locked ones until no other collapse is
        legal, then free (sharp corners kept while the targets allow).
    importance : (V,) float32 > 0, multiplies each vertex's weight (e.g. face regions).
    attributes : (V, A) float32 per-vertex data interpolated along collapses (UVs, normals,
        colours). Copies of a position whose attributes differ form a seam that collapses only
        along itself.
    position_attributes : (V, B) float32 data that follows the position (morph target deltas):
        copies weld only where it agrees, and it is blended once per collapse.
    skin_joints, skin_weights : (V, K) int32 / float32 skin influences, merged along collapses
        (union, blended, the K largest kept, renormalised); the levels carry them.
    face_groups : (M,) int32 primitive or material per face; borders between groups are seams.
    progress : ``progress(done, total)`` called now and then from the simplifier.

    Returns
    -------
    SimplifyResult with one level per target, finest first.

    Raises
    ------
    ValueError naming the element: non-finite position, index out of range, a locked vertex
    index outside [0, V), target out of range, bad per-vertex data, an unknown option or a value
    an option cannot hold.
    """
    raw = _core.simplify_animated(
        mesh.frames,
        mesh.faces,
        _resolved_options(target_ratios, options, option_fields),
        locked=_vertex_mask("locked_vertices", locked_vertices, mesh.vertex_count),
        guarded=_vertex_mask("guarded_vertices", guarded_vertices, mesh.vertex_count),
        importance=importance,
        attributes=attributes,
        position_attributes=position_attributes,
        skin_joints=skin_joints,
        skin_weights=skin_weights,
        face_groups=face_groups,
        progress=progress,
    )
    return _result(raw, mesh.fps)


def check_aqem_options(
    target_ratios: Sequence[float] | None = None, options: AqemOptions | None = None, **option_fields: object
) -> None:
    """Refuse, as :func:`simplify_animated` would for any mesh, options it cannot take: a caller
    that holds options long before the mesh (a batch manifest) checks them up front.

    Raises
    ------
    ValueError naming the option: an unknown one, a value its type cannot hold, no level, a
    ratio outside (0, 1], a face count of 0, a negative max_error, a negative frame in
    ``frame_subset``, a motion-feature option out of range. What depends on the mesh (a face
    count above its faces, a frame past its last) only :func:`simplify_animated` can refuse.
    """
    _core.check_aqem_options(_resolved_options(target_ratios, options, option_fields))


def _resolved_options(
    target_ratios: Sequence[float] | None, options: AqemOptions | None, option_fields: dict[str, object]
) -> AqemOptions:
    """The core's options from :func:`simplify_animated`'s ``target_ratios``, ``options`` and
    fields by name."""
    if target_ratios is not None:
        if np.ndim(target_ratios) != 1:
            raise ValueError(f"target_ratios: expected a list of fractions, one per level, got {target_ratios!r}")
        option_fields["target_ratios"] = list(target_ratios)
    return resolve_options(AqemOptions, options, option_fields)


def skinned_lod_chain(
    skinned: SkinnedMesh, motions: Sequence[Motion], levels: Sequence[SkinnedLevel], name: str = ""
) -> LodChain:
    """Levels of :func:`simplify_skinned` as a :class:`~animlod.model.LodChain`: ``skinned`` as
    level 0, every level playing ``motions``; errors are the AQEM errors (asset units)."""
    chain = [LodLevel(skinned, skinned.skeleton, list(motions), 0.0)]
    chain += [
        LodLevel(level.mesh, skinned.skeleton, list(motions), level.error, mesh_level=i)
        for i, level in enumerate(levels, start=1)
    ]
    return LodChain(chain, name)


def simplify_skinned(
    skinned: SkinnedMesh,
    motions: Sequence[Motion],
    target_ratios: Sequence[float] | None = None,
    options: AqemOptions | None = None,
    **option_fields: object,
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
    options, **option_fields : as for :func:`simplify_animated`, and its other keyword arguments
        except ``attributes`` and ``position_attributes``. Without an ``options`` object,
        ``placement`` defaults to ``"on_edge"`` here, so that the merged weights and the positions
        describe the same point.

    Returns
    -------
    One SkinnedLevel per target, finest first.
    """
    if "attributes" in option_fields or "position_attributes" in option_fields:
        raise ValueError("simplify_skinned: attributes come from the SkinnedMesh (uvs, normals, morph targets)")
    if isinstance(motions, Motion):
        raise ValueError("motions: expected a list of clips, got one Motion (pass [motion])")
    baked = [skinned.bake(motion).frames for motion in motions]
    poses = AnimatedMesh(skinned.faces, np.concatenate([skinned.rest_positions[None], *baked], axis=0))
    uv_count = 0 if skinned.uvs is None else 2
    morph_count = 0 if skinned.morph_targets is None else skinned.morph_targets.shape[0]
    columns = [np.zeros((skinned.vertex_count, 0), np.float32)]
    if uv_count:
        columns.append(skinned.uvs)
    if morph_count:
        columns.append(skinned.morph_targets.transpose(1, 0, 2).reshape(skinned.vertex_count, 3 * morph_count))
    fields = {"placement": "on_edge", **option_fields} if options is None else dict(option_fields)
    fields["record_positions"] = False  # the levels are all this returns
    result = simplify_animated(
        poses,
        target_ratios,
        options,
        attributes=np.concatenate(columns, axis=1),
        skin_joints=skinned.joints,
        skin_weights=skinned.weights,
        **fields,
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
            default_morph_weights=skinned.default_morph_weights if morph_count else None,
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


def _vertex_mask(name: str, indices: Sequence[int] | np.ndarray | None, vertex_count: int) -> np.ndarray | None:
    """(V,) bool with the listed vertices set, or ``indices`` itself when it is a (V,) bool mask
    (read as indices, True and False would be vertices 1 and 0); ValueError naming an index that
    is not a whole number in [0, V)."""
    if indices is None:
        return None
    given = np.asarray(indices)
    if given.dtype == np.bool_:
        if given.shape != (vertex_count,):
            raise ValueError(f"{name}: a mask must have one value per vertex ({vertex_count}), got shape {given.shape}")
        return given.copy()
    mask = np.zeros(vertex_count, dtype=bool)
    mask[whole_indices(name, given.ravel(), "entry", 0, vertex_count)] = True
    return mask


def _largest_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance between corresponding points of two (..., 3) arrays."""
    return float(np.sqrt(np.max(np.sum((a.astype(np.float64) - b) ** 2, axis=-1)))) if a.size else 0.0


def _result(raw: dict, fps: float | None) -> SimplifyResult:
    """Wrap the core's dictionaries."""

    def optional(array: np.ndarray) -> np.ndarray | None:
        return array if array.shape[0] and array.shape[-1] else None

    levels = [
        SimplifiedLevel(
            mesh=AnimatedMesh(level["faces"], level["positions"], fps=fps),
            face_sources=level["face_sources"],
            kept_vertices=level["kept_vertices"],
            vertex_map=level["vertex_map"],
            error=float(level["error"]),
            target_face_count=int(level["target_face_count"]),
            reached=bool(level["reached"]),
            collapse_count=int(level["collapse_count"]),
            stopped_by_max_error=bool(level["stopped_by_max_error"]),
            attributes=optional(level["attributes"]),
            position_attributes=optional(level["position_attributes"]),
            skin_joints=optional(level["skin_joints"]),
            skin_weights=optional(level["skin_weights"]),
        )
        for level in raw["levels"]
    ]
    return SimplifyResult(
        levels=levels,
        collapses=CollapseRecord(**raw["collapses"]),
        frames_used=raw["frames_used"],
        vertex_weights=raw["vertex_weights"],
        preparation=Preparation(**{name: int(count) for name, count in raw["preparation"].items()}),
        seconds=PhaseSeconds(**raw["seconds"]),
    )
