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
