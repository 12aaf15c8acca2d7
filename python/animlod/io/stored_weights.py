"""Level 0's skin weights made to sum to 1, as glTF requires and as the levels are built.

A LoD GLB keeps the input mesh as its level 0, but an exporter's weights can break glTF's rule
that each vertex's weights sum to 1 (the Khronos validator sums them in float32 and allows
nothing for up to two weights, one step of 1/255 per two more): Khronos' own Monster and
RiggedFigure samples have vertices at 0.24 and 0.90, a Blender export vertices at 0. Viewers
differ on such rows (three.js normalises them, others skin with them as stored), while every
level was built and measured from the normalised weights; a viewer of the second kind would jump
between level 0 and level 1. So the rows that break the rule are written normalised, all-zero
rows on their first joint (as the readers take them), and nothing else of level 0 changes.
"""

from __future__ import annotations

import numpy as np

from .glb_builder import ARRAY_BUFFER, GlbBuilder
from .gltf_document import GltfDocument
from .gltf_draco import DRACO_EXTENSION
from .gltf_drawable import Drawable
from .gltf_read import on_first_joint_when_unweighted

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


def normalise_stored_weights(builder: GlbBuilder, doc: GltfDocument, drawable: Drawable) -> str | None:
    """Rewrites, in ``builder`` (taken over from ``doc``), the WEIGHTS_n of the skinned
    ``drawable``'s primitives whose rows break the rule (once per mesh, however many drawables
    draw it): over the stored float32 data where nothing else uses it, else as new float32
    accessors. Draco-compressed primitives keep theirs: their decoder
    reads the compressed data. Returns a note for the report, None when nothing was rewritten."""
    if drawable.skin_index is None:
        return None
    mesh = drawable.mesh_index
    rewritten = [
        _normalise_primitive(builder, doc, mesh, index) for index in range(len(doc.json["meshes"][mesh]["primitives"]))
    ]
    rows = sum(count for count, _ in rewritten)
    if not rows:
        return None
    worst = max(off for _, off in rewritten)
    return (f"level 0 (the input mesh): skin weights of {rows} vertices rewritten to sum to 1, as glTF requires "
            f"(they were off by up to {worst:.3g})")  # fmt: skip


def _normalise_primitive(builder: GlbBuilder, doc: GltfDocument, mesh_index: int, index: int) -> tuple[int, float]:
    """Rows of primitive ``index`` of mesh ``mesh_index`` rewritten (read from the input), and how
    far their sums were from 1 at most."""
    primitive = doc.json["meshes"][mesh_index]["primitives"][index]
    attributes = primitive.get("attributes", {})
    names = sorted(
        (name for name in attributes if name[:8] == "WEIGHTS_" and name[8:].isdigit()), key=lambda n: int(n[8:])
    )
    written = builder.json["meshes"][mesh_index]["primitives"][index]["attributes"]
    if any(written[name] != attributes[name] or written[name] in builder.overwritten for name in names):
        # done for another drawable of the mesh
        return 0, 0.0
    if not names or DRACO_EXTENSION in (primitive.get("extensions") or {}):
        return 0, 0.0
    element = f"mesh {mesh_index} primitive {index}"
    weights = np.concatenate([doc.accessor(attributes[name], element) for name in names], axis=1).astype(np.float64)
    broken = unit_sum_breaks(weights)
    if not broken.any():
        return 0, 0.0
    stored = np.maximum(weights[broken], 0.0)
    rows = on_first_joint_when_unweighted(stored)
    weights[broken] = rows / rows.sum(axis=1, keepdims=True)
    for set_index, name in enumerate(names):
        rewritten = weights[:, 4 * set_index : 4 * set_index + 4].astype(np.float32)
        if not builder.overwrite(attributes[name], rewritten):  # the input's float weights, in place
            written[name] = builder.add(rewritten, ARRAY_BUFFER)
    return int(broken.sum()), float(np.abs(stored.sum(axis=1) - 1.0).max())
