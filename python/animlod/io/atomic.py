"""Write files and folders under a temporary name and rename them into place, so that an
interrupted or failed write never leaves a half-written file or folder under its final name
and never clobbers a good one.

Temporary names are hidden, beside the target, and carry the writer's process id:
``.NAME.animlod-PID-TOKEN.part`` for a file, ``...partdir`` for a folder, ``...old`` for the
folder being replaced. They are removed on every exit path the process controls (errors,
KeyboardInterrupt, SystemExit; the CLI turns SIGTERM into SystemExit). A process killed outright
(SIGKILL, power loss) leaves them behind; the next write into the same folder removes those
whose process is gone (:func:`clean_stale`).
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

_TEMPORARY = re.compile(r"^\..+\.animlod-(\d+)-[a-z0-9_]+\.(part|partdir|old)$")
# The longest name, in bytes of UTF-8, that atomic_write can give a file: its temporary beside
# it, ".NAME.animlod-PID-XXXXXXXX.part" (a PID of 7 digits at most), must fit Linux's NAME_MAX.
LONGEST_NAME = 255 - len(".") - len(".animlod-1234567-abcdefgh.part")


def _prefix(target: Path) -> str:
    return f".{target.name}.animlod-{os.getpid()}-"


def nearest_existing(path: str | os.PathLike) -> Path:
    """``path`` or its nearest ancestor that exists (a file or a folder; a dangling link counts),
    as relative as ``path`` is: "." when none of a relative path's folders exists."""
    found = os.fspath(path)
    while found and not os.path.lexists(found) and os.path.dirname(found) != found:
        found = os.path.dirname(found)
    return Path(found or ".")


def unwritable(path: str | os.PathLike) -> str | None:
    """Why :func:`atomic_write` could not write ``path`` (it is a folder, or its nearest existing
    folder is a file or takes no new file), or None: for work that writes its result only at the
    end."""
    if os.path.isdir(path):  # the rename onto it would fail only after the work
        return "is a folder"
    folder = Path(os.path.abspath(path)).parent
    try:
        check_writable_folder(folder)
    except NotADirectoryError:
        return f"{nearest_existing(folder)} is not a folder"
    except OSError as error:
        return f"cannot write into {error.filename} ({error.strerror})"
    return None


def check_writable_folder(path: str | os.PathLike) -> None:
    """Raise, before any work, the OSError that writing files into the folder ``path`` (made if
    missing) would meet only at the end: NotADirectoryError naming ``path`` where a file stands at
    or above it, or the system's error naming the nearest existing folder where that folder takes
    no new file (no permission, a read-only file system)."""
    found = nearest_existing(path)
    if not found.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, "Not a directory", os.fspath(path))
    try:
        fd, probe = tempfile.mkstemp(prefix=".animlod-probe-", dir=found)
    except OSError as error:  # it names the probe, a file the user never asked for
        raise type(error)(error.errno, error.strerror, os.fspath(found)) from None
    os.close(fd)
    os.unlink(probe)


@contextlib.contextmanager
def atomic_write(path: str | os.PathLike, mode: str = "wb", **open_kwargs) -> Iterator[IO]:
    """Open a temporary file beside ``path``; on success rename it to ``path``, on error remove it.

    A symbolic link is written through, to the file it names, as ``open`` would (the rename
    replaced the link with a file of its own). A device or pipe is written in place: renaming over
    it replaced ``/dev/null`` with a regular file when run as root."""
    target = Path(os.path.realpath(path))
    if target.exists() and not target.is_file() and not target.is_dir():
        with open(target, mode, **open_kwargs) as handle:
            yield handle
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    clean_stale(target.parent)
    fd, temporary = tempfile.mkstemp(prefix=_prefix(target), suffix=".part", dir=target.parent)
    try:
        with os.fdopen(fd, mode, **open_kwargs) as handle:
            yield handle
        # mkstemp creates the file 0600; give it the permissions a plain open() would.
        os.chmod(temporary, 0o666 & ~_current_umask())
        os.replace(temporary, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise


@contextlib.contextmanager
def atomic_folder(path: str | os.PathLike) -> Iterator[Path]:
    """Yield an empty temporary folder beside ``path``; on success it becomes ``path``.

    A multi-file output (the frames of a level) is written into the yielded folder and appears
    under its final name only once complete. An existing folder at ``path`` is replaced as a
    whole (so no stale frame of an earlier, longer run survives): it is renamed aside, the new
    folder renamed into place, and the old one removed. A crash between the two renames leaves
    no folder at ``path``, never a partial one. On error the temporary folder is removed.
    """
    target = Path(path)
    if target.exists() and not target.is_dir():
        raise FileExistsError(17, "File exists (expected a folder)", os.fspath(target))
    target.parent.mkdir(parents=True, exist_ok=True)
    clean_stale(target.parent)
    temporary = Path(tempfile.mkdtemp(prefix=_prefix(target), suffix=".partdir", dir=target.parent))
    try:
        yield temporary
        os.chmod(temporary, 0o777 & ~_current_umask())
        old = None
        if target.exists():
            old = target.parent / f"{_prefix(target)}{secrets.token_hex(4)}.old"
            os.rename(target, old)
        os.rename(temporary, target)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(temporary, ignore_errors=True)
        raise


@contextlib.contextmanager
def staged_files(folder: str | os.PathLike) -> Iterator[Path]:
    """Yield an empty temporary folder inside ``folder``; on success each file written into it
    is renamed into ``folder`` (replacing a file of its name), on error none is.

    For a set of files that belong together in a folder that holds others (a chain's levels
    and its manifest): a write that fails half-way no longer leaves the first levels beside an
    earlier run's manifest. The renames at the end take no time, but are one by one: a crash
    among them can still leave a mixed set, never a half-written file.
    """
    target = Path(folder)
    if target.exists() and not target.is_dir():
        raise FileExistsError(17, "File exists (expected a folder)", os.fspath(target))
    target.mkdir(parents=True, exist_ok=True)
    clean_stale(target)
    temporary = Path(tempfile.mkdtemp(prefix=_prefix(target / "staged"), suffix=".partdir", dir=target))
    try:
        yield temporary
        entries = sorted(temporary.iterdir())
        for entry in entries:  # a folder in a file's place fails the rename: before any is made
            if (target / entry.name).is_dir():
                raise IsADirectoryError(errno.EISDIR, "Is a directory", os.fspath(target / entry.name))
        for entry in entries:
            os.replace(entry, target / entry.name)
    finally:
        shutil.rmtree(temporary, ignore_errors=True)


def clean_stale(folder: str | os.PathLike) -> list[Path]:
    """Remove temporary files and folders left in ``folder`` by writers that no longer run.

    Only names of this module's pattern are touched, and only when the process id in the name
    is not alive on this machine. Returns what was removed.
    """
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        match = _TEMPORARY.match(entry.name)
        if match is None or _alive(int(match.group(1))):
            continue
        path = Path(entry.path)
        if entry.is_dir(follow_symlinks=False):
            shutil.rmtree(path, ignore_errors=True)
        else:
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
        removed.append(path)
    return removed


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    return True


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
