"""Table 1 of seeds/004 for a face LoD chain: per level, triangles, vertices, animated regions,
lattice sizes, the largest time per frame to animate over an expression sequence ("MAT") and
the surface error of the animated level against the full face.

Times are wall-clock per frame of :meth:`LevelAnimator.frame` (MPA intensities to control
displacements, then the core's rational FFD over the level's vertices); each frame is timed
``repeats`` times and the fastest kept, which removes interruptions by other processes but no
work, and the largest over the frames is the MAT. Errors are symmetric Hausdorff distances per
frame (:func:`animlod.metrics.surface_error`) as a fraction of the full face's bounding-box
diagonal, the largest over the frames.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .. import _core
from ..metrics import surface_error
from ..model import AnimatedMesh, spread_frames
from .chain import FaceLodChain
from .mpa import MpaAnimation
from .rig import LevelAnimator


@dataclass
class LevelMeasurement:
    """One row of Table 1.

    Attributes
    ----------
    geometry_level, animation_level : the level pair measured.
    triangles, vertices : size of the mesh.
    animated_regions : regions moved by at least one MPA at this level.
    lattices : e.g. "9x27 + 8x8": lattices of 27 and of 8 control points.
    active_mpas : MPAs processed (the others are skipped).
    max_frame_seconds, median_frame_seconds : time to animate one frame (MAT and typical).
    hausdorff : largest symmetric Hausdorff distance over the frames, fraction of the diagonal.
    hausdorff_units : the same in asset units.
    focus_error : largest distance over the frames from the full face's vertices in the focus
        regions (the mobile face mask, say) to the level's surface, fraction of the diagonal;
        NaN when no focus was given.
    """

    geometry_level: int
    animation_level: int
    triangles: int
    vertices: int
    animated_regions: int
    lattices: str
    active_mpas: int
    max_frame_seconds: float
    median_frame_seconds: float
    hausdorff: float
    hausdorff_units: float
    focus_error: float = float("nan")


def time_frames(animator: LevelAnimator, intensities: np.ndarray, repeats: int = 5) -> np.ndarray:
    """(T,) seconds to animate each frame, the fastest of ``repeats`` runs."""
    best = np.full(len(intensities), np.inf)
    for _ in range(repeats):  # O(repeats x T) calls into the core, each vectorised
        for frame, row in enumerate(intensities):
            start = time.perf_counter()
            animator.frame(row)
            best[frame] = min(best[frame], time.perf_counter() - start)
    return best


def time_animators(animators: list[LevelAnimator], intensities: np.ndarray, repeats: int = 5) -> list[np.ndarray]:
    """Per animator, (T,) seconds per frame, the fastest of ``repeats`` runs; the animators take
    turns within every run, so a burst of load from other processes hits them all alike."""
    best = [np.full(len(intensities), np.inf) for _ in animators]
    for _ in range(repeats):  # O(repeats x animators x T) calls into the core
        for times, animator in zip(best, animators):
            for frame, row in enumerate(intensities):
                start = time.perf_counter()
                animator.frame(row)
                times[frame] = min(times[frame], time.perf_counter() - start)
    return best


def lattice_summary(animator: LevelAnimator) -> str:
    """ "9x27 + 8x8" for 9 lattices of 27 control points and 8 of 8; "-" when none."""
    if not animator.animates:
        return "-"
    counts = np.prod(animator.sizes, axis=1)
    values, repeats = np.unique(counts, return_counts=True)
    return " + ".join(f"{r}x{v}" for v, r in sorted(zip(values.tolist(), repeats.tolist()), reverse=True))


def animate(animator: LevelAnimator, faces: np.ndarray, animation: MpaAnimation) -> AnimatedMesh:
    """The level's frames over ``animation`` as an AnimatedMesh (one core call)."""
    return AnimatedMesh(faces, animator.frames(animation.intensities), fps=animation.fps)


def measure_level(
    chain: FaceLodChain,
    geometry_level: int,
    animation_level: int,
    animation: MpaAnimation,
    reference: AnimatedMesh | None = None,
    repeats: int = 5,
    samples: int = 20000,
    error_frames: int = 0,
    focus: np.ndarray | None = None,
    times: np.ndarray | None = None,
) -> LevelMeasurement:
    """Measure one (geometry, animation) level pair: time over every frame of ``animation``,
    error over ``error_frames`` evenly spaced ones and each MPA's peak (0: all; :func:`every_nth`);
    ``reference`` is the full face animated at full detail over those frames (computed when
    None); ``focus (V,) bool`` marks the full face's vertices whose distance to the level is
    reported as ``focus_error``; ``times`` (T,) are the frame times when already measured
    (:func:`time_animators`)."""
    sampled = every_nth(animation, error_frames)
    if reference is None:
        reference = animate(chain.animator(0, 0), chain.rig.faces, sampled)
    animation_level = chain.animation_level(geometry_level, animation_level)
    animator = chain.animator(geometry_level, animation_level)
    level = chain.geometry[geometry_level]
    if times is None:
        times = time_frames(animator, animation.intensities, repeats)
    simplified = animate(animator, level.faces, sampled)
    error = surface_error(reference, simplified, samples=samples)
    worst = int(np.argmax(error.hausdorff))
    focus_error = float("nan")
    if focus is not None:
        focus_error = float(np.max(focus_distances(reference, simplified, focus) / error.diagonal))
    return LevelMeasurement(
        geometry_level=geometry_level,
        animation_level=animation_level,
        triangles=level.triangle_count,
        vertices=level.vertex_count,
        animated_regions=len(animator.regions),
        lattices=lattice_summary(animator),
        active_mpas=int(animator.active_mpas.size),
        max_frame_seconds=float(times.max()),
        median_frame_seconds=float(np.median(times)),
        hausdorff=float(error.relative_hausdorff[worst]),
        hausdorff_units=float(error.hausdorff[worst]),
        focus_error=focus_error,
    )


def focus_distances(reference: AnimatedMesh, simplified: AnimatedMesh, focus: np.ndarray) -> np.ndarray:
    """(F,) per frame, the largest distance from ``reference``'s vertices where ``focus`` is True
    to ``simplified``'s surface."""
    # Every frame in one call: the core refits one tree from frame to frame.
    squared = _core.point_mesh_squared_distance(reference.frames[:, focus], simplified.frames, simplified.faces)
    return np.sqrt(squared.max(axis=1, initial=0.0))


def measure_chain(
    chain: FaceLodChain, animation: MpaAnimation, repeats: int = 5, samples: int = 20000, error_frames: int = 0
) -> list[LevelMeasurement]:
    """Table 1: every geometry level at the finest animation level it allows."""
    reference = animate(chain.animator(0, 0), chain.rig.faces, every_nth(animation, error_frames))
    levels = range(len(chain.geometry))
    times = time_animators([chain.animator(g) for g in levels], animation.intensities, repeats)
    return [
        measure_level(
            chain,
            g,
            chain.geometry[g].animation_floor,
            animation,
            reference,
            repeats,
            samples,
            error_frames,
            times=times[g],
        )
        for g in levels
    ]


def measured_frames(weights: np.ndarray, count: int) -> np.ndarray:
    """Sorted indices of the frames an animation's error is measured on, for ``weights (T, N)``
    (blendshape weights or MPA intensities): ``count`` evenly spaced frames and, besides them,
    the frame where each driven target or MPA has its largest absolute weight; every frame when
    ``count`` is 0 or at least T.

    Evenly spaced frames alone can miss every peak: a pose folder's animation raises one target
    at a time from rest and back, and 4 of its 45 frames were all rest poses."""
    frame_count = len(weights)
    if count <= 0 or count >= frame_count:
        return np.arange(frame_count)
    magnitudes = np.abs(weights)
    peaks = magnitudes.argmax(axis=0)[magnitudes.max(axis=0) > 0.0]
    return np.union1d(spread_frames(frame_count, count), peaks)


def every_nth(animation: MpaAnimation, count: int) -> MpaAnimation:
    """The frames of ``animation`` its errors are measured on (:func:`measured_frames`: ``count``
    evenly spaced ones and each MPA's peak; all of them when ``count`` is 0)."""
    picked = measured_frames(animation.intensities, count)
    if len(picked) == animation.frame_count:
        return animation
    return MpaAnimation(animation.mpa_names, animation.intensities[picked], animation.fps)


def animation_errors(chain: FaceLodChain, animation: MpaAnimation) -> list[float]:
    """Per active tree level: the largest vertex distance (asset units) over the frames between
    the full face animated at that level and at level 0 (what deactivating regions loses)."""
    full = chain.animator(0, 0).frames(animation.intensities)
    errors = []
    for level in range(chain.tree.level_count):
        frames = chain.rig.animator(active=chain.tree.active(level)).frames(animation.intensities)
        errors.append(float(np.linalg.norm(frames - full, axis=2).max(initial=0.0)))
    return errors
