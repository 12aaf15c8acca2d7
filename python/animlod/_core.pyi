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
    feature_weighting: str = "amplitude",
    max_feature_weight: float = 4.0,
    noise_mads: float = 30.0,
) -> dict[str, Any]:
    """Motion features of (F, V, 3) frames and (M, 3) faces: edges, angle_change, connected,
    threshold, vertex_feature, feature_sizes, vertex_weights, amplitude."""

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
    feature_weighting: str = "amplitude",
    max_feature_weight: float = 4.0,
    noise_mads: float = 30.0,
) -> dict[str, Any]:
    """AQEM over all frames, any topology: {"levels": [...], "collapses": {...}, "frames_used",
    "vertex_weights", "preparation"}."""

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
