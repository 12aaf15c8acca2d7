"""The body parts that the common humanoid namings give their joints.

A capture library and a rig often name one body differently, and their names collide: CMU's
``LeftShoulder`` is Mixamo's ``LeftArm`` (the upper arm; Mixamo's ``LeftShoulder`` is the
collar), CMU's ``Neck`` is the upper neck below ``Head``, Mixamo's the lower one. So a skeleton's
naming is recognised as a whole (the naming whose names it holds most), and each joint gets the
role that its naming gives its name; two skeletons then correspond role by role. A role is a
body part, shared by the namings that have it: a naming with fewer spine or neck joints simply
lacks some roles.
"""

from __future__ import annotations

import re

from .joint_names import normalized_name, split_side, unique_index

# Roles along the body's middle, then on each side (each side's roles are prefixed by it).
_MIDDLE = ("hips", "spine", "chest", "upper chest", "neck", "upper neck", "head")
_SIDED = ("collar", "upper arm", "forearm", "hand", "thigh", "shin", "foot", "toes")

# Each naming's joint name per role ("" where it has none), the side-dependent ones without
# their side (their side word or letter, whatever its place, is the joint's side).
_NAMINGS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    # Mixamo's rigs (and Blender's and many engines' exports of them).
    "Mixamo": (("Hips", "Spine", "Spine1", "Spine2", "Neck", "", "Head"),
               ("Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase")),
    # The cgspeed conversion of CMU's library, and rigs built from it.
    "cgspeed": (("Hips", "LowerBack", "Spine", "Spine1", "Neck", "Neck1", "Head"),
                ("Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase")),
    # CMU's own ASF-to-BVH conversion.
    "CMU": (("Hips", "lowerback", "Chest", "Chest2", "lowerneck", "Neck", "Head"),
            ("Collar", "Shoulder", "Elbow", "Wrist", "Hip", "Knee", "Ankle", "Toe")),
    # Unity's humanoid avatar and VRM (Bandai-Namco's motion dataset writes these names).
    "Unity": (("Hips", "Spine", "Chest", "UpperChest", "Neck", "", "Head"),
              ("Shoulder", "UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toes")),
    # Unreal's mannequin.
    "Unreal": (("pelvis", "spine_01", "spine_02", "spine_03", "neck_01", "", "head"),
               ("clavicle", "upperarm", "lowerarm", "hand", "thigh", "calf", "foot", "ball")),
    # 3ds Max's Biped ("Bip01 L Thigh").
    "Biped": (("Pelvis", "Spine", "Spine1", "Spine2", "Neck", "", "Head"),
              ("Clavicle", "UpperArm", "Forearm", "Hand", "Thigh", "Calf", "Foot", "Toe0")),
}  # fmt: skip

# A skeleton is taken for a naming only where it holds at least this many of its roles.
MIN_ROLES = 12
ROLE_COUNT = len(_MIDDLE) + 2 * len(_SIDED)


def roles_of(names: list[str]) -> tuple[str, dict[str, int]] | None:
    """The naming that ``names`` (a skeleton's joint names) holds most roles of, and the joint
    index of each of those roles; None where no naming has ``MIN_ROLES`` of them."""
    keys = [_role_key(name) for name in names]
    once = unique_index(keys)
    best: tuple[str, dict[str, int]] | None = None
    for naming, (middle, sided) in _NAMINGS.items():
        wanted = {(None, _plain(name)): role for role, name in zip(_MIDDLE, middle) if name}
        wanted |= {(s, _plain(name)): f"{s} {role}" for role, name in zip(_SIDED, sided) for s in ("left", "right")}
        found = {wanted[key]: joint for key, joint in once.items() if key in wanted}
        if len(found) >= MIN_ROLES and (best is None or len(found) > len(best[1])):
            best = (naming, found)
    return best


def naming_label(names: list[str]) -> str:
    """What :func:`roles_of` makes of a skeleton's joint ``names``, for reports: "Mixamo naming
    (22 of 23 body parts)", or "" where it holds no naming."""
    found = roles_of(names)
    return "" if found is None else f"{found[0]} naming ({len(found[1])} of {ROLE_COUNT} body parts)"


def _role_key(name: str) -> tuple[str | None, str]:
    """(side, the rest of the name without namespace, Biped's "Bip01" prefix, case and separators)."""
    joint_side, rest = split_side(name)
    return joint_side, _plain(rest)


def _plain(name: str) -> str:
    return re.sub(r"^bip0*\d+", "", normalized_name(name))
