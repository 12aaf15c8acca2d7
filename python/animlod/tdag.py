"""TDAG: temporal and spatial level of detail for a deforming mesh (Shamir and Pascucci 2001,
"Temporal and spatial level of details for dynamic meshes"), a thin layer over the C++ core
(``cpp/include/animlod/tdag.hpp``).

One multi-resolution structure serves every frame: a vertex hierarchy of half-edge collapses
whose fields carry time tags (a collapse lives on the frames whose hierarchy uses it; its
dependencies and its error bound are tagged per frame), with each frame split into an affine
map and a residual mesh (Section 3). A query returns the coarsest mesh of a frame whose error
bound is within a tolerance; cuts update incrementally in time (:meth:`TemporalDag.advance`)
and in resolution (:meth:`TemporalDag.refine`), and the three temporal approximation levels of
Section 5 are one argument away.

Error bounds and tolerances are in asset units: a node's bound is at least the distance between
each input vertex it stands for and its position, so a mesh within a tolerance is within it of
the input frame in the two-sided Hausdorff distance.

Shapes: ``F`` frames, ``V`` input vertices, ``M`` input faces, ``C`` collapses (node ``V + c``
is made by collapse ``c``), ``V'`` / ``M'`` vertices and faces of a queried mesh.
"""

from __future__ import annotations

import operator
import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import _core
from .model import AnimatedMesh, whole_number
from .options import PlayerOptions, TdagOptions, resolve_options

GOVERNING_CHOICES = ("first", "average", "aqem", "online")


@dataclass
class TdagMesh:
    """A mesh handed out by a TDAG query.

    Attributes
    ----------
    positions : (V', 3) float32, asset units.
    faces : (M', 3) int32 indices into ``positions``, counter-clockwise; the backs of two-sided
        faces (:attr:`TemporalDag.two_sided`) follow the others, turned over.
    nodes : (V',) int32 hierarchy node of each vertex (``< V``: an input vertex).
    frame : frame of the affine map (and, at levels 2-3, of the residuals).
    cut_frame : frame the cut was computed for.
    residual_frame : frame of the residual positions.
    error_bound : largest error bound of the active nodes at ``cut_frame`` (asset units).
    """

    positions: np.ndarray
    faces: np.ndarray
    nodes: np.ndarray
    frame: int
    cut_frame: int
    residual_frame: int
    error_bound: float

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def face_count(self) -> int:
        return int(self.faces.shape[0])

    def to_animated_mesh(self) -> AnimatedMesh:
        """The mesh as a one-frame :class:`~animlod.model.AnimatedMesh`."""
        return AnimatedMesh(self.faces, self.positions[None])


@dataclass
class TdagBuildReport:
    """What the build measured (costs are quadric costs of the half-edge collapses on the real
    frames, squared asset units).

    Attributes
    ----------
    collapse_counts : (F,) int32 collapses in each frame's hierarchy.
    max_cost : (C,) float64 per collapse, its largest cost over the frames that use it.
    use_counts : (C,) int32 frames that use each collapse (``n_i`` of Section 4).
    seconds_affine, seconds_hierarchy, seconds_fields : time of the affine split, of the
        decimation(s) and of the per-frame fields.
    """

    collapse_counts: np.ndarray
    max_cost: np.ndarray
    use_counts: np.ndarray
    seconds_affine: float
    seconds_hierarchy: float
    seconds_fields: float

    @property
    def seconds(self) -> float:
        return self.seconds_affine + self.seconds_hierarchy + self.seconds_fields

    def quality_measure(self) -> tuple[float, float]:
        """Figure 6's measure: the largest cost over time of every contracted edge ``i``,
        ``max_t c_it``, averaged over all decimations (``sum_i n_i max_t c_it / N`` with
        ``N = sum_i n_i``, the formula of Section 4) and its median over all decimations (each
        edge counted ``n_i`` times, so that a governed build, where every edge is used in every
        frame, gives the plain median over edges). Returns ``(average, median)`` in squared
        asset units."""
        used = self.use_counts > 0
        if not np.any(used):
            return 0.0, 0.0
        costs, weights = self.max_cost[used], self.use_counts[used].astype(np.float64)
        average = float(np.sum(weights * costs) / np.sum(weights))
        order = np.argsort(costs, kind="stable")
        cumulative = np.cumsum(weights[order])
        median = float(costs[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])
        return average, median


@dataclass
class LevelStats:
    """Per-frame statistics of one approximation level over a walk: seconds for the call that
    makes the mesh (mean, largest, median), the largest distance between an input vertex and the
    vertex standing for it (asset units, mean over frames and largest), and mean mesh sizes."""

    mean_seconds: float
    max_seconds: float
    mean_error: float
    max_error: float
    mean_vertices: float
    mean_faces: float
    median_seconds: float


@dataclass
class PlayerReport:
    """A walk over the frames at one tolerance (see :meth:`TemporalDag.play`).

    Attributes
    ----------
    frames : frames measured (after the first).
    levels : levels 1 (affine), 2 (residual), 3 (full), each made from the cut of the frame before.
    full_query : a fresh query at (frame, tolerance) and its mesh, per frame.
    mean_splits, mean_collapses : per level-3 update.
    sequential_seconds_per_frame, double_buffered_seconds_per_frame : the level-3 walk on one
        thread and with the double-buffered player.
    median_update_seconds : level 3's cut update alone (no positions, no mesh written).
    median_fresh_cut_seconds : the fresh query's cut alone.
    """

    frames: int
    levels: list[LevelStats]
    full_query: LevelStats
    mean_splits: float
    mean_collapses: float
    sequential_seconds_per_frame: float
    double_buffered_seconds_per_frame: float
    median_update_seconds: float
    median_fresh_cut_seconds: float


def _mesh(raw: dict) -> TdagMesh:
    return TdagMesh(
        positions=raw["positions"],
        faces=raw["faces"],
        nodes=raw["nodes"],
        frame=int(raw["frame"]),
        cut_frame=int(raw["cut_frame"]),
        residual_frame=int(raw["residual_frame"]),
        error_bound=float(raw["error_bound"]),
    )


def _first_frame(first_frame: int, frame_count: int) -> int:
    """``first_frame`` as an int in [0, ``frame_count``); ValueError naming ``first_frame``, the
    argument the caller passed (the core checks it too, but calls it ``frame``)."""
    try:
        frame = operator.index(first_frame)
    except TypeError:
        raise ValueError(f"first_frame: expected an integer, got {first_frame!r}") from None
    if not 0 <= frame < frame_count:
        raise ValueError(f"first_frame: {frame} outside [0, {frame_count})")
    return frame


def _level(level: int) -> int:
    if level not in (1, 2, 3):
        raise ValueError(f"level: expected 1 (affine), 2 (residual) or 3 (full), got {level}")
    return level


class Cut:
    """One viewer's cut of a TDAG: a mesh kept up to date by incremental queries.

    Every method that changes the cut returns its mesh at the cut's frame (level 3). Cuts of one
    TDAG are independent and may be used from different threads.
    """

    def __init__(self, core: _core.TdagCut, frame_count: int) -> None:
        self._core = core
        self._frame_count = frame_count

    def query(self, frame: int, tolerance: float) -> TdagMesh:
        """Random query: the coarsest mesh of ``frame`` within ``tolerance`` (asset units)."""
        self._core.query(frame, tolerance)
        return self.mesh()

    def query_view(
        self, frame: int, camera: Sequence[float], pixels: float = 1.0, focal_pixels: float = 1000.0
    ) -> TdagMesh:
        """Random query with a screen-space tolerance: every node within ``pixels`` pixels as seen
        from ``camera`` (3,) at its distance, for a focal length of ``focal_pixels`` (viewport
        height / (2 tan(fov_y / 2)))."""
        self._core.query_view(frame, [float(c) for c in camera], pixels, focal_pixels)
        return self.mesh()

    def advance(self, frame: int | None = None, level: int = 3) -> TdagMesh:
        """Incremental in time: the mesh of ``frame`` (default: the next frame) at ``level``.

        Level 3 updates the cut where the error bounds crossed the tolerance; level 2 keeps the
        cut and takes the frame's residual positions; level 1 keeps the cut and its positions and
        applies the frame's affine map (Section 5).
        """
        if frame is None:
            frame = min(self._core.frame + 1, self._frame_count - 1)
        return _mesh(self._core.approximate(frame, _level(level)))

    def refine(self, tolerance: float) -> TdagMesh:
        """Incremental in resolution: the mesh of the cut's frame for a new tolerance."""
        self._core.refine(tolerance)
        return self.mesh()

    def refine_view(self, camera: Sequence[float], pixels: float = 1.0, focal_pixels: float = 1000.0) -> TdagMesh:
        """Incremental with a new screen-space tolerance (the camera moved)."""
        self._core.refine_view([float(c) for c in camera], pixels, focal_pixels)
        return self.mesh()

    def mesh(self) -> TdagMesh:
        """The cut's mesh at its frame."""
        return _mesh(self._core.mesh())

    def input_vertex_map(self) -> np.ndarray:
        """(V,) int32: for each input vertex, the index in :meth:`mesh` of the vertex standing for it."""
        return self._core.input_vertex_map()

    @property
    def frame(self) -> int:
        return int(self._core.frame)

    @property
    def tolerance(self) -> float:
        """Asset units; NaN for a view-dependent cut."""
        return float(self._core.tolerance)

    @property
    def active_vertex_count(self) -> int:
        return int(self._core.active_vertex_count)

    @property
    def active_face_count(self) -> int:
        return int(self._core.active_face_count)

    @property
    def last_update(self) -> tuple[int, int]:
        """(splits, collapses) done by the last query or update."""
        return int(self._core.last_split_count), int(self._core.last_collapse_count)


class Player:
    """The double-buffered player: iterating yields one :class:`TdagMesh` per frame at level 3
    while the cut of the next frame is computed on a second thread."""

    def __init__(self, core: _core.TdagPlayer) -> None:
        self._core = core

    def next(self, level: int = 3) -> TdagMesh:
        """The next frame at ``level``; level 3 waits for its cut, levels 1-2 never wait."""
        return _mesh(self._core.next(_level(level)))

    def next_available(self) -> tuple[TdagMesh, int]:
        """The next frame at level 3 if its cut is ready, else at level 2; returns (mesh, level)."""
        raw, level = self._core.next_available()
        return _mesh(raw), int(level)

    @property
    def frame(self) -> int:
        """The frame the next call hands out."""
        return int(self._core.frame)

    @property
    def done(self) -> bool:
        return bool(self._core.done)

    def __iter__(self) -> Iterator[TdagMesh]:
        while not self.done:
            yield self.next(3)


class TemporalDag:
    """A TDAG of a deforming mesh, with a cursor for incremental queries.

    Build one with :meth:`build` or :meth:`load`. :meth:`query` sets the cursor's frame and
    tolerance; :meth:`advance` and :meth:`refine` move it incrementally; :meth:`cut` makes
    independent cursors.
    """

    def __init__(self, core: _core.TemporalDag, report: TdagBuildReport | None = None) -> None:
        self._core = core
        self.report = report
        self._cursor: Cut | None = None

    # -- construction and files ----------------------------------------------------------------

    @classmethod
    def build(
        cls,
        mesh: AnimatedMesh,
        governing: str | int = "first",
        options: TdagOptions | None = None,
        *,
        progress: Callable[[int, int], None] | None = None,
        **option_fields: object,
    ) -> TemporalDag:
        """Build the TDAG of ``mesh`` (Sections 3-4).

        Parameters
        ----------
        mesh : (F, V, 3) frames and (M, 3) faces, any indexed triangle mesh.
        governing : the collapse order: ``"first"`` (decimate frame 0), ``"average"`` (the average
            mesh), a frame number (that frame), ``"aqem"`` (AQEM over all frames) or ``"online"``
            (every frame decimated in turn with a history term).
        options, **option_fields : a :class:`~animlod.TdagOptions` and/or its fields by name
            (``help(animlod.TdagOptions)``): ``history_weight`` (lambda >= 0 of the online
            construction: 0 gives every frame its own order, a very large value frame 0's order
            everywhere), ``affine_base`` (``"first"`` or ``"average"``), ``check_inversion``,
            ``boundary_quadrics``, ``use_motion_features`` (``governing="aqem"`` only) and
            ``weld`` (weld vertices equal in every frame into one TDAG vertex, as AQEM does;
            either way degenerate and repeated faces are dropped and non-manifold spots cut
            apart, so any indexed triangle mesh is taken, see :attr:`input_points`; a face
            repeated in the reverse turn, as double-sided cloth is exported, is simplified as one
            two-sided face, see :attr:`two_sided`).
        progress : ``progress(frames_done, F)`` called as the build goes.

        Raises
        ------
        ValueError naming the element: non-finite position, index out of range, every face
        degenerate, bad option.
        """
        if isinstance(governing, str) and governing in GOVERNING_CHOICES:
            option_fields["governing"] = governing
        elif isinstance(governing, (int, np.integer)) and not isinstance(governing, bool):
            option_fields.update(governing="frame", governing_frame=int(governing))
        else:
            raise ValueError(f"governing: expected one of {GOVERNING_CHOICES} or a frame number, got {governing!r}")
        options = resolve_options(TdagOptions, options, option_fields)
        core, raw = _core.build_temporal_dag(mesh.frames, mesh.faces, options, progress)
        return cls(core, TdagBuildReport(**raw))

    def to_bytes(self) -> bytes:
        """The contents of a .tdag file (versioned, checksummed)."""
        return self._core.to_bytes().tobytes()

    @classmethod
    def from_bytes(cls, data: bytes | bytearray | memoryview) -> TemporalDag:
        """Read .tdag contents; ValueError for something else, another format version or damage."""
        return cls(_core.TemporalDag.from_bytes(data))

    def save(self, path: str | os.PathLike) -> int:
        """Write the TDAG and its affine maps to ``path`` atomically; returns the size in bytes."""
        from .io.atomic import atomic_write

        with atomic_write(path, "wb") as handle:
            self._core.write(handle)  # a piece at a time: the file is never held whole
            return handle.tell()

    @classmethod
    def load(cls, path: str | os.PathLike) -> TemporalDag:
        """Read a .tdag file. Raises OSError when it cannot be read and ValueError (starting with
        the path) when it is not a TDAG, has another format version or is damaged."""
        path = os.fsdecode(path)
        with open(path, "rb"):  # the OSError Python raises: missing, a directory, no permission
            pass
        return cls(_core.TemporalDag.load(path))  # a chunk at a time: the file is never held whole

    # -- structure -------------------------------------------------------------------------------

    @property
    def frame_count(self) -> int:
        return int(self._core.frame_count)

    @property
    def vertex_count(self) -> int:
        return int(self._core.vertex_count)

    @property
    def face_count(self) -> int:
        return int(self._core.face_count)

    @property
    def collapse_count(self) -> int:
        return int(self._core.collapse_count)

    @property
    def governing(self) -> str:
        return str(self._core.governing)

    @property
    def affine_base(self) -> str:
        return str(self._core.affine_base)

    @property
    def faces(self) -> np.ndarray:
        """(M, 3) int32 faces over the TDAG's vertices (a two-sided face once: :attr:`two_sided`)."""
        return self._core.faces

    @property
    def two_sided(self) -> np.ndarray:
        """(M,) bool: faces the input also held turned over (a sheet with a face per side). The TDAG
        simplifies the front; queries hand out each live two-sided face's back after the other faces."""
        return self._core.two_sided

    @property
    def input_points(self) -> np.ndarray:
        """(input V,) int32 TDAG vertex standing for each input vertex (-1: used by no face).

        The TDAG's vertices are the input's welded points (copies along UV seams are one vertex;
        copies cut from non-manifold spots are several), so ``frame_positions(t)[input_points]``
        are the input frame's positions."""
        return self._core.input_points

    @property
    def affine_maps(self) -> np.ndarray:
        """(F, 3, 4) float64 least-squares affine map of every frame (Section 3)."""
        return self._core.affine_maps

    @property
    def children(self) -> np.ndarray:
        """(C, 2) int32 (kept, removed) child node of every collapse."""
        return self._core.children

    @property
    def stored_counts(self) -> dict:
        """Counts of the stored tagged values: dependency links, error runs, alive ranges."""
        return dict(self._core.stored_counts)

    def residuals(self, frame: int) -> np.ndarray:
        """(V, 3) float32 residual mesh of ``frame`` (the frame mapped back by its affine map)."""
        return self._core.residuals(frame)

    def frame_positions(self, frame: int) -> np.ndarray:
        """(V, 3) float32 the input frame rebuilt from the affine map and the residuals."""
        return self._core.frame_positions(frame)

    def error_bounds(self, frame: int) -> np.ndarray:
        """(C,) float64 error bound of every collapse at ``frame`` (asset units, inf where not alive)."""
        return self._core.error_bounds(frame)

    def alive(self, collapse: int) -> list[tuple[int, int]]:
        """The frame ranges [birth, death) on which ``collapse`` is in the hierarchy."""
        return [tuple(r) for r in self._core.alive(collapse)]

    def alive_mask(self, frame: int) -> np.ndarray:
        """(C,) bool: the collapses of ``frame``'s hierarchy."""
        return self._core.alive_mask(frame)

    def dependencies(self, collapse: int, frame: int) -> list[int]:
        """The collapse nodes that ``collapse`` needs at ``frame``."""
        return list(self._core.dependencies(collapse, frame))

    # -- queries -----------------------------------------------------------------------------------

    def cut(self, frame: int = 0, tolerance: float = 0.0) -> Cut:
        """A new, independent cursor at (frame, tolerance)."""
        cut = Cut(_core.TdagCut(self._core), self.frame_count)
        cut.query(frame, tolerance)
        return cut

    def query(self, frame: int, tolerance: float) -> TdagMesh:
        """Random query: the coarsest mesh of ``frame`` within ``tolerance`` (asset units).
        Sets the cursor that :meth:`advance` and :meth:`refine` move."""
        cursor = self.cut(frame, tolerance)
        self._cursor = cursor
        return cursor.mesh()

    def tolerance_for_faces(self, frame: int, faces: int) -> float:
        """The smallest tolerance (asset units) at which ``frame``'s mesh has at most ``faces``
        faces (the coarsest mesh's tolerance when none has so few): a query by size. The face
        count changes only where a collapse's error bound is passed, so the search bisects those
        bounds (a few hundred distinct values: ~10 queries). ValueError naming ``faces`` or
        ``frame``."""
        faces = whole_number("faces", faces, 1)
        bounds = self.error_bounds(frame)
        candidates = np.unique(np.concatenate([[0.0], bounds[np.isfinite(bounds)]]))
        cut = Cut(_core.TdagCut(self._core), self.frame_count)
        low, high = 0, len(candidates) - 1  # the answer's index, if the coarsest mesh is small enough
        while low < high:
            middle = (low + high) // 2
            if cut.query(frame, float(candidates[middle])).face_count <= faces:
                high = middle
            else:
                low = middle + 1
        return float(candidates[low])

    def query_view(
        self, frame: int, camera: Sequence[float], pixels: float = 1.0, focal_pixels: float = 1000.0
    ) -> TdagMesh:
        """Random query with a screen-space tolerance (see :meth:`Cut.query_view`); sets the cursor."""
        cursor = Cut(_core.TdagCut(self._core), self.frame_count)
        mesh = cursor.query_view(frame, camera, pixels, focal_pixels)
        self._cursor = cursor
        return mesh

    def advance(self, frame: int | None = None, level: int = 3) -> TdagMesh:
        """Move the cursor to ``frame`` (default: the next one) incrementally; see :meth:`Cut.advance`."""
        return self._require_cursor().advance(frame, level)

    def refine(self, tolerance: float) -> TdagMesh:
        """Give the cursor a new tolerance incrementally; see :meth:`Cut.refine`."""
        return self._require_cursor().refine(tolerance)

    @property
    def cursor(self) -> Cut:
        """The cut that :meth:`query`, :meth:`advance` and :meth:`refine` use."""
        return self._require_cursor()

    def _require_cursor(self) -> Cut:
        if self._cursor is None:
            raise ValueError("TemporalDag: no query yet (call query or query_view first)")
        return self._cursor

    # -- playing -------------------------------------------------------------------------------------

    def play(
        self, tolerance: float, first_frame: int = 0, frame_count: int | None = None, measure_error: bool = True
    ) -> PlayerReport:
        """Walk the frames from ``first_frame`` at ``tolerance`` and measure every approximation
        level, a fresh query, and the level-3 walk single- and double-buffered (in C++).
        ValueError naming ``first_frame`` when it is not a frame of the TDAG."""
        options = PlayerOptions(
            tolerance=tolerance,
            first_frame=_first_frame(first_frame, self.frame_count),
            frame_count=-1 if frame_count is None else frame_count,
            measure_error=measure_error,
        )
        raw = _core.play_temporal_dag(self._core, options)
        return PlayerReport(
            frames=int(raw["frames"]),
            levels=[LevelStats(**stats) for stats in raw["levels"]],
            full_query=LevelStats(**raw["full_query"]),
            mean_splits=float(raw["mean_splits"]),
            mean_collapses=float(raw["mean_collapses"]),
            sequential_seconds_per_frame=float(raw["sequential_seconds_per_frame"]),
            double_buffered_seconds_per_frame=float(raw["double_buffered_seconds_per_frame"]),
            median_update_seconds=float(raw["median_update_seconds"]),
            median_fresh_cut_seconds=float(raw["median_fresh_cut_seconds"]),
        )

    def player(self, tolerance: float, first_frame: int = 0) -> Player:
        """A double-buffered :class:`Player` from ``first_frame`` at ``tolerance``; ValueError
        naming ``first_frame`` when it is not a frame of the TDAG."""
        core = _core.TdagPlayer(self._core)
        core.start(tolerance, _first_frame(first_frame, self.frame_count))
        return Player(core)


def affine_split(mesh: AnimatedMesh, base: str = "first") -> tuple[np.ndarray, np.ndarray]:
    """Section 3: the least-squares affine map of every frame from the base mesh (``"first"`` or
    ``"average"``) and the residual meshes. Returns ``maps (F, 3, 4) float64`` and
    ``residuals (F, V, 3) float32``; frames whose map was singular use a translation only."""
    raw = _core.affine_split(mesh.frames, base)
    return raw["maps"], raw["residuals"]


def plot_tolerances(
    dag: TemporalDag, frame: int, tolerances: Sequence[float], path: str | os.PathLike, original: bool = True
) -> Path:
    """Draw ``frame`` at each tolerance side by side (PNG written atomically to ``path``), after
    the input frame itself when ``original``. Looks down -z (x right, y up). Returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from .io.atomic import atomic_write

    panels = []
    if original:
        panels.append((dag.frame_positions(frame), dag.faces, f"frame {frame}, {dag.face_count} faces"))
    cut = dag.cut(frame, 0.0)
    for tolerance in tolerances:
        mesh = cut.refine(float(tolerance))
        panels.append((mesh.positions, mesh.faces, f"tolerance {tolerance:.3g}: {mesh.face_count} faces"))
    corners = dag.frame_positions(frame)
    low, high = corners.min(axis=0), corners.max(axis=0)
    figure = plt.figure(figsize=(4 * len(panels), 4.5))
    for index, (positions, faces, title) in enumerate(panels):
        axes = figure.add_subplot(1, len(panels), index + 1, projection="3d")
        axes.add_collection3d(
            Poly3DCollection(
                positions[faces], facecolors=(0.75, 0.75, 0.8, 1.0), edgecolors=(0, 0, 0, 0.25), linewidths=0.2
            )
        )
        axes.set_xlim(low[0], high[0])
        axes.set_ylim(low[1], high[1])
        axes.set_zlim(low[2], high[2])
        axes.set_box_aspect(np.maximum(high - low, 1e-9))
        axes.view_init(elev=90, azim=-90)
        axes.set_axis_off()
        axes.set_title(title, fontsize=9)
    with atomic_write(path, "wb") as handle:
        figure.savefig(handle, format="png", dpi=100, bbox_inches="tight")
    plt.close(figure)
    return Path(path)
