"""A few seconds of talking, blinking and brow raising for :func:`animlod.synth.face`.

Each action is a displacement field over named regions (smoothed over the mesh so that
neighbouring regions blend) times a scalar curve of time; the jaw and the eyeballs rotate
about hinges found from the mesh. Regions in ``STILL_REGIONS`` never move.
"""

from __future__ import annotations

import numpy as np

from .. import rotations
from ..model import AnimatedMesh
from .curves import bump
from .face_model import STILL_REGIONS, FaceModel

_JAW_OPENING = 0.28  # radians at the widest


def _neighbour_average(field: np.ndarray, faces: np.ndarray, iterations: int) -> np.ndarray:
    """Jacobi smoothing of a per-vertex ``field (V,)`` over mesh edges (each vertex with its ring)."""
    edges = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    degree = np.bincount(edges[:, 0], minlength=len(field)) + 1.0
    for _ in range(iterations):
        total = field.copy()
        np.add.at(total, edges[:, 0], field[edges[:, 1]])
        field = total / degree
    return field


def _region_field(face: FaceModel, values: dict[str, float], smoothing: int = 3) -> np.ndarray:
    """``(V,)`` weight: ``values[region]`` per region, smoothed, zero outside the named regions."""
    field = np.zeros(len(face.positions))
    listed = np.zeros(len(face.positions), bool)
    for name, value in values.items():
        mask = face.region_mask(name)
        field[mask] = value
        listed |= mask
    return np.where(listed, _neighbour_average(field, face.faces, smoothing), 0.0)


def _rotate_about(points: np.ndarray, pivot: np.ndarray, axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """``points (V, 3)`` turned by ``angle (F,)`` about ``axis`` through ``pivot``: ``(F, V, 3)``."""
    turn = rotations.to_matrix(rotations.from_axis_angle(axis, angle))  # (F, 3, 3)
    return np.einsum("fij,vj->fvi", turn, points - pivot) + pivot


def _both(name: str) -> list[str]:
    return [f"{name}_left", f"{name}_right"]


def face_animation(face: FaceModel, seconds: float = 2.0, fps: float = 30.0, seed: int = 0) -> AnimatedMesh:
    """Animate ``face``: speech-like jaw and lips, a smile, blinks, a brow raise, glances.

    Parameters
    ----------
    face : a :func:`animlod.synth.face` model (its region names are used).
    seconds, fps : clip length and rate; ``F = round(seconds * fps)`` frames, at least 1.
    seed : varies the speech rhythm and the blink times; same seed, same bytes.

    Returns
    -------
    AnimatedMesh ``(F, V, 3)`` with ``face.faces``. Ears, nose, upper teeth and scalp
    (``STILL_REGIONS``) keep their rest positions in every frame.
    """
    if not (seconds > 0 and fps > 0):
        raise ValueError(f"seconds and fps must be positive, got {seconds} and {fps}")
    rng = np.random.default_rng(seed)
    frame_count = max(1, round(seconds * fps))
    t = np.arange(frame_count) / fps
    rest = face.positions.astype(np.float64)

    # Curves of time, each in [0, 1].
    syllable, phrase = rng.uniform(3.0, 4.5), rng.uniform(0.5, 1.0)
    speech = (0.5 + 0.5 * np.sin(2 * np.pi * syllable * t + rng.uniform(0, 2 * np.pi))) * (
        0.6 + 0.4 * np.sin(2 * np.pi * phrase * t + rng.uniform(0, 2 * np.pi))
    )
    smile = bump(t, 0.1 * seconds, 0.9 * seconds)
    brow = bump(t, 0.35 * seconds, 0.75 * seconds)
    blink_starts = 0.3 + 1.4 * np.arange(int(seconds / 1.4) + 1) + rng.uniform(0.0, 0.4, int(seconds / 1.4) + 1)
    blink = sum(bump(t, start, start + 0.25) for start in blink_starts)
    glance = 0.2 * (bump(t, 0.1 * seconds, 0.45 * seconds) - bump(t, 0.55 * seconds, 0.9 * seconds))

    # Displacement fields (V, 3) in metres for a curve value of 1.
    up = np.array([0.0, 1.0, 0.0])
    sideways = np.sign(rest[:, 0:1]) * np.array([1.0, 0.0, 0.0])
    fields_and_curves = [
        (_region_field(face, {"lip_upper": 1.0, "mouth": 0.3})[:, None] * np.array([0.0, 0.003, 0.002]), speech),
        (
            _region_field(
                face,
                dict.fromkeys(["mouth", "lip_upper", "lip_lower"], 1.0)
                | dict.fromkeys(_both("cheek"), 0.6)
                | dict.fromkeys(_both("zygomatic"), 0.3),
            )[:, None]
            * (0.004 * sideways + 0.003 * up),
            smile,
        ),
        (_region_field(face, dict.fromkeys(_both("eyelid_upper"), 1.0))[:, None] * -0.010 * up, blink),
        (_region_field(face, dict.fromkeys(_both("eyelid_lower"), 1.0))[:, None] * 0.002 * up, blink),
        (_region_field(face, dict.fromkeys(_both("eyebrow"), 1.0) | {"forehead": 0.4})[:, None] * 0.006 * up, brow),
    ]
    frames = rest + sum(curve[:, None, None] * field[None] for field, curve in fields_and_curves)

    # The jaw turns about a left-right axis just below and in front of the ears.
    ears = face.region_mask("ear_left") | face.region_mask("ear_right")
    hinge = rest[ears].mean(axis=0) + np.array([0.0, -0.01, 0.01])
    jaw = _region_field(
        face,
        {"jaw": 1.0, "lip_lower": 1.0, "teeth_lower": 1.0, "mouth": 0.6, "lip_upper": 0.1}
        | dict.fromkeys(_both("cheek"), 0.35),
    )
    turned = _rotate_about(rest, hinge, np.array([1.0, 0.0, 0.0]), _JAW_OPENING * speech)
    frames += jaw[None, :, None] * (turned - rest)

    # Eyeballs glance left and right about their centres.
    for eye in _both("eyeball"):
        mask = face.region_mask(eye)
        frames[:, mask] = _rotate_about(rest[mask], rest[mask].mean(axis=0), up, glance)

    still = np.isin(face.vertex_regions, [face.region_names.index(name) for name in STILL_REGIONS])
    frames[:, still] = rest[still]  # exact, whatever smoothing leaked
    return AnimatedMesh(face.faces, frames, fps=fps)
