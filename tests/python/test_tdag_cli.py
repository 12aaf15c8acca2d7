"""``animlod tdag build|query|play``: files written, tables printed, user mistakes exit 2."""

from __future__ import annotations

import pytest
from simplify_inputs import two_bone_tube

from animlod import synth
from animlod.cli import main
from animlod.io.gltf import write_glb
from animlod.io.meshseq import read_mesh
from animlod.io.npz import write_npz
from animlod.tdag import TemporalDag


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tdag")
    write_npz(folder / "bar.npz", synth.twisting_bar(frames=6, rings=10, segments=8))
    assert main(["tdag", "build", str(folder / "bar.npz"), "-o", str(folder / "bar.tdag")]) == 0
    return folder


def test_build_prints_sizes_and_the_figure6_measure(tmp_path, capsys):
    write_npz(tmp_path / "bar.npz", synth.twisting_bar(frames=4, rings=8, segments=8))
    assert main(["tdag", "build", str(tmp_path / "bar.npz"), "-o", str(tmp_path / "bar.tdag"), "--governing", "online",
                 "--history-weight", "0.5"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "file bytes / raw float32 frames" in out and "Figure 6 measure" in out and "lambda 0.5" in out
    assert (tmp_path / "bar.tdag").stat().st_size > 0


def test_query_writes_the_mesh_and_the_plot(built, capsys):
    target = built / "frame3.obj"
    assert main(["tdag", "query", str(built / "bar.tdag"), "--frame", "3", "--tolerance", "0.02", "--relative",
                 "-o", str(target), "--plot"]) == 0  # fmt: skip
    vertices, faces = read_mesh(target)
    assert 0 < len(faces) < 16 * 9 * 2 + 32
    assert (built / "frame3_tolerances.png").read_bytes()[:4] == b"\x89PNG"
    assert "error bound" in capsys.readouterr().out
    assert main(["tdag", "query", str(built / "bar.tdag"), "--frame", "4", "--tolerance", "0.01", "--level", "1",
                 "-o", str(built / "level1.ply")]) == 0  # fmt: skip
    assert "level 1 from the cut of frame 3" in capsys.readouterr().out


def test_query_by_face_count_writes_the_finest_mesh_within_it(built, capsys):
    """--faces N: the smallest tolerance whose mesh has at most N faces (a budget instead of an
    error); at levels 1-2, that of the earlier frame's cut, which they keep."""
    dag = TemporalDag.load(built / "bar.tdag")
    for level, budget in ((3, 60), (2, 100), (3, 1)):
        cut_frame = 4 if level == 3 else 3
        target = built / f"budget{level}_{budget}.obj"
        assert main(["tdag", "query", str(built / "bar.tdag"), "--frame", "4", "--faces", str(budget), "--level",
                     str(level), "-o", str(target)]) == 0  # fmt: skip
        tolerance = dag.tolerance_for_faces(cut_frame, budget)
        bounds = dag.error_bounds(cut_frame)
        coarsest = dag.query(cut_frame, float(bounds.max())).face_count
        within = f"for at most {budget} faces" if budget >= coarsest else f"the coarsest cut, over {budget} faces"
        assert f"tolerance {tolerance:.4g} ({within})" in capsys.readouterr().out
        assert len(read_mesh(target)[1]) <= max(budget, coarsest)
        below = bounds[bounds < tolerance]
        if below.size:  # the next bound down gives a mesh over the budget
            assert dag.query(cut_frame, float(below.max())).face_count > budget
    assert coarsest > 1  # the last budget is below the coarsest mesh: its tolerance is the largest bound


def test_play_prints_every_level(built, capsys):
    assert main(["tdag", "play", str(built / "bar.tdag"), "--tolerance", "0.02", "--relative"]) == 0
    out = capsys.readouterr().out
    for name in ("1 affine", "2 residual", "3 cut update", "fresh query", "double-buffered"):
        assert name in out


@pytest.mark.parametrize(
    "arguments, message",
    [
        (["query", "{dir}/bar.tdag", "--frame", "0", "--tolerance", "-1", "-o", "{dir}/x.obj"], "--tolerance"),
        (["query", "{dir}/bar.npz", "--frame", "0", "--tolerance", "1", "-o", "{dir}/x.obj"], "not a TDAG file"),
        (["query", "{dir}/bar.tdag", "--frame", "0", "--tolerance", "1", "-o", "{dir}/x.stl"], "expected an .obj"),
        (["query", "{dir}/bar.tdag", "--frame", "0", "--faces", "0", "-o", "{dir}/x.obj"], "faces: expected a whole"),
        (["query", "{dir}/bar.tdag", "--frame", "0", "--faces", "9", "--relative", "-o", "{dir}/x.obj"], "--relative"),
        (["build", "{dir}/missing.obj", "-o", "{dir}/x.tdag"], "does not exist"),
        (["build", "{dir}/bar.npz", "-o", "{dir}/x.tdag", "--governing", "best"], "--governing"),
        (["play", "{dir}/missing.tdag", "--tolerance", "1"], "missing.tdag"),
    ],
)
def test_user_mistakes_exit_2_with_one_line(built, capsys, arguments, message):
    assert main(["tdag", *[a.format(dir=built) for a in arguments]]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


@pytest.mark.parametrize(
    "arguments, message",
    [
        (["--frame", "6", "--tolerance", "0.1"], "bar.tdag: --frame 6 outside the frames 0 to 5"),
        (["--frame", "-1", "--tolerance", "0.1"], "bar.tdag: --frame -1 outside the frames 0 to 5"),
        (["--frame", "1", "--from-frame", "9", "--level", "2", "--tolerance", "0.1"],
         "bar.tdag: --from-frame 9 outside the frames 0 to 5"),
        (["--frame", "1", "--faces", "0"], "bar.tdag: faces: expected a whole number"),  # the core's check
    ],
)  # fmt: skip
def test_query_errors_name_the_tdag_file_and_the_option(built, capsys, arguments, message):
    """A frame out of range was "frame: 6 outside [0, 6)": no file, and --from-frame's blamed --frame."""
    assert main(["tdag", "query", str(built / "bar.tdag"), *arguments, "-o", str(built / "x.obj")]) == 2
    err = capsys.readouterr().err
    assert f"animlod tdag: error: {built}/{message}" in err and err.count("\n") == 1


def test_query_refuses_a_view_with_a_plot_before_writing_the_mesh(built, capsys):
    """--plot draws tolerances, not a view: the OBJ was written before --camera --plot was refused."""
    target = built / "view.obj"
    arguments = ["--frame", "1", "--tolerance", "0.1", "--camera", "0", "0", "5", "--plot", "-o", str(target)]
    assert main(["tdag", "query", str(built / "bar.tdag"), *arguments]) == 2
    assert "--plot: draws tolerances, not a view; drop --camera" in capsys.readouterr().err
    assert not target.exists()


def test_build_from_a_gltf_of_several_clips_says_which_one_it_took(tmp_path, capsys):
    """A TDAG is one mesh over one run of frames; the other clips were left out without a word."""
    skinned, motion = two_bone_tube()
    write_glb(tmp_path / "clips.glb", skinned, [motion, motion], names=["bend", "again"])
    assert main(["tdag", "build", str(tmp_path / "clips.glb"), "-o", str(tmp_path / "clips.tdag")]) == 0
    error = capsys.readouterr().err
    taken = "the TDAG is of the body's skinned mesh baked with its first clip, 'bend'"
    assert f"{taken}; 1 other (mesh, clip) pair" in error
