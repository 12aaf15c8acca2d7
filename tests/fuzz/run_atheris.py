"""Run one Python fuzz harness under atheris: ``python run_atheris.py NAME [libFuzzer flags]``.

animlod's modules are instrumented for coverage as the harness imports them; numpy and the
other libraries are not (their coverage would drown animlod's).
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import atheris

sys.path.insert(0, str(Path(__file__).resolve().parent / "python"))
import numpy  # noqa: E402, F401  (imported uninstrumented)
import pygltflib  # noqa: E402, F401

name = sys.argv.pop(1)
with atheris.instrument_imports(include=["animlod"]):
    harness = importlib.import_module(f"fuzz_{name}")


def test_one_input(data: bytes) -> None:
    harness.check(data)


atheris.Setup(sys.argv, test_one_input)
atheris.Fuzz()
