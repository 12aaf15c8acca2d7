"""Type stubs of the C++ extension animlod._core (see cpp/bindings/)."""

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

def bake_lbs(
    rest_positions: npt.ArrayLike,
    joints: npt.ArrayLike,
    weights: npt.ArrayLike,
    skin_matrices: npt.ArrayLike,
) -> npt.NDArray[np.float32]:
    """Linear blend skinning: (V, 3), (V, K), (V, K), (T, J, 4, 4) -> (T, V, 3) float32.

    Index arrays may be int32 or int64; a value outside int32 raises ValueError.
    """

def motion_features(
    frames: npt.ArrayLike,
    faces: npt.ArrayLike,
    *,
    feature_threshold: float = 0.0,
    min_angle_change: float = 0.017453292519943295,
    boundary_is_feature: bool = True,
) -> dict[str, Any]:
    """Motion features of (F, V, 3) frames and (M, 3) faces: edges, angle_change, connected,
    threshold, vertex_feature, feature_sizes, vertex_weights."""

def simplify_animated(
    frames: npt.ArrayLike,
    faces: npt.ArrayLike,
    *,
    target_ratios: Sequence[float] = [0.5],
    target_face_counts: Sequence[int] = [],
    max_error: float = ...,
    use_motion_features: bool = True,
    feature_threshold: float = 0.0,
    min_angle_change: float = 0.017453292519943295,
    boundary_is_feature: bool = True,
    boundary_quadrics: bool = True,
    check_inversion: bool = True,
    strict_inversion: bool = False,
    max_frames: int = 0,
    frame_subset: Sequence[int] = [],
    locked: npt.ArrayLike | None = None,
    importance: npt.ArrayLike | None = None,
    attributes: npt.ArrayLike | None = None,
    skin_joints: npt.ArrayLike | None = None,
    skin_weights: npt.ArrayLike | None = None,
    progress: Callable[[int, int], None] | None = None,
    placement: str = "optimal",
    position_attributes: npt.ArrayLike | None = None,
    face_groups: npt.ArrayLike | None = None,
    weld: bool = True,
    guarded: npt.ArrayLike | None = None,
) -> dict[str, Any]:
    """AQEM over all frames, any topology: {"levels": [...], "collapses": {...}, "frames_used",
    "vertex_weights", "preparation"}."""

def ffd_local_coordinates(points: npt.ArrayLike, box: npt.ArrayLike) -> npt.NDArray[np.float32]:
    """Local coordinates (V, 3) of (V, 3) points in a (4, 3) box (origin, S, T, U axes)."""

def ffd_evaluate(
    local: npt.ArrayLike, control_points: npt.ArrayLike, weights: npt.ArrayLike | None = None
) -> npt.NDArray[np.float32]:
    """Rational Bezier volume of (l, m, n, 3) control points (weights (l, m, n)) at (V, 3) local coordinates."""

def ffd_displace(
    rest: npt.ArrayLike,
    local: npt.ArrayLike,
    vertex_lattice: npt.ArrayLike,
    sizes: npt.ArrayLike,
    displacements: npt.ArrayLike,
    weights: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float32]:
    """Rest (V, 3) plus the rational FFD of each vertex's lattice displacements ((C, 3) or (F, C, 3)):
    (V, 3) or (F, V, 3)."""

def ffd_fit(
    local: npt.ArrayLike,
    targets: npt.ArrayLike,
    size: Sequence[int],
    weights: npt.ArrayLike | None = None,
    *,
    prior: npt.ArrayLike | None = None,
    smoothness: float = 0.001,
    ridge: float = 0.001,
) -> npt.NDArray[np.float64]:
    """Regularised least-squares control points (l, m, n, 3) reproducing (V, 3) targets at (V, 3) local coordinates."""

# TDAG (cpp/bindings/bind_tdag.cpp)

class TdagOptions:
    """Options of build_temporal_dag (animlod/tdag.hpp, TdagOptions)."""

    governing: str  # "first", "average", "frame", "aqem" or "online"
    governing_frame: int
    history_weight: float
    affine_base: str  # "first" or "average"
    boundary_quadrics: bool
    check_inversion: bool
    use_motion_features: bool
    weld: bool
    def __init__(self) -> None: ...

class TemporalDag:
    """A TDAG (animlod/tdag.hpp): immutable; copies share the data."""

    frame_count: int
    vertex_count: int
    face_count: int
    collapse_count: int
    node_count: int
    governing: str
    affine_base: str
    faces: npt.NDArray[np.int32]  # (M, 3)
    input_points: npt.NDArray[np.int32]  # (input V,)
    affine_maps: npt.NDArray[np.float64]  # (F, 3, 4)
    children: npt.NDArray[np.int32]  # (C, 2)
    representatives: npt.NDArray[np.int32]  # (V + C,)
    stored_counts: dict[str, int]
    def residuals(self, frame: int) -> npt.NDArray[np.float32]: ...
    def frame_positions(self, frame: int) -> npt.NDArray[np.float32]: ...
    def alive(self, collapse: int) -> list[tuple[int, int]]: ...
    def alive_mask(self, frame: int) -> npt.NDArray[np.bool_]: ...
    def dependencies(self, collapse: int, frame: int) -> list[int]: ...
    def parent(self, node: int, frame: int) -> int: ...
    def error_bounds(self, frame: int) -> npt.NDArray[np.float64]: ...
    def to_bytes(self) -> bytes: ...
    @staticmethod
    def from_bytes(data: bytes) -> TemporalDag: ...

def build_temporal_dag(
    frames: npt.ArrayLike,
    faces: npt.ArrayLike,
    options: TdagOptions = ...,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[TemporalDag, dict[str, Any]]:
    """(TemporalDag, report: collapse_counts (F,), max_cost (C,), use_counts (C,), seconds_*)."""

def affine_split(frames: npt.ArrayLike, base: str = "first") -> dict[str, Any]:
    """Section 3: maps (F, 3, 4), residuals (F, V, 3), translation_only (F,)."""

class TdagCut:
    """A cut of a TDAG (animlod/tdag.hpp, TdagCut)."""

    frame: int
    tolerance: float
    has_query: bool
    active_vertex_count: int
    active_face_count: int
    error_bound: float
    last_split_count: int
    last_collapse_count: int
    def __init__(self, dag: TemporalDag) -> None: ...
    def copy(self) -> TdagCut: ...
    def query(self, frame: int, tolerance: float) -> None: ...
    def query_view(
        self, frame: int, camera: Sequence[float], pixels: float = 1.0, focal_pixels: float = 1000.0
    ) -> None: ...
    def advance(self, frame: int) -> None: ...
    def refine(self, tolerance: float) -> None: ...
    def refine_view(self, camera: Sequence[float], pixels: float = 1.0, focal_pixels: float = 1000.0) -> None: ...
    def approximate(self, frame: int, level: int = 3) -> dict[str, Any]: ...
    def mesh(self) -> dict[str, Any]: ...
    def input_vertex_map(self) -> npt.NDArray[np.int32]: ...

class TdagPlayer:
    """Double-buffered player (animlod/tdag_player.hpp)."""

    frame: int
    done: bool
    def __init__(self, dag: TemporalDag) -> None: ...
    def start(self, tolerance: float, first_frame: int = 0) -> None: ...
    def next(self, level: int = 3) -> dict[str, Any]: ...
    def next_available(self) -> tuple[dict[str, Any], int]: ...

def play_temporal_dag(
    dag: TemporalDag, tolerance: float, first_frame: int = 0, frame_count: int = -1, measure_error: bool = True
) -> dict[str, Any]:
    """Levels 1-3, a fresh query and the level-3 walk single- and double-buffered (PlayerReport)."""
# Runtime LoD selection (cpp/include/animlod/lod_selector.hpp).

class LodCamera:
    """A perspective camera as the LoD selector sees it."""

    position: list[float]
    vertical_fov: float
    viewport_height: float
    def __init__(
        self, position: Sequence[float] = [0.0, 0.0, 0.0], vertical_fov: float = 0.8, viewport_height: float = 720.0
    ) -> None: ...

class ProjectedSphere:
    """Distance (asset units) and coverage (fraction of the viewport height) of a bounding sphere."""

    @property
    def distance(self) -> float: ...
    @property
    def coverage(self) -> float: ...

def focal_length_pixels(camera: LodCamera) -> float:
    """Pixels per asset unit at distance 1: viewport_height / (2 tan(vertical_fov / 2))."""

def project_sphere(camera: LodCamera, center: Sequence[float], radius: float) -> ProjectedSphere:
    """Distance and coverage tan(asin(r / d)) / tan(fov / 2) of a sphere; inf coverage inside it."""

def screen_error_pixels(error: float, distance: float, focal_length_px: float) -> float:
    """error / distance * focal_length_px; inf for distance <= 0."""

def level_for_coverage(coverages: npt.ArrayLike, coverage: float) -> int:
    """Finest level i with coverage >= coverages[i] (MSFT_screencoverage), else the coarsest."""

def level_for_error(errors: npt.ArrayLike, distance: float, focal_length_px: float, pixel_error: float = 1.0) -> int:
    """Coarsest level whose error / distance * focal_length_px <= pixel_error, else 0."""

class LodSelectorOptions:
    """Options of LodSelector: relative hysteresis dead band and the pixel error budget."""

    hysteresis: float
    pixel_error: float
    def __init__(self, hysteresis: float = 0.15, pixel_error: float = 1.0) -> None: ...

class LodSelector:
    """Per-character LoD state with hysteresis (no flicker at a threshold)."""

    def __init__(self, options: LodSelectorOptions = ...) -> None: ...
    def select_by_coverage(self, coverages: npt.ArrayLike, coverage: float) -> int: ...
    def select_by_error(self, errors: npt.ArrayLike, distance: float, focal_length_px: float) -> int: ...
    @property
    def level(self) -> int: ...
    @property
    def options(self) -> LodSelectorOptions: ...
    def reset(self) -> None: ...

class AnimationRateOptions:
    """Options of animation_update_interval."""

    full_rate_coverage: float
    max_interval: int
    def __init__(self, full_rate_coverage: float = 0.25, max_interval: int = 8) -> None: ...

def animation_update_interval(coverage: float, options: AnimationRateOptions = ...) -> int:
    """Frames between pose updates: 1 at or above full_rate_coverage, then floor(full / coverage), capped."""

def animation_update_due(frame: int, instance: int, interval: int) -> bool:
    """Whether an instance updating every `interval` frames updates at `frame` (staggered by instance)."""

# Clip sampling, forward kinematics and the skinning palette (cpp/include/animlod/pose.hpp).

def sample_keyframes(
    times: npt.ArrayLike,
    values: npt.ArrayLike,
    interpolation: str,
    at: npt.ArrayLike,
    rotation: bool = False,
    blend: str = "slerp",
) -> npt.NDArray[np.float32]:
    """One glTF sampler at times (T,): (N,), (N, C) or (N, 3, C) -> (T, C) float32."""

def forward_kinematics(
    parents: npt.ArrayLike,
    translations: npt.ArrayLike,
    rotations: npt.ArrayLike,
    scales: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float32]:
    """World transforms (T, J, 4, 4) float32 (numpy layout) from local T, R, S of (T, J, .) poses."""

def skin_palette(
    world: npt.ArrayLike, inverse_bind: npt.ArrayLike, joint_nodes: npt.ArrayLike | None = None
) -> npt.NDArray[np.float32]:
    """world[joint_nodes[s]] @ inverse_bind[s]: (T, J, 4, 4), (S, 4, 4) -> (T, S, 4, 4) float32."""

class MotionRefitProblem:
    """One motion LoD level's per-frame re-fit problem (Eqs. 4-8) over P points, point 0 the root;
    holds int32/float64 copies of the arrays (cpp/include/animlod/motion_refit.hpp)."""

    def __init__(
        self,
        point_count: int,
        length_pairs: npt.ArrayLike,
        key_lengths: npt.ArrayLike,
        coincident_pairs: npt.ArrayLike,
        handed_quads: npt.ArrayLike,
        key_volumes: npt.ArrayLike,
        angle_triples: npt.ArrayLike,
        key_cosines: npt.ArrayLike,
        distance_weight: float,
        string_weight: float,
        angle_weight: float,
        length_scale: float,
    ) -> None: ...
    @property
    def point_count(self) -> int: ...
    @property
    def equality_count(self) -> int: ...

class MotionRefitOptions:
    """How the per-frame SLSQP solves run (nlopt's LD_SLSQP); defaults from the C++ struct."""

    hard_constraints: bool
    ftol_rel: float
    max_evaluations: int
    feasibility_tolerance: float
    warm_start: bool
    precondition: bool
    eliminate_points: bool
    chunk_frames: int
    threads: int
    def __init__(self) -> None: ...

def motion_refit_objective(
    problem: MotionRefitProblem, x: npt.ArrayLike, original: npt.ArrayLike
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """E (Eq. 5) per frame (F,) and its gradient (F, P, 3) at x (F, P, 3) against original (F, P, 3)."""

def motion_refit_equalities(
    problem: MotionRefitProblem, x: npt.ArrayLike
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Hard equalities scaled by 1/L (F, m) and their Jacobian (F, m, P, 3)."""

def motion_refit_handedness(
    problem: MotionRefitProblem, x: npt.ArrayLike
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Handedness inequalities (<= 0 when kept) (F, Nh) and their Jacobian (F, Nh, P, 3)."""

def motion_refit_solve(
    problem: MotionRefitProblem,
    original: npt.ArrayLike,
    fallback: npt.ArrayLike,
    options: MotionRefitOptions = ...,
    cold_starts: npt.ArrayLike | None = None,
) -> dict[str, Any]:
    """SLSQP per frame on several threads: positions (T, P, 3), values (T,), evaluations (T,),
    failures [(frame, reason, fell_back)]."""
