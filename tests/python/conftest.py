"""Shared fixtures: the real development data and the crowd binary (skipped cleanly when absent)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

# ../shared/data beside the checkout, or wherever ANIMLOD_DATA points.
DATA_DIR = Path(os.environ.get("ANIMLOD_DATA", Path(__file__).resolve().parents[3] / "shared" / "data"))


@pytest.fixture(scope="session")
def data_dir() -> Path:
    if not DATA_DIR.is_dir():
        pytest.skip(f"development data not found at {DATA_DIR}")
    return DATA_DIR


@pytest.fixture(scope="module")
def client():
    """A local Dask cluster of two workers for one module's batch runs."""
    from animlod.batch import connect

    client, cluster = connect(workers=2)
    yield client
    client.close()
    cluster.close()


@pytest.fixture(scope="session")
def binary() -> Path:
    """The crowd benchmark's binary (skipped cleanly where it is not built or no display can run)."""
    from animlod.crowd import find_crowd_binary

    found = find_crowd_binary()
    if found is None:
        pytest.skip("animlod_crowd is not built (make test builds it and sets ANIMLOD_CROWD_BIN)")
    if not os.environ.get("DISPLAY") and not shutil.which("xvfb-run"):
        pytest.skip("no display and no xvfb-run")
    return found


@pytest.fixture(scope="session")
def humanoid_glb(tmp_path_factory) -> Path:
    """The procedural humanoid with a walk, as a GLB (animlod's own writer)."""
    from animlod import synth
    from animlod.io import write_glb

    path = tmp_path_factory.mktemp("humanoid") / "humanoid.glb"
    character = synth.humanoid()
    write_glb(path, character, [synth.humanoid_motion(character.skeleton, "walk")])
    return path
