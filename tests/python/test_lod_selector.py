"""The runtime LoD selector of the core (cpp/include/animlod/lod_selector.hpp) through its bindings."""

from __future__ import annotations

import math

import numpy as np
import pytest

from animlod import _core

ERRORS = [0.0, 0.01, 0.04, 0.16]
COVERAGES = [0.5, 0.25, 0.1, 0.0]


def _sweep(selector: _core.LodSelector, distances: np.ndarray, focal: float) -> list[int]:
    return [selector.select_by_error(ERRORS, float(d), focal) for d in distances]


def _changes(levels: list[int]) -> int:
    return int(np.count_nonzero(np.diff(levels)))


def test_distance_sweep_up_and_down_does_not_flicker_at_a_threshold() -> None:
    focal = 1000.0  # level 1 -> 2 threshold at distance 40 (0.04 / 40 * 1000 = 1 px)
    rng = np.random.default_rng(3)
    # Out from 5 to 300 and back, with +-3 % jitter on every step (a character walking on the spot).
    ramp = np.geomspace(5.0, 300.0, 200)
    distances = np.concatenate([ramp, ramp[::-1]]) * (1.0 + 0.03 * rng.uniform(-1, 1, 400))
    steady = _sweep(_core.LodSelector(_core.LodSelectorOptions(hysteresis=0.15)), distances, focal)
    jumpy = _sweep(_core.LodSelector(_core.LodSelectorOptions(hysteresis=0.0)), distances, focal)
    # Three thresholds crossed out and back: exactly six switches with hysteresis ...
    assert _changes(steady) == 6
    assert steady[0] == 0 and max(steady) == 3 and steady[-1] == 0
    # ... and the control without it flickers at the thresholds.
    assert _changes(jumpy) > 6


def test_hysteresis_delays_both_switches_by_the_dead_band() -> None:
    selector = _core.LodSelector(_core.LodSelectorOptions(hysteresis=0.2))
    assert selector.level == -1
    assert selector.select_by_coverage(COVERAGES, 0.3) == 1
    # Below c_0 = 0.5 but not above 0.5 * 1.2: stays at 1; above it: level 0.
    assert selector.select_by_coverage(COVERAGES, 0.59) == 1
    assert selector.select_by_coverage(COVERAGES, 0.61) == 0
    # Back down: level 0 holds until the coverage drops under 0.5 / 1.2.
    assert selector.select_by_coverage(COVERAGES, 0.45) == 0
    assert selector.select_by_coverage(COVERAGES, 0.41) == 1
    selector.reset()
    assert selector.level == -1


def test_free_functions_match_the_thresholds() -> None:
    assert _core.level_for_coverage(COVERAGES, 0.5) == 0
    assert _core.level_for_coverage(COVERAGES, 0.49) == 1
    assert _core.level_for_coverage(COVERAGES, 0.0) == 3
    assert _core.level_for_error(ERRORS, 39.0, 1000.0) == 1
    assert _core.level_for_error(ERRORS, 41.0, 1000.0) == 2
    assert _core.level_for_error(ERRORS, 41.0, 1000.0, pixel_error=2.0) == 2
    assert _core.level_for_error(ERRORS, 81.0, 1000.0, pixel_error=2.0) == 3
    assert _core.screen_error_pixels(0.02, 10.0, 500.0) == pytest.approx(1.0)


def test_projected_sphere_and_focal_length() -> None:
    camera = _core.LodCamera([1.0, 2.0, 3.0], vertical_fov=math.radians(60.0), viewport_height=720.0)
    assert camera.position == pytest.approx([1.0, 2.0, 3.0])
    focal = _core.focal_length_pixels(camera)
    assert focal == pytest.approx(360.0 / math.tan(math.radians(30.0)), rel=1e-6)
    sphere = _core.project_sphere(camera, [1.0, 2.0, -7.0], 1.0)
    assert sphere.distance == pytest.approx(10.0)
    assert sphere.coverage == pytest.approx(1.0 / math.sqrt(99.0) / math.tan(math.radians(30.0)), rel=1e-6)
    # Far away the coverage tends to the diameter over the viewport height in pixels / focal.
    far = _core.project_sphere(camera, [1.0, 2.0, -997.0], 1.0)
    assert far.coverage * 720.0 == pytest.approx(2.0 / 1000.0 * focal, rel=1e-4)
    assert math.isinf(_core.project_sphere(camera, [1.0, 2.0, 3.5], 1.0).coverage)


def test_update_interval_falls_with_distance() -> None:
    options = _core.AnimationRateOptions(full_rate_coverage=0.2, max_interval=6)
    coverages = 0.2 * 5.0 / np.linspace(1.0, 200.0, 300)  # the same character walking away
    intervals = [_core.animation_update_interval(float(c), options) for c in coverages]
    assert intervals[0] == 1 and intervals[-1] == 6
    assert all(b >= a for a, b in zip(intervals, intervals[1:]))
    assert _core.animation_update_interval(0.1, options) == 2
    due = [_core.animation_update_due(frame, 5, 3) for frame in range(30)]
    assert sum(due) == 10


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: _core.level_for_coverage([0.2, 0.4, 0.0], 0.1), "level 1"),
        (lambda: _core.level_for_error([0.0, float("nan")], 1.0, 1.0), "level 1"),
        (lambda: _core.level_for_error([], 1.0, 1.0), "no level"),
        (lambda: _core.level_for_error([[0.0, 1.0]], 1.0, 1.0), "expected shape"),
        (lambda: _core.LodSelectorOptions(hysteresis=-0.1), "hysteresis"),
        (lambda: _core.AnimationRateOptions(max_interval=0), "max_interval"),
        (lambda: _core.LodCamera([0.0, 0.0], 1.0, 720.0), "position"),
        (lambda: _core.LodCamera([0.0, 0.0, 0.0], 4.0, 720.0), "vertical_fov"),
        (lambda: _core.project_sphere(_core.LodCamera(), [0.0, 0.0, 1.0], -1.0), "radius"),
    ],
)
def test_bad_input_is_a_value_error_naming_the_element(call, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        call()
