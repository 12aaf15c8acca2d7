"""Levels a runtime (all but) never shows are named in the notes of `simplify` and `character`: a
Blender export's level 2 measured 0.0137945 and its level 3 0.0137945 of the same units, so their
screen coverages, each set by the next level's error and never increasing, met, and level 2 was
written for a range of coverage 3e-6 wide (found by a hunt over Blender exports)."""

from __future__ import annotations

from animlod.io.gltf_lod import hidden_level_notes, screen_coverages


def test_a_level_the_next_one_matches_is_named_as_never_shown():
    errors = [0.0, 0.00244, 0.0137945, 0.01379454]
    coverages = screen_coverages(errors, 2.0)
    (note,) = hidden_level_notes(errors, coverages)
    assert note.startswith("level 2 is (all but) never shown: level 3 measured about the same error or less")
    assert note.endswith(f"so a runtime goes from level 1 to level 3 at screen coverage {coverages[2]:.3g}")


def test_levels_that_each_lose_detail_are_all_shown():
    errors = [0.0, 0.001, 0.002, 0.004]
    assert hidden_level_notes(errors, screen_coverages(errors, 2.0)) == []


def test_a_coarser_level_measured_better_hides_the_one_before_it():
    # The coverages never increase: level 2 ends where level 1 does, whatever its own error.
    errors = [0.0, 0.001, 0.003, 0.002]
    (note,) = hidden_level_notes(errors, screen_coverages(errors, 2.0))
    assert note.startswith("level 2 is (all but) never shown: level 3 measured about the same error or less (0.002")
