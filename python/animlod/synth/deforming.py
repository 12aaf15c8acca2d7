"""Small deforming meshes with known motion, for unit tests: bend, twist, rigid translation.

Each mesh is one closed 2-manifold with outward (counter-clockwise) faces, and frame 0 is the
undeformed shape.
"""

from __future__ import annotations

import numpy as np

from .. import rotations
from ..model import AnimatedMesh, Motion, Skeleton, SkinnedMesh
from .geometry import cross_section, icosphere, orthonormal_frame, tube

_UP = np.array([0.0, 1.0, 0.0])


def _frame_numbers(frames: int) -> np.ndarray:
    """``(F,)`` frame numbers 0 .. F - 1; ValueError for F < 1."""
    if frames < 1:
        raise ValueError(f"frames: must be >= 1, got {frames}")
    return np.arange(frames)


def _ramp(frames: int) -> np.ndarray:
    """``(F,)`` from 0 at frame 0 to 1 at the last frame (0 for a single frame)."""
    return _frame_numbers(frames) / max(frames - 1, 1)


def _capped_prism(length: float, half_width: float, rings: int, segments: int, shape: str) -> tuple:
    """A closed prism along +Y from y = 0 to ``length`` with flat caps (fans to a centre vertex)."""
    if rings < 2:
        raise ValueError(f"rings: need at least 2, got {rings}")
    heights = np.linspace(0.0, length, rings)
    centres = heights[:, None] * _UP
    radii = np.full(rings, half_width)
    poles = np.array([[0.0, 0.0, 0.0], [0.0, length, 0.0]])
    frame = orthonormal_frame(_UP, [1.0, 0.0, 0.0])
    bar = tube(centres, radii, radii, frame, poles, cross_section(segments, shape))
    return bar.positions, bar.faces


def bending_cylinder_skinned(
    frames: int = 16,
    rings: int = 24,
    segments: int = 16,
    max_angle: float = np.pi / 2,
    fps: float = 30.0,
    shape: str = "ellipse",
) -> tuple[SkinnedMesh, Motion]:
    """A capped cylinder (radius 0.25, length 2, along +Y from the origin) on two bones.

    Bone ``"Root"`` at the origin holds the lower half; bone ``"Bend"`` at y = 1 holds the upper
    half and turns about +Z from 0 at frame 0 to ``max_angle`` at the last frame, linearly. The
    weights blend linearly over 0.8 <= y <= 1.2 (K = 2 influences). ``shape="square"`` makes it a
    box limb (half width 0.25, ``segments`` a multiple of 8 keeps its corners) whose sides facing
    +Z and -Z stay in their planes as it bends, as a modelled character's box leg at the knee.

    Returns the skin and the motion; ``skin.bake(motion)`` is :func:`bending_cylinder`.
    """
    positions, faces = _capped_prism(2.0, 0.25, rings, segments, shape)
    skeleton = Skeleton(["Root", "Bend"], [-1, 0], [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    upper = np.clip((positions[:, 1] - 0.8) / 0.4, 0.0, 1.0)
    joints = np.broadcast_to(np.array([0, 1], np.int32), (len(positions), 2))
    skin = SkinnedMesh(
        rest_positions=positions,
        faces=faces,
        joints=joints,
        weights=np.stack([1.0 - upper, upper], axis=-1),
        inverse_bind=np.linalg.inv(skeleton.rest_world_transforms()),
        skeleton=skeleton,
    )
    local = rotations.identity((frames, 2))
    local[:, 1] = rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), max_angle * _ramp(frames))
    motion = Motion(skeleton, np.zeros((frames, 3)), local, fps=fps, name="bend")
    return skin, motion


def bending_cylinder(
    frames: int = 16, rings: int = 24, segments: int = 16, max_angle: float = np.pi / 2, fps: float = 30.0
) -> AnimatedMesh:
    """The cylinder of :func:`bending_cylinder_skinned`, baked: ``(F, rings * segments + 2, 3)``.

    Frame 0 is straight; the upper half bends towards -X about the middle.
    """
    skin, motion = bending_cylinder_skinned(frames, rings, segments, max_angle, fps)
    return skin.bake(motion)


def kicking_box_leg(frames: int = 16, rings: int = 12) -> AnimatedMesh:
    """The square limb of :func:`bending_cylinder_skinned` (``rings`` rings, 8 segments) straight
    for the first three quarters of ``frames``, then kicking: its knee bent from 60 to 150 degrees
    over the last quarter. Its sides facing +Z and -Z stay in their planes throughout, so folding
    their triangles across the knee costs no quadric error (a modelled character's box leg)."""
    skin, _ = bending_cylinder_skinned(rings=rings, segments=8, shape="square")
    bent = max(frames // 4, 1)
    angles = np.zeros(len(_frame_numbers(frames)))
    angles[frames - bent :] = np.radians(np.linspace(60.0, 150.0, bent))
    turns = rotations.identity((frames, 2))
    turns[:, 1] = rotations.from_axis_angle(np.array([0.0, 0.0, 1.0]), angles)
    return skin.bake(Motion(skin.skeleton, np.zeros((frames, 3)), turns, fps=30.0, name="kick"))


def twisting_bar(
    frames: int = 16,
    rings: int = 16,
    segments: int = 16,
    max_angle: float = np.pi / 2,
    length: float = 2.0,
    half_width: float = 0.1,
    fps: float = 30.0,
) -> AnimatedMesh:
    """A capped square bar along +Y from the origin that twists about its long axis.

    A point at height y turns about +Y by ``max_angle * (y / length) * f / (F - 1)`` at frame f:
    the base stays put, the top turns most, frame 0 is untwisted. ``segments`` a multiple of 8
    keeps the square's corners.
    """
    positions, faces = _capped_prism(length, half_width, rings, segments, "square")
    angle = max_angle * _ramp(frames)[:, None] * (positions[:, 1] / length)[None]  # (F, V)
    cos, sin = np.cos(angle), np.sin(angle)
    x, y, z = positions.T
    frames_xyz = np.stack([cos * x + sin * z, np.broadcast_to(y, angle.shape), -sin * x + cos * z], axis=-1)
    return AnimatedMesh(faces, frames_xyz, fps=fps)


def translating_mesh(
    frames: int = 8,
    subdivisions: int = 2,
    radius: float = 0.5,
    step: tuple[float, float, float] = (0.1, 0.05, 0.0),
    fps: float = 30.0,
) -> AnimatedMesh:
    """An icosphere about the origin moving rigidly by ``step`` per frame (frame f at ``f * step``)."""
    positions, faces = icosphere(subdivisions, radius)
    offsets = _frame_numbers(frames)[:, None] * np.asarray(step, dtype=np.float64)  # (F, 3)
    return AnimatedMesh(faces, positions[None].astype(np.float64) + offsets[:, None], fps=fps)
