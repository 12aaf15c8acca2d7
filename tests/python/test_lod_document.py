"""Whole glTF documents through animlod.pipelines.simplify_document: nothing lost, levels valid."""

from __future__ import annotations

import copy
import json
import os
import subprocess

import numpy as np
import pygltflib
import pytest
from gltf_conformance import added_problems, problems
from gltf_edits import append_accessor, draco_compressed, edit_glb, meshopt_compressed
from simplify_inputs import ellipsoid

from animlod import synth
from animlod.cli import main
from animlod.io import read_gltf, write_glb
from animlod.io.errors import FormatError
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_drawable import read_drawables
from animlod.pipelines import DrawableSettings, drawable_levels, simplify_document

# Small enough to keep the suite quick: few drive frames, two measured frames per clip.
QUICK = {"frame_budget": 12, "measured_frames": 2}
DEV_FILES = ["gltf/RiggedFigure.glb", "gltf/SimpleSkin.gltf", "morph/MorphStressTest.gltf", "morph/Stork.glb"]


def _accessor_values(doc: GltfDocument, index: int) -> np.ndarray:
    return np.asarray(doc.accessor(index, "test"))


def _image_bytes(doc: GltfDocument, image: dict) -> bytes:
    if "bufferView" in image:
        view = doc.json["bufferViews"][image["bufferView"]]
        data = doc.buffer_bytes(view.get("buffer", 0), "test")
        start = view.get("byteOffset", 0)
        return data[start : start + view["byteLength"]]
    from animlod.io.glb_builder import _image_bytes as read
    from animlod.io.gltf_document import image_file

    return read(doc, 0, image["uri"], image_file(doc.path, image["uri"]))[0]


def _without_chain(node: dict) -> dict:
    """``node`` without what a LoD chain adds to its base node."""
    node = dict(node)
    extensions = {k: v for k, v in node.pop("extensions", {}).items() if k != "MSFT_lod"}
    extras = node.pop("extras", {})
    if isinstance(extras, dict):
        extras = {k: v for k, v in extras.items() if k not in ("MSFT_screencoverage", "animlod")}
    if extensions:
        node["extensions"] = extensions
    if extras:
        node["extras"] = extras
    return node


def _without_weights(meshes: list[dict]) -> list[dict]:
    """``meshes`` without their primitives' WEIGHTS_n (which a LoD GLB may rewrite)."""
    meshes = copy.deepcopy(meshes)
    for primitive in (p for mesh in meshes for p in mesh.get("primitives", [])):
        primitive["attributes"] = {
            k: v for k, v in primitive.get("attributes", {}).items() if not k.startswith("WEIGHTS_")
        }
    return meshes


def _assert_weights_kept_or_normalised(before: GltfDocument, after: GltfDocument) -> None:
    """Each vertex's stored skin weights as they were, or scaled to sum 1 (all-zero rows: weight 1
    on the first joint): the one change to level 0 (animlod.io.stored_weights)."""
    for mesh_index, mesh in enumerate(before.json.get("meshes", [])):
        for index, primitive in enumerate(mesh.get("primitives", [])):
            names = [k for k in primitive.get("attributes", {}) if k.startswith("WEIGHTS_")]
            if not names:
                continue
            written = after.json["meshes"][mesh_index]["primitives"][index]["attributes"]
            stored = np.hstack([before.accessor(primitive["attributes"][k], "t") for k in names]).astype(np.float64)
            kept = np.hstack([after.accessor(written[k], "t") for k in names]).astype(np.float64)
            changed = np.any(kept != stored, axis=1)
            totals = stored[changed].sum(axis=1, keepdims=True)
            first_joint = np.eye(stored.shape[1])[np.zeros(int(changed.sum()), int)]
            expected = np.where(totals > 0.0, stored[changed] / np.where(totals > 0.0, totals, 1.0), first_joint)
            np.testing.assert_allclose(kept[changed], expected, rtol=1e-6, atol=1e-7)


def _assert_document_kept(source, output) -> None:
    """Every object of ``source`` is in ``output`` at the same index with the same content, but
    for level 0's skin weights made to sum to 1 where they did not (over the stored data, or in
    new accessors)."""
    before, after = GltfDocument(source), GltfDocument(output)
    for kind in ("materials", "textures", "samplers", "skins", "scenes", "cameras"):
        assert after.json.get(kind, [])[: len(before.json.get(kind, []))] == before.json.get(kind, []), kind
    meshes = before.json.get("meshes", [])
    assert _without_weights(after.json.get("meshes", [])[: len(meshes)]) == _without_weights(meshes)
    _assert_weights_kept_or_normalised(before, after)
    nodes = len(before.json.get("nodes", []))
    for index, animation in enumerate(before.json.get("animations", [])):
        # The input's channels first, then its morph-weight channels again for the new level nodes.
        kept, count = after.json["animations"][index], len(animation["channels"])
        assert {**kept, "channels": kept["channels"][:count]} == animation
        assert all(c["target"]["path"] == "weights" and c["target"]["node"] >= nodes for c in kept["channels"][count:])
    for index, node in enumerate(before.json.get("nodes", [])):
        assert _without_chain(after.json["nodes"][index]) == _without_chain(node), f"node {index}"
    primitives = [p for mesh in meshes for p in mesh.get("primitives", [])]
    weights = {i for p in primitives for name, i in p.get("attributes", {}).items() if name.startswith("WEIGHTS_")}
    for index in set(range(len(before.json.get("accessors", [])))) - weights:  # weights: checked above
        np.testing.assert_array_equal(_accessor_values(after, index), _accessor_values(before, index))
    for index, image in enumerate(before.json.get("images", [])):
        assert _image_bytes(after, after.json["images"][index]) == _image_bytes(before, image), f"image {index}"
    assert set(before.json.get("extensionsUsed", [])) <= set(after.json.get("extensionsUsed", []))


def test_a_no_op_simplification_keeps_the_whole_document(humanoid_glb, tmp_path):
    output = tmp_path / "out.glb"
    report = simplify_document(humanoid_glb, output, [1.0], **QUICK)
    assert report.drawables[0].levels[1].faces == report.drawables[0].faces
    _assert_document_kept(humanoid_glb, output)


@pytest.mark.parametrize("name", DEV_FILES + ["gltf/Soldier.glb"])
def test_dev_files_keep_every_object_and_get_a_valid_chain(data_dir, tmp_path, name):
    source = data_dir / name
    output = tmp_path / "out.glb"
    report = simplify_document(source, output, [0.5, 0.1], **QUICK)
    _assert_document_kept(source, output)
    assert added_problems(source, output) == []
    doc = GltfDocument(output)
    drawables = read_drawables(GltfDocument(source))
    for drawable, drawn in zip(drawables, report.drawables):
        for base in drawable.nodes:
            node = doc.json["nodes"][base]
            ids = node["extensions"]["MSFT_lod"]["ids"]
            coverages = node["extras"]["MSFT_screencoverage"]
            assert len(coverages) == len(ids) + 1 and coverages[-1] == 0.0
            assert all(a >= b for a, b in zip(coverages, coverages[1:]))
            for level, node_index in enumerate(ids, start=1):
                lod = doc.json["nodes"][node_index]
                assert lod.get("skin") == drawable.skin_index
                assert lod["extras"]["animlod"]["level"] == level
                mesh = doc.json["meshes"][lod["mesh"]]
                triangles = sum(doc.accessor(p["indices"], "t").shape[0] // 3 for p in mesh["primitives"])
                assert triangles == drawn.levels[level].faces
                materials = [p.get("material") for p in mesh["primitives"]]
                assert set(materials) <= {
                    p.get("material") for p in doc.json["meshes"][drawable.mesh_index]["primitives"]
                }
        # levels that stop early say so; errors grow with the level
        errors = [level.error for level in drawn.levels]
        assert errors[0] == 0.0 and all(e >= 0 for e in errors)
    # the LoD nodes are in no scene, so a viewer that ignores MSFT_lod shows level 0 only
    in_scenes = {n for scene in doc.json.get("scenes", []) for n in scene.get("nodes", [])}
    lod_nodes = {i for node in doc.json["nodes"] for i in node.get("extensions", {}).get("MSFT_lod", {}).get("ids", [])}
    assert not (in_scenes & lod_nodes)


def test_progress_tells_each_drawables_collapses_and_measurement(humanoid_glb, tmp_path):
    """A 1.9M-triangle skinned mesh was silent for 214 s after its one line: the collapses and
    the measurement (most of the time) now say when they start."""
    lines = []
    simplify_document(humanoid_glb, tmp_path / "out.glb", [0.5, 0.25], progress=lines.append, **QUICK)
    label = "mesh 0 'skinned mesh' with skin 0"
    assert lines == [f"{label}: 3664 triangles, 1 clips", f"{label}: collapsing over 12 frames",
                     f"{label}: measuring 2 levels"]  # fmt: skip


def test_the_lod_glb_loads_in_tinygltf_and_trimesh(humanoid_glb, tmp_path):
    output = tmp_path / "out.glb"
    simplify_document(humanoid_glb, output, [0.5, 0.25], **QUICK)
    import trimesh

    scene = trimesh.load(output, force="scene")
    assert len(scene.geometry) >= 1
    probe = os.environ.get("ANIMLOD_GLTF_PROBE")
    if probe:
        summary = json.loads(subprocess.run([probe, str(output)], capture_output=True, check=True, text=True).stdout)
        assert summary["triangles"] > 0 and summary["joints"] == 41


def test_levels_reach_ten_percent_and_keep_primitives_and_skins(data_dir, tmp_path):
    report = simplify_document(data_dir / "gltf" / "RiggedFigure.glb", tmp_path / "out.glb", [0.1], **QUICK)
    level = report.drawables[0].levels[1]
    assert level.reached and level.faces <= level.target_faces
    doc = GltfDocument(tmp_path / "out.glb")
    lod = doc.json["nodes"][doc.json["nodes"][report.drawables[0].nodes[0]]["extensions"]["MSFT_lod"]["ids"][0]]
    primitive = doc.json["meshes"][lod["mesh"]]["primitives"][0]
    weights = doc.accessor(primitive["attributes"]["WEIGHTS_0"], "w")
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, atol=1e-5)
    normals = doc.accessor(primitive["attributes"]["NORMAL"], "n")
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)


def test_morph_deltas_of_a_level_match_the_input_at_unmoved_vertices(data_dir, tmp_path):
    source = data_dir / "morph" / "MorphStressTest.gltf"
    simplify_document(source, tmp_path / "out.glb", [0.5], **QUICK)
    before, after = GltfDocument(source), GltfDocument(tmp_path / "out.glb")
    base = before.json["nodes"].index(next(n for n in before.json["nodes"] if "mesh" in n))
    lod = after.json["nodes"][after.json["nodes"][base]["extensions"]["MSFT_lod"]["ids"][0]]
    for original, level in zip(before.json["meshes"][0]["primitives"], after.json["meshes"][lod["mesh"]]["primitives"]):
        positions = before.accessor(original["attributes"]["POSITION"], "p")
        level_positions = after.accessor(level["attributes"]["POSITION"], "p")
        # level vertices that sit exactly on an input vertex (not moved by any collapse)
        index = {tuple(p): i for i, p in enumerate(positions)}
        pairs = [(j, index[tuple(p)]) for j, p in enumerate(level_positions) if tuple(p) in index]
        assert len(pairs) > 10
        ours, theirs = np.array([j for j, _ in pairs]), np.array([i for _, i in pairs])
        for t_before, t_after in zip(original["targets"], level["targets"]):
            np.testing.assert_allclose(
                after.accessor(t_after["POSITION"], "d")[ours],
                before.accessor(t_before["POSITION"], "d")[theirs],
                atol=1e-6,
            )


def test_settings_take_their_fields_and_aqem_options_by_name(humanoid_glb, tmp_path):
    settings = DrawableSettings.resolve(None, {"frame_budget": 6, "max_error": 0.1})
    assert settings.frame_budget == 6 and settings.aqem == {"max_error": 0.1}
    changed = DrawableSettings.resolve(settings, {"placement": "on_edge", "measured_frames": 2})
    assert changed.aqem == {"max_error": 0.1, "placement": "on_edge"} and changed.frame_budget == 6
    assert changed.measured_frames == 2 and settings.measured_frames == DrawableSettings().measured_frames
    output = tmp_path / "out.glb"
    with pytest.raises(ValueError, match=r"^AqemOptions: unknown option 'frame_budjet'"):
        simplify_document(humanoid_glb, output, [0.5], frame_budjet=6)
    assert not output.exists()


@pytest.mark.parametrize(
    "option, value",
    [("viewport_px", 0), ("pixel_error", -1.0), ("fps", 0.0), ("fps", float("nan")), ("frame_budget", 0),
     ("measured_frames", 2.5)],
)  # fmt: skip
def test_a_setting_it_cannot_hold_is_refused_before_any_work(humanoid_glb, tmp_path, option, value):
    """A zero viewport divided the coverages by zero, a negative pixel error wrote negative
    MSFT_screencoverage values, and a zero fps was blamed on the file's rotation keys."""
    output = tmp_path / "out.glb"
    with pytest.raises(ValueError, match=rf"^{option}: must be"):
        simplify_document(humanoid_glb, output, [0.5], **{option: value})
    assert not output.exists()


def _ellipsoid_glb(path, placeholder: str | None = None):
    """An ellipsoid, and with ``placeholder`` two triangles on four vertices at its centre: a
    second "primitive" of the ellipsoid's mesh, a "mesh" of their own on a second node, or
    "alone", in place of the ellipsoid."""
    surface = ellipsoid(frames=1)
    builder = GlbBuilder()

    def primitive(positions, faces):
        return {
            "attributes": {"POSITION": builder.add(positions.astype(np.float32), bounds=True)},
            "indices": builder.add(faces.astype(np.uint32).reshape(-1, 1)),
        }

    primitives = [primitive(surface.frames[0], surface.faces)]
    collapsed = primitive(np.zeros((4, 3)), np.array([0, 1, 2, 0, 2, 3]))
    builder.json["nodes"] = [{"mesh": 0}]
    if placeholder in ("primitive", "alone"):
        primitives = primitives[1:] if placeholder == "alone" else primitives
        primitives.append(collapsed)
    builder.append("meshes", {"primitives": primitives})
    if placeholder == "mesh":
        builder.append("meshes", {"name": "placeholder", "primitives": [collapsed]})
        builder.json["nodes"].append({"mesh": 1})
    builder.json["scenes"], builder.json["scene"] = [{"nodes": list(range(len(builder.json["nodes"])))}], 0
    builder.save(path)
    return path


def test_triangles_that_draw_nothing_are_neither_measured_nor_refused(tmp_path):
    """Two triangles collapsed to the origin: as a second primitive, AQEM dropped them but the
    error still measured their corners, so every level's error was the surface's distance from
    its centre and every coverage the same; as a mesh of their own, the whole document was refused."""
    plain = simplify_document(_ellipsoid_glb(tmp_path / "plain.glb"), tmp_path / "plain_lod.glb", [0.5, 0.25], **QUICK)
    source = _ellipsoid_glb(tmp_path / "primitive.glb", "primitive")
    report = simplify_document(source, tmp_path / "primitive_lod.glb", [0.5, 0.25], **QUICK)
    expected = [level.error for level in plain.drawables[0].levels]
    np.testing.assert_allclose([level.error for level in report.drawables[0].levels], expected, rtol=1e-6)
    source = _ellipsoid_glb(tmp_path / "mesh.glb", "mesh")
    report = simplify_document(source, tmp_path / "mesh_lod.glb", [0.5, 0.25], **QUICK)
    assert [drawable.label for drawable in report.drawables] == ["mesh 0"]
    assert any("mesh 1 'placeholder'" in note and "without levels" in note for note in report.notes)
    written = GltfDocument(tmp_path / "mesh_lod.glb").json
    assert "extensions" not in written["nodes"][1] and written["meshes"][1]["name"] == "placeholder"
    source = _ellipsoid_glb(tmp_path / "alone.glb", "alone")
    with pytest.raises(FormatError, match=r"alone.glb: meshes: no mesh has a triangle with three distinct corners"):
        simplify_document(source, tmp_path / "alone_lod.glb", [0.5], **QUICK)
    assert not (tmp_path / "alone_lod.glb").exists()


def test_a_face_draws_when_any_measured_frame_gives_it_three_distinct_corners():
    """The frame-by-frame check (only faces no earlier frame draws are looked at again) against
    the definition over every frame at once: faces collapsed in the first frame and opened in a
    later one, collapsed in every frame, and with a repeated corner index."""
    rng = np.random.default_rng(3)
    frames = rng.integers(0, 3, size=(4, 12, 3)).astype(np.float64)  # few values: many corners coincide
    faces = np.vstack([rng.integers(0, 12, size=(200, 3)), [[5, 5, 6]]])
    corners = frames[:, faces]
    coincide = [np.all(corners[:, :, a] == corners[:, :, b], axis=-1) for a, b in ((0, 1), (1, 2), (2, 0))]
    expected = ~np.all(np.logical_or.reduce(coincide), axis=0)
    assert 0 < expected.sum() < len(faces) and not expected[-1]
    assert (expected & np.logical_or.reduce(coincide)[0]).any()  # some open only in a later frame
    np.testing.assert_array_equal(drawable_levels._drawn(faces, frames), expected)
    assert not drawable_levels._drawn(faces[:0], frames).size


def test_a_mesh_of_one_triangle_gets_no_levels_that_copy_it(tmp_path):
    # Its targets round to the one triangle it has: each level "reached" its target with no
    # collapse, and the chain listed two copies of the input mesh with coverages of their own.
    builder = GlbBuilder()
    corners = builder.add(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32), bounds=True)
    builder.json["meshes"] = [{"primitives": [{"attributes": {"POSITION": corners}}]}]
    builder.json["nodes"], builder.json["scenes"], builder.json["scene"] = [{"mesh": 0}], [{"nodes": [0]}], 0
    builder.save(tmp_path / "triangle.glb")
    report = simplify_document(tmp_path / "triangle.glb", tmp_path / "lod.glb", [0.5, 0.25], **QUICK)
    (drawable,) = report.drawables
    assert [level.faces for level in drawable.levels] == [1]
    assert drawable.notes == [
        "levels 1, 2 (targets 1, 1) not written: the same mesh as the input (1 faces), where the targets need no "
        "collapse"
    ]
    assert "extensions" not in GltfDocument(tmp_path / "lod.glb").json["nodes"][0]


def test_separate_writes_one_whole_document_per_level(humanoid_glb, tmp_path):
    report = simplify_document(humanoid_glb, tmp_path / "levels", [0.5, 0.25], separate=True, **QUICK)
    assert [path.name for path in report.outputs] == ["humanoid_lod1.glb", "humanoid_lod2.glb"]
    for path, level in zip(report.outputs, report.drawables[0].levels[1:]):
        doc = GltfDocument(path)
        assert len(doc.json["meshes"]) == 1
        (drawable,) = read_drawables(doc)
        assert len(drawable.geometry.faces) == level.faces
        assert len(drawable.clips) == 1
        assert path.stat().st_size < humanoid_glb.stat().st_size


def test_separate_keeps_the_meshes_an_animation_points_at(humanoid_glb, tmp_path):
    # A KHR_animation_pointer channel names the input mesh by index: dropping that mesh, now
    # drawn by no node, would renumber the meshes under the pointer.
    def point_at_mesh_0(js):
        pointer = {"KHR_animation_pointer": {"pointer": "/meshes/0/weights"}}
        js["animations"][0]["channels"].append({"sampler": 0, "target": {"path": "pointer", "extensions": pointer}})
        js.setdefault("extensionsUsed", []).append("KHR_animation_pointer")

    source = _edited(humanoid_glb, tmp_path, point_at_mesh_0)
    report = simplify_document(source, tmp_path / "levels", [0.5], separate=True, **QUICK)
    doc = GltfDocument(report.outputs[0])
    assert [mesh.get("name") for mesh in doc.json["meshes"]] == ["skinned mesh", "skinned mesh_LOD1"]


def test_separate_keeps_the_meshes_an_unknown_extension_may_name(humanoid_glb, tmp_path):
    # VRM 0.x avatars name meshes by index in their root extension (blend shape binds): dropping
    # the input mesh, drawn by no node in a level document, would renumber the meshes under it.
    def vrm_blend_shape(js):
        js.setdefault("extensions", {})["VRM"] = {"blendShapeMaster": {"blendShapeGroups": [{"binds": [{"mesh": 0}]}]}}
        js.setdefault("extensionsUsed", []).append("VRM")

    source = _edited(humanoid_glb, tmp_path, vrm_blend_shape)
    report = simplify_document(source, tmp_path / "levels", [0.5], separate=True, **QUICK)
    doc = GltfDocument(report.outputs[0])
    (bind,) = doc.json["extensions"]["VRM"]["blendShapeMaster"]["blendShapeGroups"][0]["binds"]
    assert doc.json["meshes"][bind["mesh"]]["name"] == "skinned mesh"


def test_a_draco_compressed_character_gets_uncompressed_levels_and_keeps_its_own(humanoid_glb, tmp_path):
    from animlod.io import read_lod_chains
    from animlod.pipelines.character import build_character

    compressed = draco_compressed(humanoid_glb, tmp_path / "draco.glb")
    output = tmp_path / "chain.glb"
    report = build_character(compressed, output, [0.5, 0.25], solver="newton", **QUICK)
    (levels,) = report.chains.values()
    assert [level.faces for level in levels] == sorted((level.faces for level in levels), reverse=True)
    doc = GltfDocument(output)
    assert doc.json["extensionsRequired"] == ["KHR_draco_mesh_compression"]  # the input's mesh, as it was
    compressed_meshes = [
        mesh["name"] for mesh in doc.json["meshes"] for p in mesh["primitives"] if "extensions" in p
    ]  # fmt: skip
    assert compressed_meshes == [GltfDocument(compressed).json["meshes"][0]["name"]]
    (chain,) = read_lod_chains(output)
    assert [level.mesh.face_count for level in chain.levels] == [level.faces for level in levels]


def test_separate_levels_of_a_draco_document_do_not_require_draco(humanoid_glb, tmp_path):
    # Each level document draws its level mesh, written uncompressed; the compressed input mesh
    # is dropped, and the extension with it.
    compressed = draco_compressed(humanoid_glb, tmp_path / "draco.glb")
    report = simplify_document(compressed, tmp_path / "levels", [0.5], separate=True, **QUICK)
    doc = GltfDocument(report.outputs[0])
    assert "KHR_draco_mesh_compression" not in json.dumps(doc.json)
    assert len(read_drawables(doc)[0].geometry.faces) == report.drawables[0].levels[1].faces


def test_a_meshopt_compressed_document_comes_out_whole_and_decoded(humanoid_glb, tmp_path):
    compressed = meshopt_compressed(humanoid_glb, tmp_path / "meshopt.glb")
    output = tmp_path / "out.glb"
    report = simplify_document(compressed, output, [0.5], **QUICK)
    plain = simplify_document(humanoid_glb, tmp_path / "plain.glb", [0.5], **QUICK)
    assert [level.faces for level in report.drawables[0].levels] == [level.faces for level in plain.drawables[0].levels]
    doc = GltfDocument(output)
    assert "EXT_meshopt_compression" not in json.dumps(doc.json)  # any glTF reader takes it
    (drawable,) = read_drawables(doc)
    (expected,) = read_drawables(GltfDocument(humanoid_glb))
    np.testing.assert_array_equal(drawable.geometry.positions, expected.geometry.positions)
    probe = os.environ.get("ANIMLOD_GLTF_PROBE")
    if probe:
        summary = json.loads(subprocess.run([probe, str(output)], capture_output=True, check=True, text=True).stdout)
        assert summary["triangles"] > 0 and summary["joints"] == 41


def test_gpu_instanced_meshes_have_their_levels_instanced_too(tmp_path):
    import trimesh

    from animlod.io.glb_builder import GlbBuilder

    plain = tmp_path / "sphere.glb"
    trimesh.creation.icosphere(subdivisions=3).export(plain)
    builder = GlbBuilder.from_document(GltfDocument(plain))
    offsets = builder.add(np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 3.0, 0.0]], np.float32))
    instancing = {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": offsets}}}
    (drawn,) = [node for node in builder.json["nodes"] if "mesh" in node]
    drawn["extensions"] = instancing
    for listed in ("extensionsUsed", "extensionsRequired"):
        builder.json[listed] = ["EXT_mesh_gpu_instancing"]
    source = tmp_path / "instanced.glb"
    builder.save(source)
    report = simplify_document(source, tmp_path / "out.glb", [0.5], **QUICK)
    doc = GltfDocument(tmp_path / "out.glb")
    level_nodes = [node for node in doc.json["nodes"] if node.get("extras", {}).get("animlod", {}).get("level") == 1]
    assert [node.get("extensions") for node in level_nodes] == [instancing]
    assert doc.json["extensionsRequired"] == ["EXT_mesh_gpu_instancing"]
    assert read_drawables(doc)[0].geometry.faces.shape[0] == report.drawables[0].levels[0].faces


def test_cli_writes_one_lod_glb(humanoid_glb, tmp_path, capsys):
    assert main(["simplify", str(humanoid_glb), "-o", str(tmp_path), "--ratio", "0.5", "--max-frames", "8"]) == 0
    out = capsys.readouterr().out
    assert "humanoid_lod.glb" in out and "coverage" in out
    assert (tmp_path / "humanoid_lod.glb").is_file()


def _edited(source, tmp_path, edit) -> str:
    """A copy of the GLB at ``source`` with its JSON changed by ``edit(json)``."""
    from animlod.io.glb_builder import GlbBuilder

    builder = GlbBuilder.from_document(GltfDocument(source))
    edit(builder.json)
    path = tmp_path / "edited.glb"
    builder.save(path)
    return str(path)


def _shrink_skin(js: dict, joints: int) -> None:
    """The first skin keeps only its first ``joints`` joints (and inverse binds): vertices bound
    to later joints now index past the joint list."""
    skin = js["skins"][0]
    skin["joints"] = skin["joints"][:joints]
    js["accessors"][skin["inverseBindMatrices"]]["count"] = joints


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda js: _shrink_skin(js, 3), "uses joint slot"),
        (lambda js: js["bufferViews"][0].__setitem__("byteLength", 10**9), "bufferView 0"),
        (lambda js: js["animations"][0]["channels"][0]["target"].__setitem__("node", 9999), "node 9999"),
    ],
)
def test_bad_documents_exit_with_one_line_and_no_output(humanoid_glb, tmp_path, capsys, edit, message):
    source = _edited(humanoid_glb, tmp_path, edit)
    output = tmp_path / "out.glb"
    assert main(["simplify", source, "-o", str(output)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
    assert not output.exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".out.glb")]


def test_points_and_lines_are_kept_unchanged_and_reported(humanoid_glb, tmp_path):
    def add_lines(js):
        primitive = js["meshes"][0]["primitives"][0]
        js["meshes"][0]["primitives"].append(
            {"attributes": {"POSITION": primitive["attributes"]["POSITION"]}, "mode": 1}
        )

    source = _edited(humanoid_glb, tmp_path, add_lines)
    report = simplify_document(source, tmp_path / "out.glb", [0.5], **QUICK)
    assert any("points or lines" in note for note in report.drawables[0].notes)
    doc = GltfDocument(tmp_path / "out.glb")
    lod = doc.json["nodes"][report.drawables[0].nodes[0]]["extensions"]["MSFT_lod"]["ids"][0]
    modes = [p.get("mode", 4) for p in doc.json["meshes"][doc.json["nodes"][lod]["mesh"]]["primitives"]]
    assert modes == [4, 1]  # the input's order


def test_character_chain_combines_geometry_and_motion_levels(data_dir, tmp_path):
    from animlod.io import read_lod_chains
    from animlod.metrics import surface_error
    from animlod.pipelines.character import build_character

    output = tmp_path / "character.glb"
    report = build_character(data_dir / "gltf" / "RiggedFigure.glb", output, [0.5, 0.1], solver="newton", **QUICK)
    (levels,) = report.chains.values()
    assert [level.faces for level in levels] == sorted((level.faces for level in levels), reverse=True)
    assert levels[-1].joints < levels[0].joints
    (chain,) = read_lod_chains(output)
    assert [level.motion_level for level in chain.levels] == [0, 1, 2]
    reference = chain.levels[0].mesh.bake(chain.levels[0].motions[0])
    for written, level in zip(chain.levels[1:], levels[1:]):
        # the level as any glTF engine plays it: its own skin and its own re-fitted clip
        assert written.skeleton.joint_count == level.joints + int(written.skeleton.end_sites.sum())
        played = written.mesh.bake(written.motions[0])
        measured = surface_error(reference, played, samples=2000).hausdorff.max()
        assert measured == pytest.approx(level.error, rel=0.25)
    grid = GltfDocument(output).json["nodes"][1]["extras"]["animlod_grid"]
    assert len(grid) == 3 and all(len(row) == 3 for row in grid)


def test_character_keeps_the_motion_whole_where_no_joint_can_freeze(data_dir, tmp_path):
    # SimpleSkin's two joints coincide; with the skin on the root alone, neither joint positions
    # nor skin points show joint 1's rotation, so nothing freezes; the geometry levels are still
    # written, each with the input's motion.
    import dataclasses

    from animlod.io import read_lod_chains
    from animlod.pipelines.character import build_character

    scene = read_gltf(data_dir / "gltf" / "SimpleSkin.gltf")
    (skin,) = scene.skinned_meshes
    weights = np.broadcast_to(np.eye(1, skin.joints.shape[1]), skin.weights.shape)
    on_root = dataclasses.replace(skin, joints=np.zeros_like(skin.joints), weights=weights)
    write_glb(tmp_path / "still.glb", on_root, scene.motions)
    output = tmp_path / "character.glb"
    report = build_character(tmp_path / "still.glb", output, [0.5], **QUICK)
    assert any("1 motion level(s) for 2 geometry levels" in note and "every bone of zero length" in note
               for note in report.notes)  # fmt: skip
    (levels,) = report.chains.values()
    assert [level.faces for level in levels] == [8, 4] and levels[0].joints == levels[1].joints == 2
    (chain,) = read_lod_chains(output)
    assert [level.motion_level for level in chain.levels] == [0, 0]


def test_character_freezes_a_skinned_leaf_on_its_parent_and_measures_it_on_the_skin(data_dir, tmp_path):
    # The same joints, SimpleSkin's own skin: joint 1's rotation bends the upper half, which its
    # skin's points show (skin_measure.py), so it can freeze, at the error it costs.
    from animlod.pipelines.character import build_character

    report = build_character(data_dir / "gltf" / "SimpleSkin.gltf", tmp_path / "character.glb", [0.5], **QUICK)
    (levels,) = report.chains.values()
    assert [level.joints for level in levels] == [2, 1] and levels[1].relative_error > 0.01


def test_character_refuses_a_file_without_a_skinned_animation(data_dir, tmp_path, capsys):
    assert main(["character", str(data_dir / "gltf" / "LeePerrySmith.glb"), "-o", str(tmp_path / "x.glb")]) == 2
    error = capsys.readouterr().err
    assert "no skinned mesh with an animation: a character chain needs both (`animlod simplify`" in error
    assert not (tmp_path / "x.glb").exists()


def _write_flat_shaded(path):
    """The procedural humanoid with a walk, flat shaded (every face its own three vertices with
    its normal), written to ``path``; returns the welded humanoid and the walk."""
    from animlod.model import SkinnedMesh

    character = synth.humanoid()
    walk = synth.humanoid_motion(character.skeleton, "walk")
    corners = character.faces.ravel()
    positions = character.rest_positions[character.faces].astype(np.float64)
    normals = np.cross(positions[:, 1] - positions[:, 0], positions[:, 2] - positions[:, 0])
    normals = np.repeat(normals / np.linalg.norm(normals, axis=1, keepdims=True), 3, axis=0)
    flat = SkinnedMesh(
        character.rest_positions[corners],
        np.arange(corners.size).reshape(-1, 3),
        character.joints[corners],
        character.weights[corners],
        character.inverse_bind,
        character.skeleton,
        normals=normals,
    )
    write_glb(path, flat, [walk])
    return character, walk


def _coarsest_primitive(doc, report):
    base = report.drawables[0].nodes[0]
    coarse = doc.json["nodes"][doc.json["nodes"][base]["extensions"]["MSFT_lod"]["ids"][-1]]
    return doc.json["meshes"][coarse["mesh"]]["primitives"][0]


@pytest.mark.parametrize("skinned", [True, False])
def test_morph_targets_are_shown_and_measured_at_their_default_weights(humanoid_glb, tmp_path, skinned):
    # A mesh's default morph weights (glTF's mesh `weights`, which a node's own override: a
    # Blender shape key left on) are what a viewer shows where no animation drives them. The
    # drawables showed and measured the targets at 0, unskinned ones unless read as static.
    def drawable(name, mesh_weights, node_weights=None):
        builder = GlbBuilder.from_document(GltfDocument(humanoid_glb))
        primitive = builder.json["meshes"][0]["primitives"][0]
        lift = np.zeros((builder.json["accessors"][primitive["attributes"]["POSITION"]]["count"], 3), np.float32)
        lift[:, 1] = 0.1
        primitive["targets"] = [{"POSITION": builder.add(lift, bounds=True)}]
        builder.json["meshes"][0]["weights"] = mesh_weights
        node = next(node for node in builder.json["nodes"] if node.get("mesh") == 0)
        if not skinned:
            del node["skin"]
        if node_weights is not None:
            node["weights"] = node_weights
        builder.save(tmp_path / name)
        return read_drawables(GltfDocument(tmp_path / name))[0]

    off, half, node_full = drawable("off.glb", [0.0]), drawable("half.glb", [0.5]), drawable("node.glb", [0.5], [1.0])
    np.testing.assert_array_equal(half.default_weights, [0.5])
    rest = off.rest_positions()
    np.testing.assert_allclose(half.rest_positions() - rest, np.tile([0.0, 0.05, 0.0], (len(rest), 1)), atol=1e-5)
    np.testing.assert_allclose(node_full.rest_positions() - rest, np.tile([0.0, 0.1, 0.0], (len(rest), 1)), atol=1e-5)
    if skinned:  # the walk drives the joints only: its frames show the default weights too
        clip, frames = half.clips[0], np.array([0, 5])
        expected = half.skinned.bake(clip.motion.take_frames(frames), np.full((2, 1), 0.5)).frames
        np.testing.assert_allclose(half.clip_frames(clip, frames), expected, atol=1e-6)
        assert np.abs(half.clip_frames(clip, frames) - off.clip_frames(clip, frames)).max() > 0.04


def test_a_flat_shaded_mesh_simplifies_like_the_welded_one_and_stays_flat(tmp_path):
    character, walk = _write_flat_shaded(tmp_path / "flat.glb")
    corners = character.faces.ravel()
    write_glb(tmp_path / "welded.glb", character, [walk])
    welded = simplify_document(tmp_path / "welded.glb", tmp_path / "welded_lod.glb", [0.5, 0.1], **QUICK)
    report = simplify_document(tmp_path / "flat.glb", tmp_path / "flat_lod.glb", [0.5, 0.1], **QUICK)
    assert report.drawables[0].preparation.welded_vertices == corners.size - character.vertex_count
    assert [level.faces for level in report.drawables[0].levels] == [
        level.faces for level in welded.drawables[0].levels
    ]
    assert any("normals rebuilt" in note for note in report.drawables[0].notes)
    doc = GltfDocument(tmp_path / "flat_lod.glb")
    primitive = _coarsest_primitive(doc, report)
    faces = doc.accessor(primitive["indices"], "i").reshape(-1, 3)
    level_normals = doc.accessor(primitive["attributes"]["NORMAL"], "n")[faces]
    np.testing.assert_allclose(level_normals[:, 0], level_normals[:, 1], atol=1e-6)  # flat again
    np.testing.assert_allclose(level_normals[:, 0], level_normals[:, 2], atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(level_normals, axis=2), 1.0, atol=1e-6)  # none is zero
    assert problems(tmp_path / "flat_lod.glb") == []


def test_hard_edges_keep_their_tangents_and_normal_deltas_make_no_seams(tmp_path):
    # Exporters write a tangent per corner of a hard-edged mesh, and morph targets with NORMAL
    # deltas, which differ between the copies of a position as the normals do.
    _write_flat_shaded(tmp_path / "flat.glb")

    def tangents_and_normal_target(gltf, blob):
        primitive = gltf.meshes[0].primitives[0]
        read = GltfDocument(tmp_path / "flat.glb")
        normals = read.accessor(primitive.attributes.NORMAL, "n").astype(np.float64)
        positions = read.accessor(primitive.attributes.POSITION, "p")
        across = np.cross(normals, [0.0, 1.0, 0.0]) + np.cross(normals, [0.0, 0.0, 1.0]) * 1e-3
        handedness = np.where(positions[:, 0] > 0.0, 1.0, -1.0)  # mirrored UVs on the left
        tangent = np.c_[across / np.linalg.norm(across, axis=1, keepdims=True), handedness]
        primitive.attributes.TANGENT = append_accessor(gltf, blob, tangent.astype(np.float32), "VEC4")
        delta = 0.2 * np.roll(normals, 1, axis=1).astype(np.float32)
        primitive.targets = [pygltflib.Attributes(NORMAL=append_accessor(gltf, blob, delta, "VEC3"))]
        gltf.meshes[0].weights = [0.5]

    source = edit_glb(tmp_path / "flat.glb", tmp_path / "tangents.glb", tangents_and_normal_target)
    plain = simplify_document(tmp_path / "flat.glb", tmp_path / "flat_lod.glb", [0.5, 0.1], **QUICK)
    report = simplify_document(source, tmp_path / "tangents_lod.glb", [0.5, 0.1], **QUICK)
    assert report.drawables[0].preparation.seam_vertices == plain.drawables[0].preparation.seam_vertices
    assert [level.faces for level in report.drawables[0].levels] == [level.faces for level in plain.drawables[0].levels]
    doc = GltfDocument(tmp_path / "tangents_lod.glb")
    primitive = _coarsest_primitive(doc, report)
    tangent = doc.accessor(primitive["attributes"]["TANGENT"], "t")
    normal = doc.accessor(primitive["attributes"]["NORMAL"], "n")
    np.testing.assert_allclose(np.linalg.norm(tangent[:, :3], axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(np.einsum("vc,vc->v", tangent[:, :3], normal), 0.0, atol=1e-5)
    assert problems(tmp_path / "tangents_lod.glb") == []  # unit normals too
    side = doc.accessor(primitive["attributes"]["POSITION"], "p")[:, 0]
    away = np.abs(side) > 0.05  # 5 cm from the middle, where a collapse may carry a vertex over
    assert away.mean() > 0.8
    np.testing.assert_array_equal(tangent[away, 3], np.where(side[away] > 0.0, 1.0, -1.0))
    assert np.abs(doc.accessor(primitive["targets"][0]["NORMAL"], "d")).max() > 0.05


def _hard_edged_box(path):
    """A box, each face its own 4 vertices with the face's normal, texture coordinates and their
    tangent (u along it), as exporters write hard-edged, normal-mapped props."""
    axes = np.eye(3)
    faces, columns = [], {"POSITION": [], "NORMAL": [], "TANGENT": [], "TEXCOORD_0": []}
    for normal in np.r_[axes, -axes]:
        tangent = np.roll(np.abs(normal), 1) * (1.0 if normal.sum() > 0 else -1.0)
        bitangent = np.cross(normal, tangent)
        base = len(columns["POSITION"])
        for u, v in ((0, 0), (1, 0), (1, 1), (0, 1)):
            columns["POSITION"].append(0.5 * normal + (u - 0.5) * tangent + (v - 0.5) * bitangent)
            columns["NORMAL"].append(normal)
            columns["TANGENT"].append([*tangent, 1.0])
            columns["TEXCOORD_0"].append([u, v])
        faces += [[base, base + 1, base + 2], [base, base + 2, base + 3]]
    builder = GlbBuilder()
    attributes = {
        name: builder.add(np.asarray(values, np.float32), bounds=name == "POSITION") for name, values in columns.items()
    }
    indices = builder.add(np.asarray(faces, np.uint32).reshape(-1, 1))
    builder.append("meshes", {"primitives": [{"attributes": attributes, "indices": indices}]})
    builder.append("nodes", {"mesh": 0})
    builder.json["scenes"], builder.json["scene"] = [{"nodes": [0]}], 0
    builder.save(path)
    return np.asarray(columns["NORMAL"]), np.asarray(columns["TANGENT"])


def test_a_hard_edged_boxs_levels_keep_each_faces_own_tangents(tmp_path):
    # Welded, the box's corners kept one face's vertex: the other two faces at the corner took its
    # tangent, 90 degrees off their own (normal maps shaded them wrong). Each level vertex now
    # takes the input copy of its corner whose normal is its own.
    normals, tangents = _hard_edged_box(tmp_path / "box.glb")
    report = simplify_document(tmp_path / "box.glb", tmp_path / "box_lod.glb", [1.0], **QUICK)
    doc = GltfDocument(tmp_path / "box_lod.glb")
    (level_node,) = doc.json["nodes"][0]["extensions"]["MSFT_lod"]["ids"]
    level = doc.json["meshes"][doc.json["nodes"][level_node]["mesh"]]["primitives"][0]
    level_normals = doc.accessor(level["attributes"]["NORMAL"], "n")
    level_tangents = doc.accessor(level["attributes"]["TANGENT"], "t")
    face_of = np.argmax(level_normals @ normals[::4].T, axis=1)  # which of the 6 faces
    np.testing.assert_allclose(level_normals, normals[::4][face_of], atol=1e-6)
    np.testing.assert_allclose(level_tangents, tangents[::4][face_of], atol=1e-6)
    assert report.drawables[0].levels[1].faces == 12 and len(set(face_of)) == 6


def test_a_double_sided_copy_simplifies_with_its_front_and_faces_away_from_it(humanoid_glb, tmp_path):
    # How exporters write double-sided meshes: every face again in the reverse turn, on vertices
    # of its own whose normals point the other way.
    def double_sided(gltf, blob):
        read = GltfDocument(humanoid_glb)
        primitive = gltf.meshes[0].primitives[0]
        count = read.accessor(primitive.attributes.POSITION, "p").shape[0]
        for name in ("POSITION", "NORMAL", "TEXCOORD_0", "JOINTS_0", "WEIGHTS_0"):
            values = read.accessor(getattr(primitive.attributes, name), name)
            back = -values if name == "NORMAL" else values
            both = np.concatenate([values, back]).astype(np.uint16 if name == "JOINTS_0" else np.float32)
            index = append_accessor(gltf, blob, both, f"VEC{both.shape[1]}")
            if name == "POSITION":
                gltf.accessors[index].min, gltf.accessors[index].max = both.min(0).tolist(), both.max(0).tolist()
            setattr(primitive.attributes, name, index)
        faces = read.accessor(primitive.indices, "i").reshape(-1, 3)
        reversed_copy = faces[:, ::-1] + count
        primitive.indices = append_accessor(gltf, blob, np.r_[faces, reversed_copy].ravel().astype(np.uint32), "SCALAR")

    source = edit_glb(humanoid_glb, tmp_path / "double.glb", double_sided)
    single = simplify_document(humanoid_glb, tmp_path / "single_lod.glb", [0.5, 0.1], **QUICK)
    report = simplify_document(source, tmp_path / "double_lod.glb", [0.5, 0.1], **QUICK)
    assert report.drawables[0].preparation.mirrored_faces == single.drawables[0].faces
    assert [level.faces for level in report.drawables[0].levels] == [
        2 * level.faces for level in single.drawables[0].levels
    ]
    doc = GltfDocument(tmp_path / "double_lod.glb")
    primitive = _coarsest_primitive(doc, report)
    faces = doc.accessor(primitive["indices"], "i").reshape(-1, 3)
    corners = doc.accessor(primitive["attributes"]["POSITION"], "p")[faces].astype(np.float64)
    facing = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals = doc.accessor(primitive["attributes"]["NORMAL"], "n")[faces]
    assert np.all(np.einsum("fkc,fc->fk", normals, facing) > 0.0)  # the back's normals point back


def test_levels_store_colours_texture_coordinates_and_feature_ids_as_the_input_does(humanoid_glb, tmp_path):
    # Quantised exports store colours and texture coordinates as normalised integers, and
    # application attributes such as feature IDs as plain integers.
    def quantised(gltf, blob):
        primitive = gltf.meshes[0].primitives[0]
        positions = GltfDocument(humanoid_glb).accessor(primitive.attributes.POSITION, "p")
        count = len(positions)
        shade = np.clip(np.c_[positions[:, :3] - positions.min(axis=0), np.ones(count)], 0.0, 1.0)
        primitive.attributes.COLOR_0 = append_accessor(gltf, blob, np.rint(255 * shade).astype(np.uint8), "VEC4", True)
        uv = np.rint(65535 * shade[:, :2]).astype(np.uint16)
        primitive.attributes.TEXCOORD_1 = append_accessor(gltf, blob, uv, "VEC2", True)
        # Six bands across the figure, their IDs out of order: any blend of two makes an ID
        # the input does not have.
        bands = np.digitize(positions[:, 1], np.quantile(positions[:, 1], [0.2, 0.4, 0.5, 0.6, 0.8]))
        feature = np.array([0, 7, 3, 12, 1, 9], np.uint16)[bands][:, None]
        primitive.attributes._FEATURE_ID_0 = append_accessor(gltf, blob, feature, "SCALAR")
        primitive.attributes._BATCHID = append_accessor(gltf, blob, feature.astype(np.float32), "SCALAR")

    source = edit_glb(humanoid_glb, tmp_path / "quantised.glb", quantised)
    report = simplify_document(source, tmp_path / "quantised_lod.glb", [0.5, 0.1], **QUICK)
    doc = GltfDocument(tmp_path / "quantised_lod.glb")
    base = report.drawables[0].nodes[0]
    expected = {"COLOR_0": (5121, True), "TEXCOORD_1": (5123, True), "_FEATURE_ID_0": (5123, False)}
    for node in [base, *doc.json["nodes"][base]["extensions"]["MSFT_lod"]["ids"]]:
        attributes = doc.json["meshes"][doc.json["nodes"][node]["mesh"]]["primitives"][0]["attributes"]
        for name, (component, normalized) in expected.items():
            accessor = doc.json["accessors"][attributes[name]]
            assert (accessor["componentType"], accessor.get("normalized", False)) == (component, normalized), name
        for name in ("_FEATURE_ID_0", "_BATCHID"):  # each vertex keeps an ID of the input's
            assert set(np.unique(doc.accessor(attributes[name], name))) <= {0, 7, 3, 12, 1, 9}, name
        assert np.all(doc.accessor(attributes["COLOR_0"], "c")[:, 3] == 1.0)


def test_a_vertex_whose_weights_are_all_zero_follows_its_first_listed_joint(humanoid_glb, tmp_path, capsys):
    # Blender before 2.90 and Maya2glTF write the vertices no bone deforms with all-zero weights
    # (Castle Game Engine's soldier: 174 of 9,432); three.js and Blender's importer give them
    # their first listed joint. They were refused.
    from animlod.io.glb_builder import GlbBuilder

    builder = GlbBuilder.from_document(GltfDocument(humanoid_glb))
    weights = builder.json["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"]
    zero = builder.add(np.zeros((1, 4), np.float32))  # a sparse substitution: vertex 7 weighs nothing
    index = builder.add(np.array([[7]], np.uint32))
    builder.json["accessors"][weights]["sparse"] = {
        "count": 1,
        "indices": {"bufferView": builder.json["accessors"][index]["bufferView"], "componentType": 5125},
        "values": {"bufferView": builder.json["accessors"][zero]["bufferView"]},
    }
    builder.save(tmp_path / "zero.glb")
    with pytest.warns(UserWarning, match=r"mesh 0 WEIGHTS: 1 of \d+ vertices \(first: 7\) have no positive skin"):
        mesh = read_gltf(tmp_path / "zero.glb").skinned_meshes[0]
    original = read_gltf(humanoid_glb).skinned_meshes[0]
    listed = original.joints[7][original.weights[7] > 0]
    assert mesh.weights[7].tolist() == [1.0, 0.0, 0.0, 0.0] and mesh.joints[7, 0] in listed
    assert np.array_equal(np.delete(mesh.weights, 7, axis=0), np.delete(original.weights, 7, axis=0))
    assert main(["simplify", str(tmp_path / "zero.glb"), "-o", str(tmp_path / "out.glb"), "--max-frames", "8"]) == 0
    assert "have no positive skin weight; they follow their first listed joint" in capsys.readouterr().err
    written = GltfDocument(tmp_path / "out.glb")
    (base,) = [node for node in written.json["nodes"] if "MSFT_lod" in node.get("extensions", {})]
    for level in base["extensions"]["MSFT_lod"]["ids"]:  # the input's own mesh is kept as it was
        primitive = written.json["meshes"][written.json["nodes"][level]["mesh"]]["primitives"][0]
        assert np.all(written.accessor(primitive["attributes"]["WEIGHTS_0"], "w").sum(axis=1) > 0.99)


def test_an_image_written_with_backslashes_is_embedded_and_a_missing_one_keeps_its_uri(humanoid_glb, tmp_path, capsys):
    # assimp's glTF exports of its test models name textures as their sources did: Windows paths
    # ('.\\test.png'), files on the author's machine or never shipped. They failed the whole run.
    (tmp_path / "tex").mkdir()
    (tmp_path / "tex" / "wood.png").write_bytes(b"\x89PNG wood")
    images = [{"uri": ".\\tex\\wood.png"}, {"uri": "C:\\Users\\me\\gone.png"}]
    source = _edited(humanoid_glb, tmp_path, lambda js: js.__setitem__("images", images))
    output = tmp_path / "out.glb"
    assert main(["simplify", source, "-o", str(output), "--ratio", "0.5", "--max-frames", "8"]) == 0
    err = capsys.readouterr().err
    assert f"image 1: {tmp_path / 'C:/Users/me/gone.png'} not found; the output refers to" in err
    written = GltfDocument(output)
    embedded, kept = written.json["images"]
    assert _image_bytes(written, embedded) == b"\x89PNG wood" and "uri" not in embedded
    assert kept == {"uri": "C:\\Users\\me\\gone.png"}


def test_embedded_images_take_the_type_their_bytes_say(humanoid_glb, tmp_path):
    # Texture files without a suffix, DDS textures (MSFT_texture_dds) and PNG data named .jpg:
    # the type came from the name, so two were written with "mimeType": null (invalid JSON for
    # glTF) and one as JPEG.
    png = b"\x89PNG\r\n\x1a\n" + bytes(8)
    for name, data in (("noext", png), ("actually_png.jpg", png), ("tex.dds", b"DDS " + bytes(124))):
        (tmp_path / name).write_bytes(data)
    (tmp_path / "unknown.tex").write_bytes(bytes(16))
    unknown = "data:;base64," + "A" * 4000
    images = [{"uri": name} for name in ("noext", "actually_png.jpg", "tex.dds", "unknown.tex", unknown)]
    source = _edited(humanoid_glb, tmp_path, lambda js: js.__setitem__("images", images))
    output = tmp_path / "out.glb"
    with pytest.warns(UserWarning) as caught:
        simplify_document(source, output, [0.5], **QUICK)
    said = [str(warning.message) for warning in caught]
    assert any("image 3: 'unknown.tex' is of no image type glTF knows" in line for line in said)
    assert any("image 4: its data URI is of no image type" in line and len(line) < 300 for line in said)
    written = GltfDocument(output).json["images"]
    assert [image.get("mimeType") for image in written] == ["image/png", "image/png", "image/vnd-ms.dds", None, None]
    assert written[3:] == [{"uri": "unknown.tex"}, {"uri": unknown}]
    assert [code for code, _, _ in problems(output)] == []


def test_an_image_kept_by_its_uri_is_referred_to_from_the_outputs_folder(humanoid_glb, tmp_path):
    """An image glTF has no type for (a .tga) or a missing one keeps its URI; written into another
    folder (always so in `batch`, OUT/<name>/), the relative URI as the input had it named no file."""
    (tmp_path / "textures").mkdir()
    (tmp_path / "textures" / "skin tone.tga").write_bytes(bytes(18))
    images = [{"uri": "textures/skin%20tone.tga"}, {"uri": "gone/eyes.png"}, {"uri": "https://example.com/a.png"}]
    source = _edited(humanoid_glb, tmp_path, lambda js: js.__setitem__("images", images))
    output = tmp_path / "out" / "hero" / "hero_lod.glb"
    with pytest.warns(UserWarning):
        simplify_document(source, output, [0.5], **QUICK)
    written = GltfDocument(output).json["images"]
    assert written == [{"uri": "../../textures/skin%20tone.tga"}, {"uri": "../../gone/eyes.png"}, images[2]]
    assert (output.parent / "../../textures/skin tone.tga").is_file()


def test_a_document_in_latin_1_is_read_with_a_warning_and_written_as_utf_8(humanoid_glb, tmp_path, capsys):
    # assimp's glTF exporter writes names in Latin-1 ("Terraind\xe6k" of its OBJ test set).
    data = humanoid_glb.read_bytes()
    assert data.count(b'"generator":"animlod"') == 1
    source = tmp_path / "latin1.glb"
    source.write_bytes(data.replace(b'"generator":"animlod"', b'"generator":"anim\xe6od"'))
    output = tmp_path / "out.glb"
    assert main(["simplify", str(source), "-o", str(output), "--ratio", "0.5", "--max-frames", "8"]) == 0
    assert "GLB JSON chunk: not UTF-8 text (byte" in capsys.readouterr().err
    assert GltfDocument(output).json["asset"]["generator"] == "anim\u00e6od"


def test_three_component_texture_coordinates_give_levels_their_u_and_v(humanoid_glb, tmp_path, capsys):
    # assimp's exporter writes a source's (u, v, w) as a VEC3 TEXCOORD_0, which glTF does not allow.
    def widen(gltf, blob):
        primitive = gltf.meshes[0].primitives[0]
        uv = np.asarray(GltfDocument(humanoid_glb).accessor(primitive.attributes.TEXCOORD_0, "uv"))
        primitive.attributes.TEXCOORD_0 = append_accessor(
            gltf, blob, np.c_[uv, np.full(len(uv), 0.5)].astype("f4"), "VEC3"
        )

    source = edit_glb(humanoid_glb, tmp_path / "uvw.glb", widen)
    output = tmp_path / "out.glb"
    assert main(["simplify", str(source), "-o", str(output), "--ratio", "0.5", "--max-frames", "8"]) == 0
    assert "TEXCOORD_0: VEC3, which glTF does not allow; the levels keep u and v" in capsys.readouterr().err
    plain = tmp_path / "plain.glb"
    assert main(["simplify", str(humanoid_glb), "-o", str(plain), "--ratio", "0.5", "--max-frames", "8"]) == 0
    written, expected = GltfDocument(output), GltfDocument(plain)
    level, expected_level = written.json["meshes"][-1]["primitives"][0], expected.json["meshes"][-1]["primitives"][0]
    np.testing.assert_array_equal(
        written.accessor(level["attributes"]["TEXCOORD_0"], "uv"),
        expected.accessor(expected_level["attributes"]["TEXCOORD_0"], "uv"),
    )


def test_overwrite_writes_an_accessors_own_float_data_or_nothing(humanoid_glb):
    builder = GlbBuilder.from_document(GltfDocument(humanoid_glb))
    attributes = builder.json["meshes"][0]["primitives"][0]["attributes"]
    weights, joints = attributes["WEIGHTS_0"], attributes["JOINTS_0"]
    count = builder.json["accessors"][weights]["count"]
    halves = np.full((count, 4), 0.25, np.float32)
    assert not builder.overwrite(joints, halves)  # not float data
    assert not builder.overwrite(weights, halves[:-1])  # another shape
    builder.json["meshes"][0]["primitives"].append({"attributes": {"POSITION": 0, "WEIGHTS_0": weights}})
    assert not builder.overwrite(weights, halves)  # used twice: the other user keeps its data
    builder.json["meshes"][0]["primitives"].pop()
    assert builder.overwrite(weights, halves) and builder.overwritten == {weights}
    written = GltfDocument(humanoid_glb, data=builder.to_bytes())
    np.testing.assert_array_equal(written.accessor(weights, "t"), halves)


@pytest.mark.parametrize(
    "ids, reason",
    [([0], "lists the node itself"), ([1, 1], "lists node 1 twice"), (["a"], "refers to node 'a'")],
)
def test_a_chain_whose_level_ids_are_not_other_nodes_is_refused(tmp_path, capsys, ids, reason):
    """`info` printed "levels at nodes [0, 'a']" and exited 0 for such a chain."""
    from animlod.io import read_lod_chains

    lod = tmp_path / "lod.glb"
    simplify_document(_ellipsoid_glb(tmp_path / "plain.glb"), lod, [0.5], **QUICK)

    def relist(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        gltf.nodes[0].extensions["MSFT_lod"]["ids"] = ids

    edited = edit_glb(lod, tmp_path / "edited.glb", relist)
    with pytest.raises(FormatError, match=rf"edited.glb: node 0 MSFT_lod: {reason}"):
        read_lod_chains(edited)
    capsys.readouterr()
    assert main(["info", str(edited)]) == 2
    assert reason in capsys.readouterr().err


def test_screen_coverages_that_rise_are_refused_by_info_and_read_lod_chains(tmp_path, capsys):
    """`info` printed the extras as they were, a string or rising values included."""
    from animlod.io import read_lod_chains

    lod = tmp_path / "lod.glb"
    simplify_document(_ellipsoid_glb(tmp_path / "plain.glb"), lod, [0.5], **QUICK)
    capsys.readouterr()
    assert main(["info", str(lod)]) == 0
    assert "LoD chain on node 0: levels at nodes [0, 1], coverage " in capsys.readouterr().out

    def rising(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        gltf.nodes[0].extras["MSFT_screencoverage"] = [0.1, 0.5]

    edited = edit_glb(lod, tmp_path / "edited.glb", rising)
    with pytest.raises(FormatError, match=r"node 0 extras MSFT_screencoverage: level 1: 0.5 is above level 0's 0.1"):
        read_lod_chains(edited)
    assert main(["info", str(edited)]) == 2
    assert "level 1: 0.5 is above level 0's 0.1" in capsys.readouterr().err
