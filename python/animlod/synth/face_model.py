"""A procedural head with named animation regions, and a talking, blinking animation of it.

The head follows the region layout of the facial LoD paper (seeds/004, Section 3.1, Figure 2:
about 20 regions, 2,313 triangles including eyeballs and teeth): a deformed ellipsoid with the
face towards +Z, Y up, in metres, plus two eyeballs and two teeth arcs. Each of the five parts
is a closed 2-manifold with outward faces.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .geometry import cross_section, icosphere, merge, orthonormal_frame, tube

_HEAD_RADII = np.array([0.075, 0.11, 0.095])  # half width, height, depth
_EYE_DIRECTIONS = np.array([[0.33, 0.18, 0.926], [-0.33, 0.18, 0.926]])  # left (+X), right
_EYE_RADIUS = 0.012
_MOUTH_DIRECTION = np.array([0.0, -0.46, 0.88])  # between the lips

# (centre direction, extent, amplitude in metres): Gaussian bumps on the unit sphere that push
# the ellipsoid along its direction into a face.
_FEATURES = [
    ((0.33, 0.18, 0.93), (0.13, 0.09, 0.3), -0.012),  # eye sockets
    ((-0.33, 0.18, 0.93), (0.13, 0.09, 0.3), -0.012),
    ((0.30, 0.33, 0.89), (0.2, 0.06, 0.3), 0.006),  # brow ridges
    ((-0.30, 0.33, 0.89), (0.2, 0.06, 0.3), 0.006),
    ((0.0, -0.05, 1.0), (0.07, 0.16, 0.3), 0.016),  # nose bridge and tip
    ((0.0, -0.17, 0.98), (0.07, 0.06, 0.3), 0.01),
    ((0.5, -0.2, 0.84), (0.15, 0.15, 0.3), 0.008),  # cheeks
    ((-0.5, -0.2, 0.84), (0.15, 0.15, 0.3), 0.008),
    ((0.6, 0.02, 0.8), (0.12, 0.08, 0.3), 0.006),  # cheekbones
    ((-0.6, 0.02, 0.8), (0.12, 0.08, 0.3), 0.006),
    ((0.0, -0.40, 0.91), (0.18, 0.05, 0.3), 0.009),  # lips
    ((0.0, -0.53, 0.85), (0.17, 0.05, 0.3), 0.009),
    ((0.0, -0.75, 0.66), (0.2, 0.12, 0.3), 0.01),  # chin
    ((1.0, 0.0, -0.1), (0.3, 0.22, 0.12), 0.022),  # ears
    ((-1.0, 0.0, -0.1), (0.3, 0.22, 0.12), 0.022),
]

# Regions of the head surface in priority order (the first that holds a vertex's direction
# wins): name -> (centre direction, extent). Vertices in none of them are "scalp".
_HEAD_REGIONS = {
    "ear_left": ((1.0, 0.0, -0.1), (0.45, 0.3, 0.25)),
    "ear_right": ((-1.0, 0.0, -0.1), (0.45, 0.3, 0.25)),
    "eyelid_upper_left": ((0.33, 0.25, 0.91), (0.18, 0.09, 0.3)),
    "eyelid_upper_right": ((-0.33, 0.25, 0.91), (0.18, 0.09, 0.3)),
    "eyelid_lower_left": ((0.33, 0.1, 0.94), (0.18, 0.08, 0.3)),
    "eyelid_lower_right": ((-0.33, 0.1, 0.94), (0.18, 0.08, 0.3)),
    "eyebrow_left": ((0.3, 0.39, 0.87), (0.22, 0.08, 0.3)),
    "eyebrow_right": ((-0.3, 0.39, 0.87), (0.22, 0.08, 0.3)),
    "nose": ((0.0, -0.04, 1.0), (0.13, 0.24, 0.3)),
    "lip_upper": ((0.0, -0.39, 0.92), (0.2, 0.07, 0.3)),
    "lip_lower": ((0.0, -0.53, 0.85), (0.2, 0.07, 0.3)),
    "mouth": ((0.0, -0.46, 0.88), (0.32, 0.16, 0.3)),
    "jaw": ((0.0, -0.78, 0.55), (0.6, 0.27, 0.55)),
    "zygomatic_left": ((0.58, 0.06, 0.81), (0.17, 0.11, 0.3)),
    "zygomatic_right": ((-0.58, 0.06, 0.81), (0.17, 0.11, 0.3)),
    "cheek_left": ((0.5, -0.27, 0.82), (0.22, 0.18, 0.3)),
    "cheek_right": ((-0.5, -0.27, 0.82), (0.22, 0.18, 0.3)),
    "forehead": ((0.0, 0.58, 0.81), (0.55, 0.2, 0.4)),
}
REGION_NAMES = [
    *_HEAD_REGIONS,
    "scalp",
    "eyeball_left",
    "eyeball_right",
    "teeth_upper",
    "teeth_lower",
]
# Regions face_animation never moves.
STILL_REGIONS = ("ear_left", "ear_right", "nose", "teeth_upper", "scalp")


@dataclass
class FaceModel:
    """A head mesh whose vertices are labelled with animation regions.

    Attributes
    ----------
    positions : (V, 3) float32, metres, face towards +Z, Y up.
    faces : (M, 3) int32, counter-clockwise seen from outside.
    region_names : R region names.
    vertex_regions : (V,) int32 index into ``region_names``.
    """

    positions: np.ndarray
    faces: np.ndarray
    region_names: list[str]
    vertex_regions: np.ndarray

    def region_mask(self, name: str) -> np.ndarray:
        """``(V,)`` bool, True for the vertices of region ``name`` (ValueError if unknown)."""
        if name not in self.region_names:
            raise ValueError(f"face has no region named {name!r}; regions: {', '.join(self.region_names)}")
        return self.vertex_regions == self.region_names.index(name)


def _unit(vectors: np.ndarray) -> np.ndarray:
    vectors = np.asarray(vectors, dtype=np.float64)
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def _inside(directions: np.ndarray, centre: tuple, extent: tuple) -> np.ndarray:
    """``(V,)`` bool: directions within the axis-aligned ellipsoid ``centre +- extent``."""
    return np.sum(((directions - _unit(centre)) / np.asarray(extent)) ** 2, axis=-1) < 1.0


def _head_surface(directions: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Points ``(V, 3)`` of the head in unit ``directions (V, 3)``: ellipsoid plus features."""
    radii = _HEAD_RADII * scale
    # The jaw narrows towards the chin.
    narrowing = 1.0 - 0.18 * np.clip(-directions[:, 1:2], 0.0, 1.0) * np.array([1.0, 0.0, 0.3])
    surface = directions * radii * narrowing
    for centre, extent, amplitude in _FEATURES:
        weight = np.exp(-np.sum(((directions - _unit(centre)) / np.asarray(extent)) ** 2, axis=-1))
        surface += (amplitude * weight)[:, None] * directions
    return surface


def _head(rings: int, segments: int, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Latitude-longitude head with poles on the Y axis; returns positions, faces, directions.

    Both angles are warped as ``a - k sin(n a + c)`` (monotone while ``n k < 1``) so that rings
    and meridians crowd around the face, where the regions are small, and thin out at the back.
    """
    uniform = np.pi * np.arange(1, rings + 1) / (rings + 1)
    polar = uniform - 0.3 * np.sin(2.0 * uniform - np.pi)  # from the bottom pole up, dense mid-height
    frame = orthonormal_frame([0.0, 1.0, 0.0], [1.0, 0.0, 0.0])  # outline angle -pi/2 faces +Z
    around = 2.0 * np.pi * np.arange(segments) / segments
    around = around - 0.85 * np.sin(around + 0.5 * np.pi)
    sphere = tube(
        -np.cos(polar)[:, None] * frame[2], np.sin(polar), np.sin(polar), frame,
        np.array([[0.0, -1.0, 0.0], [0.0, 1.0, 0.0]]), np.stack([np.cos(around), np.sin(around)], -1),
    )  # fmt: skip
    directions = _unit(sphere.positions)
    return _head_surface(directions, scale), sphere.faces, directions


def _teeth_arc(height: float, front: float, arc_radius: float, span: float) -> tuple[np.ndarray, np.ndarray]:
    """A closed square bar bent into a horizontal arc behind the lips, open side backwards."""
    half_length = 0.5 * span * arc_radius
    frame = orthonormal_frame([1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    centres = np.linspace(-half_length, half_length, 7)[:, None] * frame[2]
    bar = tube(centres, np.full(7, 0.005), np.full(7, 0.003), frame,
               np.array([[-half_length, 0.0, 0.0], [half_length, 0.0, 0.0]]), cross_section(8, "square"))  # fmt: skip
    x, y, z = bar.positions.T
    angle, reach = x / arc_radius, arc_radius + z  # bending keeps orientation (Jacobian > 0)
    centre_z = front - arc_radius
    return np.stack([reach * np.sin(angle), height + y, centre_z + reach * np.cos(angle)], -1), bar.faces


def face(seed: int = 0) -> FaceModel:
    """A head of 2,304 triangles with the regions in ``REGION_NAMES``.

    Head ellipsoid 1,920 triangles, eyeballs 2 x 80 (icospheres), teeth 2 x 112. ``seed``
    scales the head by up to +-4 % per axis; same seed, same bytes.
    """
    rng = np.random.default_rng(seed)
    scale = 1.0 + 0.04 * rng.uniform(-1.0, 1.0, size=3)
    head_positions, head_faces, directions = _head(24, 40, scale)
    head_region = np.full(len(head_positions), REGION_NAMES.index("scalp"), dtype=np.int32)
    for index, (centre, extent) in reversed(list(enumerate(_HEAD_REGIONS.values()))):
        head_region[_inside(directions, centre, extent)] = index  # earlier regions overwrite later ones

    eye_positions, eye_faces = icosphere(1, _EYE_RADIUS)
    eye_centres = _head_surface(_unit(_EYE_DIRECTIONS), scale) - 0.2 * _EYE_RADIUS * _unit(_EYE_DIRECTIONS)
    _, mouth_height, mouth_front = _head_surface(_unit(_MOUTH_DIRECTION[None]), scale)[0]
    arc_radius = 0.032 * scale[0]
    parts = [
        (head_positions, head_faces),
        (eye_positions + eye_centres[0], eye_faces),
        (eye_positions + eye_centres[1], eye_faces),
        _teeth_arc(mouth_height + 0.006, mouth_front - 0.011, arc_radius, 1.8),
        _teeth_arc(mouth_height - 0.006, mouth_front - 0.013, arc_radius, 1.8),
    ]
    positions, faces, part = merge(parts)
    # The head is part 0 (its vertices come first); the other parts are one region each.
    part_regions = np.array([0] + [REGION_NAMES.index(name) for name in REGION_NAMES[-4:]], dtype=np.int32)
    vertex_regions = part_regions[part]
    vertex_regions[: len(head_region)] = head_region
    return FaceModel(positions.astype(np.float32), faces, list(REGION_NAMES), vertex_regions)
