"""Structures of real-world glTF exports that the development files do not have (the Khronos sample
characters, Mixamo, VRM, Blender and 3ds Max exports), rebuilt small from procedural meshes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib
from gltf_edits import append_accessor, edit_glb
from simplify_inputs import two_bone_tube

from animlod.io.gltf import read_gltf, write_glb
from animlod.pipelines.lod_document import simplify_document


def _two_bone_glb(path: Path) -> Path:
    skinned, motion = two_bone_tube()
    write_glb(path, skinned, [motion])
    return path


def test_primitives_with_four_and_eight_influences_keep_integer_joints(tmp_path: Path) -> None:
    """A mesh whose first primitive has 8 influences (JOINTS_1/WEIGHTS_1, as Mixamo and VRM exports
    write for dense areas) and whose second has 4: the 4-influence primitive is padded with joint 0 at
    weight 0. The padding was float32 and turned every joint slot into a float (IndexError)."""

    def second_set_on_a_copy(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        primitive = gltf.meshes[0].primitives[0]
        count = gltf.accessors[primitive.attributes.POSITION].count
        eight = pygltflib.Primitive(
            **{**vars(primitive), "attributes": pygltflib.Attributes(**vars(primitive.attributes))}
        )
        eight.attributes.JOINTS_1 = append_accessor(gltf, blob, np.ones((count, 4), np.uint8), "VEC4")
        eight.attributes.WEIGHTS_1 = append_accessor(gltf, blob, np.zeros((count, 4), np.float32), "VEC4")
        gltf.meshes[0].primitives = [eight, primitive]

    source = edit_glb(_two_bone_glb(tmp_path / "plain.glb"), tmp_path / "mixed.glb", second_set_on_a_copy)
    skinned = read_gltf(source).skinned_meshes[0]
    assert skinned.joints.dtype.kind in "iu"
    reference = read_gltf(tmp_path / "plain.glb").skinned_meshes[0]
    vertices = len(reference.rest_positions)
    np.testing.assert_allclose(skinned.rest_positions[vertices:], reference.rest_positions, atol=1e-6)
    report = simplify_document(source, tmp_path / "lod.glb")
    assert report.drawables and (tmp_path / "lod.glb").is_file()
