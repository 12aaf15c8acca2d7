"""The fuzz harnesses in make test: the registry is consistent, every saved crash of a Python
harness is replayed (the C++ ones are replayed by ctest), and any byte string given to a
reader ends in data or a FormatError naming the file within 1 s (a property test over
deterministic mutations of each harness's seeds)."""

from __future__ import annotations

import importlib
import sys
import time
from pathlib import Path

import numpy as np
import pytest

FUZZ_DIR = Path(__file__).resolve().parents[1] / "fuzz"
sys.path[:0] = [str(FUZZ_DIR), str(FUZZ_DIR / "python")]

from run import load_registry  # noqa: E402  (tests/fuzz/run.py)
from seeds import SEEDS, data_dir  # noqa: E402

HARNESSES = load_registry()
PYTHON = [h for h in HARNESSES if h.language == "python"]
# Mutated inputs per reader; enough to reach each reader's error paths in a few seconds.
MUTATIONS = 40
SECONDS_PER_INPUT = 1.0


def test_registry_matches_the_harness_files() -> None:
    listed = {(h.name, h.language) for h in HARNESSES}
    on_disk = {(p.stem[len("fuzz_") :], "cpp") for p in (FUZZ_DIR / "cpp").glob("fuzz_*.cpp")}
    on_disk |= {(p.stem[len("fuzz_") :], "python") for p in (FUZZ_DIR / "python").glob("fuzz_*.py")}
    assert listed == on_disk
    for harness in HARNESSES:
        assert harness.seeds in SEEDS, harness
        assert harness.dictionary is None or (FUZZ_DIR / "dicts" / harness.dictionary).is_file(), harness
    assert {p.name for p in (FUZZ_DIR / "crashes").iterdir()} <= {h.name for h in HARNESSES}


def _check(name: str):
    return importlib.import_module(f"fuzz_{name}").check


def _saved(name: str) -> list[Path]:
    folder = FUZZ_DIR / "crashes" / name
    return sorted(folder.iterdir()) if folder.is_dir() else []


@pytest.mark.parametrize(
    "harness, path",
    [(h.name, p) for h in PYTHON for p in _saved(h.name)],
    ids=lambda value: value if isinstance(value, str) else value.name,
)
def test_saved_crash_is_fixed(harness: str, path: Path) -> None:
    """Each input the fuzzer saved now ends in data or a FormatError naming the file, in time."""
    start = time.perf_counter()
    _check(harness)(path.read_bytes())
    assert time.perf_counter() - start < 5 * SECONDS_PER_INPUT  # timeouts were saved at 5 s instrumented


def _mutations(seed: bytes, rng: np.random.Generator, count: int) -> list[bytes]:
    """Truncations, byte flips, spliced repeats and random bytes: what libFuzzer does first."""
    out = [b"", rng.bytes(4096)]
    data = np.frombuffer(seed, np.uint8)
    for _ in range(count):
        kind = rng.integers(4)
        if kind == 0 and len(seed) > 1:
            out.append(seed[: rng.integers(1, len(seed))])
        elif kind == 1 and len(seed):
            flipped = data.copy()
            positions = rng.integers(0, len(seed), size=rng.integers(1, 8))
            flipped[positions] = rng.integers(0, 256, size=positions.size)
            out.append(flipped.tobytes())
        elif kind == 2 and len(seed) > 2:
            a, b = sorted(rng.integers(0, len(seed), size=2))
            out.append(seed[:b] + seed[a:b] * int(rng.integers(1, 4)) + seed[b:])
        else:
            out.append(rng.bytes(int(rng.integers(1, 512))))
    return out


@pytest.mark.parametrize("harness", PYTHON, ids=lambda h: h.name)
def test_any_bytes_end_in_data_or_format_error_within_a_second(harness) -> None:
    rng = np.random.default_rng(12)
    seeds = SEEDS[harness.seeds](data_dir())
    check = _check(harness.name)
    slowest = (0.0, b"")
    for seed in sorted(seeds.values(), key=len)[:4]:
        for data in _mutations(seed, rng, MUTATIONS // 4):
            start = time.perf_counter()
            check(data)  # raises for anything but data or a FormatError naming the file
            slowest = max(slowest, (time.perf_counter() - start, data))
    assert slowest[0] < SECONDS_PER_INPUT, f"{harness.name}: {slowest[0]:.2f} s on {slowest[1][:80]!r}"
