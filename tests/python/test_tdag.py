"""The TDAG through its Python API: random queries are valid manifold meshes within the
tolerance, incremental updates equal fresh queries, the online build reproduces the governed
one, files round-trip, and bad input is a ValueError naming the element."""

from __future__ import annotations

import io
import os
from unittest import mock

import numpy as np
import pytest

from animlod import AnimatedMesh, TemporalDag, _core, synth
from animlod.cli import main
from animlod.tdag import affine_split


@pytest.fixture(scope="module")
def bending() -> AnimatedMesh:
    """A bending cylinder that also swings and grows as a whole (affine and local motion)."""
    mesh = synth.bending_cylinder(frames=8, rings=14, segments=10)
    angle = np.linspace(0.0, 0.6, mesh.frame_count)
    cos, sin = np.cos(angle)[:, None], np.sin(angle)[:, None]
    x, y, z = np.moveaxis(mesh.frames, -1, 0)
    grow = np.linspace(1.0, 1.3, mesh.frame_count)[:, None]
    frames = np.stack([grow * (cos * x - sin * z) + 0.2 * angle[:, None], grow * y, grow * (sin * x + cos * z)], -1)
    return AnimatedMesh(mesh.faces, frames)


@pytest.fixture(scope="module")
def dag(bending: AnimatedMesh) -> TemporalDag:
    return TemporalDag.build(bending)


def _diagonal(points: np.ndarray) -> float:
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


def _check_mesh(dag: TemporalDag, cut, tolerance: float) -> None:
    """Valid manifold (every directed edge once, no degenerate face, every vertex used) and
    every input vertex within the tolerance of the vertex standing for it."""
    mesh = cut.mesh()
    faces = mesh.faces
    assert faces.min() >= 0 and faces.max() < mesh.vertex_count
    assert np.all((faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2]))
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    assert len(np.unique(directed, axis=0)) == len(directed)
    assert len(np.unique(faces)) == mesh.vertex_count
    assert mesh.error_bound <= tolerance
    original = dag.frame_positions(cut.frame)
    distance = np.linalg.norm(original - mesh.positions[cut.input_vertex_map()], axis=1)
    assert distance.max() <= tolerance + 1e-5


def _canonical(mesh) -> tuple:
    """Nodes and faces as node triples (smallest first, orientation kept), sorted."""
    triples = mesh.nodes[mesh.faces]
    shift = np.argmin(triples, axis=1)
    rows = np.arange(len(triples))[:, None]
    rolled = triples[rows, (shift[:, None] + np.arange(3)) % 3]
    return tuple(np.sort(mesh.nodes)), tuple(map(tuple, rolled[np.lexsort(rolled.T[::-1])]))


def test_random_queries_are_valid_manifold_meshes_within_tolerance(dag: TemporalDag, bending: AnimatedMesh):
    rng = np.random.default_rng(3)
    scale = _diagonal(bending.frames[0])
    for _ in range(25):
        frame = int(rng.integers(dag.frame_count))
        tolerance = float(scale * 0.2 * rng.random() ** 2)
        cut = dag.cut(frame, tolerance)
        _check_mesh(dag, cut, tolerance)
    exact = dag.query(2, 0.0)
    assert exact.face_count == bending.face_count and exact.vertex_count == bending.vertex_count
    assert dag.query(2, 10 * scale).face_count < 0.05 * bending.face_count


def test_advance_and_refine_equal_fresh_queries(bending: AnimatedMesh):
    rng = np.random.default_rng(5)
    scale = _diagonal(bending.frames[0])
    for dag in (TemporalDag.build(bending), TemporalDag.build(bending, "online", history_weight=0.3)):
        tolerance = 0.05 * scale
        dag.query(0, tolerance)
        for _ in range(30):
            if rng.random() < 0.3:
                tolerance = float(scale * 0.2 * rng.random() ** 2)
                mesh = dag.refine(tolerance)
            else:
                frame = int(rng.integers(dag.frame_count)) if rng.random() < 0.3 else None
                mesh = dag.advance(frame)
            fresh = dag.cut(dag.cursor.frame, tolerance).mesh()
            assert _canonical(mesh) == _canonical(fresh)
            _check_mesh(dag, dag.cursor, tolerance)


def test_levels_and_player(dag: TemporalDag, bending: AnimatedMesh):
    tolerance = 0.03 * _diagonal(bending.frames[0])
    cut = dag.cut(1, tolerance)
    level1 = cut.advance(2, level=1)
    level2 = cut.advance(2, level=2)
    assert level1.cut_frame == level2.cut_frame == 1 and level1.residual_frame == 1 and level2.residual_frame == 2
    # Level 1 is the previous cut's residual positions under frame 2's affine map.
    maps = dag.affine_maps
    residual = dag.residuals(1)[dag._core.representatives[level1.nodes]]
    np.testing.assert_allclose(level1.positions, residual @ maps[2][:, :3].T + maps[2][:, 3], atol=1e-5)
    level3 = cut.advance(2, level=3)
    assert level3.cut_frame == 2 and _canonical(level3) == _canonical(dag.cut(2, tolerance).mesh())

    meshes = list(dag.player(tolerance))
    assert [m.cut_frame for m in meshes] == list(range(dag.frame_count))
    assert _canonical(meshes[5]) == _canonical(dag.cut(5, tolerance).mesh())
    report = dag.play(tolerance)
    assert report.frames == dag.frame_count - 1
    assert report.levels[2].max_error <= tolerance + 1e-5 and report.full_query.max_error <= tolerance + 1e-5
    assert report.levels[0].max_error > report.levels[1].max_error  # the residuals matter here


def test_online_with_huge_history_weight_equals_governed(bending: AnimatedMesh):
    governed = TemporalDag.build(bending, "first", check_inversion=False)
    online = TemporalDag.build(bending, "online", history_weight=1e9, check_inversion=False)
    np.testing.assert_array_equal(governed.children, online.children)
    for frame in range(bending.frame_count):
        np.testing.assert_array_equal(governed.error_bounds(frame), online.error_bounds(frame))
    # lambda = 0: each frame its own order, so collapses get partial time tags.
    own = TemporalDag.build(bending, "online", history_weight=0.0)
    assert own.collapse_count > governed.collapse_count
    assert any(own.alive(c) != [(0, bending.frame_count)] for c in range(own.collapse_count))
    assert own.stored_counts["alive_ranges"] >= own.collapse_count


def test_governing_choices_and_figure6_measure(bending: AnimatedMesh):
    measures = {}
    for governing in ("first", "average", 5, "aqem", "online"):
        dag = TemporalDag.build(bending, governing, history_weight=0.0)
        report = dag.report
        assert report.collapse_counts.shape == (bending.frame_count,)
        assert np.all(report.use_counts >= 1) and report.use_counts.max() <= bending.frame_count
        measures[str(governing)] = report.quality_measure()
    # The per-frame optimal decimation (online, lambda 0) has the smallest average measure.
    assert measures["online"][0] <= min(value[0] for value in measures.values())


def test_affine_split_recovers_a_known_affine_motion():
    base = synth.translating_mesh(frames=1, subdivisions=2).frames[0].astype(np.float64)
    rng = np.random.default_rng(1)
    maps = [np.hstack([np.eye(3), np.zeros((3, 1))])]
    for _ in range(3):
        maps.append(np.hstack([np.eye(3) + 0.3 * rng.normal(size=(3, 3)), rng.normal(size=(3, 1)) * 10]))
    frames = np.stack([base @ m[:, :3].T + m[:, 3] for m in maps])
    found, residuals = affine_split(AnimatedMesh(synth.translating_mesh(frames=1, subdivisions=2).faces, frames))
    np.testing.assert_allclose(found, np.stack(maps), atol=1e-4)
    np.testing.assert_allclose(residuals, np.broadcast_to(base, residuals.shape), atol=1e-4)


def test_save_load_round_trip_and_damaged_files(dag: TemporalDag, tmp_path):
    path = tmp_path / "mesh.tdag"
    size = dag.save(path)
    assert path.stat().st_size == size
    loaded = TemporalDag.load(path)
    assert loaded.to_bytes() == dag.to_bytes() == path.read_bytes() and loaded.report is None
    for view in (bytearray(path.read_bytes()), memoryview(path.read_bytes())):  # any bytes-like object
        assert TemporalDag.from_bytes(view).to_bytes() == dag.to_bytes()
    with pytest.raises(ValueError, match="expected contiguous bytes"):
        TemporalDag.from_bytes(np.frombuffer(path.read_bytes(), np.uint8)[::2])
    for frame in (0, 4):
        np.testing.assert_array_equal(loaded.frame_positions(frame), dag.frame_positions(frame))
        assert _canonical(loaded.query(frame, 0.02)) == _canonical(dag.cut(frame, 0.02).mesh())

    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x10
    (tmp_path / "damaged.tdag").write_bytes(bytes(data))
    with pytest.raises(ValueError, match=r"damaged\.tdag: corrupted TDAG file: checksum mismatch"):
        TemporalDag.load(tmp_path / "damaged.tdag")
    data = bytearray(path.read_bytes())
    data[8] = 0
    (tmp_path / "old.tdag").write_bytes(bytes(data))
    with pytest.raises(ValueError, match="format version 0 was written by an older animlod"):
        TemporalDag.load(tmp_path / "old.tdag")
    (tmp_path / "text.tdag").write_text("hello")
    with pytest.raises(ValueError, match="not a TDAG file"):
        TemporalDag.load(tmp_path / "text.tdag")
    (tmp_path / "cut.tdag").write_bytes(path.read_bytes()[:-10])
    with pytest.raises(ValueError, match=r"cut\.tdag: truncated or padded TDAG file"):
        TemporalDag.load(tmp_path / "cut.tdag")
    with pytest.raises(FileNotFoundError):
        TemporalDag.load(tmp_path / "missing.tdag")
    with pytest.raises(IsADirectoryError):
        TemporalDag.load(tmp_path)


def test_save_writes_a_piece_at_a_time_and_a_failing_write_keeps_the_old_file(dag: TemporalDag, tmp_path):
    class Recording(io.BytesIO):
        def __init__(self) -> None:
            super().__init__()
            self.writes = 0

        def write(self, data) -> int:
            self.writes += 1
            return super().write(data)

    handle = Recording()
    dag._core.write(handle)
    assert handle.getvalue() == dag.to_bytes() and handle.writes > 2

    class DiskFull(Recording):
        def write(self, data) -> int:
            if self.writes == 2:
                raise OSError(28, "No space left on device")
            return super().write(data)

    with pytest.raises(OSError, match="No space left"):
        dag._core.write(DiskFull())
    path = tmp_path / "mesh.tdag"
    path.write_bytes(b"the old file")
    real_open = os.fdopen

    class FullDisk:  # the temporary file atomic_write opens, full after one write
        def __init__(self, fd, mode, **kwargs) -> None:
            self.file, self.writes = real_open(fd, mode, **kwargs), 0

        def __enter__(self):
            return self

        def __exit__(self, *exc) -> None:
            self.file.close()

        def write(self, data) -> int:
            self.writes += 1
            if self.writes == 2:
                raise OSError(28, "No space left on device")
            return self.file.write(data)

        def tell(self) -> int:
            return self.file.tell()

        def seek(self, *where) -> int:
            return self.file.seek(*where)

    with mock.patch("animlod.io.atomic.os.fdopen", FullDisk), pytest.raises(OSError, match="No space left"):
        dag.save(path)
    assert path.read_bytes() == b"the old file"
    assert [entry.name for entry in tmp_path.iterdir()] == ["mesh.tdag"]


def test_a_two_sided_sheet_simplifies_like_its_front_and_queries_give_both_sides(tmp_path, capsys):
    # Double-sided cloth exported as every face again in the reverse turn on vertices of its own:
    # both sides were cut apart at every edge and locked, and the TDAG had no collapse at all.
    x, y = np.meshgrid(np.linspace(0, 1, 12), np.linspace(0, 1, 12))
    corner = np.arange(144).reshape(12, 12)[:-1, :-1].ravel()
    front = np.concatenate(
        [np.stack([corner, corner + 1, corner + 12], 1), np.stack([corner + 1, corner + 13, corner + 12], 1)]
    )
    frames = np.stack([np.stack([x, y, 0.1 * t * np.sin(3 * x) * np.cos(2 * y)], -1).reshape(-1, 3) for t in range(4)])
    one = TemporalDag.build(AnimatedMesh(front, frames))
    both = TemporalDag.build(
        AnimatedMesh(np.concatenate([front, front[:, ::-1] + 144]), np.concatenate([frames, frames], 1))
    )
    assert one.collapse_count > 0 and both.collapse_count == one.collapse_count
    assert both.two_sided.all() and not one.two_sided.any() and both.face_count == one.face_count
    np.testing.assert_array_equal(both.input_points[144:], both.input_points[:144])
    both.save(tmp_path / "sheet.tdag")
    for dag in (both, TemporalDag.load(tmp_path / "sheet.tdag")):
        single, double = one.query(3, 0.2), dag.query(3, 0.2)
        m = len(single.faces)
        assert m < len(front) and len(double.faces) == 2 * m
        np.testing.assert_array_equal(double.faces[:m], single.faces)
        np.testing.assert_array_equal(double.faces[m:], single.faces[:, [0, 2, 1]])
    # The CLI counts the input's faces with both sides, as the query's.
    query = ["tdag", "query", str(tmp_path / "sheet.tdag"), "--frame", "3", "--tolerance", "0"]
    assert main([*query, "-o", str(tmp_path / "q.obj")]) == 0
    assert f"{2 * len(front)} faces (input 144, {2 * len(front)})" in capsys.readouterr().out


def test_bad_input_is_a_named_value_error(dag: TemporalDag, bending: AnimatedMesh):
    frames = bending.frames.copy()
    frames[2, 7, 1] = np.nan
    with pytest.raises(ValueError, match="frame 2, vertex 7: non-finite position"):
        _core.build_temporal_dag(frames, bending.faces)
    with pytest.raises(ValueError, match=r"frames: expected shape \(F, V, 3\)"):
        _core.build_temporal_dag(frames[..., :2], bending.faces)
    with pytest.raises(ValueError, match="governing_frame: frame 9 outside"):
        TemporalDag.build(bending, 9)
    with pytest.raises(ValueError, match="governing"):
        TemporalDag.build(bending, "last")
    with pytest.raises(ValueError, match="tolerance: must be >= 0"):
        dag.query(0, -1.0)
    with pytest.raises(ValueError, match=r"frame: 8 outside \[0, 8\)"):
        dag.query(8, 0.1)
    with pytest.raises(ValueError, match="level"):
        dag.cut(0, 0.1).advance(1, level=4)


@pytest.mark.parametrize("first_frame", [8, -1, np.int64(99)])
def test_play_and_player_name_the_first_frame_they_were_given(dag: TemporalDag, first_frame):
    # The core's check reads "frame: 8 outside [0, 8)", a name neither method takes.
    message = rf"^first_frame: {int(first_frame)} outside \[0, 8\)$"
    with pytest.raises(ValueError, match=message):
        dag.play(0.1, first_frame=first_frame, measure_error=False)
    with pytest.raises(ValueError, match=message):
        dag.player(0.1, first_frame)


def test_player_takes_a_whole_first_frame_only(dag: TemporalDag):
    with pytest.raises(ValueError, match=r"^first_frame: expected an integer, got 1.5$"):  # a pybind TypeError before
        dag.player(0.1, 1.5)
    with pytest.raises(ValueError, match=r"^first_frame: expected an integer, got 1.5$"):
        dag.play(0.1, first_frame=1.5)
    dag.play(0.1, first_frame=7, measure_error=False)  # the last frame is in range
    dag.player(0.1, np.int64(7))


def test_view_dependent_query_is_finer_near_the_camera(dag: TemporalDag):
    positions = dag.frame_positions(0)
    low, high = positions.min(axis=0), positions.max(axis=0)
    middle = 0.5 * (low + high)
    camera = [middle[0], low[1] - 0.3, middle[2]]  # below the bottom end of the cylinder
    mesh = dag.query_view(0, camera, pixels=150.0, focal_pixels=500.0)
    assert 0 < mesh.face_count < dag.face_count
    median = np.median(np.linalg.norm(positions - camera, axis=1))
    near = np.linalg.norm(mesh.positions - camera, axis=1) < median
    assert near.sum() > (~near).sum()
    other = [middle[0], high[1] + 0.3, middle[2]]
    moved = dag.cursor.refine_view(other, pixels=150.0, focal_pixels=500.0)
    fresh = dag.cut(0, 0.0).query_view(0, other, pixels=150.0, focal_pixels=500.0)
    assert _canonical(moved) == _canonical(fresh)


def test_real_sequences_build_and_query(data_dir):
    from animlod.io.gltf import read_gltf
    from animlod.io.meshseq import read_sequence

    crane = read_sequence(sorted((data_dir / "meshseq" / "crane").glob("*.obj"))[:3])
    dag = TemporalDag.build(crane)
    tolerance = 0.02 * _diagonal(crane.frames[0])
    cut = dag.cut(0, tolerance)
    assert cut.active_face_count < 0.5 * crane.face_count
    cut.advance(2)
    _check_mesh(dag, cut, tolerance)
    # A morph-animated glTF with UV-seam copies and bow-ties on the stored indices.
    parrot = read_gltf(data_dir / "morph" / "Parrot.glb").morph_animations[0]
    dag = TemporalDag.build(parrot)
    assert dag.vertex_count < parrot.vertex_count  # seam copies welded
    points = dag.input_points
    np.testing.assert_allclose(dag.frame_positions(3)[points[points >= 0]], parrot.frames[3][points >= 0], atol=1e-4)
    cut = dag.cut(3, 0.05 * _diagonal(parrot.frames[3]))
    _check_mesh(dag, cut, 0.05 * _diagonal(parrot.frames[3]))
