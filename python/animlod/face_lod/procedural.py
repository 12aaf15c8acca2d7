"""The procedural face (:func:`animlod.synth.face`) as a rig: regions, groups, lattices, MPAs,
expressions and active tree from :mod:`animlod.synth.face_mpa`."""

from __future__ import annotations

from dataclasses import dataclass

from .. import synth
from ..synth import face_mpa
from .active_tree import ActiveTree
from .mpa import Expression
from .regions import FaceRegions, region_groups
from .rig import FaceRig


@dataclass
class ProceduralFace:
    """Everything face LoD needs about the procedural head.

    Attributes
    ----------
    rig : the full face with its 21 MPAs on 3x3x3 lattices.
    expressions : smile, anger, surprise and sadness.
    tree : the active tree of Figure 7 (4 levels).
    """

    rig: FaceRig
    expressions: list[Expression]
    tree: ActiveTree


def procedural_face(seed: int = 0) -> ProceduralFace:
    """The head of :func:`animlod.synth.face` (``seed`` scales it), rigged for face LoD."""
    model = synth.face(seed)
    labels = face_mpa.animation_labels(model)
    regions = FaceRegions(model.region_names, labels, region_groups(model.region_names, face_mpa.REGION_GROUPS))
    rig = FaceRig(model.positions, model.faces, regions, lattice_weights=face_mpa.LATTICE_WEIGHTS)
    for name, (names, field) in face_mpa.mpa_fields(model).items():
        rig.add_mpa(rig.mpa_from_field(name, names, field, min_displacement=1e-5))
    expressions = [Expression(name, dict(values)) for name, values in face_mpa.EXPRESSIONS.items()]
    return ProceduralFace(rig, expressions, ActiveTree(face_mpa.ACTIVE_TREE, regions))
