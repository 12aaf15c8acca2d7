"""An output that cannot be written is refused before the work, by every command that writes one.

The levels of a long character or clip are written only at the end; a folder that takes no new
file (no permission, a read-only file system) or a file standing where a folder must be made was
found only then, after minutes of work, and motion called either "Not a directory".
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest

import animlod.cli.batch
import animlod.cli.character
import animlod.cli.demo
import animlod.cli.face
import animlod.cli.motion
import animlod.cli.simplify
import animlod.cli.tdag
from animlod.cli import main

# (module, its run function, argv with OUT for the output): one per command that takes -o.
COMMANDS = [
    (animlod.cli.simplify, "run", ["simplify", "in.glb", "-o", "OUT/in_lod.glb"]),
    (animlod.cli.simplify, "run", ["simplify", "frames", "-o", "OUT/levels"]),
    (animlod.cli.character, "run", ["character", "in.glb", "-o", "OUT/in_character.glb"]),
    (animlod.cli.motion, "run", ["motion", "in.bvh", "-o", "OUT/levels"]),
    (animlod.cli.face, "run", ["face", "-o", "OUT/face"]),
    (animlod.cli.tdag, "run_build", ["tdag", "build", "frames", "-o", "OUT/in.tdag"]),
    (animlod.cli.tdag, "run_query", ["tdag", "query", "in.tdag", "--frame", "0", "--faces", "9", "-o", "OUT/q.obj"]),
    (animlod.cli.batch, "run", ["batch", "library", "-o", "OUT/batch"]),
    (animlod.cli.demo, "run", ["demo", "-o", "OUT/demo"]),
]
IDS = [" ".join(argv[:2]) for _, _, argv in COMMANDS]


@pytest.fixture
def work_done(monkeypatch):
    """Replace every command's work by a record of its call."""
    calls: list[str] = []
    for module, name, _ in COMMANDS:
        monkeypatch.setattr(module, name, lambda args, name=name: calls.append(args.command) or 0)
    return calls


@pytest.fixture
def closed_folder(tmp_path):
    """A folder that takes no new file, and the reason the system gives: a folder without write
    permission, or for root (whom permissions do not stop) /sys where it refuses new files."""
    if os.geteuid() != 0:
        folder = tmp_path / "closed"
        folder.mkdir()
        folder.chmod(0o500)
        yield folder, "Permission denied"
        folder.chmod(0o700)
        return
    folder = Path("/sys")
    try:
        fd, probe = tempfile.mkstemp(dir=folder)
    except OSError as error:
        yield folder, error.strerror
        return
    os.close(fd)
    os.unlink(probe)
    pytest.skip("/sys takes new files here and the tests run as root: no folder refuses them")


def _argv(argv: list[str], out: Path) -> list[str]:
    return [word.replace("OUT", os.fspath(out)) for word in argv]


@pytest.mark.parametrize("module, name, argv", COMMANDS, ids=IDS)
def test_a_folder_that_takes_no_file_is_refused_before_the_work(
    module, name, argv, closed_folder, work_done, capsys
) -> None:
    folder, reason = closed_folder
    assert main(_argv(argv, folder)) == 2
    assert work_done == []
    err = capsys.readouterr().err.strip()
    assert err == f"animlod {argv[0]}: error: {folder}: {reason}"


@pytest.mark.parametrize("module, name, argv", COMMANDS, ids=IDS)
def test_a_file_where_a_folder_must_be_made_is_refused_before_the_work(
    module, name, argv, tmp_path, work_done, capsys
) -> None:
    (tmp_path / "taken").write_text("")
    assert main(_argv(argv, tmp_path / "taken" / "sub")) == 2
    assert work_done == []
    err = capsys.readouterr().err.strip()
    assert err == f"animlod {argv[0]}: error: {tmp_path / 'taken'}: is a file where the output needs a folder"


@pytest.mark.parametrize("module, name, argv", COMMANDS, ids=IDS)
def test_a_writable_output_goes_on_to_the_work_and_the_probe_leaves_nothing(
    module, name, argv, tmp_path, work_done
) -> None:
    assert main(_argv(argv, tmp_path)) == 0
    assert work_done == [argv[0]]
    assert list(tmp_path.iterdir()) == []


def test_motion_levels_in_a_closed_folder_name_it_before_the_work(closed_folder, tmp_path, monkeypatch) -> None:
    import animlod.motion_lod.chain as chain
    from animlod.pipelines.motion import build_motion_levels

    def no_work(*args, **kwargs):
        raise AssertionError("the levels were built before the refusal")

    monkeypatch.setattr(chain, "build_motion_chain", no_work)
    folder, reason = closed_folder
    with pytest.raises(OSError, match=reason) as raised:
        build_motion_levels(tmp_path / "in.bvh", folder / "levels", levels=2)
    assert not isinstance(raised.value, NotADirectoryError)
    assert raised.value.filename == os.fspath(folder)


def test_sequence_levels_in_a_closed_folder_name_it_before_reading(closed_folder, tmp_path) -> None:
    from animlod.pipelines.lod_sequence import simplify_sequence

    folder, reason = closed_folder
    with pytest.raises(OSError, match=reason) as raised:  # the input does not exist: it was not read
        simplify_sequence(tmp_path / "missing_frames", folder / "levels", (0.5,))
    assert raised.value.filename == os.fspath(folder)
