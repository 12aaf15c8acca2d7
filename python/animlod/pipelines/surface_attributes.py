"""The vertex attributes a skinned mesh's materials read besides normals, which
:class:`animlod.SkinnedMesh` does not carry whole: tangents, vertex colours and every set of
texture coordinates (a lightmap's TEXCOORD_1; TEXCOORD_0 too, which SkinnedMesh holds only where
every primitive has it), for writers of new documents (`animlod motion`'s level GLBs), whose
materials name them (``texCoord: 1``) and would otherwise draw wrong or not validate.

Where one piece of a joined mesh (a primitive, a part) lacks one, it is drawn as glTF draws a
primitive without it: colours white, texture coordinates (0, 0); tangents are not invented, and
are left out unless every piece has them (a viewer then derives them, as for the others).
"""

from __future__ import annotations

import numpy as np

from ..io.gltf_mesh import MeshGeometry, transform_tangents

# Normals are SkinnedMesh's (made where a part lacks them); skinning attributes are rewritten per level.
_SURFACE_PREFIXES = ("TANGENT", "TEXCOORD_", "COLOR_")


def joined_surface(pieces: list[tuple[dict[str, np.ndarray], int]]) -> dict[str, np.ndarray]:
    """The surface attributes of ``pieces`` ((attributes by glTF name, vertex count) each, in
    vertex order) as one mesh's, ``(V, width)`` float32 by name."""
    names = sorted({name for attributes, _ in pieces for name in attributes if name.startswith(_SURFACE_PREFIXES)})
    joined = {}
    for name in names:
        present = [attributes[name] for attributes, _ in pieces if name in attributes]
        if name == "TANGENT" and len(present) < len(pieces):
            continue
        width = max(values.shape[1] for values in present)  # a VEC3 colour beside VEC4 ones gets alpha 1
        fill = 1.0 if name.startswith("COLOR_") else 0.0
        values = np.full((sum(count for _, count in pieces), width), fill, np.float32)
        start = 0
        for attributes, count in pieces:
            if name in attributes:
                values[start : start + count, : attributes[name].shape[1]] = attributes[name]
            start += count
        joined[name] = values
    return joined


def node_surface(geometry: MeshGeometry, placement: np.ndarray) -> dict[str, np.ndarray]:
    """The surface attributes of a skinned mesh's ``geometry``, its primitives joined, in the space
    ``placement (4, 4)`` takes its vertices to (tangents turned with them)."""
    surface = joined_surface([(primitive.attributes, primitive.vertex_count) for primitive in geometry.primitives])
    if "TANGENT" in surface:
        surface["TANGENT"] = transform_tangents(placement, surface["TANGENT"])
    return surface
