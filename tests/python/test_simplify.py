"""AQEM through animlod.simplify: invariants on procedural and real sequences."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from simplify_inputs import bending_tube, directed_edges_unique, ellipsoid, tube, tube_with_bow_tie_and_fin

from animlod import _core
from animlod.aqem import simplify_animated
from animlod.io.npz import write_npz
from animlod.model import AnimatedMesh


def test_levels_respect_targets_and_stay_valid_manifolds():
    mesh = bending_tube()
    result = simplify_animated(mesh, (0.5, 0.25, 0.1))
    assert [level.target_face_count for level in result.levels] == [180, 90, 36]
    for level in result.levels:
        assert level.reached
        assert level.mesh.face_count <= level.target_face_count
        assert level.mesh.frames.shape == (mesh.frame_count, level.kept_vertices.size, 3)
        assert level.mesh.faces.min() >= 0 and level.mesh.faces.max() < level.kept_vertices.size
        assert directed_edges_unique(level.mesh.faces)
        # Every input vertex maps to a kept vertex, and kept vertices map to themselves.
        assert level.vertex_map.min() >= 0
        np.testing.assert_array_equal(level.vertex_map[level.kept_vertices], np.arange(level.kept_vertices.size))
    errors = [level.error for level in result.levels]
    assert errors == sorted(errors) and errors[-1] > errors[0]
    collapses = [level.collapse_count for level in result.levels]
    assert collapses == sorted(collapses) and collapses[-1] == result.collapses.removed.size


def test_collapse_record_replays_to_the_last_level():
    mesh = bending_tube(frames=3)
    result = simplify_animated(mesh, (0.3,))
    record, level = result.collapses, result.levels[0]
    assert record.positions.shape == (record.removed.size, 3, 3)
    # The last collapse that touched each kept vertex gave it its final positions.
    last = {int(kept): i for i, kept in enumerate(record.kept)}
    for kept_index, vertex in enumerate(level.kept_vertices):
        expected = record.positions[last[vertex]] if vertex in last else mesh.frames[:, vertex]
        np.testing.assert_array_equal(level.mesh.frames[:, kept_index], expected)
    assert np.all(record.cost >= 0) and np.all(record.error >= 0)


@pytest.mark.parametrize("passes", [False, True])
def test_a_record_without_positions_keeps_the_levels_and_the_order(passes: bool):
    # Over 100k edges the engine runs collapse passes, whose two halves keep records of their own.
    mesh = ellipsoid(frames=2, rings=190, segments=190) if passes else bending_tube()
    full = simplify_animated(mesh, (0.5, 0.1))
    lean = simplify_animated(mesh, (0.5, 0.1), record_positions=False)
    assert full.collapses.positions.shape == (full.collapses.removed.size, mesh.frame_count, 3)
    assert lean.collapses.positions.shape == (0, mesh.frame_count, 3)
    for name in ("removed", "kept", "cost", "error"):
        np.testing.assert_array_equal(getattr(lean.collapses, name), getattr(full.collapses, name))
    for a, b in zip(full.levels, lean.levels, strict=True):
        assert a.mesh.faces.tobytes() == b.mesh.faces.tobytes()
        assert a.mesh.frames.tobytes() == b.mesh.frames.tobytes()


def test_output_is_deterministic():
    mesh = bending_tube()
    first = simplify_animated(mesh, (0.2,))
    second = simplify_animated(mesh, (0.2,))
    assert first.levels[0].mesh.faces.tobytes() == second.levels[0].mesh.faces.tobytes()
    assert first.levels[0].mesh.frames.tobytes() == second.levels[0].mesh.frames.tobytes()
    assert first.collapses.removed.tobytes() == second.collapses.removed.tobytes()


def test_identical_frames_give_the_single_frame_result():
    single = AnimatedMesh(bending_tube().faces, bending_tube().frames[-1:])
    repeated = AnimatedMesh(single.faces, np.repeat(single.frames, 4, axis=0))
    one = simplify_animated(single, (0.5, 0.2))
    four = simplify_animated(repeated, (0.5, 0.2))
    for a, b in zip(one.levels, four.levels):
        np.testing.assert_array_equal(a.mesh.faces, b.mesh.faces)
        np.testing.assert_allclose(b.mesh.frames, np.repeat(a.mesh.frames, 4, axis=0), atol=1e-6)
        assert b.error == pytest.approx(a.error, rel=1e-6, abs=1e-12)


def test_no_face_flips_in_any_frame():
    mesh = ellipsoid()
    level = simplify_animated(mesh, (0.08,)).levels[0]
    corners = level.mesh.frames[:, level.mesh.faces]  # (F, M', 3, 3)
    normals = np.cross(corners[:, :, 1] - corners[:, :, 0], corners[:, :, 2] - corners[:, :, 0])
    # The ellipsoid is convex and centred at the origin: outward normals agree with the centroid.
    assert np.all(np.sum(normals * corners.mean(axis=2), axis=-1) > 0)


def test_locked_vertices_keep_their_positions():
    mesh = bending_tube()
    locked = np.arange(84, 96)  # the ring at the elbow
    level = simplify_animated(mesh, (0.15,), locked_vertices=locked).levels[0]
    np.testing.assert_array_equal(level.kept_vertices[level.vertex_map[locked]], locked)
    np.testing.assert_array_equal(level.mesh.frames[:, level.vertex_map[locked]], mesh.frames[:, locked])


def test_importance_protects_a_region():
    mesh = ellipsoid(frames=1)
    right = mesh.frames[0, :, 0] > 0.3
    importance = np.where(right, 1000.0, 1.0).astype(np.float32)
    plain = simplify_animated(mesh, (0.25,), use_motion_features=False).levels[0]
    weighted = simplify_animated(mesh, (0.25,), use_motion_features=False, importance=importance).levels[0]
    assert right[weighted.kept_vertices].sum() > right[plain.kept_vertices].sum()


def test_max_error_stops_early_and_says_so():
    mesh = ellipsoid(frames=2)
    unbounded = simplify_animated(mesh, (0.9, 0.1))
    bound = unbounded.levels[0].error
    bounded = simplify_animated(mesh, (0.9, 0.1), max_error=bound)
    assert bounded.levels[0].reached and not bounded.levels[1].reached
    assert bounded.levels[1].error <= bound
    assert bounded.levels[1].mesh.face_count > 0.1 * mesh.face_count


def test_frame_sampling_covers_the_motion_and_positions_every_frame():
    mesh = bending_tube(frames=9)
    result = simplify_animated(mesh, (0.3,), max_frames=3)
    np.testing.assert_array_equal(result.frames_used, [0, 4, 8])
    assert result.levels[0].mesh.frame_count == 9
    explicit = simplify_animated(mesh, (0.3,), frame_subset=[8, 0, 4])
    np.testing.assert_array_equal(explicit.levels[0].mesh.faces, result.levels[0].mesh.faces)


def test_quadrics_over_every_frame_past_the_memory_limit_take_the_frames_that_fit():
    # A long dense capture's quadrics over every frame (80 bytes per point and frame) failed to
    # allocate; past the limit they are taken over the most frames that fit, as max_frames takes them.
    mesh = bending_tube(frames=9)
    every = simplify_animated(mesh, (0.3,))
    assert every.frames_used.size == 9
    fits_three = 80 * mesh.vertex_count * 3 + 79
    limited = simplify_animated(mesh, (0.3,), quadric_memory_limit=fits_three)
    sampled = simplify_animated(mesh, (0.3,), max_frames=3)
    np.testing.assert_array_equal(limited.frames_used, sampled.frames_used)
    np.testing.assert_array_equal(limited.levels[0].mesh.frames, sampled.levels[0].mesh.frames)
    assert simplify_animated(mesh, (0.3,), quadric_memory_limit=0).frames_used.size == 9  # no limit
    chosen = simplify_animated(mesh, (0.3,), quadric_memory_limit=fits_three, max_frames=5)
    assert chosen.frames_used.size == 5  # the caller's max_frames wins


def test_a_limited_sequence_says_how_many_frames_its_quadrics_took(tmp_path):
    from animlod.pipelines.lod_sequence import simplify_sequence

    mesh = bending_tube(frames=6)
    write_npz(tmp_path / "tube.npz", mesh)
    report = simplify_sequence(tmp_path / "tube.npz", tmp_path / "out", (0.5,), measure=False,
                               quadric_memory_limit=80 * mesh.vertex_count * 2)  # fmt: skip
    assert report.frames_used == 2 and report.levels[0].faces > 0


def test_uvs_are_carried_as_attributes():
    mesh = bending_tube(frames=2)
    rest = mesh.frames[0]
    uvs = np.stack([rest[:, 0], np.arctan2(rest[:, 2], rest[:, 1])], axis=1).astype(np.float32)
    level = simplify_animated(mesh, (0.5,), attributes=uvs, placement="on_edge").levels[0]
    assert level.attributes.shape == (level.kept_vertices.size, 2)
    # On-edge placement interpolates u with the same parameter as x in the rest pose.
    np.testing.assert_allclose(level.attributes[:, 0], level.mesh.frames[0, :, 0], atol=1e-5)


def test_progress_reports_the_collapses():
    calls = []
    result = simplify_animated(bending_tube(), (0.1,), progress=lambda done, total: calls.append((done, total)))
    planned = (360 - 36 + 1) // 2
    assert calls[0] == (0, planned) and calls[-1] == (result.collapses.removed.size, planned)


def test_degenerate_repeated_and_unreferenced_are_dropped_and_counted():
    mesh = bending_tube(frames=2)
    extra = mesh.frames[:, :1] + np.float32(5.0)  # vertex 192: no face uses it
    faces = np.concatenate([mesh.faces, mesh.faces[:1], [[0, 0, 1]]])
    result = simplify_animated(AnimatedMesh(faces, np.concatenate([mesh.frames, extra], axis=1)), (0.5,))
    clean = simplify_animated(mesh, (0.5,))
    assert result.preparation.duplicate_faces == 1
    assert result.preparation.degenerate_faces == 1
    assert result.preparation.unreferenced_vertices == 1
    assert result.levels[0].vertex_map[192] == -1
    np.testing.assert_array_equal(result.levels[0].mesh.faces, clean.levels[0].mesh.faces)
    np.testing.assert_array_equal(result.levels[0].kept_vertices, clean.levels[0].kept_vertices)


def test_targets_out_of_range_are_named():
    mesh = bending_tube(frames=2)
    with pytest.raises(ValueError, match=r"target_face_counts: 400 outside \[1, 360\]"):
        simplify_animated(mesh, target_face_counts=[400])
    with pytest.raises(ValueError, match="placement"):
        simplify_animated(mesh, placement="middle")
    with pytest.raises(ValueError, match="target_ratios: expected a list of fractions, one per level, got 0.5"):
        simplify_animated(mesh, 0.5)  # "'float' object is not iterable" before
    with pytest.raises(ValueError, match=r"locked_vertices: entry 0 9999 has an index outside \[0, 192\)"):
        simplify_animated(mesh, locked_vertices=[9999])
    with pytest.raises(ValueError, match="guarded_vertices: entry 1 10.9 has an index that is not a whole number"):
        simplify_animated(mesh, guarded_vertices=[3, 10.9])  # was truncated to 10
    # A (V,) bool mask is a mask: read as indices it locked vertices 0 and 1 alone.
    mask = np.zeros(mesh.vertex_count, bool)
    mask[::3] = True
    by_mask = simplify_animated(mesh, target_ratios=[0.3], locked_vertices=mask).levels[0]
    by_index = simplify_animated(mesh, target_ratios=[0.3], locked_vertices=np.flatnonzero(mask)).levels[0]
    np.testing.assert_array_equal(by_mask.mesh.faces, by_index.mesh.faces)
    assert np.isin(np.flatnonzero(mask), by_mask.kept_vertices).all()


def test_a_tiny_ratio_stops_at_the_smallest_reachable_level():
    mesh = bending_tube(frames=2)
    level = simplify_animated(mesh, (0.005,)).levels[0]
    assert not level.reached
    assert level.target_face_count == 2
    assert 2 < level.mesh.face_count < 40


def test_open_borders_keep_their_outline():
    positions, faces = tube(rings=10, segments=16)
    mesh = AnimatedMesh(faces, positions[None])
    level = simplify_animated(mesh, (0.3,)).levels[0]
    ends = level.mesh.frames[0, :, 0]
    assert ends.min() == pytest.approx(-1.0) and ends.max() == pytest.approx(1.0)


def test_features_that_find_nothing_leave_the_collapse_order_of_features_off():
    # A still sphere with capture-like jitter: the default weighting finds nothing and must change
    # nothing, bit for bit; the paper's rule turns the noise into features (the control).
    from animlod import synth

    rest = synth.translating_mesh(frames=1, subdivisions=3)
    rng = np.random.default_rng(7)
    frames = rest.frames + rng.uniform(-0.005, 0.005, (12, rest.vertex_count, 3))
    mesh = AnimatedMesh(rest.faces, frames.astype(np.float32))
    plain = simplify_animated(mesh, (0.5, 0.1), use_motion_features=False).collapses
    default = simplify_animated(mesh, (0.5, 0.1))
    assert np.all(default.vertex_weights == 1)
    for name in ("removed", "kept", "positions", "cost", "error"):
        np.testing.assert_array_equal(getattr(default.collapses, name), getattr(plain, name))
    paper = simplify_animated(mesh, (0.5, 0.1), feature_weighting="paper")
    assert paper.vertex_weights.max() > 1
    assert not np.array_equal(paper.collapses.removed, plain.removed)
    expected = r"^MotionFeatureOptions.feature_weighting: expected one of 'amplitude', 'paper', got 'Paper'$"
    with pytest.raises(ValueError, match=expected):
        simplify_animated(mesh, (0.5,), feature_weighting="Paper")


def test_crane_sequence_at_ten_percent(data_dir):
    from animlod.io.meshseq import read_sequence

    mesh = read_sequence(data_dir / "meshseq" / "crane")
    diagonal = float(np.linalg.norm(np.ptp(mesh.frames[0], axis=0)))
    for use_motion_features in (True, False):
        result = simplify_animated(mesh, (0.5, 0.25, 0.1), use_motion_features=use_motion_features)
        for level in result.levels:
            assert level.reached and level.mesh.face_count <= level.target_face_count
            assert directed_edges_unique(level.mesh.faces)
            assert math.isfinite(level.error)
    # Without feature weights the collapse order is the plain animated quadric's: small error.
    assert result.levels[-1].error < 0.02 * diagonal


def test_a_bow_tie_vertex_and_a_three_face_edge_simplify_without_new_holes():
    mesh = tube_with_bow_tie_and_fin()
    faces, frames = mesh.faces, mesh.frames
    result = simplify_animated(mesh, (0.5,))
    assert result.preparation.split_vertices >= 1
    level = result.levels[0]
    assert level.reached and level.mesh.face_count <= 183
    assert level.vertex_map.min() >= 0
    # No new holes: the border edges of the output are the input's (the tube's two rims and
    # the fin's two free sides), as many as there were.
    assert _border_edge_count(level.mesh.faces) <= _border_edge_count(faces)
    # The pieces stay stitched where they touched.
    for vertex in (0, 13):
        np.testing.assert_array_equal(level.mesh.frames[:, level.vertex_map[vertex]], frames[:, vertex])


def test_many_non_manifold_pieces_are_prepared_as_each_piece_alone():
    # Enough copies for the preparation's two workers (each takes half of the points), which
    # must cut every bow tie and fin as the preparation of one piece does.
    piece = tube_with_bow_tie_and_fin()
    copies = 240
    offsets = (np.arange(copies) * piece.vertex_count)[:, None, None]
    faces = (piece.faces[None] + offsets).reshape(-1, 3)
    shifts = np.arange(copies, dtype=np.float32)[:, None] * np.float32([3.0, 0.0, 0.0])
    frames = (piece.frames[:, None] + shifts[None, :, None]).reshape(piece.frame_count, -1, 3)
    alone = simplify_animated(piece, (0.5,)).preparation
    together = simplify_animated(AnimatedMesh(faces, frames), (0.5,))
    prep = together.preparation
    assert prep.face_count == copies * alone.face_count and prep.face_count * 3 >= 2 * 131072
    assert prep.split_vertices == copies * alone.split_vertices > 0
    assert (prep.welded_vertices, prep.seam_vertices) == (copies * alone.welded_vertices, 0)
    assert together.levels[0].reached and _border_edge_count(together.levels[0].mesh.faces) <= _border_edge_count(faces)


def test_an_unwelded_mesh_simplifies_like_the_welded_one():
    mesh = bending_tube(frames=3)
    corners = mesh.faces.ravel()
    unwelded = AnimatedMesh(np.arange(corners.size).reshape(-1, 3), mesh.frames[:, corners])
    result = simplify_animated(unwelded, (0.5, 0.1))
    assert result.preparation.welded_vertices == corners.size - mesh.vertex_count
    reference = simplify_animated(mesh, (0.5, 0.1))
    for level, expected in zip(result.levels, reference.levels):
        assert level.reached and expected.reached
        assert level.mesh.face_count == expected.mesh.face_count


def test_uv_seams_stay_seams():
    mesh = bending_tube(frames=2)
    # Cut the tube's UV chart along its first column of vertices: faces on one side of the cut
    # use copies with u = 1 instead of 0.
    segments = 12  # bending_tube's vertices go round each ring of 12
    ring = np.arange(mesh.vertex_count) % segments
    copies = np.flatnonzero(ring == 0)
    copy_of = np.full(mesh.vertex_count, -1)
    copy_of[copies] = mesh.vertex_count + np.arange(copies.size)
    faces = mesh.faces.copy()
    wraps = np.any(ring[faces] == segments - 1, axis=1)
    faces[wraps] = np.where(ring[faces[wraps]] == 0, copy_of[faces[wraps]], faces[wraps])
    frames = np.concatenate([mesh.frames, mesh.frames[:, copies]], axis=1)
    u = np.concatenate([ring / segments, np.ones(copies.size)]).astype(np.float32)
    uvs = np.stack([u, np.zeros_like(u)], axis=1)
    result = simplify_animated(AnimatedMesh(faces, frames), (0.3,), attributes=uvs)
    assert result.preparation.welded_vertices == copies.size
    assert result.preparation.seam_vertices == copies.size
    level = result.levels[0]
    # Every face keeps UVs from one side of the seam: no face spans u = 0 .. 1.
    face_u = level.attributes[level.mesh.faces, 0]
    assert np.all(np.ptp(face_u, axis=1) < 0.5)
    # The seam is still closed: copies of one position share it in every frame.
    seam = level.attributes[:, 0] == 1.0
    assert seam.any()
    positions = level.mesh.frames[0]
    on_seam = np.isin(positions.view([("", positions.dtype)] * 3), positions[seam].view([("", positions.dtype)] * 3))
    assert np.count_nonzero(on_seam) == 2 * np.count_nonzero(seam)


def _border_edge_count(faces: np.ndarray) -> int:
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return int(np.count_nonzero(counts == 1))


def test_a_sequence_from_rest_keeps_its_vertices_on_the_surface():
    # A cylinder that starts straight and bends: in its first frames a strip of its side has a
    # quadric nearly flat along the axis, and Eq. 5's minimiser slid far along it (level 3 of
    # 1,000 frames was 2.35 diagonals off in frame 1, its plane distances tiny). A minimiser out
    # of the edge's reach now takes the fallback, as a singular quadric's does.
    from animlod.metrics import surface_error
    from animlod.synth.deforming import bending_cylinder

    mesh = bending_cylinder(frames=1000)
    level = simplify_animated(mesh, target_face_counts=[77]).levels[0].mesh
    first = [AnimatedMesh(each.faces, each.frames[:10]) for each in (mesh, level)]
    error = surface_error(*first, samples=2000)
    assert (error.hausdorff / error.diagonal).max() < 0.05


def test_inversion_check_rejects_a_collapse_that_folds_a_star():
    # A flat star: centre 0, ring vertices alternating radius 1 and 0.25. Only the centre may
    # move (the ring is locked); every collapse costs 0, so ties pick the lowest edge, (0, 1),
    # which folds two triangles over; Eq. 7 must pick a collapse that folds nothing.
    k = np.arange(8)
    radius = np.where(k % 2 == 0, 1.0, 0.25)
    ring = np.stack([radius * np.cos(np.pi * k / 4), radius * np.sin(np.pi * k / 4), 0 * k], axis=1)
    mesh = AnimatedMesh(
        np.stack([np.zeros(8, int), 1 + k, 1 + (k + 1) % 8], axis=1), np.concatenate([[[0, 0, 0]], ring])[None]
    )

    def normal_z(check_inversion: bool) -> tuple[np.ndarray, int]:
        result = simplify_animated(
            mesh,
            target_face_counts=[6],
            locked_vertices=1 + k,
            use_motion_features=False,
            check_inversion=check_inversion,
        )
        corners = result.levels[0].mesh.frames[0][result.levels[0].mesh.faces]
        return np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])[:, 2], int(
            result.collapses.kept[0]
        )

    unchecked, kept_unchecked = normal_z(False)
    checked, kept_checked = normal_z(True)
    assert kept_unchecked == 1 and np.count_nonzero(unchecked < 0) == 2
    assert kept_checked == 2 and np.all(checked > 0)


def test_an_exception_in_progress_stops_the_run_cleanly():
    calls = []

    def interrupt(done: int, total: int) -> None:
        calls.append(done)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        simplify_animated(bending_tube(), (0.1,), progress=interrupt)
    assert calls == [0]  # raised at the first report, before any collapse
    assert simplify_animated(bending_tube(), (0.1,)).levels[0].reached  # still usable afterwards


def test_int64_indices_are_range_checked_not_wrapped():
    # Regression: forcecast turned index 2**32 + 5 into 5, silently simplifying another mesh.
    mesh = bending_tube(frames=3)
    narrow = _core.simplify_animated(mesh.frames, mesh.faces)
    wide = _core.simplify_animated(mesh.frames, mesh.faces.astype(np.int64))
    np.testing.assert_array_equal(wide["levels"][0]["faces"], narrow["levels"][0]["faces"])
    faces = mesh.faces.astype(np.int64)
    faces[3, 1] += 2**32
    with pytest.raises(ValueError, match=r"^faces: element \(3, 1\) = 4294967\d+ does not fit int32$"):
        _core.simplify_animated(mesh.frames, faces)
    joints = np.zeros((mesh.vertex_count, 1), np.uint64)
    joints[7, 0] = 2**63
    with pytest.raises(ValueError, match=r"^skin_joints: element \(7, 0\) = 9223372036854775808 does not fit int32$"):
        _core.simplify_animated(
            mesh.frames, mesh.faces, skin_joints=joints, skin_weights=np.ones((mesh.vertex_count, 1), np.float32)
        )
    with pytest.raises(ValueError, match=r"^faces: expected an integer array \(int32 or int64\), got dtype float64$"):
        _core.simplify_animated(mesh.frames, mesh.faces.astype(np.float64))


def test_welding_joins_exactly_the_copies_equal_everywhere():
    # Four copies of every vertex of a tube: one equal to it in every frame (welds; -0 is 0), one
    # equal in frame 0 only, one with another skin, one with the same skin listed in another
    # order with a zero-weight influence (welds). Welding is keyed by a hash over all of these.
    mesh = bending_tube(frames=2)
    n = mesh.vertex_count
    same = mesh.frames.copy()
    same[same == 0.0] = -0.0
    later = mesh.frames.copy()
    later[1] += 0.25
    frames = np.concatenate([mesh.frames, same, later, mesh.frames, mesh.frames], axis=1)
    joints = np.tile(np.array([[0, 1, 2]], np.int32), (5 * n, 1))
    weights = np.tile(np.array([[0.75, 0.25, 0.0]], np.float32), (5 * n, 1))
    weights[3 * n : 4 * n] = [0.5, 0.5, 0.0]
    joints[4 * n :] = [1, 0, 3]
    weights[4 * n :] = [0.25, 0.75, 0.0]
    faces = np.concatenate([mesh.faces + k * n for k in range(5)])
    result = simplify_animated(AnimatedMesh(faces, frames), (0.5,), skin_joints=joints, skin_weights=weights)
    assert result.preparation.welded_vertices == 2 * n
    # The welded copies' faces repeat the tube's and are dropped; the other two copies stay.
    assert result.preparation.duplicate_faces == 2 * mesh.face_count
    assert result.preparation.face_count == 3 * mesh.face_count


def test_a_stray_vertex_in_one_frame_welds_no_other_vertex():
    # The weld's cell was 1e-6 of the largest extent over all frames: one vertex a million units
    # out in one frame made it a unit wide in every frame, and the whole tube welded into a few
    # points. Each frame now has its own cell, and copies weld only where every frame agrees.
    mesh = bending_tube(frames=5)
    frames = mesh.frames.copy()
    frames[2, 7] = [1e6, 0.0, 0.0]
    result = simplify_animated(AnimatedMesh(mesh.faces, frames), (0.5,))
    assert result.preparation.welded_vertices == 0
    assert result.preparation.face_count == mesh.face_count
    assert result.levels[0].mesh.face_count == mesh.face_count // 2


def test_phase_seconds_account_for_the_call():
    # Small meshes take the greedy order (no pass chooses anything); one above 100k edges takes
    # collapse passes, which rank and choose.
    for mesh, passes in ((bending_tube(), False), (ellipsoid(frames=1, rings=190, segments=190), True)):
        start = time.perf_counter()
        seconds = simplify_animated(mesh, (0.1,), use_motion_features=False).seconds
        wall = time.perf_counter() - start
        phases = vars(seconds)
        assert all(value >= 0.0 for value in phases.values()), phases
        assert seconds.total <= wall
        assert seconds.ranking > 0.0 and seconds.collapsing > 0.0 and seconds.levels > 0.0
        assert (seconds.choosing > 0.0) == passes
