"""A glTF document simplified with a max error: the notes say what stopped each level, and levels
the max error left the same as the one before are not written (no copies in the MSFT_lod chain)."""

from __future__ import annotations

import numpy as np
from simplify_inputs import ellipsoid

from animlod.cli import main
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_drawable import read_drawables
from animlod.pipelines import simplify_document

QUICK = {"frame_budget": 12, "measured_frames": 2}
RATIOS = [0.5, 0.25, 0.1]
# The ellipsoid's (520 faces) levels at RATIOS: 0.01 stops level 1 short of its 260 faces after
# some collapses; 0.03 stops level 3 short of its 52, with fewer faces than level 2.
STOPS_LEVEL_1, STOPS_LEVEL_3 = 0.01, 0.03


def _glb(path, positions: np.ndarray, faces: np.ndarray):
    """One node drawing one static triangle mesh."""
    builder = GlbBuilder()
    primitive = {
        "attributes": {"POSITION": builder.add(positions.astype(np.float32), bounds=True)},
        "indices": builder.add(faces.astype(np.uint32).reshape(-1, 1)),
    }
    builder.append("meshes", {"name": "shape", "primitives": [primitive]})
    builder.json["nodes"] = [{"mesh": 0}]
    builder.json["scenes"], builder.json["scene"] = [{"nodes": [0]}], 0
    builder.save(path)
    return path


def _ellipsoid_glb(tmp_path):
    surface = ellipsoid(frames=1)
    return _glb(tmp_path / "ellipsoid.glb", surface.frames[0], surface.faces)


def _octahedron_glb(tmp_path):
    """8 faces: two collapses make a tetrahedron, and no collapse of a closed mesh goes further."""
    positions = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], np.float32)
    faces = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    return _glb(tmp_path / "octahedron.glb", positions, faces)


def _triangles(doc: GltfDocument, mesh: int) -> int:
    return sum(doc.accessor(p["indices"], "t").shape[0] // 3 for p in doc.json["meshes"][mesh]["primitives"])


def _assert_chain(path, levels) -> None:
    """Node 0 of the LoD GLB ``path`` chains exactly the written ``levels`` (LevelReports, level 0
    first): one node a level, their faces, the report's coverages, non-increasing and ending at 0."""
    doc = GltfDocument(path)
    node = doc.json["nodes"][0]
    ids = node["extensions"]["MSFT_lod"]["ids"]
    coverages = node["extras"]["MSFT_screencoverage"]
    assert len(ids) == len(levels) - 1 and len(doc.json["meshes"]) == len(levels)
    assert coverages == [level.coverage for level in levels] and coverages[-1] == 0.0
    assert all(a >= b for a, b in zip(coverages, coverages[1:]))
    assert [_triangles(doc, doc.json["nodes"][i]["mesh"]) for i in ids] == [level.faces for level in levels[1:]]
    assert len({level.faces for level in levels}) == len(levels)  # no two levels the same


def test_a_level_the_max_error_stops_names_it_and_ends_the_chain(tmp_path):
    """Found on monkey.gltf with --max-error 0.001: every level short of its target was blamed on
    "no legal collapse left", and levels 2 and 3 were copies of level 1 with coverages 1, 1, 1, 0."""
    output = tmp_path / "lod.glb"
    report = simplify_document(_ellipsoid_glb(tmp_path), output, RATIOS, max_error=STOPS_LEVEL_1, **QUICK)
    (drawable,) = report.drawables
    assert [level.level for level in drawable.levels] == [0, 1]
    level = drawable.levels[1]
    assert level.target_faces < level.faces < drawable.faces and not level.reached
    stop, dropped = drawable.notes
    assert stop.startswith(f"level 1: stopped at {level.faces} faces (target {level.target_faces}): max error 0.01 ")
    assert float(stop.rsplit("this level's largest AQEM error: ", 1)[1]) <= STOPS_LEVEL_1
    assert dropped.startswith("levels 2, 3 (targets 130, 52) not written: the same mesh as level 1")
    assert "the max error 0.01 stopped the collapses" in dropped
    assert not any("no legal collapse" in note for note in drawable.notes)
    _assert_chain(output, drawable.levels)


def test_a_level_short_of_its_target_but_coarser_than_the_one_before_is_written(tmp_path):
    output = tmp_path / "lod.glb"
    report = simplify_document(_ellipsoid_glb(tmp_path), output, RATIOS, max_error=STOPS_LEVEL_3, **QUICK)
    (drawable,) = report.drawables
    assert [level.reached for level in drawable.levels] == [True, True, True, False]
    assert drawable.levels[3].faces < drawable.levels[2].faces
    (note,) = drawable.notes
    assert note.startswith(f"level 3: stopped at {drawable.levels[3].faces} faces (target 52): max error 0.03 reached")
    _assert_chain(output, drawable.levels)


def test_a_level_no_collapse_can_reach_is_not_blamed_on_a_generous_max_error(tmp_path):
    """A max error given is no reason by itself: here the topology's minimum stops the levels."""
    for max_error in (np.inf, 1000.0):
        output = tmp_path / "lod.glb"
        report = simplify_document(_octahedron_glb(tmp_path), output, RATIOS, max_error=max_error, **QUICK)
        (drawable,) = report.drawables
        assert [level.faces for level in drawable.levels] == [8, 4]
        assert drawable.notes == [
            "levels 2, 3 (targets 2, 1) not written: the same mesh as level 1 (4 faces), where no legal collapse "
            "was left"
        ]
        _assert_chain(output, drawable.levels)


def test_separate_writes_only_the_levels_that_differ(tmp_path):
    folder = tmp_path / "levels"
    source = _ellipsoid_glb(tmp_path)
    report = simplify_document(source, folder, RATIOS, separate=True, max_error=STOPS_LEVEL_1, **QUICK)
    (drawable,) = report.drawables
    assert [path.name for path in report.outputs] == ["ellipsoid_lod1.glb"]
    assert sorted(path.name for path in folder.iterdir()) == ["ellipsoid_lod1.glb"]
    (written,) = read_drawables(GltfDocument(report.outputs[0]))
    assert len(written.geometry.faces) == drawable.levels[1].faces < drawable.faces


def test_separate_draws_a_shorter_chain_at_its_coarsest_level(tmp_path):
    """The ellipsoid has three levels, the octahedron one: the files of levels 2 and 3 draw it at
    its level 1, and say so."""
    surface = ellipsoid(frames=1)
    octahedron = GltfDocument(_octahedron_glb(tmp_path))
    builder = GlbBuilder.from_document(GltfDocument(_glb(tmp_path / "one.glb", surface.frames[0], surface.faces)))
    source = octahedron.json["meshes"][0]["primitives"][0]
    primitive = {
        "attributes": {
            "POSITION": builder.add(octahedron.accessor(source["attributes"]["POSITION"], "t"), bounds=True)
        },
        "indices": builder.add(octahedron.accessor(source["indices"], "t").astype(np.uint32).reshape(-1, 1)),
    }
    builder.append("meshes", {"name": "octahedron", "primitives": [primitive]})
    builder.json["nodes"].append({"mesh": 1, "translation": [4.0, 0.0, 0.0]})
    builder.json["scenes"][0]["nodes"] = [0, 1]
    builder.save(tmp_path / "two.glb")
    report = simplify_document(tmp_path / "two.glb", tmp_path / "levels", RATIOS, separate=True, **QUICK)
    assert [path.name for path in report.outputs] == ["two_lod1.glb", "two_lod2.glb", "two_lod3.glb"]
    round_shape, pointed = report.drawables
    assert len(round_shape.levels) == 4 and [level.faces for level in pointed.levels] == [8, 4]
    assert pointed.notes[-1] == "two_lod2.glb, two_lod3.glb draw level 1"
    for path, level in zip(report.outputs, round_shape.levels[1:]):
        doc = GltfDocument(path)
        assert [_triangles(doc, node["mesh"]) for node in doc.json["nodes"]] == [level.faces, 4]


def test_no_level_is_written_where_the_max_error_allows_no_collapse(tmp_path):
    source = _ellipsoid_glb(tmp_path)
    output = tmp_path / "lod.glb"
    report = simplify_document(source, output, RATIOS, max_error=0.0, **QUICK)
    (drawable,) = report.drawables
    assert [level.faces for level in drawable.levels] == [520] and drawable.levels[0].coverage == 0.0
    assert drawable.notes == [
        "levels 1, 2, 3 (targets 260, 130, 52) not written: the same mesh as the input (520 faces), where the max "
        "error 0 stopped the collapses"
    ]
    doc = GltfDocument(output)
    assert "extensions" not in doc.json["nodes"][0] and len(doc.json["meshes"]) == 1  # no chain of copies
    folder = tmp_path / "levels"
    report = simplify_document(source, folder, RATIOS, separate=True, max_error=0.0, **QUICK)
    assert report.outputs == [] and not folder.exists()
    assert report.notes == ["no file written: no drawable has a level coarser than its input (see its notes)"]


def test_cli_says_the_max_error_stopped_the_level(tmp_path, capsys):
    source = _ellipsoid_glb(tmp_path)
    output = tmp_path / "lod.glb"
    assert main(["simplify", str(source), "-o", str(output), "--max-error", "0.01", "--max-frames", "8"]) == 0
    out = capsys.readouterr().out
    assert "note: level 1: stopped at" in out and "max error 0.01 reached" in out
    assert "note: levels 2, 3 (targets 130, 52) not written" in out and "no legal collapse" not in out
