"""A skinned mesh whose bind shape has another scale than what its skin makes of it: positions
quantized to normalized int16 with the scale folded into the inverse bind matrices, as gltfpack
writes them (KHR_mesh_quantization), and as a centimetre mesh under a 0.01 armature (Mixamo's
Xbot.glb) amounts to. Sizes, errors and switch coverages must be those of what a viewer shows,
not of the stored positions' scale."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_drawable import read_drawables
from animlod.io.gltf_write import write_glb
from animlod.pipelines import simplify_document
from animlod.synth import humanoid, humanoid_motion

SHORT = 5122


def _quantized_accessor(builder: GlbBuilder, values: np.ndarray) -> int:
    """``values`` (V, 3) in [-1, 1] as a normalized int16 accessor with a 4-byte-aligned stride."""
    padded = np.zeros((len(values), 4), np.int16)
    padded[:, :3] = np.round(values * 32767)
    view = {"buffer": 0, "byteOffset": builder._append(padded.tobytes()), "byteLength": padded.nbytes, "byteStride": 8}
    accessor = {"bufferView": builder.append("bufferViews", view), "componentType": SHORT, "normalized": True,
                "count": len(values), "type": "VEC3", "min": padded[:, :3].min(0).tolist(),
                "max": padded[:, :3].max(0).tolist()}  # fmt: skip
    return builder.append("accessors", accessor)


def _quantize(source: Path, target: Path) -> float:
    """``source`` with every POSITION (and morph target POSITION) stored as normalized int16 over
    a scale folded into the inverse bind matrices; the scale."""
    doc = GltfDocument(source)
    builder = GlbBuilder.from_document(doc)
    document = builder.json
    positions = [doc.accessor(p["attributes"]["POSITION"], "test") for m in document["meshes"] for p in m["primitives"]]
    scale = float(max(np.abs(p).max() for p in positions)) * 1.001
    for mesh in document["meshes"]:
        for primitive in mesh["primitives"]:
            for attributes in [primitive["attributes"], *primitive.get("targets", [])]:
                stored = doc.accessor(attributes["POSITION"], "test") / scale
                attributes["POSITION"] = _quantized_accessor(builder, stored)
    for skin in document["skins"]:
        inverse_bind = doc.accessor(skin["inverseBindMatrices"], "test").reshape(-1, 4, 4)  # column-major
        folded = inverse_bind * np.array([scale, scale, scale, 1.0])[None, :, None]  # IBM @ S(scale)
        skin["inverseBindMatrices"] = builder.add(folded.reshape(-1, 16).astype(np.float32))
    for key in ("extensionsUsed", "extensionsRequired"):
        document.setdefault(key, []).append("KHR_mesh_quantization")
    builder.prune()
    builder.save(target)
    return scale


@pytest.fixture(scope="module")
def character(tmp_path_factory) -> tuple[Path, Path, float]:
    folder = tmp_path_factory.mktemp("bind_scale")
    mesh = humanoid()
    # One morph target: the upper body swells by 5% of the figure's height.
    height = np.ptp(mesh.rest_positions[:, 1])
    swell = np.where(mesh.rest_positions[:, 1:2] > np.median(mesh.rest_positions[:, 1]), 0.05 * height, 0.0)
    mesh = dataclasses.replace(mesh, morph_targets=(swell * np.array([1.0, 0.0, 0.0]))[None].astype(np.float32))
    plain = folder / "humanoid.glb"
    write_glb(plain, mesh, [humanoid_motion(mesh.skeleton, "walk")])
    quantized = folder / "humanoid_quantized.glb"
    return plain, quantized, _quantize(plain, quantized)


def test_the_rest_pose_is_what_the_skin_shows(character):
    plain, quantized, scale = character
    original, stored = read_drawables(GltfDocument(plain))[0], read_drawables(GltfDocument(quantized))[0]
    size = np.linalg.norm(np.ptp(original.rest_positions(), axis=0))
    assert scale > 1.5  # the stored positions are smaller than the figure by that much
    np.testing.assert_allclose(stored.bind_positions() * scale, original.bind_positions(), atol=1e-3 * size)
    np.testing.assert_allclose(stored.rest_positions(), original.rest_positions(), atol=1e-3 * size)
    assert np.abs(original.rest_morph_targets()).max() > 0.01 * size
    np.testing.assert_allclose(stored.rest_morph_targets(), original.rest_morph_targets(), atol=1e-3 * size)


def test_errors_and_coverages_do_not_depend_on_the_stored_scale(character, tmp_path):
    plain, quantized, _ = character
    reports = [simplify_document(path, tmp_path / f"{path.stem}_lod.glb") for path in (plain, quantized)]
    levels = [report.drawables[0].levels for report in reports]
    assert [level.faces for level in levels[0]] == [level.faces for level in levels[1]]
    for ours, theirs in zip(*levels):
        assert theirs.relative_error == pytest.approx(ours.relative_error, rel=0.1, abs=1e-4)
        assert theirs.coverage == pytest.approx(ours.coverage, rel=0.1, abs=1e-4)


def test_the_skinned_nodes_own_transform_changes_no_level(character, tmp_path):
    # glTF skinning ignores the skinned mesh node's transform, so a viewer shows the same figure;
    # the bind shape under it (3x here) must not weigh in the collapses as a pose of its own.
    plain, _, _ = character
    doc = GltfDocument(plain)
    builder = GlbBuilder.from_document(doc)
    node = next(node for node in builder.json["nodes"] if "skin" in node)
    node.update(scale=[3.0, 3.0, 3.0], translation=[0.5, 0.0, -0.25])
    moved = tmp_path / "humanoid_moved.glb"
    builder.save(moved)
    reports = [simplify_document(path, tmp_path / f"{path.stem}_lod.glb") for path in (plain, moved)]
    levels = [report.drawables[0].levels for report in reports]
    assert [level.faces for level in levels[0]] == [level.faces for level in levels[1]]
    for ours, theirs in zip(*levels):
        assert theirs.relative_error == pytest.approx(ours.relative_error, rel=1e-3, abs=1e-6)
