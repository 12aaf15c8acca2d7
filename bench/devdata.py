"""Where the real development data is: ../shared/data beside the checkout, or wherever
ANIMLOD_DATA points (the same rule as tests/python/conftest.py). Benchmarks skip the cases
whose files are absent."""

from __future__ import annotations

import os
from pathlib import Path

DATA_DIR = Path(os.environ.get("ANIMLOD_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"))
