"""``make sanitize``: load the ASan + UBSan build of ``animlod._core`` in place of the normal one.

Python imports ``sitecustomize`` at start-up from ``sys.path``; the Makefile puts this folder on
PYTHONPATH and names the sanitized extension in ``ANIMLOD_SANITIZED_CORE``, so pytest and every
Python process the tests start (CLI runs, workers) use it. The finder goes in front of the
editable install's own (which the .pth files installed before this runs). Without the variable
nothing changes.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import os
import sys

_PATH = os.environ.get("ANIMLOD_SANITIZED_CORE")


class _SanitizedCore(importlib.abc.MetaPathFinder):
    def find_spec(
        self, fullname: str, path: object = None, target: object = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname != "animlod._core" or not _PATH:
            return None
        return importlib.util.spec_from_file_location(fullname, _PATH)


if _PATH:
    if not os.path.isfile(_PATH):
        raise SystemExit(f"ANIMLOD_SANITIZED_CORE: {_PATH}: no such file")
    sys.meta_path.insert(0, _SanitizedCore())
