"""Procedural assets, deterministic from a seed: the embedded default and most tests' input.

- :func:`humanoid` and :func:`humanoid_motion`: a 41-joint skinned character and its cyclic
  walk, run and jump (:func:`humanoid_with_clips`: the character with one clip of each);
- :func:`face` and :func:`face_animation`: a head with named animation regions;
- :func:`bending_cylinder`, :func:`twisting_bar`, :func:`translating_mesh`,
  :func:`kicking_box_leg`: small deforming meshes with known motion for unit tests;
- :func:`icosphere`: a geodesic sphere;
- :func:`tail_clips`: a joint chain with a clip that moves all of it and one that moves half.
"""

from .deforming import bending_cylinder, bending_cylinder_skinned, kicking_box_leg, translating_mesh, twisting_bar
from .face_animation import face_animation
from .face_model import REGION_NAMES, STILL_REGIONS, FaceModel, face
from .gait import KINDS, STILL_FINGER_CHAIN, humanoid_motion, humanoid_with_clips
from .geometry import icosphere
from .humanoid_body import END_SITES, humanoid, humanoid_skeleton
from .tail import tail_clips

__all__ = [
    "END_SITES",
    "KINDS",
    "REGION_NAMES",
    "STILL_FINGER_CHAIN",
    "STILL_REGIONS",
    "FaceModel",
    "bending_cylinder",
    "bending_cylinder_skinned",
    "face",
    "face_animation",
    "humanoid",
    "humanoid_motion",
    "humanoid_skeleton",
    "humanoid_with_clips",
    "icosphere",
    "kicking_box_leg",
    "tail_clips",
    "translating_mesh",
    "twisting_bar",
]
