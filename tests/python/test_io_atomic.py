import os
import stat

import pytest

from animlod.io.atomic import atomic_write, unwritable


def test_atomic_write_leaves_no_partial_file_and_normal_permissions(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_write(target, "w") as handle:
        handle.write("half")
        raise RuntimeError("interrupted")
    assert target.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["out.txt"]
    with atomic_write(target, "w") as handle:
        handle.write("new")
    umask = os.umask(0)
    os.umask(umask)
    assert target.read_text() == "new"
    assert stat.S_IMODE(target.stat().st_mode) == 0o666 & ~umask


def test_a_link_is_written_through_and_a_pipe_in_place(tmp_path):
    """The rename replaced a symbolic link with a file of its own (its target kept the old bytes)
    and `-o /dev/null` with a regular file when run as root."""
    (tmp_path / "real").mkdir()
    real = tmp_path / "real" / "out.txt"
    real.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    with atomic_write(link, "w") as handle:
        handle.write("new")
    assert link.is_symlink() and real.read_text() == "new"
    pipe = tmp_path / "pipe"
    os.mkfifo(pipe)
    reader = os.open(pipe, os.O_RDONLY | os.O_NONBLOCK)  # so that opening it to write does not block
    try:
        with atomic_write(pipe, "w") as handle:
            handle.write("through")
        assert os.read(reader, 100) == b"through"
    finally:
        os.close(reader)
    assert stat.S_ISFIFO(pipe.stat().st_mode) and sorted(p.name for p in tmp_path.iterdir()) == [
        "link.txt",
        "pipe",
        "real",
    ]


def test_unwritable_names_a_folder_in_the_files_place(tmp_path):
    # atomic_write's rename onto the folder failed only after the work, naming its temporary file.
    (tmp_path / "out").mkdir()
    assert unwritable(tmp_path / "out") == "is a folder"
    assert unwritable(tmp_path / "out" / "report.json") is None
