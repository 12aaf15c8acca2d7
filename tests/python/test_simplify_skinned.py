"""simplify_skinned: AQEM over the rest pose and baked motions; the levels still skin."""

from __future__ import annotations

import numpy as np
import pytest
from simplify_inputs import directed_edges_unique, two_bone_tube

from animlod import synth
from animlod.aqem import simplify_skinned


def test_skinned_levels_skin_with_valid_merged_weights():
    skinned, motion = two_bone_tube()  # an open tube with UVs
    levels = simplify_skinned(skinned, [motion], (0.5, 0.2))
    assert [level.target_face_count for level in levels] == [180, 72]
    with pytest.raises(ValueError, match=r"motions: expected a list of clips, got one Motion \(pass \[motion\]\)"):
        simplify_skinned(skinned, motion, (0.5, 0.2))
    for level in levels:
        mesh = level.mesh
        assert mesh.face_count <= level.target_face_count
        assert directed_edges_unique(mesh.faces)
        assert mesh.joints.shape == (mesh.vertex_count, 2)
        assert mesh.joints.min() >= 0 and mesh.joints.max() < skinned.skeleton.joint_count
        np.testing.assert_allclose(mesh.weights.sum(axis=1), 1.0, rtol=1e-6)
        assert np.all(np.diff(mesh.weights, axis=1) <= 0)
        assert mesh.uvs.shape == (mesh.vertex_count, 2)
        # Re-skinned with the merged weights, the level follows the poses AQEM placed it in to
        # within 15% of the tube radius (0.2).
        assert level.skinning_error < 0.03
    # At 50% the tube's straight parts collapse without error: skinning reproduces it exactly.
    assert levels[0].skinning_error < 1e-5


def test_reskinned_level_stays_close_to_the_original_animation():
    from animlod.metrics import surface_error

    skinned, motion = two_bone_tube()
    level = simplify_skinned(skinned, [motion], (0.25,))[0]
    error = surface_error(skinned.bake(motion), level.mesh.bake(motion), samples=2000)
    # Within 2% of the bounding-box diagonal in every frame of the bend.
    assert error.summary()["hausdorff_max"] < 0.02


def test_procedural_humanoid_walk_still_skins():
    skinned = synth.humanoid()
    walk = synth.humanoid_motion(skinned.skeleton, "walk")
    levels = simplify_skinned(skinned, [walk], (0.5, 0.2))
    height = float(np.ptp(skinned.rest_positions[:, 1]))
    for level in levels:
        mesh = level.mesh
        assert mesh.face_count <= level.target_face_count
        assert directed_edges_unique(mesh.faces)
        assert mesh.joints.max() < skinned.skeleton.joint_count
        np.testing.assert_allclose(mesh.weights.sum(axis=1), 1.0, rtol=1e-5)
        assert level.skinning_error < 0.02 * height
    errors = [level.error for level in levels]
    assert errors == sorted(errors)


def test_bending_cylinder_level_follows_the_bend_after_reskinning():
    from animlod.metrics import surface_error

    skinned, motion = synth.bending_cylinder_skinned(frames=8)
    level = simplify_skinned(skinned, [motion], (0.2,))[0]
    error = surface_error(skinned.bake(motion), level.mesh.bake(motion), samples=2000)
    assert error.summary()["hausdorff_max"] < 0.02


def test_levels_convert_to_the_one_chain_type():
    from animlod.aqem import simplify_animated, skinned_lod_chain

    character = synth.humanoid()
    walk = synth.humanoid_motion(character.skeleton, "walk")
    levels = simplify_skinned(character, [walk], (0.5, 0.25))
    chain = skinned_lod_chain(character, [walk], levels, "humanoid")
    assert [level.mesh.face_count for level in chain.levels] == [3664, 1832, 916]
    assert [level.mesh_level for level in chain.levels] == [0, 1, 2] and chain.levels[0].error == 0.0
    baked = character.bake(walk)
    animated = simplify_animated(baked, (0.5,)).lod_chain(baked)
    assert animated.levels[0].mesh is baked and animated.levels[1].error > 0.0
