"""Animation structure of :func:`animlod.synth.face` for facial LoD (seeds/004, Sections 3-4).

Plain data and displacement fields, no lattices: :mod:`animlod.face_lod.procedural` turns them
into a rig. What is here:

- :func:`animation_labels`: the face's region labels with the gaps of "scalp" between the
  regions of the face closed (the regions of ``face_model`` leave thin strips of scalp between,
  say, cheek and jaw; a region lattice must cover them, or they would never move);
- ``REGION_GROUPS``: face mask, ears, eyes and teeth with importance weights (Section 4.1.1);
- ``ACTIVE_TREE``: the regions animated at each level (Figure 7: level 0 everything, level 1
  upper and lower mask, level 2 lower mask, level 3 nothing; the lower teeth move with the
  lower mask);
- :func:`mpa_fields`: 20 Minimum Perceptible Actions as displacement fields (metres at
  intensity 1) over named regions, and ``EXPRESSIONS``: smile, anger, surprise, sadness as
  weighted MPAs (Figure 4);
- ``LATTICE_WEIGHTS``: rational weights for the regions whose middle should follow the middle
  control point more closely (the cheeks puff, the lips purse).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .face_model import FaceModel

Field = Callable[[np.ndarray], np.ndarray]

_SIDES = ("left", "right")
UPPER_MASK = ["eyebrow_left", "eyebrow_right", "eyelid_upper_left", "eyelid_upper_right",
              "eyelid_lower_left", "eyelid_lower_right", "forehead"]  # fmt: skip
LOWER_MASK = ["zygomatic_left", "zygomatic_right", "mouth", "lip_upper", "lip_lower",
              "cheek_left", "cheek_right", "jaw"]  # fmt: skip
REGION_GROUPS: dict[str, tuple[list[str], float]] = {
    "face_mask": ([*UPPER_MASK, *LOWER_MASK, "nose", "scalp"], 1.0),
    "ears": (["ear_left", "ear_right"], 0.1),
    "eyes": (["eyeball_left", "eyeball_right"], 0.1),
    "teeth": (["teeth_upper", "teeth_lower"], 0.1),
}
# Level k of the active tree animates ACTIVE_TREE[k] (nested, shrinking, the last one empty).
# The lower teeth stay with the lower mask: left at rest while the jaw opens they would show
# through the open mouth and the chin.
ACTIVE_TREE: list[list[str]] = [
    [*UPPER_MASK, *LOWER_MASK, "teeth_lower", "nose", "eyeball_left", "eyeball_right", "ear_left", "ear_right"],
    [*UPPER_MASK, *LOWER_MASK, "teeth_lower"],
    [*LOWER_MASK, "teeth_lower"],
    [],
]
# Regions whose scalp gaps are filled by animation_labels (the moving face, not ears or parts).
_FILLED = [*UPPER_MASK, *LOWER_MASK, "nose"]


def _centre_weight(heavy: float) -> np.ndarray:
    weights = np.ones((3, 3, 3))
    weights[1, 1, :] = heavy
    return weights


LATTICE_WEIGHTS: dict[str, np.ndarray] = {
    "cheek_left": _centre_weight(2.0),
    "cheek_right": _centre_weight(2.0),
    "lip_upper": _centre_weight(1.5),
    "lip_lower": _centre_weight(1.5),
}

EXPRESSIONS: dict[str, dict[str, float]] = {
    "smile": {"smile": 1.0, "raise_cheeks": 0.8, "raise_lower_eyelids": 0.5, "stretch_lips": 0.3, "open_jaw": 0.15},
    "anger": {"lower_eyebrows": 1.0, "squeeze_eyebrows": 1.0, "wrinkle_nose": 0.6, "frown": 0.6,
              "pucker_lips": 0.4, "raise_lower_eyelids": 0.6},
    "surprise": {"raise_eyebrows": 1.0, "widen_eyes": 1.0, "open_jaw": 0.8, "pucker_lips": 0.3},
    "sadness": {"raise_inner_eyebrows": 1.0, "frown": 1.0, "close_eyelids": 0.35, "lower_lower_lip": 0.4,
                "look_down": 0.5},
}  # fmt: skip


def animation_labels(face: FaceModel, max_rings: int = 3) -> np.ndarray:
    """(V,) int32 region labels of ``face`` for animation: ``face.vertex_regions`` with every scalp
    vertex of the front half (z > 0) within ``max_rings`` mesh rings of a face-mask region given
    that region (the nearest in rings; ties to the region listed first in ``REGION_NAMES``). The
    back of the head stays scalp."""
    names = face.region_names
    labels = face.vertex_regions.astype(np.int64)
    scalp = (labels == names.index("scalp")) & (face.positions[:, 2] > 0.0)
    filled = np.isin(labels, [names.index(name) for name in _FILLED])
    edges = np.sort(face.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    edges = np.unique(edges, axis=0)
    both = np.concatenate([edges, edges[:, ::-1]])
    open_ = scalp.copy()
    for _ in range(max_rings):  # O(rings) passes, vectorised over edges
        step = both[filled[both[:, 0]] & open_[both[:, 1]]]
        if step.size == 0:
            break
        best = np.full(len(labels), np.iinfo(np.int64).max)
        np.minimum.at(best, step[:, 1], labels[step[:, 0]])
        reached = np.unique(step[:, 1])
        labels[reached] = best[reached]
        open_[reached] = False
        filled[reached] = True
    return labels.astype(np.int32)


def _bump(points: np.ndarray, centre: np.ndarray, radii: tuple[float, float, float]) -> np.ndarray:
    """(V,) Gaussian exp(-|(p - c) / r|^2)."""
    return np.exp(-np.sum(((points - centre) / np.asarray(radii)) ** 2, axis=1))


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _rotation(points: np.ndarray, pivot: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """(V, 3) displacement of ``points`` turned by ``angle`` about ``axis`` through ``pivot`` (Rodrigues)."""
    axis = axis / np.linalg.norm(axis)
    arm = points - pivot
    turned = arm * np.cos(angle) + np.cross(axis, arm) * np.sin(angle)
    turned += np.outer(arm @ axis, axis) * (1 - np.cos(angle))
    return turned - arm


def mpa_fields(face: FaceModel) -> dict[str, tuple[list[str], Field]]:
    """The MPAs of ``face``: name -> (regions it acts on, displacement field at intensity 1).

    Each field maps points ``(V, 3)`` (metres, face towards +Z, Y up, X to the face's left) to
    displacements ``(V, 3)``; feature points (brows, lip corners, cheeks, eye centres, the jaw
    hinge) are measured on ``face`` so that the fields follow its seed-dependent proportions.
    """

    def centre(name: str) -> np.ndarray:
        return face.positions[face.region_mask(name)].astype(np.float64).mean(axis=0)

    up, side, forward = np.eye(3)[1], np.eye(3)[0], np.eye(3)[2]
    brows = [centre(f"eyebrow_{s}") for s in _SIDES]
    inner_brows = [brow * np.array([0.4, 1.0, 1.0]) for brow in brows]
    lids_upper = [centre(f"eyelid_upper_{s}") for s in _SIDES]
    lids_lower = [centre(f"eyelid_lower_{s}") for s in _SIDES]
    eyes = [centre(f"eyeball_{s}") for s in _SIDES]
    cheeks = [centre(f"cheek_{s}") for s in _SIDES]
    zygos = [centre(f"zygomatic_{s}") for s in _SIDES]
    mouth = centre("mouth")
    half_width = 0.5 * float(np.ptp(face.positions[face.region_mask("mouth"), 0]))
    corners = [mouth + np.array([half_width, 0.0, -0.004]), mouth + np.array([-half_width, 0.0, -0.004])]
    lip_line = 0.5 * (centre("lip_upper")[1] + centre("lip_lower")[1])
    ears = face.region_mask("ear_left") | face.region_mask("ear_right")
    hinge = face.positions[ears].astype(np.float64).mean(axis=0) + np.array([0.0, -0.01, 0.01])
    nose = centre("nose")
    brow_regions = ["eyebrow_left", "eyebrow_right", "forehead", "eyelid_upper_left", "eyelid_upper_right"]
    mouth_regions = ["mouth", "lip_upper", "lip_lower", "cheek_left", "cheek_right", "jaw",
                     "zygomatic_left", "zygomatic_right"]  # fmt: skip

    def pair(points: np.ndarray, spots: list[np.ndarray], radii: tuple[float, float, float]) -> np.ndarray:
        return sum(_bump(points, spot, radii) for spot in spots)

    def outward(points: np.ndarray) -> np.ndarray:
        return np.sign(points[:, :1]) * side  # away from the midline, per side

    brow_radii = (0.03, 0.018, 0.05)
    fields: dict[str, tuple[list[str], Field]] = {
        "raise_eyebrows": (brow_regions, lambda p: 0.006 * pair(p, brows, brow_radii)[:, None] * up),
        "lower_eyebrows": (brow_regions, lambda p: -0.004 * pair(p, brows, brow_radii)[:, None] * up),
        "squeeze_eyebrows": (
            brow_regions,
            lambda p: pair(p, brows, (0.022, 0.016, 0.05))[:, None] * (-0.004 * outward(p) - 0.0015 * up),
        ),
        "raise_inner_eyebrows": (
            brow_regions,
            lambda p: 0.005 * pair(p, inner_brows, (0.014, 0.015, 0.05))[:, None] * up,
        ),
        "close_eyelids": (
            ["eyelid_upper_left", "eyelid_upper_right"],
            lambda p: -0.010 * pair(p, lids_upper, (0.016, 0.014, 0.05))[:, None] * up,
        ),
        "widen_eyes": (
            ["eyelid_upper_left", "eyelid_upper_right", "eyebrow_left", "eyebrow_right"],
            lambda p: 0.003 * pair(p, lids_upper, (0.016, 0.012, 0.05))[:, None] * up,
        ),
        "raise_lower_eyelids": (
            ["eyelid_lower_left", "eyelid_lower_right"],
            lambda p: 0.0025 * pair(p, lids_lower, (0.016, 0.012, 0.05))[:, None] * up,
        ),
        "open_jaw": (
            ["jaw", "lip_lower", "teeth_lower", "mouth", "cheek_left", "cheek_right"],
            lambda p: _smoothstep((lip_line + 0.004 - p[:, 1]) / 0.012)[:, None] * _rotation(p, hinge, side, 0.25),
        ),
        "smile": (
            mouth_regions,
            lambda p: (
                pair(p, corners, (0.016, 0.016, 0.05))[:, None] * (0.004 * outward(p) + 0.004 * up - 0.001 * forward)
            ),
        ),
        "frown": (mouth_regions, lambda p: -0.004 * pair(p, corners, (0.014, 0.014, 0.05))[:, None] * up),
        "stretch_lips": (
            mouth_regions,
            lambda p: 0.005 * pair(p, corners, (0.018, 0.012, 0.05))[:, None] * outward(p),
        ),
        "pucker_lips": (
            ["mouth", "lip_upper", "lip_lower", "jaw", "cheek_left", "cheek_right"],
            lambda p: (
                _bump(p, mouth, (0.03, 0.018, 0.05))[:, None] * (0.005 * forward)
                - 0.003 * pair(p, corners, (0.015, 0.015, 0.05))[:, None] * outward(p)
            ),
        ),
        "raise_upper_lip": (
            ["lip_upper", "mouth", "nose"],
            lambda p: 0.003 * _bump(p, mouth + np.array([0.0, 0.008, 0.0]), (0.02, 0.01, 0.05))[:, None] * up,
        ),
        "lower_lower_lip": (
            ["lip_lower", "mouth", "jaw"],
            lambda p: -0.003 * _bump(p, mouth + np.array([0.0, -0.006, 0.0]), (0.02, 0.01, 0.05))[:, None] * up,
        ),
        "puff_cheeks": (
            ["cheek_left", "cheek_right", "zygomatic_left", "zygomatic_right", "jaw", "mouth"],
            lambda p: 0.006 * pair(p, cheeks, (0.02, 0.02, 0.05))[:, None] * (0.7 * outward(p) + 0.7 * forward),
        ),
        "raise_cheeks": (
            [
                "cheek_left",
                "cheek_right",
                "zygomatic_left",
                "zygomatic_right",
                "eyelid_lower_left",
                "eyelid_lower_right",
                "mouth",
            ],
            lambda p: 0.003 * pair(p, zygos, (0.022, 0.02, 0.05))[:, None] * up,
        ),
        "wrinkle_nose": (
            ["nose", "lip_upper", "cheek_left", "cheek_right", "zygomatic_left", "zygomatic_right"],
            lambda p: 0.002 * _bump(p, nose, (0.015, 0.02, 0.05))[:, None] * (up - 0.5 * forward),
        ),
    }
    for name, axis, angle in (("look_left", up, 0.35), ("look_right", up, -0.35), ("look_up", side, -0.25),
                              ("look_down", side, 0.25)):  # fmt: skip
        fields[name] = (
            ["eyeball_left", "eyeball_right"],
            lambda p, axis=axis, angle=angle: np.where(
                (p[:, :1] > 0), _rotation(p, eyes[0], axis, angle), _rotation(p, eyes[1], axis, angle)
            ),
        )
    return fields
