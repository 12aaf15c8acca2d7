"""Custom batch jobs for tests/python/test_batch.py (imported by name on the Dask workers).

They stand for what goes wrong on a farm: a worker process that dies in the middle of an
asset (a crash in native code, the kernel's out-of-memory killer), once or every time; and for
a studio's job whose options may each take values of several kinds; and for the core's thread
limit an asset runs under.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Sequence
from pathlib import Path

from animlod import thread_limit
from animlod.pipelines import simplify_asset


def crash_once(source: str, output: str, *, progress=None, marker: str = "", **options: object):
    """First attempt: write half an output, then SIGKILL this worker process. Later attempts
    (``marker`` exists): the simplify job, as normal."""
    if not Path(marker).exists():
        Path(marker).write_text(str(os.getpid()))
        Path(output, "half_written_lod.glb").write_bytes(b"glTF\x02\x00\x00\x00")
        os.kill(os.getpid(), signal.SIGKILL)
    return simplify_asset(source, output, progress=progress, **options)


def always_crash(source: str, output: str, *, progress=None, **options: object):
    """Every attempt writes half an output and kills its worker."""
    Path(output, "half_written_lod.glb").write_bytes(b"glTF\x02\x00\x00\x00")
    os.kill(os.getpid(), signal.SIGKILL)


def several_kinds(
    source: str,
    output: str,
    *,
    progress=None,
    frames: list[int] | str | None = None,
    rate: float | str | None = None,
    tags: Sequence[str] = (),
):
    """Options that take a value of either of two kinds (``frames``: a list of whole numbers or a
    string such as "all"), and a list whose default is empty (``tags``); runs the simplify job."""
    return simplify_asset(source, output, progress=progress)


def report_threads(source: str, output: str, *, progress=None, **options: object):
    """The simplify job, with a note of the core's thread limit while it ran."""
    result = simplify_asset(source, output, progress=progress, **options)
    result.notes.append(f"core threads: {thread_limit()}")
    return result
