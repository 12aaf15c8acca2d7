"""Face LoD levels of the procedural face: geometry with region importance, animation floors,
lattice reduction, Table 1 measurement, and the runtime selection from the view."""

from __future__ import annotations

import numpy as np
import pytest

from animlod.face_lod import FaceLodOptions, build_face_lod, expression_sequence, procedural_face
from animlod.face_lod.measure import animation_errors, every_nth, measure_level
from animlod.face_lod.selection import (
    Camera,
    coverage_thresholds,
    frame_step,
    level_for_coverage,
    projected_coverage,
    select_face_levels,
    skipped_frames,
)


@pytest.fixture(scope="module")
def face():
    return procedural_face()


@pytest.fixture(scope="module")
def animation(face):
    return expression_sequence(face.expressions, face.rig.mpa_names, seconds_each=0.5, fps=20)


@pytest.fixture(scope="module")
def chain(face, animation):
    return build_face_lod(face.rig, face.tree, animation)


def test_levels_follow_the_papers_sizes(chain):
    counts = [level.triangle_count for level in chain.geometry]
    assert counts[0] == 2304
    assert counts[1] <= round(2304 * 1533 / 2313) and counts[2] <= round(2304 * 357 / 2313)
    assert counts[1] > counts[2]
    floors = [level.animation_floor for level in chain.geometry]
    assert floors == [0, 1, chain.tree.level_count - 1]
    errors = [level.geometric_error for level in chain.geometry]
    assert errors[0] == 0.0 < errors[1] < errors[2]


def test_region_labels_stay_consistent_after_simplification(chain):
    full = chain.rig.regions
    for level in chain.geometry[1:]:
        np.testing.assert_array_equal(level.regions.vertex_regions, full.vertex_regions[level.kept_vertices])
        assert len(level.regions.vertex_regions) == level.vertex_count
        corners = level.regions.vertex_regions[level.faces]
        assert np.all(np.any(corners == level.face_regions[:, None], axis=1))  # a face's region is a corner's
        # Every region animated at the level's floor still has vertices to move.
        for name in chain.tree.active(level.animation_floor):
            assert np.any(level.regions.vertex_regions == full.index(name)), name


def test_region_importance_sends_ears_eyes_and_teeth_first(face, animation, chain):
    plain = build_face_lod(face.rig, face.tree, animation, FaceLodOptions(region_importance=False))
    low = ["ear_left", "ear_right", "eyeball_left", "eyeball_right", "teeth_upper", "teeth_lower"]
    full = face.rig.regions

    def kept_share(level) -> float:
        return float(np.isin(level.regions.vertex_regions, full.indices(low)).sum()) / level.vertex_count

    # With importance the low-weight regions hold a clearly smaller share of the kept vertices than
    # without (they are closed parts, eyeballs and teeth, which edge collapses cannot remove).
    assert kept_share(chain.geometry[2]) < 0.75 * kept_share(plain.geometry[2])
    assert kept_share(chain.geometry[1]) < kept_share(plain.geometry[1])


def test_coarse_levels_use_fitted_2x2x2_lattices_where_geometry_lost_as_much(chain):
    level1 = chain.geometry[1]
    assert chain.geometry[0].reduced == frozenset()
    assert level1.reduced, "some regions are reduced at level 1"
    for region, error in chain.reduction_error.items():
        assert (region in level1.reduced) == (error <= level1.geometric_error), region
    animator = chain.animator(1)
    sizes = {name: tuple(size) for name, size in zip(animator.regions, animator.sizes)}
    for name in animator.regions:
        assert sizes[name] == ((2, 2, 2) if name in level1.reduced else (3, 3, 3))
    # The eyes only rotate: a rotation is linear, so a 2x2x2 lattice reproduces it exactly.
    assert chain.reduction_error["eyeball_left"] < 1e-6


def test_the_coarsest_level_animates_nothing_and_finer_floors_hold(chain, animation):
    coarsest = chain.animator(len(chain.geometry) - 1)
    assert not coarsest.animates
    assert coarsest.frame(animation.intensities[5]) is coarsest.rest
    assert chain.animation_level(1, 0) == 1  # Figure 6: geometry level 1 cannot animate like level 0
    assert chain.animation_level(1, 2) == 2


def test_table_one_measurement(chain, animation):
    sampled = every_nth(animation, 6)
    rows = [measure_level(chain, g, chain.geometry[g].animation_floor, sampled, repeats=1, samples=2000)
            for g in range(3)]  # fmt: skip
    assert rows[0].hausdorff < 1e-9  # the full face against itself
    assert 0.0 < rows[1].hausdorff < rows[2].hausdorff < 0.2
    assert rows[0].lattices == f"{rows[0].animated_regions}x27"
    assert "x8" in rows[1].lattices and rows[2].lattices == "-"
    assert rows[2].animated_regions == 0 and rows[2].active_mpas == 0
    errors = animation_errors(chain, sampled)
    assert errors[0] == 0.0 and errors == sorted(errors) and errors[-1] > 0.0


def test_measured_frames_hold_every_mpas_peak(chain, animation):
    """The expression sequence rises from rest and falls back: its first and last frames, the
    two evenly spaced ones, are both at rest, and measured alone the active tree lost nothing."""
    sampled = every_nth(animation, 2)
    peaks = np.abs(animation.intensities).max(axis=0)
    np.testing.assert_array_equal(np.abs(sampled.intensities).max(axis=0), peaks)
    assert sampled.frame_count < animation.frame_count
    assert animation_errors(chain, sampled) == animation_errors(chain, animation)


def test_projected_coverage_and_thresholds():
    camera = Camera()
    near, far = projected_coverage(0.12, 0.5, camera), projected_coverage(0.12, 5.0, camera)
    assert near > far > 0.0
    assert far == pytest.approx(0.12 / 5.0 / np.tan(np.radians(30.0)), rel=1e-3)
    thresholds = coverage_thresholds([0.0, 0.001, 0.01], 0.12, camera, 1.0)
    assert thresholds[-1] == 0.0 and thresholds[0] > thresholds[1] > 0.0
    # At the threshold, the next level's error projects to exactly the tolerance (1 pixel).
    assert 0.001 * thresholds[0] * camera.viewport_height_px / (2 * 0.12) == pytest.approx(1.0)
    assert [level_for_coverage(thresholds, c) for c in (10.0, thresholds[0], 0.5 * thresholds[0], 0.0)] == [0, 0, 1, 2]
    assert coverage_thresholds([0.0, 0.01, 0.005], 0.12, camera, 1.0)[1] == coverage_thresholds(
        [0.0, 0.01, 0.01], 0.12, camera, 1.0)[1]  # fmt: skip
    # MSFT_lod's range: a level without error, or within rounding of the face, takes over at 1 (it
    # gave an infinity, which JSON cannot hold, or 4e10).
    assert coverage_thresholds([0.0, 0.0, 1e-12, 0.01], 0.12, camera, 1.0)[:2] == [1.0, 1.0]


def test_frame_skipping_grows_with_distance_and_keeps_the_duration():
    steps = [frame_step(projected_coverage(0.12, d, Camera()), 0.25, 4) for d in (0.3, 1.0, 2.0, 4.0, 40.0)]
    assert steps == sorted(steps) and steps[0] == 1 and steps[-1] == 4
    shown = skipped_frames(10, 3)
    np.testing.assert_array_equal(shown, [0, 0, 0, 3, 3, 3, 6, 6, 6, 9])
    assert len(shown) == 10  # same duration: a skipped frame repeats the last pose
    with pytest.raises(ValueError, match="at least 1"):
        skipped_frames(10, 0)


def test_selection_lowers_the_animation_level_to_the_geometry(chain):
    floors = [level.animation_floor for level in chain.geometry]
    geometry_thresholds = [0.5, 0.1, 0.0]
    animation_thresholds = [0.2, 0.01, 0.005, 0.0]  # animation alone would stay detailed longer
    near = select_face_levels(1.0, geometry_thresholds, animation_thresholds, floors)
    assert (near.geometry_level, near.animation_level, near.frame_step) == (0, 0, 1)
    middle = select_face_levels(0.3, geometry_thresholds, animation_thresholds, floors)
    assert (middle.geometry_level, middle.animation_level) == (1, 1)  # level 0 wanted, lowered by geometry 1
    far = select_face_levels(0.05, geometry_thresholds, animation_thresholds, floors)
    assert far.geometry_level == 2 and far.animation_level == floors[2]  # level 1 wanted, lowered by geometry 2
    assert far.frame_step > middle.frame_step >= near.frame_step
    with pytest.raises(ValueError, match="coverage: must be a number >= 0, got nan"):
        select_face_levels(float("nan"), geometry_thresholds, animation_thresholds, floors)
    with pytest.raises(ValueError, match=r"animation floors: 7 outside \[0, 4\)"):
        select_face_levels(0.3, geometry_thresholds, animation_thresholds, [0, 1, 7])
