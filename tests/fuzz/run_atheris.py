"""Run one Python fuzz harness under atheris: ``python run_atheris.py NAME [libFuzzer flags]``.

Only animlod's functions are instrumented for coverage (numpy's would drown them). The editable
install loads animlod through a custom importer, which atheris.instrument_imports cannot
patch, so the functions are patched after import, one by one.
"""

from __future__ import annotations

import gc
import hashlib
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


# The input is saved before the exception goes to atheris: its own crash report was seen to die
# (SIGALRM of the -timeout watchdog, under load) before libFuzzer wrote the artifact.
ARTIFACTS = next((arg.split("=", 1)[1] for arg in sys.argv if arg.startswith("-artifact_prefix=")), "./")


def test_one_input(data: bytes) -> None:
    try:
        harness.check(data)
    except BaseException:
        Path(f"{ARTIFACTS}crash-{hashlib.sha1(data).hexdigest()}").write_bytes(data)
        raise


atheris.Setup(sys.argv, test_one_input)
atheris.Fuzz()
