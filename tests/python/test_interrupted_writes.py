"""Outputs survive SIGKILL: a process writing a multi-level output (level folders of OBJ frames,
NPZ, BVH, a manifest) is killed at random points; every file or folder under a final name then
parses and is complete, and the next run removes what the killed one left behind."""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from animlod import synth
from animlod.io import read_bvh, read_npz, read_sequence, write_bvh, write_npz, write_sequence
from animlod.io.atomic import _TEMPORARY, atomic_folder, atomic_write, clean_stale
from animlod.io.manifest import read_lod_manifest, write_lod_manifest

LEVELS = 4
FRAMES = 12
KILLS = 8
MESH = synth.twisting_bar(frames=FRAMES, rings=24, segments=24)
MOTION = synth.humanoid_motion(synth.humanoid_skeleton(), "walk")
# Forked writers start at once (no interpreter start-up), so the kills land inside the writes.
FORK = multiprocessing.get_context("fork")


def _write_chain(out: Path) -> None:
    """What `animlod simplify`/`motion` write for a chain, level after level."""
    rows = []
    for level in range(LEVELS):
        write_sequence(out / f"bar_lod{level}", MESH, "obj")
        write_npz(out / f"bar_lod{level}.npz", MESH)
        write_bvh(out / f"walk_lod{level}.bvh", MOTION)
        rows.append({"files": [f"bar_lod{level}"], "error": float(level)})
    write_lod_manifest(out / "bar_lod.json", "mesh", rows)


def _write_chain_once_started(out: Path, started) -> None:
    started.set()
    _write_chain(out)


def _start(out: Path):
    """A forked writer of the chain, returned once it has started writing: the kills' delays count
    from the writes."""
    started = FORK.Event()
    process = FORK.Process(target=_write_chain_once_started, args=(out, started))
    process.start()
    started.wait()
    return process


def _check_final_outputs(out: Path) -> int:
    """Every entry under a final name is complete; returns how many there are."""
    expected, walk_frames = MESH, MOTION.frame_count
    final = [entry for entry in out.iterdir() if not _TEMPORARY.match(entry.name)] if out.is_dir() else []
    for entry in final:
        if entry.is_dir():
            mesh = read_sequence(entry)
            assert mesh.frame_count == FRAMES, entry
            np.testing.assert_array_equal(mesh.frames, expected.frames)
        elif entry.suffix == ".npz":
            np.testing.assert_array_equal(read_npz(entry).frames, expected.frames)
        elif entry.suffix == ".bvh":
            assert read_bvh(entry).frame_count == walk_frames
        elif entry.suffix == ".json":
            assert len(read_lod_manifest(entry)["levels"]) == LEVELS
        else:
            raise AssertionError(f"unexpected output {entry}")
    return len(final)


def test_sigkill_at_random_points_leaves_only_complete_outputs(tmp_path: Path) -> None:
    # The shortest of three whole writes sets the kills' window, so that one slow write cannot
    # widen it past the writes (in one whole pytest run all 8 kills missed them).
    durations = []
    for _ in range(3):
        process = _start(tmp_path / "full")
        start = time.perf_counter()
        process.join()
        durations.append(time.perf_counter() - start)
        assert process.exitcode == 0
        assert _check_final_outputs(tmp_path / "full") == 3 * LEVELS + 1
    duration = min(durations)

    out = tmp_path / "killed"
    rng = np.random.default_rng(7)
    seen_partial = 0
    for delay in rng.uniform(0.0, duration, size=KILLS):
        process = _start(out)
        time.sleep(delay)
        process.kill()  # SIGKILL
        process.join()
        _check_final_outputs(out)
        seen_partial += any(_TEMPORARY.match(entry.name) for entry in out.iterdir()) if out.is_dir() else 0
    # The kills landed mid-write at least once (a temporary was left), or the test proved nothing.
    assert seen_partial > 0

    process = _start(out)
    process.join()
    assert process.exitcode == 0
    assert _check_final_outputs(out) == 3 * LEVELS + 1
    assert not [entry.name for entry in out.iterdir() if _TEMPORARY.match(entry.name)]  # stale ones cleaned


def test_stale_temporaries_of_dead_processes_are_removed_and_live_ones_kept(tmp_path: Path) -> None:
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead_pid = int(dead.stdout)
    (tmp_path / f".a.obj.animlod-{dead_pid}-x1y2.part").write_text("half")
    (tmp_path / f".lod1.animlod-{dead_pid}-abc_9.partdir").mkdir()
    (tmp_path / f".lod1.animlod-{dead_pid}-abc_9.partdir" / "frame_0000.obj").write_text("v 0 0 0\n")
    live = tmp_path / f".b.obj.animlod-{os.getpid()}-zz.part"
    live.write_text("being written")
    keep = tmp_path / ".b.obj.part"  # not ours: left alone
    keep.write_text("x")
    removed = clean_stale(tmp_path)
    assert sorted(path.name for path in removed) == sorted(
        [f".a.obj.animlod-{dead_pid}-x1y2.part", f".lod1.animlod-{dead_pid}-abc_9.partdir"]
    )
    assert sorted(path.name for path in tmp_path.iterdir()) == sorted([live.name, keep.name])


def test_atomic_folder_replaces_a_longer_old_folder_and_cleans_up_on_error(tmp_path: Path) -> None:
    target = tmp_path / "lod1"
    with atomic_folder(target) as folder:
        for index in range(3):
            (folder / f"frame_{index}.obj").write_text("old")
    with pytest.raises(RuntimeError), atomic_folder(target) as folder:
        (folder / "frame_0.obj").write_text("new")
        raise RuntimeError("interrupted")
    assert sorted(path.name for path in target.iterdir()) == ["frame_0.obj", "frame_1.obj", "frame_2.obj"]
    assert sorted(path.name for path in tmp_path.iterdir()) == ["lod1"]
    with atomic_folder(target) as folder:
        (folder / "frame_0.obj").write_text("new")
    assert [path.read_text() for path in target.iterdir()] == ["new"]  # no stale frame of the longer run
    assert sorted(path.name for path in tmp_path.iterdir()) == ["lod1"]
    (tmp_path / "file").write_text("x")
    with pytest.raises(FileExistsError), atomic_folder(tmp_path / "file"):
        pass


def test_keyboard_interrupt_inside_a_write_removes_the_temporary(tmp_path: Path) -> None:
    with pytest.raises(KeyboardInterrupt), atomic_write(tmp_path / "out.bvh", "w") as handle:
        handle.write("HIERARCHY")
        raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_sigterm_during_a_cli_write_removes_the_temporary(tmp_path: Path) -> None:
    """The CLI turns SIGTERM into an exception, so atomic_write's cleanup runs."""
    script = (
        "import os, signal, sys\n"
        "from animlod.cli import main\n"
        "import animlod.cli.info as info\n"
        "from animlod.io.atomic import atomic_write\n"
        "def run(args):\n"
        "    with atomic_write(sys.argv[1] + '/out.glb', 'wb') as handle:\n"
        "        handle.write(b'half')\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "        handle.write(b'never')\n"
        "info.run = run\n"
        "sys.exit(main(['info', 'x']))\n"
    )
    done = subprocess.run([sys.executable, "-c", script, str(tmp_path)], capture_output=True, text=True)
    assert done.returncode == 143 and done.stderr == "animlod info: terminated\n"
    assert list(tmp_path.iterdir()) == []


def test_a_non_finite_number_is_named_and_nothing_is_written(tmp_path: Path) -> None:
    """JSON has no NaN or infinity: Python's json wrote them as NaN and Infinity, which every strict
    glTF or JSON reader refuses. The writers name where the number is and write nothing."""
    from animlod.io.glb_builder import GlbBuilder

    with pytest.raises(ValueError, match=r"levels\.json: JSON /levels/1/error: not a finite number"):
        write_lod_manifest(tmp_path / "levels.json", "mesh", [{"error": 0.0}, {"error": float("inf")}])
    builder = GlbBuilder()
    builder.append("nodes", {"extras": {"animlod": {"error": float("nan")}}})
    with pytest.raises(ValueError, match=r"JSON /nodes/0/extras/animlod/error: not a finite number"):
        builder.save(tmp_path / "level.glb")
    assert list(tmp_path.iterdir()) == []


def test_a_sequence_level_interrupted_while_written_leaves_no_folder(tmp_path: Path, monkeypatch) -> None:
    """`simplify` wrote each level's frames into a temporary folder beside an empty folder of the
    level's name, made first: an interrupted run left that empty folder under a final name."""
    import animlod.io.meshseq as meshseq
    from animlod.pipelines.lod_sequence import simplify_sequence

    write_sequence(tmp_path / "bar", synth.twisting_bar(frames=3, rings=8, segments=6), "obj")
    written = meshseq.write_mesh

    def interrupted_in_level_2(path, *args, **kwargs):
        if "bar_lod2" in str(path):
            raise KeyboardInterrupt
        written(path, *args, **kwargs)

    monkeypatch.setattr(meshseq, "write_mesh", interrupted_in_level_2)
    with pytest.raises(KeyboardInterrupt):
        simplify_sequence(tmp_path / "bar", tmp_path / "out", measure=False)
    assert sorted(entry.name for entry in (tmp_path / "out").iterdir()) == ["bar_lod1"]
