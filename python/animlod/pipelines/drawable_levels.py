"""AQEM levels of one glTF drawable, with every primitive, attribute and morph target carried.

The drawable's primitives are simplified together (faces keep their primitive, borders between
primitives are seams), over frames that cover its animations: the rest pose, each morph target
at full weight, and frames spread over every clip. Skinned and morphed drawables use one point
of each collapsed edge for every frame (``placement="on_edge"``), so that the carried skin
weights and morph deltas reproduce the simplified poses; static ones use Eq. 5's optimum.

Attributes are carried as the glTF has them: UVs, colours and normals per wedge (copies of a
position with different values form seams), morph position deltas per position. Hard normal
edges are the exception: where a primitive's copies of a position differ in their normals (flat
or faceted shading), those normals would lock nearly every point, so the primitive is welded
without normals (and tangents) and its normals are rebuilt on each level from the level's own
faces, split where faces meet at more than a crease angle (every face on its own for a flat
shaded primitive). Where three or more normals met (the corners of hard edges, such as spike
tips), the vertices are guarded: they stay in place while the targets can be reached without
moving them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..aqem import Preparation, SimplifiedLevel, simplify_animated
from ..io.gltf_drawable import Clip, Drawable
from ..io.gltf_lod import PrimitiveArrays
from ..io.gltf_mesh import PrimitiveGeometry, transform_points
from ..io.gltf_write import influence_sets
from ..metrics import hausdorff_distances
from ..model import AnimatedMesh, SkinnedMesh, morphed, spread_frames
from ..normals import corner_normals, pairs_within_groups, shading_crease, unit_vectors
from ..options import AqemOptions

_SKIN_PREFIXES = ("JOINTS_", "WEIGHTS_")
_NORMAL_ATTRIBUTES = ("NORMAL", "TANGENT")
# Most points sampled on each surface per measured frame (on top of the vertices; measure_samples).
_MEASURE_SAMPLES = 4000
# The rest pose joins the drive frames where it leaves the bind shape by more than this share of
# its diagonal: float noise of the inverse bind matrices (3e-7 on Soldier.glb) is the same shape.
_SAME_SHAPE = 1e-5


@dataclass(frozen=True)
class DrawableSettings:
    """How each drawable of a glTF document becomes levels: the settings that
    :func:`~animlod.pipelines.simplify_document` and
    :func:`~animlod.pipelines.character.build_character` share.

    Attributes
    ----------
    fps : rate at which animations are sampled; None (the default): the rate of their keys, at
        least 30 fps (:meth:`~animlod.io.gltf_document.GltfDocument.sample_rate`).
    frame_budget : most frames that drive AQEM per drawable (the rest pose, each morph target at
        full weight and frames spread over every clip).
    measured_frames : frames per clip at which each level's error is measured.
    pixel_error, viewport_px : the screen error a level may show where its coverage starts
        (see :func:`animlod.io.gltf_lod.screen_coverages`).
    aqem : fields of :class:`~animlod.AqemOptions` that replace the pipeline's AQEM defaults
        (motion features off; ``placement`` ``"on_edge"`` for skinned or morphed drawables, so
        that the carried weights and deltas reproduce the poses, else ``"optimal"``).
    """

    fps: float | None = None
    frame_budget: int = 48
    measured_frames: int = 12
    pixel_error: float = 1.0
    viewport_px: float = 1080.0
    aqem: Mapping[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # A zero viewport divided the coverages by zero and a negative pixel error wrote negative
        # MSFT_screencoverage; a zero fps was blamed on the input's keys.
        for name in ("fps", "pixel_error", "viewport_px"):
            value = getattr(self, name)
            if name == "fps" and value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int | float) or not 0 < value < np.inf:
                raise ValueError(f"{name}: must be a positive number, got {value!r}")
        for name in ("frame_budget", "measured_frames"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
                raise ValueError(f"{name}: must be a whole number of at least 1, got {value!r}")

    @classmethod
    def resolve(cls, settings: DrawableSettings | None, keywords: Mapping[str, object]) -> DrawableSettings:
        """``settings`` (the defaults when None) changed by ``keywords``: a keyword naming a
        field above replaces it, any other is an AQEM option. Raises ValueError naming an unknown
        option or a value it cannot hold, before any work."""
        settings = settings or cls()
        own = {name for name in cls.__dataclass_fields__ if name != "aqem"}
        aqem = {**settings.aqem, **{name: value for name, value in keywords.items() if name not in own}}
        AqemOptions(**aqem)
        return dataclasses.replace(settings, aqem=aqem, **{name: keywords[name] for name in own & keywords.keys()})


@dataclass
class DrawableLevel:
    """One level of a drawable.

    Attributes
    ----------
    simplified : the AQEM level (faces, kept vertices, carried data; positions of the drive frames).
    primitives : the level's triangle primitives, node-local, ready to write.
    skinned : the level as a world-space skinned mesh (skinned drawables), else None.
    bind : (V', 3) the level's bind shape (the space of the drawable's ``bind_positions``).
    morph_targets : (N, V', 3) its morph deltas in that space, or None.
    default_weights : (N,) the weights its targets show where no animation drives them, or None.
    error : asset units, max over measured frames of the Hausdorff distance to the input (0 when
        simplify_drawable was asked not to measure).
    """

    simplified: SimplifiedLevel
    primitives: list[PrimitiveArrays]
    skinned: SkinnedMesh | None
    bind: np.ndarray
    morph_targets: np.ndarray | None
    default_weights: np.ndarray | None = None
    error: float = 0.0

    def rest_positions(self) -> np.ndarray:
        """(V', 3) what a viewer shows of the level with no animation (see Drawable.rest_positions)."""
        if self.skinned is not None:
            return self.skinned.rest_pose()
        return morphed(self.bind, self.morph_targets, self.default_weights)


@dataclass
class DrawableLevels:
    """Levels of a drawable, finest first, with its size (bounding-box diagonal of its rest pose as
    a viewer shows it)."""

    levels: list[DrawableLevel]
    size: float
    preparation: Preparation
    notes: list[str] = field(default_factory=list)


@dataclass
class _Layout:
    """Where each attribute sits in the matrix handed to AQEM."""

    columns: dict[str, tuple[int, int]]  # name -> (first column, width)
    target_columns: list[dict[str, tuple[int, int]]]  # per morph target: NORMAL/TANGENT deltas
    crease: list[float | None]  # per primitive: crease angle of rebuilt normals, None when carried
    width: int


def simplify_drawable(
    drawable: Drawable,
    ratios: Sequence[float],
    settings: DrawableSettings | None = None,
    importance: np.ndarray | None = None,
    measure: bool = True,
    progress: Callable[[str], None] | None = None,
) -> DrawableLevels:
    """AQEM levels of ``drawable`` at ``ratios``, each measured over every clip; ``progress`` is
    called with a line of text as the collapses and the measurement start.

    ``settings`` says how many frames drive and measure the levels and which AQEM options
    replace the pipeline's (unlike :func:`animlod.simplify_animated`, motion features are off
    unless ``use_motion_features=True`` is given; see the comment below). ``importance`` (V,)
    float32 > 0 multiplies each vertex's weight (the face's regions). ``measure=False`` leaves
    every level's ``error`` at 0, for callers that measure what they write themselves (the
    character chain, the face levels): measuring is most of the work on characters with clips.
    """
    settings = settings or DrawableSettings()
    geometry = drawable.geometry
    matrix, layout = _attribute_matrix(drawable)
    deltas = drawable.morph_targets
    position_attributes = None if deltas is None else deltas.transpose(1, 0, 2).reshape(len(geometry.positions), -1)
    animated = drawable.skinned is not None or deltas is not None
    # Motion features are off unless asked for: on skinned and morphed glTF characters, whose levels
    # are re-skinned or re-morphed, the amplitude weights moved the max-over-frames error between
    # -15% and +47% against features off with no consistent sign, and the paper's were worse almost
    # everywhere (README, AQEM section: bench/bench_aqem.py --tables characters).
    options = {
        "placement": "on_edge" if animated else "optimal",
        "use_motion_features": False,
        **settings.aqem,
        "record_positions": False,  # the levels are all this keeps
    }
    rest = drawable.rest_positions()
    size = float(np.linalg.norm(np.ptp(rest, axis=0)))
    frames, bind_drives = _drive_frames(drawable, rest, size, settings.frame_budget)
    if not bind_drives and not {"frame_subset", "max_frames"} & options.keys():
        options["frame_subset"] = tuple(range(1, len(frames)))  # frame 0 carried along the edges, no quadrics
    say = progress or (lambda _line: None)
    say(f"{drawable.label}: collapsing over {len(frames)} frames")
    result = simplify_animated(
        AnimatedMesh(geometry.faces, frames),
        ratios,
        attributes=matrix if layout.width else None,
        position_attributes=position_attributes,
        skin_joints=None if drawable.skinned is None else drawable.skinned.joints,
        skin_weights=None if drawable.skinned is None else drawable.skinned.weights,
        face_groups=geometry.face_groups,
        guarded_vertices=_sharp_corners(drawable, layout),
        importance=importance,
        **options,
    )
    levels = [_level(drawable, level, layout) for level in result.levels]
    notes = []
    rebuilt = [geometry.primitives[k].index for k, crease in enumerate(layout.crease) if crease is not None]
    if rebuilt:
        notes.append(f"primitives {rebuilt}: hard normal edges; normals rebuilt on each level (crease angle)")
    if geometry.other_primitives:
        notes.append(f"primitives {geometry.other_primitives}: points or lines, kept unchanged")
    if measure:
        say(f"{drawable.label}: measuring {len(levels)} levels")
        _measure(drawable, levels, settings.measured_frames)
    return DrawableLevels(levels, size, result.preparation, notes)


def _drive_frames(drawable: Drawable, rest: np.ndarray, size: float, budget: int) -> tuple[np.ndarray, bool]:
    """(F, V, 3) world positions AQEM works over: the bind shape (frame 0, from which _level reads
    the levels' stored positions), the rest pose ``rest`` (diagonal ``size``) where a viewer shows
    something else, each morph target at full weight on the rest pose (the others at 0), then
    frames spread evenly over every clip (at least two per clip), F <= ``budget`` where the clips
    allow; and whether the bind shape drives the collapses. It does where it is the rest pose. A
    viewer never shows any other bind shape (a skinned mesh node's own transform, which skinning
    ignores, scales and moves it; a morphed mesh shows its default weights): its quadrics would
    weigh a pose nobody sees, by the square of that scale."""
    bind = drawable.bind_positions()
    frames = [bind[None]]
    bind_drives = bool(np.abs(rest - bind).max() <= _SAME_SHAPE * size)
    if not bind_drives:
        frames.append(rest[None])
    if drawable.geometry.targets is not None:
        deltas = drawable.rest_morph_targets()
        undriven = rest - np.einsum("n,nvc->vc", drawable.default_weights, deltas).astype(np.float32)
        frames.append(undriven[None] + deltas)
    clips = drawable.clips
    remaining = max(budget - sum(len(f) for f in frames), 2 * len(clips))
    lengths = np.array([clip.frame_count for clip in clips], np.float64)
    for clip, share in zip(clips, lengths / max(lengths.sum(), 1.0)):
        count = int(np.clip(round(share * remaining), 2, clip.frame_count))
        frames.append(drawable.clip_frames(clip, spread_frames(clip.frame_count, count)))
    return np.concatenate(frames).astype(np.float32, copy=False), bind_drives


def _attribute_matrix(drawable: Drawable) -> tuple[np.ndarray, _Layout]:
    """(V, A) float32 of every per-wedge attribute (all but POSITION and skin) and morph
    NORMAL/TANGENT deltas, primitives one after another; absent values are 0 (faces of one
    primitive never blend with another's)."""
    primitives = drawable.geometry.primitives
    columns: dict[str, tuple[int, int]] = {}
    width = 0

    def column(name: str, size: int) -> None:
        nonlocal width
        if name not in columns:
            columns[name] = (width, size)
            width += size
        elif columns[name][1] < size:
            raise ValueError(f"{drawable.label}: attribute {name} has different widths across primitives")

    for primitive in primitives:
        for name, values in primitive.attributes.items():
            if name != "POSITION" and not name.startswith(_SKIN_PREFIXES):
                column(name, values.shape[1])
    target_columns: list[dict[str, tuple[int, int]]] = []
    for t in range(len(primitives[0].targets) if primitives else 0):
        per_target = {}
        for primitive in primitives:
            for name, values in primitive.targets[t].items():
                if name != "POSITION":
                    key = f"target {t} {name}"
                    column(key, values.shape[1])
                    per_target[name] = columns[key]
        target_columns.append(per_target)
    starts = drawable.geometry.vertex_starts
    matrix = np.zeros((starts[-1], width), np.float32)
    crease = []
    for k, primitive in enumerate(primitives):
        rows = slice(starts[k], starts[k + 1])
        crease.append(_crease_angle(primitive))
        # Rebuilt normals: the copies of a position differ in normals, tangents and their morph
        # deltas, which would make every hard edge a seam; the level takes them from its kept
        # vertices instead (_level).
        rebuilt = crease[k] is not None
        for name, values in primitive.attributes.items():
            if name in columns and not (rebuilt and name in _NORMAL_ATTRIBUTES):
                first, size = columns[name]
                matrix[rows, first : first + values.shape[1]] = values
        for t, target in enumerate(primitive.targets):
            for name, values in target.items():
                if name != "POSITION" and not (rebuilt and name in _NORMAL_ATTRIBUTES):
                    first, size = target_columns[t][name]
                    matrix[rows, first : first + values.shape[1]] = values
    return matrix, _Layout(columns, target_columns, crease, width)


def _crease_angle(primitive: PrimitiveGeometry) -> float | None:
    """None when the primitive's normals can be carried (no two copies of a position differ in
    them); otherwise the crease angle its rebuilt normals use: 0 for flat shading."""
    normals = primitive.attributes.get("NORMAL")
    return None if normals is None else shading_crease(primitive.attributes["POSITION"], normals, primitive.faces)


def _sharp_corners(drawable: Drawable, layout: _Layout) -> np.ndarray:
    """Vertices of primitives with rebuilt normals where three or more normals meet (a corner of
    hard edges, such as a spike's tip): guarded, so they stay while the targets allow."""
    starts = drawable.geometry.vertex_starts
    corners = []
    for k, primitive in enumerate(drawable.geometry.primitives):
        if layout.crease[k] is None:
            continue
        _, point = np.unique(primitive.attributes["POSITION"], axis=0, return_inverse=True)
        point = point.ravel()
        distinct = np.unique(np.concatenate([point[:, None], primitive.attributes["NORMAL"]], axis=1), axis=0)
        normals_at = np.bincount(distinct[:, 0].astype(np.int64), minlength=point.max() + 1)
        corners.append(np.flatnonzero(normals_at[point] >= 3) + starts[k])
    return np.concatenate(corners) if corners else np.zeros(0, np.int64)


def _level(drawable: Drawable, level: SimplifiedLevel, layout: _Layout) -> DrawableLevel:
    """The level's bind shape, deltas and skin, and its primitives in node-local space."""
    geometry = drawable.geometry
    rest = level.mesh.frames[0]  # the bind shape (_drive_frames)
    deltas = None
    if level.position_attributes is not None:
        deltas = level.position_attributes.reshape(len(rest), -1, 3).transpose(1, 0, 2)
    skinned = None
    if drawable.skinned is not None:
        skinned = SkinnedMesh(
            rest_positions=rest,
            faces=level.mesh.faces,
            joints=level.skin_joints,
            weights=level.skin_weights,
            inverse_bind=drawable.skinned.inverse_bind,
            skeleton=drawable.skinned.skeleton,
            morph_targets=deltas,
            default_morph_weights=drawable.skinned.default_morph_weights,
        )
    to_local = np.linalg.inv(drawable.world)
    groups = geometry.face_groups[level.face_sources]
    primitives = []
    for k, source in enumerate(geometry.primitives):
        faces = level.mesh.faces[groups == k]
        if len(faces) == 0:
            continue
        used, local_faces = np.unique(faces, return_inverse=True)
        local_faces = local_faces.reshape(-1, 3)
        kept = level.kept_vertices[used] - geometry.vertex_starts[k]  # the input vertices kept
        rebuilt = layout.crease[k] is not None
        attributes = {"POSITION": transform_points(to_local, rest[used]).astype(np.float32)}
        for name, values in source.attributes.items():
            if name in layout.columns:
                first = layout.columns[name][0]
                attributes[name] = _level_column(level, used, first, values, kept if _carried(name, rebuilt) else None)
        _tidy_directions(attributes)
        if skinned is not None:
            attributes.update(_skin_columns(drawable, skinned.joints[used], skinned.weights[used]))
        targets = []
        for t, target in enumerate(source.targets):
            arrays = {}
            for name, values in target.items():
                if name == "POSITION":
                    arrays[name] = (deltas[t][used] @ to_local[:3, :3].T).astype(np.float32)
                else:
                    first = layout.target_columns[t][name][0]
                    arrays[name] = _level_column(level, used, first, values, kept if _carried(name, rebuilt) else None)
            targets.append(arrays)
        primitive = PrimitiveArrays(source.index, attributes, local_faces, targets, used)
        if layout.crease[k] is not None:
            primitive = with_crease_normals(primitive, layout.crease[k])
            if "TANGENT" in primitive.attributes:
                inputs = kept[np.searchsorted(used, primitive.vertices)]
                _take_corner_tangents(primitive.attributes, source.attributes, inputs)
        primitives.append(primitive)
    return DrawableLevel(level, primitives, skinned, rest, deltas, drawable.default_weights)


def _carried(name: str, rebuilt: bool) -> bool:
    """Whether a level's vertex takes attribute ``name`` from the input vertex it keeps rather
    than the collapses' blend: application attributes (``_``-prefixed, such as feature IDs, whose
    blend means nothing: IDs 0 and 7 would give 3.5) and, with rebuilt normals, normals, tangents
    and their morph deltas, which the matrix does not carry (_attribute_matrix)."""
    return name.startswith("_") or (rebuilt and name in _NORMAL_ATTRIBUTES)


def _level_column(
    level: SimplifiedLevel, used: np.ndarray, first: int, values: np.ndarray, kept: np.ndarray | None
) -> np.ndarray:
    """The values of the level's vertices ``used`` of an attribute or morph delta (the input's
    ``values``) that starts at column ``first`` of the matrix: the kept input vertices' own
    (``kept``, see :func:`_carried`) or the collapses' blend."""
    if kept is not None:
        return values[kept].astype(np.float32)
    return level.attributes[used, first : first + values.shape[1]].copy()


def _tidy_directions(attributes: dict[str, np.ndarray]) -> None:
    """Interpolated normals back to unit length, tangents too (perpendicular to the normals)
    with w = +-1, colours in [0, 1]."""
    if "NORMAL" in attributes:
        attributes["NORMAL"] = unit_vectors(attributes["NORMAL"])
    if "TANGENT" in attributes:
        tangent = attributes["TANGENT"]
        tangent[:, :3] = _tangent_directions(tangent[:, :3], attributes.get("NORMAL"))
        tangent[:, 3] = np.where(tangent[:, 3] < 0.0, -1.0, 1.0)
    for name in attributes:
        if name.startswith("COLOR_"):
            np.clip(attributes[name], 0.0, 1.0, out=attributes[name])


def _tangent_directions(
    tangents: np.ndarray, normals: np.ndarray | None, fallback: np.ndarray | None = None
) -> np.ndarray:
    """Unit ``tangents`` made perpendicular to the unit ``normals`` (Gram-Schmidt), if any. A
    tangent along its normal (a hard edge's corner that kept another face's vertex) has nothing
    across it: it takes ``fallback`` (its face's texture direction) across the normal where that
    has a part across it, else any perpendicular direction: a zero vector is no tangent."""
    if normals is None:
        return unit_vectors(tangents)

    def across(vectors: np.ndarray, unit_normals: np.ndarray) -> np.ndarray:
        return vectors - np.einsum("vc,vc->v", vectors, unit_normals)[:, None] * unit_normals

    result = across(tangents, normals)
    lost = ~result.any(axis=1)
    if fallback is not None:
        result[lost] = across(fallback[lost], normals[lost])
        lost = ~result.any(axis=1)
    result[lost] = np.cross(normals[lost], np.eye(3)[np.argmin(np.abs(normals[lost]), axis=1)])
    return unit_vectors(result)


def _take_corner_tangents(attributes: dict[str, np.ndarray], inputs: dict[str, np.ndarray], kept: np.ndarray) -> None:
    """Each vertex of a level with rebuilt normals takes the tangent (and handedness) of the input
    vertex that shares its kept vertex's position and texture coordinates and whose normal is
    nearest its own: the input's copy of that corner on the vertex's own side of the hard edge.
    The kept vertex's tangent is one side's, 90 degrees off on a box's other faces."""
    positions = inputs["POSITION"]
    uvs = inputs.get("TEXCOORD_0", np.zeros((len(positions), 0)))
    _, group = np.unique(np.c_[positions.astype(np.float64), uvs], axis=0, return_inverse=True)
    group = group.ravel()
    vertex, candidate = pairs_within_groups(group, group[kept])  # the kept vertex itself among them
    closeness = np.einsum("pc,pc->p", inputs["NORMAL"][candidate].astype(np.float64), attributes["NORMAL"][vertex])
    block = np.flatnonzero(np.r_[True, vertex[1:] != vertex[:-1]])  # each level vertex's first pair
    chosen = candidate[np.lexsort((-closeness, vertex))[block]]
    tangent = inputs["TANGENT"][chosen].astype(np.float32)
    tangent[:, :3] = _tangent_directions(tangent[:, :3], attributes["NORMAL"], attributes["TANGENT"][:, :3])
    tangent[:, 3] = np.where(tangent[:, 3] < 0.0, -1.0, 1.0)
    attributes["TANGENT"] = tangent


def _texture_tangents(positions: np.ndarray, uvs: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F, 3) each face's direction of increasing u (dP/du from its corners' texture
    coordinates, as MikkTSpace starts from); zero where the face's UVs are degenerate."""
    edges = positions[faces[:, 1:]] - positions[faces[:, :1]]  # (F, 2, 3)
    steps = (uvs[faces[:, 1:]] - uvs[faces[:, :1]]).astype(np.float64)  # (F, 2, 2)
    area = steps[:, 0, 0] * steps[:, 1, 1] - steps[:, 1, 0] * steps[:, 0, 1]
    usable = np.abs(area) > 1e-12
    direction = edges[:, 0] * steps[:, 1, 1:2] - edges[:, 1] * steps[:, 0, 1:2]
    return np.where(usable[:, None], direction / np.where(usable, area, 1.0)[:, None], 0.0)


def with_crease_normals(primitive: PrimitiveArrays, crease: float) -> PrimitiveArrays:
    """``primitive`` with normals from its own faces: each corner gets the area-weighted normal
    of the faces around its vertex that turn from its face by at most ``crease`` radians, and
    a vertex whose corners get different normals is split. Tangents are re-orthogonalised."""
    positions = primitive.attributes["POSITION"].astype(np.float64)
    faces = primitive.faces
    corner_vertex, corner_face = faces.ravel(), np.repeat(np.arange(len(faces)), 3)
    normal = corner_normals(positions, faces, crease)
    # One output vertex per (vertex, normal).
    keys = np.concatenate([corner_vertex[:, None].astype(np.float32), normal], axis=1)
    _, first, new_index = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    source = corner_vertex[first]
    attributes = {name: values[source] for name, values in primitive.attributes.items()}
    attributes["NORMAL"] = normal[first].astype(np.float32)
    if "TANGENT" in attributes:
        tangent = attributes["TANGENT"]
        uvs = primitive.attributes.get("TEXCOORD_0")
        fallback = None if uvs is None else _texture_tangents(positions, uvs, faces)[corner_face[first]]
        tangent[:, :3] = _tangent_directions(tangent[:, :3], attributes["NORMAL"], fallback)
    targets = [{name: values[source] for name, values in target.items()} for target in primitive.targets]
    return PrimitiveArrays(primitive.source, attributes, new_index.reshape(-1, 3), targets, primitive.vertices[source])


def _skin_columns(drawable: Drawable, joints: np.ndarray, weights: np.ndarray) -> dict[str, np.ndarray]:
    """JOINTS_n / WEIGHTS_n of skeleton-ordered influences, back in the skin's own joint slots."""
    rig = drawable.rig
    slot_of_joint = np.empty(len(rig.remap), np.int64)
    slot_of_joint[rig.remap] = np.arange(len(rig.remap))
    return influence_sets(np.where(weights > 0.0, slot_of_joint[joints], 0), weights)


def measure_samples(drawable: Drawable) -> int:
    """Points drawn on each surface per measured frame, on top of its vertices: one per face of the
    input, at most _MEASURE_SAMPLES. They catch what lies inside faces, so their density per face
    is what counts: with a fixed count, a character split into 60 meshes drew 4,000 on each, and
    measuring took 12 of its 20 s."""
    return min(_MEASURE_SAMPLES, len(drawable.geometry.faces))


def _measure(drawable: Drawable, levels: list[DrawableLevel], measured_frames: int) -> None:
    """Each level's error: max over clips and ``measured_frames`` frames per clip (the rest pose
    when there is no clip) of the Hausdorff distance to the input, in asset units."""
    faces = drawable.geometry.faces
    for clip, frames, positions in _measured_poses(drawable, measured_frames):
        original = AnimatedMesh(faces[_drawn(faces, positions)], positions)
        posed = [AnimatedMesh(lv.simplified.mesh.faces, posed_frames(drawable, lv, clip, frames)) for lv in levels]
        errors = hausdorff_distances(
            original, posed, measure_samples(drawable), at_least=[level.error for level in levels]
        )
        for level, error in zip(levels, errors):
            level.error = error


def split_empty(drawables: list[Drawable], measured_frames: int) -> tuple[list[Drawable], list[Drawable]]:
    """``drawables`` that draw something, and those that draw nothing (:func:`draws_nothing`), each
    in their order."""
    empty = [draws_nothing(drawable, measured_frames) for drawable in drawables]
    return [d for d, skip in zip(drawables, empty) if not skip], [d for d, skip in zip(drawables, empty) if skip]


def draws_nothing(drawable: Drawable, measured_frames: int) -> bool:
    """Whether no triangle of ``drawable`` has three distinct corner positions at rest or in the
    measured frames of its clips (a placeholder collapsed to a point, or no triangle at all):
    there is nothing to simplify."""
    faces = drawable.geometry.faces
    return not any(_drawn(faces, positions).any() for _, _, positions in _measured_poses(drawable, measured_frames))


def _measured_poses(drawable: Drawable, measured_frames: int) -> Iterator[tuple[Clip | None, np.ndarray, np.ndarray]]:
    """``(clip, frames, positions (T, V, 3))`` of the poses a level's error is measured in: the
    rest pose (clip None), then ``measured_frames`` frames spread over each clip."""
    yield None, np.zeros(1, int), drawable.rest_positions()[None]
    for clip in drawable.clips:
        frames = spread_frames(clip.frame_count, measured_frames)
        yield clip, frames, drawable.clip_frames(clip, frames)


def _drawn(faces: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """``(F,) bool``: the faces with three distinct corner positions in some of ``frames`` (T, V, 3).
    The others draw nothing, and AQEM drops them: measured, a placeholder primitive collapsed to
    the origin set every level's error to the distance from there to the surface."""
    drawn = np.zeros(len(faces), bool)
    undecided = np.arange(len(faces))
    for positions in frames:  # frame by frame, only the faces no earlier frame draws (few after the first)
        corners = positions[faces[undecided]]  # (U, 3, 3)
        coincide = [np.all(corners[:, a] == corners[:, b], axis=-1) for a, b in ((0, 1), (1, 2), (2, 0))]
        distinct = ~np.logical_or.reduce(coincide)
        drawn[undecided[distinct]] = True
        undecided = undecided[~distinct]
        if undecided.size == 0:
            break
    return drawn


def posed_frames(drawable: Drawable, level: DrawableLevel, clip: Clip | None, frames: np.ndarray) -> np.ndarray:
    """(T, V', 3) world positions of the level in the given frames of ``clip`` (None: rest)."""
    if clip is None:
        return level.rest_positions()[None]
    weights = None if clip.morph_weights is None else clip.morph_weights[frames]
    if level.skinned is not None:
        return level.skinned.bake(clip.motion.take_frames(frames), weights).frames
    weights = level.default_weights if weights is None else weights
    return morphed(level.bind, level.morph_targets, weights, len(frames))
