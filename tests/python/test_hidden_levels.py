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


def test_levels_within_the_pixel_error_at_full_screen_are_named_so():
    # A Blender prop's levels 1 and 2 measured 3.4e-8 and 8.3e-4 of its size: both coverages are
    # clamped at 1, and the note said level 3 "measured about the same error or less".
    errors = [0.0, 3.36e-08, 0.000826, 0.01]
    coverages = screen_coverages(errors, 1.0)
    notes = hidden_level_notes(errors, coverages)
    assert notes == [
        "level 1 is (all but) never shown: level 2's error (0.000826) is within the pixel error even at full "
        "screen, so a runtime goes from level 0 to level 2 at screen coverage 1"
    ]


def test_the_notes_of_simplify_show_the_errors_of_its_table(humanoid_glb, tmp_path):
    # The notes gave errors in asset units beside a table of errors relative to the diagonal. A
    # pixel error the size of the viewport puts every level within it at full screen.
    from animlod.pipelines import simplify_document

    report = simplify_document(humanoid_glb, tmp_path / "lod.glb", [0.5, 0.25, 0.1], pixel_error=1e6,
                               frame_budget=12, measured_frames=2)  # fmt: skip
    (drawable,) = report.drawables
    notes = [note for note in drawable.notes if "never shown" in note]
    assert [note.split(":")[0] for note in notes] == [
        "level 1 is (all but) never shown",
        "level 2 is (all but) never shown",
    ]
    assert f"level 2's error ({drawable.levels[2].relative_error:.3g})" in notes[0]
    assert f"({drawable.levels[2].error:.3g})" not in notes[0]  # the asset units' figure differs


def test_the_notes_of_character_show_the_errors_of_its_table(data_dir, tmp_path):
    # SimpleSkin's levels 1 and 2 (4 and 2 triangles) measure 0.327 of its diagonal: the note said 0.73.
    from animlod.pipelines.character import build_character

    report = build_character(data_dir / "gltf" / "SimpleSkin.gltf", tmp_path / "lod.glb", solver="newton")
    ((label, chain),) = report.chains.items()
    (note,) = [note for note in report.notes if "never shown" in note]
    assert note.startswith(f"{label}: level 1 is (all but) never shown: level 2 measured about the same error")
    assert f"({chain[2].relative_error:.3g} against {chain[1].relative_error:.3g})" in note
