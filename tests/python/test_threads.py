"""The core's thread limit (animlod.set_thread_limit, ANIMLOD_THREADS): checked, kept, and never
a change in what the core computes."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

from animlod import AnimatedMesh, TemporalDag, set_thread_limit, simplify_animated, synth, thread_limit


@pytest.fixture
def one_thread():
    set_thread_limit(1)
    yield
    set_thread_limit(0)


def test_the_limit_is_checked_and_zero_lifts_it(one_thread) -> None:
    assert thread_limit() == 1
    for bad in (-1, 1.5, True, "2"):
        with pytest.raises(ValueError, match="threads: must be a whole number"):
            set_thread_limit(bad)
    assert thread_limit() == 1
    set_thread_limit(0)
    assert thread_limit() == os.cpu_count()


def _bumpy_frames() -> AnimatedMesh:
    """123k edges (collapse passes, halves on two workers) over 3 frames (face quadrics on two)."""
    positions, faces = synth.icosphere(6)
    rng = np.random.default_rng(7)
    radii = 1.0 + 0.02 * rng.standard_normal((3, len(positions), 1))
    squash = np.array([1.0, 1.0, 1.0]) + np.linspace(0.0, 0.3, 3)[:, None] * np.array([0.0, -1.0, 0.5])
    return AnimatedMesh(faces, (positions[None] * radii * squash[:, None, :]).astype(np.float32))


def test_aqem_levels_are_the_same_on_one_thread(one_thread) -> None:
    mesh = _bumpy_frames()
    alone = simplify_animated(mesh, (0.5, 0.1))
    set_thread_limit(0)
    shared = simplify_animated(mesh, (0.5, 0.1))
    for a, b in zip(alone.levels, shared.levels, strict=True):
        np.testing.assert_array_equal(a.mesh.faces, b.mesh.faces)
        np.testing.assert_array_equal(a.mesh.frames, b.mesh.frames)


@pytest.mark.parametrize(("value", "expected", "warns"), [("1", 1, False), ("x2", None, True)])
def test_the_environment_sets_the_starting_limit(value, expected, warns) -> None:
    run = subprocess.run(
        [sys.executable, "-c", "import animlod; print(animlod.thread_limit())"],
        env={**os.environ, "ANIMLOD_THREADS": value},
        capture_output=True,
        text=True,
        check=True,
    )
    assert int(run.stdout) == (expected or os.cpu_count())
    assert ("ANIMLOD_THREADS='x2' is not a whole number" in run.stderr) == warns


def test_tdag_fields_measured_on_threads_equal_one_threads(one_thread) -> None:
    # Threads measure a frame each (tdag_build.cpp); recorded in frame order, every field and
    # the build report are those of one thread.
    mesh = synth.bending_cylinder(frames=7, rings=12, segments=10)
    alone = TemporalDag.build(mesh, "first")
    set_thread_limit(0)
    shared = TemporalDag.build(mesh, "first")
    assert alone.to_bytes() == shared.to_bytes()
    for name in ("collapse_counts", "max_cost", "use_counts"):
        np.testing.assert_array_equal(getattr(alone.report, name), getattr(shared.report, name))
