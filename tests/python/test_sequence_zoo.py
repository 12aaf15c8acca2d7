"""Sequences as real pipelines export them: quirks of the files that reached a wrong result."""

from __future__ import annotations

import numpy as np
import pytest

from animlod import synth
from animlod.cli import main
from animlod.io.meshseq import read_sequence, write_sequence
from animlod.io.npz import read_npz, write_npz
from animlod.io.obj import read_obj

SQUARE = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\nf 1 3 2\nf 1 4 3\n"


def test_obj_with_a_utf8_byte_order_mark_keeps_its_first_vertex(tmp_path):
    # Windows tools (.NET's Encoding.UTF8, Notepad) start a text file with a byte order mark: the
    # first statement "v 0 0 0" must still be a vertex, or every face index shifts by one.
    (tmp_path / "plain.obj").write_text(SQUARE)
    (tmp_path / "bom.obj").write_bytes(b"\xef\xbb\xbf" + SQUARE.encode())
    plain, bom = read_obj(tmp_path / "plain.obj"), read_obj(tmp_path / "bom.obj")
    assert np.array_equal(plain[0], bom[0]) and np.array_equal(plain[1], bom[1])
    for index in range(3):
        (tmp_path / "frames").mkdir(exist_ok=True)
        (tmp_path / "frames" / f"mesh_{index:04d}.obj").write_bytes(b"\xef\xbb\xbf" + SQUARE.encode())
    assert read_sequence(tmp_path / "frames").frames.shape == (3, 5, 3)


def test_npz_with_an_integer_frame_rate_is_read(tmp_path):
    # np.savez(..., fps=30) stores an int64; the rate is as clear as 30.0.
    mesh = synth.twisting_bar(frames=3, rings=4, segments=4)
    path = tmp_path / "bar.npz"
    np.savez(path, format_version=1, faces=mesh.faces.astype(np.int64), frames=mesh.frames.astype(np.float64), fps=30)
    read = read_npz(path)
    assert read.fps == 30.0 and np.array_equal(read.frames, mesh.frames)
    np.savez(path, format_version=1, faces=mesh.faces, frames=mesh.frames, fps=0)
    with pytest.raises(ValueError, match="key 'fps': must be positive or NaN, got 0"):
        read_npz(path)


@pytest.fixture(scope="module")
def single_frame_tdag(tmp_path_factory):
    folder = tmp_path_factory.mktemp("tdag1")
    mesh = synth.twisting_bar(frames=3, rings=6, segments=6)
    write_npz(folder / "bar.npz", mesh)
    assert main(["tdag", "build", str(folder / "bar.npz"), "-o", str(folder / "bar.tdag")]) == 0
    write_npz(folder / "one.npz", type(mesh)(mesh.faces, mesh.frames[:1]))
    assert main(["tdag", "build", str(folder / "one.npz"), "-o", str(folder / "one.tdag")]) == 0
    return folder


@pytest.mark.parametrize(
    "arguments, message",
    [
        # A table of zeros measured over no frame read as a result; a single-frame sequence or the
        # last frame leave nothing to play.
        (["{dir}/one.tdag"], "one.tdag: --first-frame 0 leaves no frame to play"),
        (["{dir}/bar.tdag", "--first-frame", "2"], "bar.tdag: --first-frame 2 leaves no frame to play"),
        (["{dir}/bar.tdag", "--frames", "-3"], "--frames"),
        (["{dir}/bar.tdag", "--frames", "0"], "--frames"),
        (["{dir}/bar.tdag", "--first-frame", "5"], "bar.tdag: --first-frame 5 outside the frames 0 to 2"),
    ],
)
def test_tdag_play_with_no_frame_to_walk_exits_2(single_frame_tdag, capsys, arguments, message):
    code = main(["tdag", "play", *[a.format(dir=single_frame_tdag) for a in arguments], "--tolerance", "0.01"])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1 and "Traceback" not in err


def test_simplify_says_which_sequence_levels_stopped_short_of_their_target(tmp_path, capsys):
    # --max-error stops the collapses: levels 2 and 3 came out equal, and the table showed no target.
    frames = tmp_path / "frames"
    write_sequence(frames, synth.twisting_bar(frames=4, rings=12, segments=8))
    args = ["simplify", str(frames), "-o", str(tmp_path / "out"), "--no-metrics", "--max-error", "1e-9"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "target" in out.splitlines()[2]
    assert "note: level 1: stopped at" in out and "max error 1e-09 reached" in out
    assert main(["simplify", str(frames), "-o", str(tmp_path / "out2"), "--no-metrics"]) == 0
    assert "note:" not in capsys.readouterr().out


def test_levels_of_ply_frames_given_by_a_glob_without_suffix_are_ply(tmp_path):
    # 'frames/*' names PLY frames without saying so: the levels came out as OBJ.
    from animlod.pipelines.lod_sequence import simplify_sequence

    write_sequence(tmp_path / "frames", synth.twisting_bar(frames=3, rings=8, segments=6), fmt="ply")
    report = simplify_sequence(str(tmp_path / "frames" / "*"), tmp_path / "out", (0.5,), measure=False)
    assert [path.suffix for path in sorted(report.levels[0].path.iterdir())] == [".ply"] * 3


def test_a_long_sequence_is_measured_in_chunks_of_frames_at_the_same_points(tmp_path, monkeypatch):
    # Every frame's points in float64 at once: 1.4 GB to measure 1000 frames of a 441-vertex cloth.
    from animlod import metrics
    from animlod.pipelines import lod_sequence

    mesh = synth.twisting_bar(frames=11, rings=8, segments=6)
    write_npz(tmp_path / "bar.npz", mesh)
    whole = lod_sequence.simplify_sequence(tmp_path / "bar.npz", tmp_path / "whole", (0.5, 0.2))
    measured_frames = []

    def spy(original, simplified, samples, seed=0):
        measured_frames.append(original.frame_count)
        return metrics.surface_error(original, simplified, samples, seed)

    per_frame = mesh.vertex_count * 2 + 2 * 10000  # at most: a level has fewer vertices
    monkeypatch.setattr(lod_sequence, "_MEASURED_POINTS_PER_CHUNK", 3 * per_frame)
    monkeypatch.setattr(lod_sequence, "surface_error", spy)
    chunked = lod_sequence.simplify_sequence(tmp_path / "bar.npz", tmp_path / "chunked", (0.5, 0.2))
    assert measured_frames and max(measured_frames) <= 5
    for a, b in zip(whole.levels, chunked.levels):
        assert a.surface == b.surface and a.error == b.error
