"""The output folder of a batch: one folder per asset, appearing whole or not at all.

Layout of OUT::

    OUT/<asset name>/...                 the job's files and .animlod-asset.json (its record)
    OUT/catalogue.parquet                one row per asset and level (written by the runner)
    OUT/.animlod-batch/lock              held by the running batch (flock)
    OUT/.animlod-batch/staging/...       assets being written

A job writes into a staging folder of its own (unique per attempt: host, process, token); when
it has finished, the record is added and the folder is renamed to ``OUT/<name>`` (an older
version is renamed aside first, then removed). A worker killed mid-asset leaves only its
staging folder, which no reader looks at, and which the runner removes when the batch ends or
the next one starts. Unlike :func:`animlod.io.atomic.atomic_folder`, nothing here decides by
process id whether a temporary is stale: workers may run on other machines that share OUT.
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
from ..io.detect import BATCH_STATE

RECORD = ".animlod-asset.json"
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
    """Write ``record`` into ``staging`` and rename it to ``root/name``, replacing an older one."""
    with atomic_write(staging / RECORD, "w", encoding="utf-8") as handle:
        json.dump(record, handle, indent=1)
        handle.write("\n")
    target = root / name
    if target.exists() and not target.is_dir():
        raise FileExistsError(17, "is a file; the asset's outputs go in a folder of that name", os.fspath(target))
    target.parent.mkdir(parents=True, exist_ok=True)
    old = None
    if target.exists():
        old = staging.with_name(staging.name + ".old")
        os.rename(target, old)
    os.rename(staging, target)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return target


def read_record(root: Path, name: str) -> dict | None:
    """The record of asset ``name`` from an earlier run, or None (absent or unreadable)."""
    try:
        record = json.loads((root / name / RECORD).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return record if isinstance(record, dict) else None


def earlier_assets(root: Path, names: set[str]) -> list[str]:
    """The assets of earlier runs into ``root`` that ``names`` does not hold: the folders with a
    record (an asset renamed or taken out of the spec since), by name."""
    found = (path.parent.relative_to(root).as_posix() for path in root.rglob(RECORD))
    return sorted(name for name in found if name not in names and not name.startswith(BATCH_STATE))


def discard(staging: Path) -> None:
    shutil.rmtree(staging, ignore_errors=True)
