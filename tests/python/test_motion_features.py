"""Motion features (paper section "Rotation connected graph") through animlod.simplify."""

from __future__ import annotations

import math

import numpy as np
import pytest
from simplify_inputs import bending_tube

from animlod import _core, synth
from animlod.aqem import motion_features
from animlod.model import AnimatedMesh


def test_a_hinge_reports_its_exact_angle_change():
    fold = math.radians(30)
    frames = np.array(
        [
            [[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -1, 0]],
            [[0, 0, 0], [1, 0, 0], [0.5, 1, 0], [0.5, -math.cos(fold), math.sin(fold)]],
        ],
        np.float32,
    )
    hinge = AnimatedMesh([[0, 1, 2], [1, 0, 3]], frames)
    features = motion_features(hinge, feature_threshold=0.1, boundary_is_feature=False, feature_weighting="paper")
    np.testing.assert_array_equal(features.edges[0], [0, 1])
    assert features.angle_change[0] == pytest.approx(fold, rel=1e-6)
    assert features.amplitude[0] == pytest.approx(fold, rel=1e-6)
    np.testing.assert_array_equal(features.connected, [True, False, False, False, False])
    np.testing.assert_array_equal(features.vertex_weights, [2, 2, 1, 1])  # Eq. 6: the feature's size
    # The default weighs by amplitude: 30 degrees is over twice T = 0.1 rad, the largest weight.
    amplitude = motion_features(hinge, feature_threshold=0.1, boundary_is_feature=False, max_feature_weight=3.0)
    np.testing.assert_array_equal(amplitude.vertex_weights, [3, 3, 1, 1])


def test_a_rigidly_translating_mesh_has_no_motion_features():
    features = motion_features(synth.translating_mesh(frames=8))
    assert features.feature_sizes.size == 0
    assert np.all(features.vertex_weights == 1)
    assert features.angle_change.max() < math.radians(1)


def test_a_bending_cylinder_has_its_features_at_the_bend():
    mesh = synth.bending_cylinder(frames=8)
    features = motion_features(mesh, feature_weighting="paper")
    in_feature = features.vertex_feature >= 0
    height = mesh.frames[0, :, 1]
    # The skin weights blend over 0.8 <= y <= 1.2: the elbow; nothing else bends.
    assert in_feature.any()
    assert height[in_feature].min() >= 0.75 and height[in_feature].max() <= 1.25
    sizes = features.feature_sizes[features.vertex_feature[in_feature]]
    np.testing.assert_array_equal(features.vertex_weights[in_feature], sizes)
    assert np.all(features.vertex_weights[~in_feature] == 1)
    # The amplitude weighting finds the elbow too, with weights in (1, 4].
    amplitude = motion_features(mesh)
    weighted = amplitude.vertex_weights > 1
    assert weighted.any() and amplitude.vertex_weights.max() <= 4
    assert height[weighted].min() >= 0.75 and height[weighted].max() <= 1.25


def test_a_uniform_twist_stays_below_the_one_degree_floor():
    features = motion_features(synth.twisting_bar(frames=16))
    assert features.angle_change.max() < math.radians(1)
    assert features.feature_sizes.size == 0


def test_boundaries_are_features_by_default():
    features = motion_features(bending_tube(frames=2, bend=0.0))
    np.testing.assert_array_equal(features.feature_sizes, [12, 12])  # the two open ends


def test_crane_features_are_found(data_dir):
    from animlod.io.meshseq import read_sequence

    mesh = read_sequence(data_dir / "meshseq" / "crane")
    features = motion_features(mesh, feature_weighting="paper")
    assert features.edges.shape == (30000, 2)  # closed genus-0 mesh: E = 3M / 2
    assert 0 < features.threshold < math.pi
    assert features.feature_sizes.sum() == np.count_nonzero(features.vertex_feature >= 0)
    # The capture noise puts the paper's THR inside the noise: features of over a thousand
    # vertices, weighing over a thousand each. The amplitude threshold sits above the noise, and
    # its weights stay bounded on the few edges that move far more than the rest.
    assert features.vertex_weights.max() > 1000
    amplitude = motion_features(mesh)
    assert amplitude.threshold > 5 * np.median(amplitude.amplitude)
    assert np.count_nonzero(amplitude.vertex_weights > 1) < 0.05 * mesh.vertex_count
    assert amplitude.vertex_weights.max() <= 4


def test_an_unknown_weighting_is_refused_by_name():
    mesh = bending_tube(frames=3)
    expected = r"^MotionFeatureOptions.feature_weighting: expected one of 'amplitude', 'paper', got 'size'$"
    with pytest.raises(ValueError, match=expected):
        motion_features(mesh, feature_weighting="size")
    with pytest.raises(ValueError, match=r"max_feature_weight must be finite and >= 1"):
        motion_features(mesh, max_feature_weight=0.5)


def test_int64_faces_are_range_checked_not_wrapped():
    # Regression: forcecast turned index 2**32 + 1 into 1.
    mesh = bending_tube(frames=3)
    wide = _core.motion_features(mesh.frames, mesh.faces.astype(np.int64))
    np.testing.assert_array_equal(wide["edges"], _core.motion_features(mesh.frames, mesh.faces)["edges"])
    faces = mesh.faces.astype(np.int64)
    faces[0, 2] = -(2**31) - 1
    with pytest.raises(ValueError, match=r"^faces: element \(0, 2\) = -2147483649 does not fit int32$"):
        _core.motion_features(mesh.frames, faces)


def _dihedral_reference(mesh: AnimatedMesh, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """numpy's g_i (largest step) and a_i (range of the unwrapped angle) per edge: the signed
    angle between the normals of the faces going lower -> higher and higher -> lower along it."""
    faces = np.asarray(mesh.faces, np.int64)
    starts, ends = faces.ravel(), np.roll(faces, -1, axis=1).ravel()
    vertex_count = mesh.frames.shape[1]
    keys = np.minimum(starts, ends) * vertex_count + np.maximum(starts, ends)
    edge_of_side = np.searchsorted(edges[:, 0].astype(np.int64) * vertex_count + edges[:, 1], keys)
    face_of_side = np.repeat(np.arange(len(faces)), 3)
    sided = np.full((len(edges), 2), -1)
    sided[edge_of_side, (starts > ends).astype(int)] = face_of_side
    interior = (sided >= 0).all(axis=1)
    frames = mesh.frames.astype(np.float64)
    corners = frames[:, faces]
    normals = np.cross(corners[:, :, 1] - corners[:, :, 0], corners[:, :, 2] - corners[:, :, 0])
    n0, n1 = normals[:, sided[interior, 0]], normals[:, sided[interior, 1]]
    along = frames[:, edges[interior, 1]] - frames[:, edges[interior, 0]]
    along /= np.linalg.norm(along, axis=2, keepdims=True)
    angles = np.arctan2(np.einsum("fei,fei->fe", np.cross(n0, n1), along), np.einsum("fei,fei->fe", n0, n1))
    steps = np.diff(angles, axis=0)
    steps = np.where(steps > np.pi, steps - 2 * np.pi, np.where(steps < -np.pi, steps + 2 * np.pi, steps))
    unwrapped = np.concatenate([np.zeros((1, steps.shape[1])), np.cumsum(steps, axis=0)])
    change, amplitude = np.zeros(len(edges)), np.zeros(len(edges))
    change[interior] = np.abs(steps).max(axis=0)
    amplitude[interior] = unwrapped.max(axis=0) - unwrapped.min(axis=0)
    return change, amplitude


def test_dihedral_changes_of_a_mesh_split_over_threads_match_numpy():
    # Over 8,192 edges: the core splits the edges between threads (kEdgesPerThread = 4,096).
    mesh = synth.bending_cylinder(frames=6, rings=100, segments=48)
    noise = np.random.default_rng(3).normal(scale=0.004, size=mesh.frames.shape).astype(np.float32)
    mesh = AnimatedMesh(mesh.faces, mesh.frames + noise)
    features = motion_features(mesh, feature_weighting="paper")
    assert len(features.edges) > 2 * 4096
    change, amplitude = _dihedral_reference(mesh, np.asarray(features.edges))
    np.testing.assert_allclose(features.angle_change, change, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(features.amplitude, amplitude, rtol=1e-5, atol=1e-6)
