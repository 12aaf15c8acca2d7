"""Whole glTF documents as game and DCC exports write them, which the development files do not
have: instances at zero scale, point clouds beside meshes, LoD chains already in the file, extras
that are not objects. Each is rebuilt small from a procedural sphere."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pygltflib
import pytest
from gltf_edits import append_accessor, edit_glb
from simplify_inputs import ellipsoid, two_bone_tube

from animlod.cli import main
from animlod.io import read_lod_chains
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf import write_glb
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines.lod_document import simplify_document


def _sphere_glb(path: Path, nodes: list[dict], points: bool = False) -> Path:
    """A bumpy sphere (mesh 0) drawn by ``nodes`` (each given its ``mesh``), all in the scene;
    with ``points``, also a point cloud of its vertices (mesh 1) drawn by a node of its own."""
    sphere = ellipsoid(frames=1, rings=16, segments=24)
    positions = (sphere.frames[0] * (1.0 + 0.05 * np.sin(7.0 * sphere.frames[0][:, :1]))).astype(np.float32)
    builder = GlbBuilder()
    position = builder.add(positions, bounds=True)
    indices = builder.add(sphere.faces.astype(np.uint32).reshape(-1, 1))
    builder.append(
        "meshes", {"name": "ball", "primitives": [{"attributes": {"POSITION": position}, "indices": indices}]}
    )
    for node in nodes:
        builder.append("nodes", {**node, "mesh": 0})
    if points:
        builder.append("meshes", {"name": "cloud", "primitives": [{"attributes": {"POSITION": position}, "mode": 0}]})
        builder.append("nodes", {"name": "scan", "mesh": 1})
    builder.json["scenes"], builder.json["scene"] = [{"nodes": list(range(len(builder.json["nodes"])))}], 0
    builder.save(path)
    return path


def _level_errors(report) -> list[list[float]]:
    return [[level.error for level in drawable.levels] for drawable in report.drawables]


def test_an_instance_at_zero_scale_leaves_the_others_their_levels(tmp_path: Path) -> None:
    """A node at zero scale is valid glTF (an instance hidden at rest, a prop that pops in by an
    animated scale); where it came first among the nodes of a mesh, or was the only one, the whole
    file was refused: "its world transform is singular (a zero scale)". The mesh is now read through
    its first node that has an extent, and every node gets the chain."""
    plain = simplify_document(_sphere_glb(tmp_path / "plain.glb", [{"name": "shown"}]), tmp_path / "plain_lod.glb")
    hidden_first = _sphere_glb(tmp_path / "hidden.glb", [{"name": "hidden", "scale": [0, 0, 0]}, {"name": "shown"}])
    report = simplify_document(hidden_first, tmp_path / "hidden_lod.glb")
    assert report.drawables[0].nodes == [1, 0]
    assert _level_errors(report) == _level_errors(plain)
    doc = GltfDocument(tmp_path / "hidden_lod.glb")
    assert all(len(doc.json["nodes"][base]["extensions"]["MSFT_lod"]["ids"]) == 3 for base in (0, 1))

    only_hidden = simplify_document(
        _sphere_glb(tmp_path / "pop.glb", [{"name": "pop", "scale": [0, 0, 0]}]), tmp_path / "pop_lod.glb"
    )
    assert _level_errors(only_hidden) == _level_errors(plain)  # taken in the mesh's own space


def test_a_skinned_mesh_nodes_zero_scale_changes_nothing(tmp_path: Path) -> None:
    """Skinning ignores the mesh node's own transform, so a viewer shows the character whatever
    that node's scale; at zero scale the file was refused."""
    skinned, motion = two_bone_tube()
    write_glb(tmp_path / "tube.glb", skinned, [motion])

    def zero_scale(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        next(node for node in gltf.nodes if node.mesh is not None).scale = [0.0, 0.0, 0.0]

    edit_glb(tmp_path / "tube.glb", tmp_path / "zero.glb", zero_scale)
    plain = simplify_document(tmp_path / "tube.glb", tmp_path / "tube_lod.glb")
    zero = simplify_document(tmp_path / "zero.glb", tmp_path / "zero_lod.glb")
    np.testing.assert_allclose(_level_errors(zero), _level_errors(plain), rtol=1e-5)
    # And the LoD GLB reads back (read_lod_chains refused the zero-scale base node as singular).
    (read,), (written,) = read_lod_chains(tmp_path / "zero_lod.glb"), read_lod_chains(tmp_path / "tube_lod.glb")
    assert [level.mesh.face_count for level in read.levels] == [level.mesh.face_count for level in written.levels]


def test_a_point_cloud_beside_a_mesh_is_kept_and_named(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A mesh of points or lines alone (a scan's point cloud, a wireframe helper) drawn by a node
    made `simplify` and `info` refuse the whole file ("has no triangle primitive"); it stays as it
    is, named by both."""
    source = _sphere_glb(tmp_path / "scan.glb", [{"name": "ball"}], points=True)
    assert main(["simplify", str(source), "-o", str(tmp_path / "scan_lod.glb")]) == 0
    note = "kept as they are, without levels (points or lines only): mesh 1 'cloud' (nodes [1])"
    assert note in capsys.readouterr().out
    doc = GltfDocument(tmp_path / "scan_lod.glb")
    assert doc.json["nodes"][1] == {"name": "scan", "mesh": 1} and doc.json["meshes"][1]["name"] == "cloud"
    assert "MSFT_lod" in doc.json["nodes"][0]["extensions"]
    for path in (source, tmp_path / "scan_lod.glb"):
        assert main(["info", str(path)]) == 0
        assert "mesh 1 'cloud', drawn by nodes [1]: points or lines only" in capsys.readouterr().out


def test_an_msft_lod_chain_in_the_input_is_kept(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A chain already in the file (an artist's levels, or animlod's output simplified again) had
    its ids replaced by the new chain's, its level nodes left in no chain and read as meshes of
    their own. It stays; the nodes without one get theirs, and a file with nothing left to chain is
    refused in one line."""
    source = _sphere_glb(tmp_path / "balls.glb", [{"name": "a"}, {"name": "b", "translation": [3, 0, 0]}])
    simplify_document(source, tmp_path / "once.glb", (0.5,))
    assert main(["simplify", str(tmp_path / "once.glb"), "-o", str(tmp_path / "twice.glb")]) == 2
    err = capsys.readouterr().err.strip()
    assert "once.glb: meshes: every node that draws a mesh has an MSFT_lod chain already" in err
    assert len(err.splitlines()) == 1 and not (tmp_path / "twice.glb").exists()

    def drop_the_second_chain(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        gltf.nodes[1].extensions = {}

    edit_glb(tmp_path / "once.glb", tmp_path / "half.glb", drop_the_second_chain)
    before = GltfDocument(tmp_path / "half.glb").json["nodes"]
    report = simplify_document(tmp_path / "half.glb", tmp_path / "again.glb", (0.5,))
    assert "kept with the MSFT_lod chains they have" not in " ".join(report.notes)  # node 1 of the pair has none
    after = GltfDocument(tmp_path / "again.glb").json["nodes"]
    assert after[0]["extensions"] == before[0]["extensions"] and after[0]["extras"] == before[0]["extras"]
    assert after[1]["extensions"]["MSFT_lod"]["ids"] == [len(before)]


def test_separate_levels_keep_node_extras_that_are_not_objects(tmp_path: Path) -> None:
    """glTF allows any JSON value as extras; `--separate` dropped a node's that was not an object
    (a string an exporter tags nodes with), where the LoD GLB keeps it as ``original_extras``."""
    source = _sphere_glb(tmp_path / "tagged.glb", [{"name": "ball", "extras": "exported by X"}])
    (level,) = simplify_document(source, tmp_path / "levels", (0.5,), separate=True).outputs
    extras = GltfDocument(level).json["nodes"][0]["extras"]
    assert extras["original_extras"] == "exported by X" and extras["animlod"]["level"] == 1


def test_the_levels_of_an_animated_node_are_no_animated_trees_of_their_own(tmp_path: Path, capsys) -> None:
    """A level node plays its base node's channels, so a simplified file of a turning static mesh
    had one animated tree per level beside the base's: `info` named them "other animated trees",
    and a skeleton of the animated nodes would have taken them for bones."""

    def turning(gltf: pygltflib.GLTF2, blob: bytearray) -> None:
        times = append_accessor(gltf, blob, np.array([[0.0], [1.0]], np.float32), "SCALAR")
        turns = append_accessor(gltf, blob, np.array([[0, 0, 0, 1], [0, 0.6, 0, 0.8]], np.float32), "VEC4")
        sampler = pygltflib.AnimationSampler(input=times, output=turns)
        target = pygltflib.AnimationChannelTarget(node=0, path="rotation")
        channel = pygltflib.AnimationChannel(sampler=0, target=target)
        gltf.animations.append(pygltflib.Animation(name="turn", samplers=[sampler], channels=[channel]))

    source = edit_glb(_sphere_glb(tmp_path / "still.glb", [{"name": "ball"}]), tmp_path / "turning.glb", turning)
    simplify_document(source, tmp_path / "turning_lod.glb")
    assert GltfDocument(tmp_path / "turning_lod.glb").alternate_nodes() == {1, 2, 3}
    assert main(["info", str(tmp_path / "turning_lod.glb")]) == 0
    out = capsys.readouterr().out
    assert "animated node tree: 1 joints, root 'ball'" in out and "other animated trees" not in out


def test_character_keeps_the_chain_a_skinned_mesh_has(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """`animlod character` on `simplify`'s output replaced the skinned mesh node's chain as
    `simplify` did (its ids changed, its level nodes left in no chain); nothing else is left to
    build a character chain of here, so it is refused in one line, before anything is written."""
    skinned, motion = two_bone_tube()
    write_glb(tmp_path / "arm.glb", skinned, [motion])
    simplify_document(tmp_path / "arm.glb", tmp_path / "levels.glb", (0.5,))
    assert main(["character", str(tmp_path / "levels.glb"), "-o", str(tmp_path / "character.glb")]) == 2
    err = capsys.readouterr().err.strip()
    assert "levels.glb: skins: every skinned mesh's node has an MSFT_lod chain already" in err
    assert len(err.splitlines()) == 1 and not (tmp_path / "character.glb").exists()
