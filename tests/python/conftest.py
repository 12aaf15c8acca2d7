"""Shared fixtures: the real development data (skipped cleanly when absent)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# ../shared/data beside the checkout, or wherever ANIMLOD_DATA points.
DATA_DIR = Path(os.environ.get("ANIMLOD_DATA", Path(__file__).resolve().parents[3] / "shared" / "data"))


@pytest.fixture(scope="session")
def data_dir() -> Path:
    if not DATA_DIR.is_dir():
        pytest.skip(f"development data not found at {DATA_DIR}")
    return DATA_DIR
