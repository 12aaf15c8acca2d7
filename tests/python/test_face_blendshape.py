"""Blendshape faces: ranking, pruning, simplification with targets carried, readers, real files."""

from __future__ import annotations

import dataclasses

import numpy as np
import pygltflib
import pytest

from animlod.face_lod import BlendshapeFace, BlendshapeLodOptions, build_blendshape_lod, procedural_face, rank_targets
from animlod.face_lod.blendshape import (
    TIMED_FRAMES,
    BlendshapeLevel,
    measure_blendshape_lod,
    one_at_a_time,
    prune_levels,
    target_contributions,
)
from animlod.face_lod.lod_glb import gltf_face_levels, read_gltf_face, write_gltf_face_lod
from animlod.face_lod.measure import measured_frames
from animlod.face_lod.mpa import expression_sequence
from animlod.face_lod.sources import pose_files, read_pose_face
from animlod.io import write_obj
from animlod.io.errors import FormatError
from animlod.synth import icosphere


@pytest.fixture(scope="module")
def face() -> BlendshapeFace:
    """The procedural face's MPAs baked as blendshapes, animated by its expressions."""
    procedural = procedural_face()
    rig = procedural.rig
    animation = expression_sequence(procedural.expressions, rig.mpa_names, seconds_each=0.5, fps=20)
    return BlendshapeFace(rig.positions, rig.faces, rig.animator().targets(), rig.mpa_names, animation.intensities)


def test_pruning_no_target_reproduces_the_blendshape_face_exactly(face):
    expected = face.frames().frames
    levels = build_blendshape_lod(face, BlendshapeLodOptions(face_counts=[len(face.faces)], target_fractions=[1, 1]))
    for level in levels:
        assert len(level.kept_targets) == face.target_count
        assert level.frames(face.weights).frames.tobytes() == expected.tobytes()
        np.testing.assert_allclose(level.frame(face.weights[7]), expected[7], atol=1e-7)  # float32 runtime path
    # Control: pruning half the targets (unused ones go first, then used ones) changes some frame.
    pruned = build_blendshape_lod(face, BlendshapeLodOptions(face_counts=[len(face.faces)], target_fractions=[1, 0.5]))
    assert np.abs(pruned[1].frames(face.weights).frames - expected).max() > 1e-4


def test_targets_are_ranked_by_the_largest_displacement_they_cause():
    neutral = np.random.default_rng(0).normal(size=(6, 3)).astype(np.float32)
    faces = np.array([[0, 1, 2], [0, 2, 3], [3, 4, 5]])
    targets = np.zeros((4, 6, 3), np.float32)
    targets[0, 0] = [1.0, 0, 0]  # 1.0 at weight up to 0.5 -> 0.5
    targets[1, 1] = [0, 0.3, 0]  # 0.3 at weight 1 -> 0.3
    targets[2, 2] = [0, 0, 2.0]  # 2.0 at weight up to 0.4 -> 0.8
    targets[3, 3] = [0, 0.6, 0]  # never driven: judged at weight 1 (driven at run time) -> 0.6
    weights = np.array([[0.5, 1.0, 0.0, 0.0], [0.0, 0.0, -0.4, 0.0]])
    face = BlendshapeFace(neutral, faces, targets, ["a", "b", "c", "d"], weights)
    np.testing.assert_allclose(target_contributions(face), [0.5, 0.3, 0.8, 0.6])
    np.testing.assert_array_equal(rank_targets(face), [2, 3, 0, 1])


def test_levels_prune_what_moves_less_than_their_geometric_error(face):
    levels = build_blendshape_lod(face, BlendshapeLodOptions(ratios=(0.5, 0.15, 0.08)))
    contributions = target_contributions(face)
    assert [level.triangle_count for level in levels] == sorted([level.triangle_count for level in levels])[::-1]
    for level in levels[1:-1]:
        kept = set(level.kept_targets.tolist())
        for index, contribution in enumerate(contributions):
            assert (index in kept) == (contribution > level.geometric_error)
        assert level.targets.shape == (len(kept), len(level.neutral), 3)
    assert len(levels[-1].kept_targets) == 0 and not levels[-1].targets.size  # the coarsest animates nothing
    assert len(levels[2].kept_targets) < face.target_count  # the rule does prune here
    kept_all = build_blendshape_lod(face, BlendshapeLodOptions(ratios=(0.5, 0.15, 0.08), animate_coarsest=True))
    assert len(kept_all[-1].kept_targets) > 0
    rows = measure_blendshape_lod(face, levels, repeats=1, max_frames=8, samples=2000)
    assert rows[0].hausdorff < 1e-9 and rows[1].hausdorff < 0.05
    assert [row.targets for row in rows] == [len(level.kept_targets) for level in levels]


def test_the_input_level_is_not_measured(face, monkeypatch):
    """Level 0 draws the face itself: error 0 without measuring it (it gave float rounding for a
    quarter of the time of face-poses' measurement); a copy of it is measured."""
    import animlod.metrics

    levels = build_blendshape_lod(face, BlendshapeLodOptions(ratios=(0.5,)))
    measured = []
    frame_hausdorff = animlod.metrics.frame_hausdorff

    def counted(*args, **kwargs):
        measured.append(args[1])
        return frame_hausdorff(*args, **kwargs)

    monkeypatch.setattr(animlod.metrics, "frame_hausdorff", counted)
    rows = measure_blendshape_lod(face, levels, repeats=1, max_frames=4, samples=500)
    assert len(measured) == 1 and rows[0].hausdorff == rows[0].hausdorff_units == 0.0
    copy = dataclasses.replace(levels[0], neutral=levels[0].neutral.copy())
    measure_blendshape_lod(face, [copy], repeats=1, max_frames=4, samples=500)
    assert len(measured) == 2


def test_blends_are_timed_on_a_bounded_sample_of_a_long_clip(monkeypatch):
    """Every frame of a clip was timed, repeats times per level: 30 of the 50 s `animlod face`
    took on a 3,000-frame clip of a 41k-vertex head."""
    positions, faces = icosphere(1, 0.1)
    targets = np.broadcast_to(0.02 * np.eye(3)[:, None], (3, len(positions), 3))
    weights = np.abs(np.sin(np.linspace(0.0, 40.0, 3000)[:, None] + np.arange(3)))
    face = BlendshapeFace(positions, faces, targets, ["x", "y", "z"], weights)
    (level,) = build_blendshape_lod(face, BlendshapeLodOptions(ratios=()))
    blended = []
    monkeypatch.setattr(type(level), "frame", lambda self, row: blended.append(row))
    measure_blendshape_lod(face, [level], repeats=2, max_frames=4, samples=200)
    assert len(blended) == 2 * TIMED_FRAMES
    blended.clear()
    measure_blendshape_lod(face, [level], repeats=1, max_frames=4, samples=200, timed_frames=0)
    assert len(blended) == len(weights)  # 0: every frame, as before


def test_errors_are_measured_where_every_target_peaks():
    """A pose folder's animation raises one target at a time from rest and back (15 frames
    each): of its 45 frames, 4 evenly spaced ones (0, 15, 29, 44) are all at rest, which
    reported the coarsest level (no targets) at its rest error, 0.28% for face-poses against
    18.9% over every frame."""
    positions, faces = icosphere(2, 0.1)
    targets = np.broadcast_to(0.02 * np.eye(3)[:, None], (3, len(positions), 3))  # shifts along x, y, z
    face = BlendshapeFace(positions, faces, targets, ["x", "y", "z"], one_at_a_time(3))
    weights = face.weights.copy()
    weights[:, 1] *= -1.0  # a clip may drive a target below zero: its peak is its largest |weight|
    np.testing.assert_array_equal(np.abs(weights[measured_frames(weights, 4)]).max(axis=0), [1.0, 1.0, 1.0])
    levels = build_blendshape_lod(face, BlendshapeLodOptions(ratios=(0.5,)))
    assert levels[-1].kept_targets.size == 0
    few = measure_blendshape_lod(face, levels, repeats=1, max_frames=4, samples=500)
    every = measure_blendshape_lod(face, levels, repeats=1, max_frames=len(face.weights), samples=500)
    assert few[-1].hausdorff_units == pytest.approx(every[-1].hausdorff_units, rel=1e-3)
    assert few[-1].hausdorff_units > 0.019  # a whole target's 0.02 shift, not the rest pose's error


def test_targets_that_only_turn_normals_are_kept(face):
    # Such a target moves no vertex: its contribution is 0, and the error rule would drop it.
    weakest = int(np.argmin(target_contributions(face)))
    shading = np.arange(face.target_count) == weakest
    options = BlendshapeLodOptions(ratios=(0.5, 0.15, 0.08))
    assert not all(weakest in level.kept_targets for level in build_blendshape_lod(face, options)[1:-1])
    every = BlendshapeLodOptions(ratios=options.ratios, target_fractions=[1.0] * 4)
    levels = build_blendshape_lod(face, every)  # not pruned yet
    prune_levels(face, levels, options, shading_only=shading)
    assert all(weakest in level.kept_targets for level in levels[1:-1])
    assert len(levels[-1].kept_targets) == 0  # the coarsest animates nothing still


def test_bad_blendshape_input_is_named():
    neutral = np.zeros((4, 3), np.float32)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    with pytest.raises(ValueError, match=r"morph target 1 'blink' has shape \(3, 3\): expected \(4, 3\)"):
        BlendshapeFace(neutral, faces, [np.zeros((4, 3)), np.zeros((3, 3))], ["smile", "blink"], np.zeros((1, 2)))
    with pytest.raises(ValueError, match=r"weights of shape \(1, 3\), expected \(T, 2\)"):
        BlendshapeFace(neutral, faces, np.zeros((2, 4, 3)), ["smile", "blink"], np.zeros((1, 3)))
    face = BlendshapeFace(neutral, faces, np.zeros((2, 4, 3)), ["smile", "blink"], np.zeros((1, 2)))
    with pytest.raises(ValueError, match="target fraction of level 1: 1.5 is outside"):
        build_blendshape_lod(face, BlendshapeLodOptions(face_counts=[2], target_fractions=[1.0, 1.5]))


def test_pose_folders_pick_the_neutral_face(tmp_path, face):
    for name in ("3.obj", "10.obj", "2.obj"):
        write_obj(tmp_path / name, face.neutral + 0.01 * int(name.split(".")[0]), face.faces)
    assert [p.name for p in pose_files(tmp_path)] == ["2.obj", "3.obj", "10.obj"]  # natural order
    write_obj(tmp_path / "face_neutral.obj", face.neutral, face.faces)
    assert pose_files(tmp_path)[0].name == "face_neutral.obj"
    assert pose_files(tmp_path, neutral="10.obj")[0].name == "10.obj"
    posed = read_pose_face(tmp_path)
    assert posed.names == ["2", "3", "10"] and posed.target_count == 3
    np.testing.assert_allclose(posed.targets[2], 0.1, atol=1e-6)
    with pytest.raises(FormatError, match="no file named 'absent.obj'"):
        pose_files(tmp_path, neutral="absent.obj")
    scans = tmp_path / "scans"  # a scanned pose set's rest mesh, named after its folder
    scans.mkdir()
    for name in ("1.obj", "4.obj", "scans.obj"):
        write_obj(scans / name, face.neutral, face.faces)
    assert [p.name for p in pose_files(scans)] == ["scans.obj", "1.obj", "4.obj"]
    single = tmp_path / "single"
    single.mkdir()
    write_obj(single / "only.obj", face.neutral, face.faces)
    with pytest.raises(FormatError, match="holds 1 OBJ/PLY file"):
        pose_files(single)


MORPH_FILES = ["morph/Parrot.glb", "morph/Stork.glb", "morph/MorphStressTest.gltf",
               "meshseq/Flamingo-morph-glTF/Flamingo.glb"]  # fmt: skip


@pytest.mark.parametrize("name", MORPH_FILES)
def test_every_morph_target_file_gets_levels(data_dir, name):
    face = read_gltf_face(data_dir / name).face
    assert face.target_count > 0 and len(face.weights) > 1
    levels = build_blendshape_lod(face)
    counts = [level.triangle_count for level in levels]
    assert counts == sorted(counts, reverse=True) and counts[-1] < 0.15 * counts[0]
    for level in levels:
        assert level.targets.shape == (len(level.kept_targets), len(level.neutral), 3)
        assert level.faces.max() < len(level.neutral)
        if face.uvs is not None:
            assert level.uvs.shape == (len(level.neutral), 2)
    # A level keeping every target blends to the same silhouette as the input, within its error.
    rows = measure_blendshape_lod(face, levels[:2], repeats=1, max_frames=6, samples=2000)
    assert rows[1].hausdorff < 0.2


@pytest.mark.parametrize("name", MORPH_FILES)
def test_every_morph_target_file_as_one_lod_glb(data_dir, tmp_path, name):
    source = read_gltf_face(data_dir / name)
    levels = gltf_face_levels(source)
    face = source.face
    contributions = target_contributions(face)
    for level in levels.levels[1:-1]:
        assert level.kept_targets.tolist() == np.flatnonzero(contributions > level.geometric_error).tolist()
    assert levels.levels[-1].kept_targets.size == 0  # the coarsest level animates nothing
    errors = [0.0] + [1.0 + level.geometric_error for level in levels.levels[1:]]
    coverages = [0.5 / (1 + index) for index in range(len(levels.levels) - 1)] + [0.0]
    path = tmp_path / "face_lod.glb"
    write_gltf_face_lod(path, source, levels, errors, coverages)
    glb = pygltflib.GLTF2().load(str(path))
    assert "MSFT_lod" in glb.extensionsUsed
    base = source.drawable.nodes[0]
    ids = glb.nodes[base].extensions["MSFT_lod"]["ids"]
    assert len(ids) == len(levels.levels) - 1
    assert glb.nodes[base].extras["MSFT_screencoverage"] == coverages
    base_mesh = glb.meshes[glb.nodes[base].mesh]
    for node, level in zip(ids, levels.levels[1:]):
        mesh = glb.meshes[glb.nodes[node].mesh]
        # Every level keeps every target slot, so the base node's morph-weight clip drives it.
        assert [len(p.targets) for p in mesh.primitives] == [len(p.targets) for p in base_mesh.primitives]
        assert glb.nodes[node].extras["animlod"]["targets"] == level.kept_targets.tolist()
    for animation in glb.animations:  # each level plays the base node's morph weights
        driven = {c.target.node: c.sampler for c in animation.channels if c.target.path == "weights"}
        if base in driven:
            assert all(driven.get(node) == driven[base] for node in ids)
        assert glb.nodes[node].extras["animlod"]["triangles"] == level.triangle_count
    assert len(glb.animations) == len(source.doc.gltf.animations)  # the input's clips are kept


def test_the_face_pose_scans_as_a_blendshape_face(data_dir):
    face = read_pose_face(data_dir / "meshseq" / "face-poses")  # its rest mesh, face-poses.obj, is the neutral
    assert face.names == ["1", "4", "9"]
    assert face.target_count == 3 and face.vertex_count == 29299
    levels = build_blendshape_lod(face, BlendshapeLodOptions(ratios=(0.5,), animate_coarsest=True))
    assert levels[1].triangle_count <= len(face.faces) // 2 + 1
    assert list(levels[1].kept_targets) == [0, 1, 2]  # every expression moves the face more than level 1 loses
    weights = np.eye(3)
    rows = measure_blendshape_lod(face, levels[:2], repeats=1, max_frames=3, samples=2000)
    assert rows[1].hausdorff < 0.01
    assert levels[1].frames(weights).frame_count == 3


def test_a_target_no_clip_drives_is_measured_at_full_weight():
    # Pruned at weight 1 (rigs drive it at run time) but measured only over the clip, where it
    # never moves: a level without it reported error 0.
    positions, faces = icosphere(2, 0.1)
    targets = np.zeros((2, len(positions), 3), np.float32)
    targets[0, :, 0], targets[1, :, 1] = 0.02, 0.005  # x driven by the clip, y by nothing
    weights = np.column_stack([one_at_a_time(1)[:, 0], np.zeros(len(one_at_a_time(1)))])
    face = BlendshapeFace(positions, faces, targets, ["x", "y"], weights)
    without_y = BlendshapeLevel(
        face.faces, face.neutral, face.targets[:1], np.array([0]), np.arange(len(positions)), None, 0.0
    )
    (row,) = measure_blendshape_lod(face, [without_y], repeats=1, max_frames=4, samples=500)
    assert row.hausdorff_units == pytest.approx(0.005, rel=1e-3)
