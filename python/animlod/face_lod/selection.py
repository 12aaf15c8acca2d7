"""Runtime choice of a face's levels from the view (seeds/004, Sections 4.2 and 4.2.3, Figure 6).

The viewpoint gives the projected size of the face (its bounding sphere's diameter as a
fraction of the viewport height, the "screen coverage" of MSFT_lod). From it the geometry level
and the animation level (active tree) are chosen from thresholds derived from each level's
error in asset units; then the animation level is lowered to the one the geometry level allows
(Figure 6: the animation depends on the geometric description of its regions), and the frame
step of frame skipping grows as the face gets smaller on screen.

The coverage-to-level rule is the one of the LoD GLB (level i is used while the coverage is at
least c_i, thresholds decreasing, the last 0); it and the frame step are the core's runtime LoD
selector's (cpp/include/animlod/lod_selector.hpp), so a face picks its levels as the crowd and
engines do.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .. import _core


@dataclass
class Camera:
    """A perspective camera: vertical field of view (radians) and viewport height (pixels)."""

    vertical_fov: float = math.radians(60.0)
    viewport_height_px: int = 720


@dataclass
class FaceSelection:
    """What to draw and animate for one face in one frame.

    Attributes
    ----------
    geometry_level : index of the mesh level.
    animation_level : active tree level (never finer than the geometry level allows).
    frame_step : update the animation every ``frame_step`` frames (1: every frame).
    coverage : the face's projected size, fraction of the viewport height.
    """

    geometry_level: int
    animation_level: int
    frame_step: int
    coverage: float


def projected_coverage(radius: float, distance: float, camera: Camera) -> float:
    """Fraction of the viewport height covered by a sphere of ``radius`` at ``distance`` (both in
    asset units): the sphere's angular diameter over the field of view, in tangent space."""
    if not (distance > 0.0 and radius > 0.0):
        raise ValueError(f"projected coverage: radius and distance must be positive, got {radius} and {distance}")
    if distance <= radius:
        return math.inf  # the camera is inside the sphere
    half_angle = math.asin(radius / distance)
    return math.tan(half_angle) / math.tan(0.5 * camera.vertical_fov)


def coverage_thresholds(errors: Sequence[float], radius: float, camera: Camera, pixel_tolerance: float) -> list[float]:
    """MSFT_screencoverage thresholds ``[c_0, ..., c_L]`` for levels with ``errors`` (asset units).

    Level i+1 may replace level i once its error projects to at most ``pixel_tolerance`` pixels:
    an error e on a face of coverage c spans ``e c H / (2 radius)`` pixels, so
    ``c_i = 2 radius tolerance / (e_{i+1} H)``: the LoD GLB's rule
    (:func:`animlod.io.gltf_lod.screen_coverages`, the face's diameter as its size), clamped to
    MSFT_lod's range [0, 1], non-increasing (a coarser level is never assumed better than a finer
    one), the last 0. Unclamped, a level 1 within float rounding of the face put a threshold of
    4e10 in the GLB (and one of error 0 an infinity, which JSON cannot hold).
    """
    from ..io.gltf_lod import screen_coverages

    return screen_coverages(list(errors), 2.0 * radius, pixel_tolerance, camera.viewport_height_px)


def level_for_coverage(thresholds: Sequence[float], coverage: float) -> int:
    """The first level i whose threshold ``thresholds[i] <= coverage`` (the LoD GLB rule)."""
    return int(_core.level_for_coverage(np.asarray(thresholds, dtype=np.float32), coverage))


def frame_step(coverage: float, full_rate_coverage: float, max_step: int) -> int:
    """Frame skipping (Section 4.2.3): a face covering at least ``full_rate_coverage`` of the
    viewport height is animated every frame; smaller ones every ``floor(full / coverage)``
    frames, at most ``max_step`` (the step grows linearly with the view distance)."""
    rate = _core.AnimationRateOptions(full_rate_coverage=full_rate_coverage, max_interval=max_step)
    return int(_core.animation_update_interval(coverage, rate))


def skipped_frames(frame_count: int, step: int) -> np.ndarray:
    """(F,) the animation frame shown at each display frame with frame skipping: frame
    ``(i // step) * step``, so only every ``step``-th frame is computed. The animation keeps its
    duration (the paper's drawback, durations varying with distance, does not arise: a skipped
    frame repeats the last computed pose instead of advancing the clip)."""
    if step < 1:
        raise ValueError(f"frame step: must be at least 1, got {step}")
    return (np.arange(frame_count) // step) * step


def select_face_levels(
    coverage: float,
    geometry_thresholds: Sequence[float],
    animation_thresholds: Sequence[float],
    animation_floors: Sequence[int],
    full_rate_coverage: float = 0.25,
    max_step: int = 4,
) -> FaceSelection:
    """Figure 6 at run time: the geometry level and the animation level from the face's
    projected ``coverage``, the animation level lowered to the finest one the geometry level
    allows (``animation_floors[g]``), and the frame step of frame skipping."""
    if len(animation_floors) != len(geometry_thresholds):
        raise ValueError(f"animation floors: {len(animation_floors)} for {len(geometry_thresholds)} geometry levels")
    if not coverage >= 0.0:
        raise ValueError(f"coverage: must be a number >= 0, got {coverage}")
    outside = [floor for floor in animation_floors if not 0 <= floor < len(animation_thresholds)]
    if outside:
        raise ValueError(f"animation floors: {outside[0]} outside [0, {len(animation_thresholds)})")
    geometry = level_for_coverage(geometry_thresholds, coverage)
    animation = max(level_for_coverage(animation_thresholds, coverage), int(animation_floors[geometry]))
    return FaceSelection(geometry, animation, frame_step(coverage, full_rate_coverage, max_step), coverage)
