"""Cyclic walk, run and jump motions for the procedural humanoid.

Every joint angle is a periodic function of the gait phase, so a clip of ``cycles`` whole
cycles loops: the frame after the last equals frame 0. Locomotion is in place (a treadmill):
the root sways and bobs but does not travel. Joint angles are intrinsic XYZ Euler angles in
the joint's T-pose frame (character facing +Z, left side +X): a negative X angle swings a
hanging limb forward, a positive X angle bends a knee, and right-side angles mirror the left
ones as ``(x, -y, -z)``.

``STILL_FINGER_CHAIN`` (the left ring finger) is held at its rest rotation in every motion,
so that a joint that does not move can be told apart from one that barely moves (the other
fingers curl by a few degrees).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

from .. import rotations
from ..model import Motion, Skeleton, SkinnedMesh
from .curves import bump, raised
from .humanoid_body import FINGERS, humanoid

STILL_FINGER_CHAIN = ("LeftHandRing1", "LeftHandRing2")
KINDS = ("walk", "run", "jump")


@dataclass(frozen=True)
class GaitStyle:
    """Amplitudes of a locomotion cycle, radians and metres."""

    period: float  # seconds per cycle (two steps)
    hip_swing: float  # thigh swing either side of vertical
    knee_stance: float  # knee bend while loading the stance leg
    knee_swing: float  # peak knee bend in early swing
    arm_down: float  # arms lowered from the T-pose
    arm_swing: float  # arm swing either side
    elbow: float  # resting elbow bend
    lean: float  # forward lean of the spine
    pelvis_yaw: float  # pelvis twist; the chest counter-twists
    bob: float  # vertical travel of the hips
    sway: float  # sideways travel of the hips
    running: bool  # a flight phase: highest with the legs apart (a walk is lowest there)


_STYLES = {
    "walk": GaitStyle(1.1, 0.40, 0.25, 1.0, 1.25, 0.30, 0.25, 0.04, 0.08, 0.025, 0.025, False),
    "run": GaitStyle(0.7, 0.65, 0.45, 1.7, 1.20, 0.60, 1.40, 0.15, 0.12, 0.05, 0.015, True),
}
_JUMP_PERIOD = 1.2


def _xyz(x: np.ndarray | float = 0.0, y: np.ndarray | float = 0.0, z: np.ndarray | float = 0.0) -> np.ndarray:
    """Stack Euler angles into ``(T, 3)``, broadcasting scalars."""
    return np.stack(np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float), np.asarray(z, float)), -1)


def _gait_side(phase: np.ndarray, style: GaitStyle) -> dict[str, np.ndarray]:
    """Euler angles ``(T, 3)`` of one side's limbs; ``phase`` 0 has this leg vertical in swing.

    The thigh swings as ``hip_swing * sin(phase)`` (forward first), the arm opposite; the
    stance leg is at mid-stance at ``phase == pi``.
    """
    hip = style.hip_swing * np.sin(phase)
    knee = style.knee_swing * raised(phase, -1.0, 2) + style.knee_stance * raised(phase, 2.0, 4)
    push_off = raised(phase, -1.6, 4)  # toes bend up just before the foot leaves the ground
    arm = style.arm_swing * np.sin(phase)  # a positive X angle swings the hanging arm back
    elbow = style.elbow + 0.5 * style.arm_swing * (1.0 - np.sin(phase))
    curl = 0.25 + 0.05 * np.sin(phase)
    angles = {
        "UpLeg": _xyz(-hip),
        "Leg": _xyz(knee),
        "Foot": _xyz(0.6 * (hip - knee) + 0.3 * push_off),
        "ToeBase": _xyz(-0.4 * push_off),
        "Shoulder": _xyz(0.0, 0.0, 0.04 + 0.02 * np.sin(phase)),
        "Arm": _xyz(arm, 0.0, -style.arm_down),
        "ForeArm": _xyz(0.0, -elbow),
        "Hand": _xyz(0.0, 0.0, -0.1 - 0.05 * np.sin(phase)),
    }
    angles.update(_finger_angles(curl))
    return angles


def _finger_angles(curl: np.ndarray) -> dict[str, np.ndarray]:
    """Left-side curls: fingers bend towards the palm (-Y in the T-pose) about -Z."""
    angles = {}
    for k, finger in enumerate(FINGERS):
        spread = 0.2 * k  # each finger curls a little more than the one before it
        angles[f"Hand{finger}1"] = _xyz(0.0, 0.0, -(1.0 + spread) * curl)
        angles[f"Hand{finger}2"] = _xyz(0.0, 0.0, -(1.2 + spread) * curl)
    return angles


def _gait(phase: np.ndarray, style: GaitStyle) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Root displacement ``(T, 3)`` from the rest pose and Euler angles per joint of a walk or run."""
    apart = 0.5 - 0.5 * np.cos(2.0 * phase)  # 0 at mid-stance, 1 with the legs furthest apart
    # A walker vaults over the stance leg (lowest with both feet down); a runner flies
    # between steps (highest with the legs apart). Mid-stance keeps the rest height.
    bob = style.bob * apart * (1.0 if style.running else -1.0)
    root = _xyz(-style.sway * np.cos(phase), bob, 0.0)
    twist = style.pelvis_yaw * np.sin(phase)  # left hip forward while the left thigh swings forward
    angles = {
        "Hips": _xyz(0.0, -twist, 0.3 * style.pelvis_yaw * np.cos(phase)),
        "Spine": _xyz(0.4 * style.lean, 0.4 * twist),
        "Spine1": _xyz(0.3 * style.lean, 0.6 * twist),
        "Spine2": _xyz(0.3 * style.lean, 0.6 * twist),
        # The chest ends up twisted by 0.6 * twist; neck and head undo that, the lean and the
        # pelvis roll, so the head stays level and looks ahead.
        "Neck": _xyz(-0.5 * style.lean, -0.3 * twist, -0.3 * style.pelvis_yaw * np.cos(phase)),
        "Head": _xyz(-0.5 * style.lean + 0.02 * np.sin(2.0 * phase), -0.3 * twist),
    }
    for side, side_phase in (("Left", phase), ("Right", phase + np.pi)):
        angles.update(_sided(side, _gait_side(side_phase, style)))
    return root, angles


def _jump(u: np.ndarray, skeleton: Skeleton, scale: float) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Root displacement and Euler angles of a standing jump; ``u`` is the cycle fraction in [0, 1).

    Crouch (0-0.42), take-off at 0.42, flight (0.42-0.78, the root on a parabola), landing
    crouch (0.78-1). While the feet are down the legs follow the hip drop by two-bone inverse
    kinematics, so the ankles stay under the hips and the feet stay flat. ``scale`` scales the
    crouch depth and the jump height.
    """
    crouch = bump(u, 0.0, 0.42) + 0.8 * bump(u, 0.78, 1.0)
    flight = np.clip((u - 0.42) / 0.36, 0.0, 1.0)
    drop = 0.22 * scale * crouch
    rise = 0.35 * scale * 4.0 * flight * (1.0 - flight)
    tuck = 0.12 * scale * bump(u, 0.45, 0.75)
    root = _xyz(0.0, rise - drop, 0.0)

    thigh = float(np.linalg.norm(skeleton.offsets[skeleton.index("LeftLeg")]))
    shin = float(np.linalg.norm(skeleton.offsets[skeleton.index("LeftFoot")]))
    reach = np.clip(thigh + shin - 0.005 - drop - tuck, 0.2 * (thigh + shin), None)  # hip to ankle
    hip = np.arccos(np.clip((thigh**2 + reach**2 - shin**2) / (2.0 * thigh * reach), -1.0, 1.0))
    knee = np.pi - np.arccos(np.clip((thigh**2 + shin**2 - reach**2) / (2.0 * thigh * shin), -1.0, 1.0))
    arm = 0.6 * crouch - 2.0 * bump(u, 0.32, 0.72)  # back while crouching, up through the flight
    lean = 0.5 * crouch
    side = {
        "UpLeg": _xyz(-hip),
        "Leg": _xyz(knee),
        "Foot": _xyz(hip - knee + 0.3 * bump(u, 0.36, 0.5)),
        "ToeBase": _xyz(-0.3 * bump(u, 0.3, 0.45)),
        "Shoulder": _xyz(0.0, 0.0, 0.05 * bump(u, 0.32, 0.72)),
        "Arm": _xyz(arm, 0.0, -1.2),
        "ForeArm": _xyz(0.0, -0.3 - 0.4 * crouch),
        "Hand": _xyz(0.0, 0.0, -0.1 * crouch),
    }
    side.update(_finger_angles(0.25 + 0.1 * crouch))
    angles = {
        "Spine": _xyz(0.4 * lean),
        "Spine1": _xyz(0.3 * lean),
        "Spine2": _xyz(0.3 * lean),
        "Neck": _xyz(-0.5 * lean),
        "Head": _xyz(-0.4 * lean + 0.05 * bump(u, 0.4, 0.8)),
    }
    angles.update(_sided("Left", side))
    angles.update(_sided("Right", side))
    return root, angles


def _sided(side: str, angles: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Name left-side limb angles for ``side``, mirroring them for the right: ``(x, -y, -z)``."""
    mirror = np.array([1.0, -1.0, -1.0]) if side == "Right" else np.ones(3)
    return {side + name: value * mirror for name, value in angles.items()}


def humanoid_with_clips(seed: int = 0) -> tuple[SkinnedMesh, list[Motion]]:
    """:func:`~animlod.synth.humanoid` and one clip of each of ``KINDS`` for it (the default
    cycles and fps), all from ``seed``: the procedural character `demo` and the crowd write."""
    character = humanoid(seed=seed)
    return character, [humanoid_motion(character.skeleton, kind, seed=seed) for kind in KINDS]


def humanoid_motion(
    skeleton: Skeleton, kind: str = "walk", cycles: int = 2, fps: float = 30.0, seed: int = 0
) -> Motion:
    """A cyclic walk (1.1 s), run (0.7 s) or standing jump (1.2 s) for :func:`humanoid`'s skeleton.

    Parameters
    ----------
    skeleton : a skeleton with :func:`humanoid`'s joint names (ValueError naming a missing joint).
    kind : ``"walk"``, ``"run"`` or ``"jump"``.
    cycles : whole cycles in the clip; frame ``cycles * round(period * fps)`` would equal frame 0.
    fps : frames per second.
    seed : jitters every amplitude by up to +-8 %; same seed, same bytes.

    Returns
    -------
    Motion with ``T = cycles * round(period * fps)`` frames, named ``kind``. End sites and
    ``STILL_FINGER_CHAIN`` keep their rest rotations.
    """
    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {KINDS}, got {kind!r}")
    if cycles < 1:
        raise ValueError(f"cycles: must be >= 1, got {cycles}")
    if not (fps > 0 and np.isfinite(fps)):
        raise ValueError(f"fps: must be positive, got {fps}")
    rng = np.random.default_rng(seed)
    period = _STYLES[kind].period if kind in _STYLES else _JUMP_PERIOD
    frames_per_cycle = max(2, round(period * fps))
    phase = 2.0 * np.pi * np.arange(cycles * frames_per_cycle) / frames_per_cycle
    if kind == "jump":
        displacement, angles = _jump((phase / (2.0 * np.pi)) % 1.0, skeleton, 1.0 + 0.08 * rng.uniform(-1, 1))
    else:
        style = _STYLES[kind]
        amplitudes = [f.name for f in fields(style) if f.name not in ("period", "running")]
        jitter = {name: getattr(style, name) * (1.0 + 0.08 * rng.uniform(-1, 1)) for name in amplitudes}
        displacement, angles = _gait(phase, replace(style, **jitter))

    local = np.broadcast_to(skeleton.rest_rotations, (phase.size,) + skeleton.rest_rotations.shape).copy()
    for name, euler in angles.items():
        if name in STILL_FINGER_CHAIN:
            continue  # held at rest on purpose: a joint whose motion importance is exactly zero
        joint = skeleton.index(name)
        local[:, joint] = rotations.multiply(skeleton.rest_rotations[joint], rotations.from_euler(euler, "XYZ"))
    return Motion(skeleton, skeleton.offsets[0] + displacement, local, fps=float(fps), name=kind)
