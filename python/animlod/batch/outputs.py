"""The output folder of a batch: one folder per asset, appearing whole or not at all.

Layout of OUT::

    OUT/<asset name>/...                 the job's files and .animlod-asset.json (its record)
    OUT/catalogue.parquet                one row per asset and level (written by the runner)
    OUT/.animlod-batch/lock              held by the running batch (flock)
    OUT/.animlod-batch/staging/...       assets being written

A job writes into a staging folder of its own (unique per attempt: host, process, token); when
it has finished, the record is added and the folder is renamed to ``OUT/<name>``, or, where that
folder is there already, the asset's own files are moved into it (:func:`publish`): the folders
of other assets nested in it (an earlier run's ``hero/run`` in ``hero``) stay as they are. A
worker killed mid-asset leaves only its staging folder, which no reader looks at, and which the
runner removes when the batch ends or the next one starts; one killed while it moves files into
an existing folder leaves at worst a record whose outputs are not all there, which the next run
redoes. Unlike :func:`animlod.io.atomic.atomic_folder`, nothing here decides by process id
whether a temporary is stale: workers may run on other machines that share OUT.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import secrets
import shutil
import socket
from collections.abc import Iterator
from pathlib import Path

from ..io.atomic import atomic_write
from ..io.detect import ASSET_RECORD, BATCH_STATE, recorded_outputs

CATALOGUE = "catalogue.parquet"


class BatchBusy(OSError):
    """Another batch holds the lock of the output folder."""


def prepare_output(root: str | os.PathLike) -> Path:
    """Create the output folder; FileExistsError naming it when it is a file."""
    folder = Path(root)
    if folder.exists() and not folder.is_dir():
        raise FileExistsError(17, "is a file; a batch writes into a folder", os.fspath(folder))
    (folder / BATCH_STATE / "staging").mkdir(parents=True, exist_ok=True)
    return folder


@contextlib.contextmanager
def output_lock(root: Path) -> Iterator[None]:
    """Hold ``OUT/.animlod-batch/lock`` for the run; BatchBusy when another batch holds it."""
    path = root / BATCH_STATE / "lock"
    with open(path, "a+", encoding="utf-8") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.seek(0)
            holder = handle.read().strip() or "another process"
            raise BatchBusy(11, f"another animlod batch ({holder}) is writing here", os.fspath(root)) from None
        handle.seek(0)
        handle.truncate()
        handle.write(f"{socket.gethostname()} pid {os.getpid()}\n")
        handle.flush()
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def clear_staging(root: Path) -> list[Path]:
    """Remove every staging folder (only while the lock is held and no task runs); returns them."""
    staging = root / BATCH_STATE / "staging"
    removed = []
    for entry in sorted(staging.iterdir()) if staging.is_dir() else []:
        shutil.rmtree(entry, ignore_errors=True)
        removed.append(entry)
    return removed


def staging_folder(root: Path, name: str) -> Path:
    """A new, empty folder for one attempt at asset ``name``."""
    flat = name.replace("/", "%")
    folder = root / BATCH_STATE / "staging" / f"{flat}.{socket.gethostname()}-{os.getpid()}-{secrets.token_hex(4)}"
    folder.mkdir(parents=True)
    return folder


def publish(staging: Path, root: Path, name: str, record: dict) -> Path:
    """Write ``record`` into ``staging`` and move the asset's files to ``root/name``: one rename
    where that folder is new. Into an existing one, the outputs its older record lists and what
    the new files take the place of go first, then the record moves in, then the new files: a
    record never finds an older file in place of one of its outputs (a worker killed meanwhile
    leaves some missing, and the next run redoes the asset). The rest stays: the folders of other
    assets nested in it, files the asset did not write.

    Raises FileExistsError, before anything moves, where a file is in the way of the folder or a
    new file would take the place of another asset's folder."""
    with atomic_write(staging / ASSET_RECORD, "w", encoding="utf-8") as handle:
        json.dump(record, handle, indent=1)
        handle.write("\n")
    target = root / name
    blocking = next((path for path in (target, *target.parents) if path.is_relative_to(root) and path.is_file()), None)
    if blocking is not None:
        raise FileExistsError(17, f"is a file where the outputs of asset {name!r} need a folder", os.fspath(blocking))
    if not target.exists():
        target.parent.mkdir(parents=True, exist_ok=True)
        os.rename(staging, target)
        return target
    new = sorted(path.name for path in staging.iterdir() if path.name != ASSET_RECORD)
    for entry in new:
        if _holds_an_asset(target / entry):
            reason = f"is another asset's folder, where asset {name!r} writes its output {entry}; left as it is"
            raise FileExistsError(17, reason, os.fspath(target / entry))
    older = (recorded_outputs(target) or set()) - set(new)  # None: no record it can read lists nothing
    for entry in sorted(older) + new:
        if not _holds_an_asset(target / entry):  # an older output another asset was written into stays
            _remove(target / entry)
    os.replace(staging / ASSET_RECORD, target / ASSET_RECORD)
    for entry in new:
        os.rename(staging / entry, target / entry)
    staging.rmdir()
    return target


def _holds_an_asset(path: Path) -> bool:
    """Whether ``path`` is a folder with an asset's record in or below it."""
    return path.is_dir() and not path.is_symlink() and any(path.rglob(ASSET_RECORD))


def _remove(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path)
    elif os.path.lexists(path):
        path.unlink()


def earlier_assets(root: Path, names: set[str]) -> list[str]:
    """The assets of earlier runs into ``root`` that ``names`` does not hold: the folders with a
    record (an asset renamed or taken out of the spec since), by name."""
    found = (path.parent.relative_to(root).as_posix() for path in root.rglob(ASSET_RECORD))
    return sorted(name for name in found if name not in names and not name.startswith(BATCH_STATE))


def discard(staging: Path) -> None:
    shutil.rmtree(staging, ignore_errors=True)
