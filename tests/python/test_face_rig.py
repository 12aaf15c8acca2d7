"""Regions, MPAs, the rig and the active tree on the procedural face."""

from __future__ import annotations

import numpy as np
import pytest

from animlod.face_lod import ActiveTree, Expression, FaceRegions, FaceRig, Mpa, RegionGroup, procedural_face
from animlod.face_lod.mpa import expression_intensities, expression_sequence
from animlod.synth import face_mpa


@pytest.fixture(scope="module")
def face():
    return procedural_face()


def test_the_procedural_face_has_the_papers_structure(face):
    rig = face.rig
    assert len(rig.mpas) >= 12
    assert {e.name for e in face.expressions} >= {"smile", "anger", "surprise", "sadness"}
    assert {g.name for g in rig.regions.groups} == {"face_mask", "ears", "eyes", "teeth"}
    assert face.tree.active(face.tree.level_count - 1) == frozenset()
    # Every MPA moves the face, and every expression uses MPAs of the rig.
    animator = rig.animator()
    for index in range(len(rig.mpas)):
        weights = np.zeros(len(rig.mpas))
        weights[index] = 1.0
        assert np.abs(animator.frame(weights) - rig.positions).max() > 5e-4, rig.mpas[index].name
    for expression in face.expressions:
        assert np.any(expression_intensities(expression, rig.mpa_names))


def test_scalp_gaps_between_face_regions_are_closed():
    from animlod import synth

    model = synth.face()
    labels = face_mpa.animation_labels(model)
    scalp = model.region_names.index("scalp")
    assert (labels == scalp).sum() < (model.vertex_regions == scalp).sum()
    # Only scalp vertices change label, and ears, eyeballs and teeth keep theirs.
    changed = labels != model.vertex_regions
    assert np.all(model.vertex_regions[changed] == scalp)
    # Only the face is filled: the back of the head stays scalp.
    assert np.all(model.positions[changed, 2] > 0.0)


def test_zero_intensity_leaves_the_mesh_unchanged(face):
    rig = face.rig
    animator = rig.animator()
    assert np.any(animator.weights != 1.0)  # rational weights are in play (cheeks, lips)
    assert animator.frame(np.zeros(len(rig.mpas))).tobytes() == rig.positions.tobytes()
    frames = animator.frames(np.zeros((3, len(rig.mpas))))
    assert frames.tobytes() == np.broadcast_to(rig.positions, frames.shape).tobytes()


def test_mpas_add_up_linearly_so_levels_are_exact_blendshapes(face):
    rig = face.rig
    animator = rig.animator()
    a = np.random.default_rng(0).uniform(-1, 1, len(rig.mpas))
    b = np.random.default_rng(1).uniform(-1, 1, len(rig.mpas))
    combined = animator.frame(a + b).astype(np.float64)
    separate = animator.frame(a).astype(np.float64) + animator.frame(b) - rig.positions
    np.testing.assert_allclose(combined, separate, atol=1e-6)
    targets = animator.targets()
    np.testing.assert_allclose(rig.positions + np.tensordot(a, targets, axes=1), animator.frame(a), atol=1e-6)


def test_inactive_regions_do_not_move_at_a_level(face):
    rig, tree = face.rig, face.tree
    smile = expression_intensities(next(e for e in face.expressions if e.name == "smile"), rig.mpa_names)
    full = rig.animator().frame(smile)
    for level in range(tree.level_count):
        active = tree.active(level)
        moved = rig.animator(active=active).frame(smile)
        inactive = ~rig.regions.mask(active) if active else np.ones(len(moved), bool)
        assert moved[inactive].tobytes() == rig.positions[inactive].tobytes(), level
        # Active regions move as at full detail (control: the smile moves the lower mask).
        if "mouth" in active:
            mouth = rig.regions.mask(["mouth"])
            np.testing.assert_array_equal(moved[mouth], full[mouth])
            assert np.abs(moved[mouth] - rig.positions[mouth]).max() > 1e-3
    assert not rig.animator(active=tree.active(tree.level_count - 1)).animates


def test_mpa_on_a_region_that_does_not_exist_is_named(face):
    rig = face.rig
    bad = Mpa("wiggle_antenna", {"antenna": np.zeros((3, 3, 3, 3))})
    with pytest.raises(ValueError, match="MPA 'wiggle_antenna': no region named 'antenna'"):
        FaceRig(rig.positions, rig.faces, rig.regions, [bad])
    wrong_shape = Mpa("tiny", {"mouth": np.zeros((2, 2, 2, 3))})
    with pytest.raises(ValueError, match=r"MPA 'tiny', region 'mouth': displacements of shape \(2, 2, 2, 3\)"):
        FaceRig(rig.positions, rig.faces, rig.regions, [wrong_shape])
    with pytest.raises(ValueError, match="expression 'wink': no MPA named 'close_left_eye'"):
        expression_intensities(Expression("wink", {"close_left_eye": 1.0}), rig.mpa_names)
    with pytest.raises(ValueError, match="no region named 'antenna'"):
        rig.animator(active=["antenna"])


def test_labels_that_do_not_cover_the_mesh_are_named(face):
    rig = face.rig
    labels = rig.regions.vertex_regions.copy()
    labels[17] = -1
    with pytest.raises(ValueError, match="do not cover the mesh: vertex 17 has label -1"):
        FaceRegions(rig.regions.names, labels, rig.regions.groups)
    with pytest.raises(ValueError, match="do not cover the mesh: 1161 labels for 1162 vertices"):
        FaceRig(rig.positions, rig.faces, FaceRegions(rig.regions.names, labels[1:] * 0, rig.regions.groups))
    with pytest.raises(ValueError, match="region 'nose': in no region group"):
        FaceRegions(["nose", "mouth"], [0, 1], [RegionGroup("g", ["mouth"], 1.0)])


def test_active_tree_levels_must_nest_and_end_empty(face):
    names = face.rig.regions
    with pytest.raises(ValueError, match="level 1: region 'mouth' is not active at level 0"):
        ActiveTree([["jaw"], ["mouth"], []], names)
    with pytest.raises(ValueError, match="must animate no region"):
        ActiveTree([["jaw"]], names)
    with pytest.raises(ValueError, match="active tree level 0: no region named 'antenna'"):
        ActiveTree([["antenna"], []], names)
    tree = face.tree
    shrink = tree.transition(0, 2)
    assert shrink.kind == "shrink" and "eyeball_left" in shrink.deactivated and not shrink.activated
    assert tree.transition(2, 1).kind == "expand"
    assert tree.level_of("mouth") == tree.level_count - 2 and tree.level_of("scalp") == -1


def test_expression_sequence_plays_each_expression_in_turn(face):
    animation = expression_sequence(face.expressions, face.rig.mpa_names, seconds_each=0.5, fps=20)
    assert animation.frame_count == 4 * 10
    smile = expression_intensities(face.expressions[0], face.rig.mpa_names)
    peak = animation.intensities[:10][np.argmax(np.abs(animation.intensities[:10]).sum(1))]
    np.testing.assert_allclose(peak / np.abs(peak).max(), smile / np.abs(smile).max())
    np.testing.assert_array_equal(animation.intensities[[0, 9, 10]], 0.0)
