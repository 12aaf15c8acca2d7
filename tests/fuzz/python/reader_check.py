"""What every Python fuzz harness shares: hand the bytes to a reader as a file and accept only
data or a FormatError that names that file.

A harness module ``fuzz_NAME.py`` defines ``check(data: bytes) -> None``, usually one call of
:func:`read_as`. Anything else that escapes (IndexError, RecursionError, MemoryError, a
ValueError that is not a FormatError, a FormatError naming another file) is a finding: atheris
saves the input, and the regression test replays it.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from animlod.io.errors import FormatError

# One scratch folder per process, in memory where the system has it.
_SCRATCH = Path(tempfile.mkdtemp(prefix="animlod-fuzz-", dir="/dev/shm" if os.path.isdir("/dev/shm") else None))


def read_as(data: bytes, suffix: str, reader: Callable[[Path], Any]) -> Any:
    """Write ``data`` to a file named ``*suffix`` and read it; None when the reader refused it."""
    path = _SCRATCH / f"input{suffix}"
    path.write_bytes(data)
    try:
        return reader(path)
    except FormatError as error:
        if not str(error).startswith(str(path)):
            raise AssertionError(f"FormatError does not name the file it read: {error}") from error
        return None
