"""Level 0's skin weights made to sum to 1, as glTF requires and as the levels are built.

A LoD GLB keeps the input mesh as its level 0, but an exporter's weights can break glTF's rule
that each vertex's weights sum to 1 (the Khronos validator sums them in float32 and allows
nothing for up to two weights, one step of 1/255 per two more): Khronos' own Monster and
RiggedFigure samples have vertices at 0.24 and 0.90, a Blender export vertices at 0. Viewers
differ on such rows (three.js normalises them, others skin with them as stored), while every
level was built and measured from the normalised weights; a viewer of the second kind would jump
between level 0 and level 1. So the rows that break the rule are written normalised, all-zero
rows on their first joint (as the readers take them), and nothing else of level 0 changes.
`animlod info` counts the same rows (:func:`stored_unit_sum_breaks`) and says it in the same words.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from .glb_builder import ARRAY_BUFFER, GlbBuilder
from .gltf_document import GltfDocument
from .gltf_draco import DRACO_EXTENSION
from .gltf_read import on_first_joint_when_unweighted

if TYPE_CHECKING:  # gltf_drawable may count with this module (stored_unit_sum_breaks)
    from .gltf_drawable import Drawable

_SUM_STEP = 0.0039216  # the validator's allowance per two weights beyond two: about 1/255


def unit_sum_breaks(weights: np.ndarray) -> np.ndarray:
    """(V,) whether each row of ``weights (V, 4 S)`` (S sets of four, as JOINTS_s/WEIGHTS_s
    interleave them: component 0 of every set, then component 1, ...) breaks the validator's
    float32 unit-sum rule."""
    sets = weights.shape[1] // 4
    total = np.zeros(len(weights), np.float32)
    for column in np.arange(4 * sets).reshape(sets, 4).T.ravel():
        total = (total + np.maximum(weights[:, column], 0.0).astype(np.float32)).astype(np.float32)
    allowed = _SUM_STEP * ((np.count_nonzero(weights > 0.0, axis=1) + 1) // 2 - 1)
    return np.abs(total.astype(np.float64) - 1.0) > allowed


class UnitSumBreaks(NamedTuple):
    """The vertices of a mesh whose stored skin weights break glTF's unit sum, and how far their
    sums were from 1 at most."""

    vertices: int
    worst: float

    def describe(self) -> str:
        """The finding in words, as `animlod info` and the LoD writers' notes give it."""
        return (f"skin weights of {self.vertices} vertices did not sum to 1 as glTF requires "
                f"(off by up to {self.worst:.3g})")  # fmt: skip


def stored_unit_sum_breaks(doc: GltfDocument, mesh_index: int) -> UnitSumBreaks:
    """The vertices of mesh ``mesh_index`` whose stored weights break the rule (:func:`unit_sum_breaks`):
    those level 0 of a LoD GLB writes normalised."""
    return _breaks(_stored_weights(doc, mesh_index))


def normalise_stored_weights(builder: GlbBuilder, doc: GltfDocument, drawable: Drawable) -> str | None:
    """Rewrites, in ``builder`` (taken over from ``doc``), the WEIGHTS_n of the skinned
    ``drawable``'s primitives whose rows break the rule (once per mesh, however many drawables
    draw it): over the stored float32 data where nothing else uses it, else as new float32
    accessors. Draco-compressed primitives keep theirs: their decoder
    reads the compressed data. Returns a note for the report, None when nothing was rewritten."""
    if drawable.skin_index is None:
        return None
    mesh = drawable.mesh_index
    stored = _stored_weights(doc, mesh)
    written = builder.json["meshes"][mesh]["primitives"]
    if any(
        written[weights.primitive]["attributes"][name] != accessor or accessor in builder.overwritten
        for weights in stored
        for name, accessor in weights.accessors.items()
    ):  # done for another drawable of the mesh
        return None
    breaks = _breaks(stored)
    if not breaks.vertices:
        return None
    for weights in stored:
        _write_normalised(builder, written[weights.primitive]["attributes"], weights)
    return f"level 0 (the input mesh): {breaks.describe()}; written normalised"


class _StoredWeights(NamedTuple):
    """A primitive's skin weights as stored: its index in the mesh, its WEIGHTS_n accessors by
    name (set order), and ``values (V, 4 S)`` float64, set after set."""

    primitive: int
    accessors: dict[str, int]
    values: np.ndarray


def _stored_weights(doc: GltfDocument, mesh_index: int) -> list[_StoredWeights]:
    """The skin weights of each primitive of mesh ``mesh_index`` that has them, but for
    Draco-compressed ones (level 0 keeps their compressed data)."""
    found = []
    for index, primitive in enumerate(doc.json["meshes"][mesh_index]["primitives"]):
        attributes = primitive.get("attributes", {})
        names = sorted(
            (name for name in attributes if name[:8] == "WEIGHTS_" and name[8:].isdigit()), key=lambda n: int(n[8:])
        )
        if not names or DRACO_EXTENSION in (primitive.get("extensions") or {}):
            continue
        element = f"mesh {mesh_index} primitive {index}"
        values = np.concatenate([doc.accessor(attributes[name], element) for name in names], axis=1)
        found.append(_StoredWeights(index, {name: attributes[name] for name in names}, values.astype(np.float64)))
    return found


def _breaks(stored: list[_StoredWeights]) -> UnitSumBreaks:
    """What breaks the rule in ``stored``, each set of accessors counted once (UniVRM's primitives
    share one vertex buffer)."""
    distinct = {tuple(weights.accessors.values()): weights.values for weights in stored}
    sums = [np.maximum(values[unit_sum_breaks(values)], 0.0).sum(axis=1) for values in distinct.values()]
    off = np.abs(np.concatenate(sums or [np.zeros(0)]) - 1.0)
    return UnitSumBreaks(len(off), float(off.max(initial=0.0)))


def _write_normalised(builder: GlbBuilder, written: dict, stored: _StoredWeights) -> None:
    """The rows of ``stored`` that break the rule normalised, all-zero ones on their first joint
    (as the readers take them), into ``written`` (the primitive's attributes in ``builder``)."""
    weights = stored.values.copy()
    broken = unit_sum_breaks(weights)
    if not broken.any():
        return
    rows = on_first_joint_when_unweighted(np.maximum(weights[broken], 0.0))
    weights[broken] = rows / rows.sum(axis=1, keepdims=True)
    for set_index, (name, accessor) in enumerate(stored.accessors.items()):
        rewritten = weights[:, 4 * set_index : 4 * set_index + 4].astype(np.float32)
        if not builder.overwrite(accessor, rewritten):  # the input's float weights, in place
            written[name] = builder.add(rewritten, ARRAY_BUFFER)
