"""Shapes of game and DCC glTF exports that a bug hunt of `animlod character` and `animlod motion`
found mishandled, rebuilt small from procedural meshes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib
from gltf_edits import append_accessor, edit_glb
from simplify_inputs import two_bone_tube

from animlod.io.gltf import write_glb
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines.motion import build_motion_levels
from animlod.pipelines.surface_attributes import joined_surface

# A quarter turn about x: the mesh node's parent in the tests below (Blender's Z-up armature object).
_TURN = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def _lightmapped_tube(tmp_path: Path) -> tuple[Path, dict[str, np.ndarray]]:
    """The two-bone tube with a lightmap's TEXCOORD_1 (which its material's occlusion texture
    reads), vertex colours as normalized unsigned bytes and tangents, its mesh node under a
    turned parent; and those attributes as stored."""
    skinned, motion = two_bone_tube()
    count = skinned.vertex_count
    stored = {
        "TEXCOORD_1": np.linspace([0.0, 1.0], [1.0, 0.0], count).astype(np.float32),
        "COLOR_0": np.linspace([0, 64, 128, 255], [255, 128, 64, 255], count).astype(np.uint8),
        "TANGENT": np.tile(np.array([[0.0, 0.0, 1.0, -1.0]], np.float32), (count, 1)),
    }

    def lightmapped(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        attributes = gltf.meshes[0].primitives[0].attributes
        for name, values in stored.items():
            width = {2: "VEC2", 4: "VEC4"}[values.shape[1]]
            setattr(attributes, name, append_accessor(gltf, blob, values, width, normalized=name == "COLOR_0"))
        png = b"\x89PNG\r\n\x1a\n" + bytes(24)
        offset = len(blob)
        blob.extend(png)
        gltf.bufferViews.append(pygltflib.BufferView(buffer=0, byteOffset=offset, byteLength=len(png)))
        gltf.images.append(pygltflib.Image(bufferView=len(gltf.bufferViews) - 1, mimeType="image/png"))
        gltf.textures.append(pygltflib.Texture(source=0))
        gltf.materials.append(pygltflib.Material(name="baked", occlusionTexture={"index": 0, "texCoord": 1}))
        gltf.meshes[0].primitives[0].material = 0
        mesh_node = next(n for n, node in enumerate(gltf.nodes) if node.mesh is not None)
        gltf.scenes[0].nodes.remove(mesh_node)
        gltf.nodes.append(pygltflib.Node(name="armature", children=[mesh_node], rotation=[0.5**0.5, 0, 0, 0.5**0.5]))
        gltf.scenes[0].nodes.append(len(gltf.nodes) - 1)

    write_glb(tmp_path / "tube.glb", skinned, [motion])
    return edit_glb(tmp_path / "tube.glb", tmp_path / "lightmapped.glb", lightmapped), stored


def test_motion_levels_keep_the_attributes_the_materials_read(tmp_path: Path) -> None:
    """The motion levels' GLBs dropped every vertex attribute but positions, normals and the first
    texture coordinates: a material reading TEXCOORD_1 (a lightmap) then named an attribute the
    mesh lacked (an error for the glTF-Validator), and vertex colours and tangents were lost."""
    source, stored = _lightmapped_tube(tmp_path)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    assert len(report.files) == 2
    for files in report.files:
        written = GltfDocument(tmp_path / "levels" / files[-1])
        (primitive,) = written.json["meshes"][0]["primitives"]
        assert written.json["materials"][primitive["material"]]["occlusionTexture"]["texCoord"] == 1
        read = {name: np.asarray(written.accessor(primitive["attributes"][name], "test")) for name in stored}
        np.testing.assert_array_equal(read["TEXCOORD_1"], stored["TEXCOORD_1"])
        np.testing.assert_allclose(read["COLOR_0"], stored["COLOR_0"] / 255.0, atol=1e-7)
        # The levels store the mesh as its parent turns it: tangents turn with the positions.
        np.testing.assert_allclose(read["TANGENT"][:, :3], stored["TANGENT"][:, :3] @ _TURN.T, atol=1e-6)
        np.testing.assert_array_equal(read["TANGENT"][:, 3], stored["TANGENT"][:, 3])


def test_tangents_of_a_skinned_mesh_at_zero_scale_stay_as_stored(tmp_path: Path) -> None:
    """Skinning ignores the mesh node's transform, and a mesh at zero scale is read in its own
    space; its tangents were turned by the zero-scale transform instead, to zero vectors."""
    source, stored = _lightmapped_tube(tmp_path)

    def squashed(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        next(node for node in gltf.nodes if node.name == "armature").scale = [0.0, 0.0, 0.0]

    edit_glb(source, tmp_path / "squashed.glb", squashed)
    report = build_motion_levels(tmp_path / "squashed.glb", tmp_path / "levels", levels=2)
    for files in report.files:
        written = GltfDocument(tmp_path / "levels" / files[-1])
        (primitive,) = written.json["meshes"][0]["primitives"]
        np.testing.assert_allclose(written.accessor(primitive["attributes"]["TANGENT"], "test"), stored["TANGENT"])


def test_motion_levels_keep_the_texture_coordinates_of_a_textured_primitive_beside_a_plain_one(
    tmp_path: Path,
) -> None:
    """A mesh whose textured primitive has TEXCOORD_0 and whose plain one (eyes, a belt buckle) has
    none lost them in the motion levels' GLBs, the textured material reading an attribute its
    primitive lacked."""
    skinned, motion = two_bone_tube()
    halves = np.array_split(skinned.faces, 2)

    def textured_and_plain(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        textured = gltf.meshes[0].primitives[0]
        plain = pygltflib.Attributes(**{**vars(textured.attributes), "TEXCOORD_0": None})
        parts = []
        for material, (faces, attributes) in enumerate(zip(halves, [textured.attributes, plain])):
            indices = append_accessor(gltf, blob, faces.astype(np.uint32).reshape(-1, 1), "SCALAR")
            parts.append(pygltflib.Primitive(attributes=attributes, indices=indices, material=material))
        gltf.meshes[0].primitives = parts
        gltf.materials += [pygltflib.Material(name="printed", occlusionTexture={"index": 0}), pygltflib.Material()]
        gltf.textures.append(pygltflib.Texture())  # no image: a viewer draws it white

    write_glb(tmp_path / "tube.glb", skinned, [motion])
    source = edit_glb(tmp_path / "tube.glb", tmp_path / "textured_and_plain.glb", textured_and_plain)
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    for files in report.files:
        written = GltfDocument(tmp_path / "levels" / files[-1])
        textured = written.json["meshes"][0]["primitives"][0]
        assert textured["material"] == 0
        used = np.unique(halves[0])
        uvs = written.accessor(textured["attributes"]["TEXCOORD_0"], "test")
        np.testing.assert_array_equal(uvs, skinned.uvs[used])


def test_pieces_without_an_attribute_are_drawn_as_glTF_draws_them() -> None:
    """Joined pieces (primitives, parts) where one lacks an attribute: colours white (a VEC3 colour
    beside VEC4 ones with alpha 1), texture coordinates (0, 0), tangents left out."""
    coloured = {
        "COLOR_0": np.full((2, 3), 0.5, np.float32),
        "COLOR_1": np.full((2, 4), 0.25, np.float32),
        "TEXCOORD_1": np.ones((2, 2), np.float32),
        "TANGENT": np.tile(np.float32([1, 0, 0, 1]), (2, 1)),
    }
    plain = {"COLOR_0": np.full((1, 4), 0.75, np.float32)}
    joined = joined_surface([(coloured, 2), (plain, 1)])
    assert sorted(joined) == ["COLOR_0", "COLOR_1", "TEXCOORD_1"]
    np.testing.assert_array_equal(joined["COLOR_0"], [[0.5, 0.5, 0.5, 1.0]] * 2 + [[0.75] * 4])
    np.testing.assert_array_equal(joined["COLOR_1"], [[0.25] * 4] * 2 + [[1.0] * 4])
    np.testing.assert_array_equal(joined["TEXCOORD_1"], [[1.0, 1.0]] * 2 + [[0.0, 0.0]])
