"""``animlod simplify`` on small sequences written to a temporary folder."""

from __future__ import annotations

import numpy as np
import pytest
from simplify_inputs import bending_tube, tube_with_bow_tie_and_fin, twisting_cylinder, wrapped_texture

from animlod.cli import main
from animlod.io.meshseq import read_mesh, read_sequence, write_mesh, write_sequence
from animlod.io.npz import read_npz, write_npz
from animlod.io.obj import ObjTexture, read_obj_textured, write_obj


def test_simplify_an_obj_sequence_writes_each_level_as_a_sequence(tmp_path, capsys):
    source = tmp_path / "tube"
    source.mkdir()
    write_sequence(source, bending_tube(frames=3))
    code = main(["simplify", str(source), "-o", str(tmp_path / "out"), "--ratio", "0.5", "0.2", "--no-metrics"])
    assert code == 0
    for level, faces in ((1, 180), (2, 72)):
        mesh = read_sequence(tmp_path / "out" / f"tube_lod{level}")
        assert mesh.frame_count == 3 and mesh.face_count <= faces
    printed = capsys.readouterr()
    assert "AQEM error" in printed.out and "180" in printed.out
    assert "\r" not in printed.err  # no progress bar where stderr is no terminal


def test_each_level_frame_keeps_its_input_file_name(tmp_path):
    """Level frames were written as frame_0000, frame_0001, ...: a capture's frame numbers
    (mesh_0048 .. mesh_0050) were lost. Where two frames share a name (a.obj and a.ply), the
    level's frames are numbered."""
    tube = bending_tube(frames=3)
    write_sequence(tmp_path / "capture", tube, names=["mesh_0048", "mesh_0049", "mesh_0050"])
    assert main(["simplify", str(tmp_path / "capture"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    for level in (1, 2, 3):
        written = sorted(path.name for path in (tmp_path / "out" / f"capture_lod{level}").iterdir())
        assert written == ["mesh_0048.obj", "mesh_0049.obj", "mesh_0050.obj"]
    # Each name holds its own frame: the level's frame is nearest to the input's of its name.
    level = read_sequence(tmp_path / "out" / "capture_lod1")
    centres = tube.frames.mean(axis=1)
    nearest = [np.linalg.norm(centres - frame.mean(axis=0), axis=1).argmin() for frame in level.frames]
    assert nearest == [0, 1, 2] and len(np.unique(centres.round(3), axis=0)) == 3
    (tmp_path / "twice").mkdir()
    write_mesh(tmp_path / "twice" / "a.obj", tube.frames[0], tube.faces)
    write_mesh(tmp_path / "twice" / "a.ply", tube.frames[1], tube.faces)
    assert main(["simplify", str(tmp_path / "twice"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    assert sorted(path.name for path in (tmp_path / "out" / "twice_lod1").iterdir()) == [
        "frame_0000.ply",
        "frame_0001.ply",
    ]
    with pytest.raises(ValueError, match="names: 2 names for 3 frames, or names that repeat"):
        write_sequence(tmp_path / "bad", tube, names=["a", "b"])
    for names in (["a", "A", "b"], ["a", "b", "../c"], ["a", "b", ".c"]):
        with pytest.raises(ValueError, match="names that repeat"):
            write_sequence(tmp_path / "bad", tube, names=names)
    assert not (tmp_path / "bad").exists()


def test_an_obj_sequences_texture_coordinates_reach_every_level(tmp_path, capsys):
    """OBJ frames with vt lines: the levels were written without them (a warning said so). Now
    each level frame has them, the seam's copies apart, each corner's u near the angle of its
    position about the axis; one OBJ file's level too. The frames twist the cylinder about its
    axis from its rest pose, which keeps every surface point's height: v (the height) holds in
    every frame, as it can only where a level's vertex is one point of the surface in all of
    them (the placement on the collapsed edge; the default elsewhere, one optimal position per
    frame, slid the vertices by up to 1.5 rings between the rest frame and the others)."""
    rest, twisted = twisting_cylinder()
    texture = ObjTexture(*wrapped_texture(rest))
    (tmp_path / "shot").mkdir()
    for index, frame in enumerate(twisted):
        write_obj(tmp_path / "shot" / f"shot_{index}.obj", frame, rest.faces, texture)
    write_obj(tmp_path / "rest.obj", rest.frames[0], rest.faces, texture)
    for source in ("shot", "rest.obj"):  # --plot reads the levels back
        command = ["simplify", str(tmp_path / source), "-o", str(tmp_path / "out"), "--no-metrics", "--plot"]
        assert main(command) == 0
    assert main(["info", str(tmp_path / "shot")]) == 0
    printed = capsys.readouterr()
    assert "not read" not in printed.err  # no warning that they are not read (the levels' included)
    assert f"vertices: {rest.vertex_count}, 276 with their texture coordinates" in printed.out
    height = np.ptp(rest.frames[0][:, 1])
    levels = [sorted((tmp_path / "out" / f"shot_lod{level}").iterdir()) for level in (1, 2, 3)]
    for frames in [*levels, *([tmp_path / "out" / f"rest_lod{level}.obj"] for level in (1, 2, 3))]:
        for path in frames:
            positions, faces, written, _, _, _ = read_obj_textured(path)
            assert written is not None and len(written.uvs) > len(positions)  # the seam stays open in uv
            corners, uvs = positions[faces], written.uvs[written.corners]
            np.testing.assert_allclose(
                uvs[..., 1] * height, corners[..., 1] - rest.frames[0][:, 1].min(), atol=1e-3 * height
            )
        # u: the angle at rest, linear along each edge (chord) as the coordinates are: near it
        positions, faces, written, _, _, _ = read_obj_textured(frames[0])
        angle = np.arctan2(positions[faces][..., 2], positions[faces][..., 0]) / (2 * np.pi)
        off = np.abs((written.uvs[written.corners][..., 0] - angle + 0.5) % 1.0 - 0.5)
        assert off.max() < 0.05, (frames[0], off.max())


def _unit_rows(vectors: np.ndarray) -> np.ndarray:
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def _face_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    corners = positions[faces].astype(np.float64)
    return _unit_rows(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]))


def _shaded_normals(shading: str, frame: np.ndarray, faces: np.ndarray, rng: np.random.Generator):
    """The normals an exporter writes for ``shading``: smooth (one per position), noisy (one per
    corner, 1e-4 apart), flat (each face's own, at half length), quads (each quad's own, its two
    triangles 3 degrees apart: the tube's quads are bent)."""
    from animlod.io.obj import ObjNormals
    from animlod.normals import vertex_normals

    count = len(faces)
    if shading == "smooth":
        return ObjNormals(vertex_normals(frame, faces), faces)
    if shading == "noisy":
        per_corner = vertex_normals(frame, faces)[faces].reshape(-1, 3) + rng.normal(0.0, 1e-4, (3 * count, 3))
        return ObjNormals(per_corner.astype(np.float32), np.arange(3 * count).reshape(-1, 3))
    own = _face_normals(frame, faces)
    if shading == "quads":  # tube(): triangle q and q + count / 2 make quad q
        own = np.tile(_unit_rows(own[: count // 2] + own[count // 2 :]), (2, 1))
    return ObjNormals(0.5 * own, np.repeat(np.arange(count), 3).reshape(-1, 3))


@pytest.mark.parametrize(
    "shading, said",
    [("smooth", "smooth"), ("noisy", "smooth"), ("flat", "flat"), ("quads", "flat"),
     ("clockwise", "flat, pointing against the faces' winding")],
)  # fmt: skip
def test_an_obj_sequences_normals_are_rebuilt_on_every_level_as_shaded(tmp_path, capsys, shading, said):
    # Levels were written without the input's vn lines; now each level frame gets normals from its
    # own faces: one per position where the input is smooth (exporters' rounding aside), each
    # face's own where it is flat (a bent quad's normal, shorter than 1, included), pointing where
    # the input's point.
    from animlod.normals import vertex_normals

    tube = bending_tube(frames=3)
    faces = tube.faces[:, ::-1] if shading == "clockwise" else tube.faces
    rng = np.random.default_rng(5)
    (tmp_path / "shot").mkdir()
    for index, frame in enumerate(tube.frames):
        normals = _shaded_normals("flat" if shading == "clockwise" else shading, frame, tube.faces, rng)
        write_obj(tmp_path / "shot" / f"shot_{index}.obj", frame, faces, normals=normals)
    assert main(["info", str(tmp_path / "shot")]) == 0
    assert f"normals: {said}, rebuilt on each level" in capsys.readouterr().out
    assert main(["simplify", str(tmp_path / "shot"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    assert "not read" not in capsys.readouterr().err
    outward = -1.0 if shading == "clockwise" else 1.0  # along the winding's normal, or against it
    for level in (1, 2, 3):
        for path in sorted((tmp_path / "out" / f"shot_lod{level}").iterdir()):
            positions, level_faces, _, written, _, _ = read_obj_textured(path)
            assert written is not None
            if said == "smooth":
                np.testing.assert_array_equal(written.corners, level_faces)  # one normal per position
                np.testing.assert_allclose(written.normals, vertex_normals(positions, level_faces), atol=1e-6)
            else:
                along = np.einsum("fkc,fc->fk", written.normals[written.corners], _face_normals(positions, level_faces))
                assert (outward * along).min() > 0.9999


@pytest.mark.parametrize("shading", ["smooth", "flat"])
def test_normals_of_obj_frames_among_ply_ones_are_written_per_vertex_where_smooth(tmp_path, capsys, shading):
    # A PLY frame makes the levels PLY, whose vertices hold one normal each: smooth normals are
    # written so (they were dropped with a warning), flat ones named and not written.
    from animlod.io.ply import read_ply_attributes
    from animlod.normals import vertex_normals

    tube = bending_tube(frames=2)
    (tmp_path / "mixed").mkdir()
    normals = _shaded_normals(shading, tube.frames[0], tube.faces, np.random.default_rng(0))
    write_obj(tmp_path / "mixed" / "f_0.obj", tube.frames[0], tube.faces, normals=normals)
    write_mesh(tmp_path / "mixed" / "f_1.ply", tube.frames[1], tube.faces)
    assert main(["simplify", str(tmp_path / "mixed"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    said = capsys.readouterr().err
    assert sorted(path.name for path in (tmp_path / "out" / "mixed_lod1").iterdir()) == ["f_0.ply", "f_1.ply"]
    positions, faces, _, written, _ = read_ply_attributes(tmp_path / "out" / "mixed_lod1" / "f_1.ply")
    if shading == "smooth":
        assert "not written" not in said
        np.testing.assert_allclose(written, vertex_normals(positions, faces), atol=1e-6)
    else:
        assert "its normals are not written: they shade it flat or with hard edges, and the levels are PLY" in said
        assert written is None


def test_one_mesh_file_gives_one_file_per_level_and_dotted_names_keep_their_levels_apart(tmp_path):
    """A single OBJ/PLY gave a folder per level holding frame_0000; NPZ levels of walk.v2.npz were
    all written to walk.npz (the suffix swapped instead of appended), each over the last."""
    tube = bending_tube(frames=1)
    write_mesh(tmp_path / "tube.v2.ply", tube.frames[0], tube.faces)
    write_npz(tmp_path / "walk.v2.npz", bending_tube(frames=2))
    for source in ("tube.v2.ply", "walk.v2.npz"):
        assert main(["simplify", str(tmp_path / source), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    suffix = {"tube.v2": "ply", "walk.v2": "npz"}
    expected = [f"{stem}_lod{level}.{ext}" for stem, ext in suffix.items() for level in (1, 2, 3)]
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == expected
    faces = [read_mesh(tmp_path / "out" / f"tube.v2_lod{level}.ply")[1].shape[0] for level in (1, 2, 3)]
    assert faces == sorted(faces, reverse=True) and faces[0] < tube.face_count


def test_the_measurement_of_a_sequence_reports_its_progress(tmp_path):
    # On long sequences it takes longer than the simplification, which it followed in silence.
    from animlod.pipelines.lod_sequence import simplify_sequence

    source = tmp_path / "tube"
    write_sequence(source, bending_tube(frames=3))
    (source / "._tube_0000.obj").write_bytes(b"\x00\x05\x16\x07")  # a macOS resource fork: no frame
    calls = []
    simplify_sequence(source, tmp_path / "out", [0.5, 0.2], measuring=lambda done, total: calls.append((done, total)))
    assert calls == [(0, 2), (1, 2), (2, 2)]


def test_a_long_sequence_is_measured_on_evenly_spaced_frames(tmp_path, capsys):
    # Every frame of a 300-frame, 20k-triangle sequence took 61 s to measure against 2.3 s to
    # simplify; the errors are over frames spread from the first to the last, and say so.
    from animlod.metrics import surface_error
    from animlod.model import AnimatedMesh
    from animlod.pipelines import lod_sequence

    tube = bending_tube(frames=11)
    write_npz(tmp_path / "tube.npz", tube)
    report = lod_sequence.simplify_sequence(tmp_path / "tube.npz", tmp_path / "out", [0.3], measured_frames=4)
    level = read_npz(report.levels[0].path)
    frames = [0, 3, 7, 10]
    expected = surface_error(*(AnimatedMesh(m.faces, m.frames[frames]) for m in (tube, level)), samples=10000)
    assert report.frames_measured == 4 and report.levels[0].surface == expected.summary()
    every = lod_sequence.simplify_sequence(tmp_path / "tube.npz", tmp_path / "all", [0.3], measured_frames=None)
    assert every.frames_measured == 11
    assert main(["simplify", str(tmp_path / "tube.npz"), "-o", str(tmp_path / "cli"), "--metric-frames", "4"]) == 0
    assert "over 4 of the 11 frames, evenly spaced (--metric-frames 11: all)" in capsys.readouterr().out
    assert main(["simplify", str(tmp_path / "tube.npz"), "-o", str(tmp_path / "cli"), "--metric-frames", "0"]) == 2
    assert "--metric-frames: expected at least 1 frame, got 0" in capsys.readouterr().err


def test_simplify_npz_with_metrics_and_plot(tmp_path, capsys):
    write_npz(tmp_path / "tube.npz", bending_tube(frames=2))
    code = main(["simplify", str(tmp_path / "tube.npz"), "-o", str(tmp_path / "out"), "--ratio", "0.3", "--plot"])
    assert code == 0
    level = read_npz(tmp_path / "out" / "tube_lod1.npz")
    assert level.face_count <= 108
    assert (tmp_path / "out" / "tube_levels.png").stat().st_size > 1000
    assert "e-0" in capsys.readouterr().out  # a measured Hausdorff/RMS value


def test_plot_of_a_sequence_with_a_bow_tie_shows_the_features_simplify_used(tmp_path, capsys):
    """The plot found the features again on the raw input, which a bow tie (scans, CAD exports)
    refuses: the levels were written, then the run failed with exit code 2."""
    mesh = tube_with_bow_tie_and_fin()
    write_sequence(tmp_path / "scan", mesh, "obj")
    assert main(["simplify", str(tmp_path / "scan"), "-o", str(tmp_path / "out"), "--no-metrics", "--plot"]) == 0
    assert (tmp_path / "out" / "scan_levels.png").stat().st_size > 1000
    assert "non-manifold" not in capsys.readouterr().err


def test_a_level_short_of_its_target_says_what_stopped_it(tmp_path, capsys):
    """Any finite --max-error was named as the reason; a generous one is not what stops a level
    that no legal collapse can reach (the core says which stopped it)."""
    write_npz(tmp_path / "tube.npz", bending_tube(frames=2))
    for max_error, why in (("1e9", "no legal collapse left"), ("1e-4", "max error 0.0001 reached")):
        arguments = ["--ratio", "0.001", "--max-error", max_error, "--no-metrics"]
        assert main(["simplify", str(tmp_path / "tube.npz"), "-o", str(tmp_path / "out"), *arguments]) == 0
        assert f"): {why}" in capsys.readouterr().out


def test_levels_where_max_error_stopped_the_collapses_are_not_written_twice(tmp_path, capsys):
    """Levels 2 and 3 of a sequence stopped by --max-error were written as copies of one mesh,
    folders that differ only in name, while a glTF chain left them out with a note."""
    write_sequence(tmp_path / "tube", bending_tube(frames=3), "obj")
    arguments = ["--ratio", "0.5", "0.25", "0.1", "--max-error", "1e-4", "--no-metrics"]
    assert main(["simplify", str(tmp_path / "tube"), "-o", str(tmp_path / "out"), *arguments]) == 0
    out = capsys.readouterr().out
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == ["tube_lod1", "tube_lod2"]
    faces = [read_sequence(tmp_path / "out" / f"tube_lod{level}").face_count for level in (1, 2)]
    assert faces[0] > faces[1] > 36  # the second stopped short of its target, 90
    assert f"note: level 2: stopped at {faces[1]} faces (target 90): max error 0.0001 reached" in out
    assert f"note: level 3 (target 36) not written: the same mesh as level 2 ({faces[1]} faces)" in out
    assert "where the max error 0.0001 stopped the collapses" in out


def test_a_sequence_summary_says_what_the_preparation_dropped(tmp_path, capsys):
    """A glTF drawable's summary said which faces the simplifier dropped before simplifying; a
    sequence's said nothing, so the levels' targets looked off by the repeated faces."""
    mesh = bending_tube(frames=2)
    write_npz(tmp_path / "tube.npz", type(mesh)(np.concatenate([mesh.faces, mesh.faces[:5]]), mesh.frames))
    assert main(["simplify", str(tmp_path / "tube.npz"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    summary = capsys.readouterr().out.splitlines()[0]
    assert summary.startswith(f"{mesh.face_count + 5} triangles, 2 frames; welded 0 vertices")
    assert summary.endswith("5 degenerate or repeated faces dropped")


def test_bad_ratio_and_bad_mesh_exit_with_code_2(tmp_path, capsys):
    write_npz(tmp_path / "tube.npz", bending_tube(frames=2))
    assert main(["simplify", str(tmp_path / "tube.npz"), "-o", str(tmp_path / "out"), "--ratio", "1.5"]) == 2
    assert "--ratio" in capsys.readouterr().err
    # 0 quietly meant the default; a count of frames is one or more.
    assert main(["simplify", str(tmp_path / "tube.npz"), "-o", str(tmp_path / "out"), "--max-frames", "0"]) == 2
    assert "--max-frames: must be >= 1, got 0" in capsys.readouterr().err
    mesh = bending_tube(frames=2)
    flat = np.zeros_like(mesh.frames)  # every vertex at one point: no face has an area
    write_npz(tmp_path / "bad.npz", type(mesh)(mesh.faces, flat))
    assert main(["simplify", str(tmp_path / "bad.npz"), "-o", str(tmp_path / "out"), "--no-metrics"]) == 2
    assert "every face is degenerate" in capsys.readouterr().err


def test_feature_weighting_is_chosen_by_name_and_an_unknown_one_exits_with_code_2(tmp_path, capsys):
    write_npz(tmp_path / "tube.npz", bending_tube(frames=3))
    tube, out = str(tmp_path / "tube.npz"), str(tmp_path / "out")
    assert main(["simplify", tube, "-o", out, "--feature-weighting", "paper", "--no-metrics"]) == 0
    assert read_npz(tmp_path / "out" / "tube_lod1.npz").face_count > 0
    capsys.readouterr()
    assert main(["simplify", tube, "-o", out, "--feature-weighting", "size"]) == 2
    error = capsys.readouterr().err
    assert "--feature-weighting" in error and "'size'" in error and "Traceback" not in error
    assert len(error.strip().splitlines()) <= 2  # argparse's usage line, then the one message
    assert main(["simplify", tube, "-o", out, "--feature-weighting", "paper", "--no-features"]) == 2
    assert "--feature-weighting: cannot be combined with --no-features" in capsys.readouterr().err


def test_feature_options_leave_the_pipeline_default_unless_asked():
    from argparse import Namespace

    from animlod.cli.simplify import feature_options

    assert feature_options(Namespace(no_features=False, feature_weighting=None)) == {}
    assert feature_options(Namespace(no_features=True, feature_weighting=None)) == {"use_motion_features": False}
    chosen = feature_options(Namespace(no_features=False, feature_weighting="amplitude"))
    assert chosen == {"use_motion_features": True, "feature_weighting": "amplitude"}
