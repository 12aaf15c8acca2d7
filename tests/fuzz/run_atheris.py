"""Run one Python fuzz harness under atheris: ``python run_atheris.py NAME [libFuzzer flags]``.

Only animlod's functions are instrumented for coverage (numpy's would drown them). The editable
install loads animlod through a custom importer, which atheris.instrument_imports cannot
patch, so the functions are patched after import, one by one.
"""

from __future__ import annotations

import gc
import importlib
import sys
import types
from pathlib import Path

import atheris

sys.path.insert(0, str(Path(__file__).resolve().parent / "python"))
import numpy  # noqa: F401  (imported uninstrumented)
import pygltflib  # noqa: F401

name = sys.argv.pop(1)
harness = importlib.import_module(f"fuzz_{name}")
for function in [obj for obj in gc.get_objects() if isinstance(obj, types.FunctionType)]:
    if (function.__module__ or "").startswith("animlod"):
        atheris.instrument_func(function)


def test_one_input(data: bytes) -> None:
    harness.check(data)


atheris.Setup(sys.argv, test_one_input)
atheris.Fuzz()
