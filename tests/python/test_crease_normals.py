"""Normals rebuilt from a level's own faces (``drawable_levels.with_crease_normals``, for meshes
with hard edges): every corner gets a unit normal and every tangent a unit direction across it,
whatever the faces (glTF requires unit NORMAL and TANGENT vectors)."""

from __future__ import annotations

import numpy as np

from animlod.io.gltf_lod import PrimitiveArrays
from animlod.pipelines.drawable_levels import with_crease_normals


def _primitive(positions, faces, tangents=None, uvs=None) -> PrimitiveArrays:
    positions = np.asarray(positions, np.float32)
    attributes = {"POSITION": positions, "NORMAL": np.zeros_like(positions)}
    if tangents is not None:
        attributes["TANGENT"] = np.asarray(tangents, np.float32)
    if uvs is not None:
        attributes["TEXCOORD_0"] = np.asarray(uvs, np.float32)
    return PrimitiveArrays(0, attributes, np.asarray(faces), [], np.arange(len(positions)))


def _corner_normals(result: PrimitiveArrays) -> np.ndarray:
    return result.attributes["NORMAL"][result.faces].astype(np.float64)


def test_flat_shading_gives_each_corner_its_faces_unit_normal():
    # At crease 0 a corner joins only faces turned by 0 degrees from its own; the test of its
    # face against itself once failed by rounding for about half the faces, leaving zero normals.
    rng = np.random.default_rng(7)
    positions = rng.random((60, 3))
    faces = np.array([rng.choice(60, 3, replace=False) for _ in range(200)])
    result = with_crease_normals(_primitive(positions, faces), 0.0)
    corners = positions[faces]
    face_normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    face_normal /= np.linalg.norm(face_normal, axis=1, keepdims=True)
    np.testing.assert_allclose(_corner_normals(result), np.repeat(face_normal[:, None], 3, axis=1), atol=1e-6)


def test_a_degenerate_faces_corners_get_a_unit_normal():
    # Two faces of a quad, a zero-area face on its diagonal, and a lone zero-area face.
    positions = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0], [3, 0, 0], [4, 0, 0], [5, 0, 0]]
    faces = [[0, 1, 2], [0, 2, 3], [0, 4, 2], [5, 6, 7]]
    for crease in (0.0, np.radians(30.0)):
        normals = _corner_normals(with_crease_normals(_primitive(positions, faces), crease))
        np.testing.assert_allclose(np.linalg.norm(normals, axis=2), 1.0, atol=1e-6)
        np.testing.assert_allclose(normals[:2], [[[0, 0, 1]] * 3] * 2, atol=1e-6)  # the quad as it was


# A floor (normal +y) and a wall (normal +z) meeting at a hard edge, every vertex with the
# floor's tangent +z: the wall's corners, split off at the crease, have it along their normal.
_L_POSITIONS = [[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1], [1, 1, 0], [0, 1, 0]]
_L_FACES = [[0, 2, 1], [0, 3, 2], [0, 1, 4], [0, 4, 5]]
_L_TANGENTS = [[0, 0, 1, -1]] * 6


def test_a_tangent_along_its_corners_new_normal_turns_across_it():
    result = with_crease_normals(_primitive(_L_POSITIONS, _L_FACES, _L_TANGENTS), 0.0)
    tangent, normal = result.attributes["TANGENT"].astype(np.float64), result.attributes["NORMAL"]
    np.testing.assert_allclose(np.linalg.norm(tangent[:, :3], axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(np.einsum("vc,vc->v", tangent[:, :3], normal), 0.0, atol=1e-6)
    np.testing.assert_array_equal(tangent[:, 3], -1.0)


def test_a_tangent_along_its_corners_new_normal_follows_its_faces_texture():
    # With texture coordinates u = x, v = y, the wall's u runs along +x: its corners' tangent.
    uvs = [[x, y] for x, y, _ in _L_POSITIONS]
    result = with_crease_normals(_primitive(_L_POSITIONS, _L_FACES, _L_TANGENTS, uvs), 0.0)
    tangent, normal = result.attributes["TANGENT"][:, :3], result.attributes["NORMAL"]
    wall = np.abs(normal[:, 2] - 1.0) < 1e-6
    assert wall.sum() == 4
    np.testing.assert_allclose(tangent[wall], [[1, 0, 0]] * 4, atol=1e-6)
    np.testing.assert_allclose(tangent[~wall], [[0, 0, 1]] * 4, atol=1e-6)  # the floor's kept
