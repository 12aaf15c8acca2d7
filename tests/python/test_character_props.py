"""`animlod character` gives the meshes no clip skins levels of their own: a sword hung from a
hand, a prop drawn by a joint's own node, a rock beside the character. Each node that draws one,
and each copy of it on a motion level's skeleton, is the base of an MSFT_lod chain of its own
(pipelines/character.py, attachments.copy_level_chains)."""

from __future__ import annotations

import numpy as np
import pytest
from gltf_conformance import problems
from gltf_poses import node_named

from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines.character import build_character
from animlod.synth.geometry import icosphere

QUICK = {"frame_budget": 12, "measured_frames": 2}
PROPS = ("sword", "LeftHand", "rock")  # hung from a joint, drawn by a joint's node, beside


@pytest.fixture(scope="module")
def character_with_props(humanoid_glb, tmp_path_factory):
    """The procedural humanoid walking with a spinning sword (320 triangles) under its right hand,
    a sphere drawn by its left hand's joint node and a rock at the scene's root; the input, its
    LoD GLB and the build's report."""
    folder = tmp_path_factory.mktemp("props")
    builder = GlbBuilder.from_document(GltfDocument(humanoid_glb))
    nodes = builder.json["nodes"]
    by_name = {node.get("name"): index for index, node in enumerate(nodes)}
    points, faces = icosphere(2, 0.05)
    blade = points * np.array([0.3, 2.0, 0.3], np.float32)  # long along the hand's bone
    mesh = {
        "primitives": [
            {
                "attributes": {"POSITION": builder.add(blade.astype(np.float32), bounds=True)},
                "indices": builder.add(faces.astype(np.uint32).reshape(-1, 1)),
            }
        ]
    }
    sword_mesh = builder.append("meshes", mesh)
    sword = builder.append("nodes", {"name": "sword", "mesh": sword_mesh, "translation": [0.02, 0.08, 0.0]})
    nodes[by_name["RightHand"]].setdefault("children", []).append(sword)
    nodes[by_name["LeftHand"]]["mesh"] = sword_mesh
    rock = builder.append("nodes", {"name": "rock", "mesh": sword_mesh, "translation": [1.0, 0.0, 0.0]})
    builder.json["scenes"][0]["nodes"].append(rock)
    animation = builder.json["animations"][0]
    keys = builder.json["accessors"][animation["samplers"][0]["input"]]["count"]
    angles = np.linspace(0.0, np.pi, keys)
    spin = np.stack([np.zeros(keys), np.sin(angles / 2), np.zeros(keys), np.cos(angles / 2)], axis=1)
    animation["samplers"].append(
        {"input": animation["samplers"][0]["input"], "output": builder.add(spin.astype(np.float32))}
    )
    animation["channels"].append(
        {"sampler": len(animation["samplers"]) - 1, "target": {"node": sword, "path": "rotation"}}
    )
    source = folder / "props.glb"
    builder.save(source)
    output = folder / "props_lod.glb"
    lines = []
    report = build_character(source, output, [0.5, 0.1], solver="newton", progress=lines.append, **QUICK)
    return source, output, report, lines


def test_every_prop_gets_levels_and_no_note_says_it_stays_at_full_detail(character_with_props):
    _, _, report, _ = character_with_props
    (other,) = report.others  # one mesh, drawn by three nodes
    assert len(other.nodes) == 3
    assert [level.faces for level in other.levels][0] == 320
    assert len(other.levels) == 3 and other.levels[-1].faces < 100
    assert not [note for note in report.notes if "full detail" in note]


def _chain(doc: GltfDocument, node: int) -> tuple[list[int], list[float]]:
    own = doc.json["nodes"][node]
    return own["extensions"]["MSFT_lod"]["ids"], own["extras"]["MSFT_screencoverage"]


def test_each_copy_of_a_prop_on_a_motion_level_has_level_nodes_of_its_own(character_with_props):
    # A level node listed by several bases is one node in several places: the copies (sharing the
    # input's meshes) kept the input's ids, and a joint's own mesh's copy no coverages at all.
    _, output, _, _ = character_with_props
    doc = GltfDocument(output)
    nodes = doc.json["nodes"]
    listed = [child for node in nodes for child in node.get("children", [])]
    scenes = [root for scene in doc.json["scenes"] for root in scene["nodes"]]
    motion_levels = {a.name.rsplit("@motion", 1)[1] for a in doc.gltf.animations if "@motion" in (a.name or "")}
    assert len(motion_levels) >= 2
    all_levels = []
    for prop in PROPS:
        base = node_named(doc, prop)
        ids, coverages = _chain(doc, base)
        meshes = [nodes[level]["mesh"] for level in ids]
        assert len(ids) == 2 and len(set(meshes)) == 2 and nodes[base]["mesh"] not in meshes
        all_levels += ids
        copies = [] if prop == "rock" else [f"{prop}@motion{m}" for m in motion_levels]  # the rock hangs from no joint
        for name in copies:
            copy = node_named(doc, name)
            copy_ids, copy_coverages = _chain(doc, copy)
            assert [nodes[level]["mesh"] for level in copy_ids] == meshes
            assert copy_coverages == coverages
            motion_level = int(name.rsplit("@motion", 1)[1])  # said by each node of the copy's chain
            assert [nodes[node]["extras"]["animlod"]["motion_level"] for node in [copy, *copy_ids]] == [
                motion_level
            ] * 3
            for level in copy_ids:  # where the copy is: a joint's own mesh's copy has no transform
                assert nodes[level]["name"].endswith(name[len(prop) :])
                assert {k: nodes[level].get(k) for k in ("translation", "rotation", "scale", "matrix")} == {
                    k: nodes[copy].get(k) for k in ("translation", "rotation", "scale", "matrix")
                }
            all_levels += copy_ids
    assert len(set(all_levels)) == len(all_levels)  # each level node has one base
    assert not set(all_levels) & (set(listed) | set(scenes))  # in no scene, as MSFT_lod asks
    assert problems(output) == []


def test_the_spin_of_a_prop_drives_its_copies_levels_in_each_level_clip(character_with_props):
    # The sword's rotation channel is carried to its copy in each `@motion<m>` clip; the copy's
    # level nodes play it through the same sampler, as the input's levels play the input clip's.
    _, output, _, _ = character_with_props
    doc = GltfDocument(output)
    for animation in doc.gltf.animations:
        suffix = animation.name[animation.name.index("@") :] if "@" in (animation.name or "") else ""
        holder = node_named(doc, f"sword{suffix}")
        (sampler,) = [c.sampler for c in animation.channels if (c.target.node, c.target.path) == (holder, "rotation")]
        driven = {c.target.node for c in animation.channels if c.sampler == sampler and c.target.path == "rotation"}
        assert driven == {holder, *_chain(doc, holder)[0]}


def test_a_prop_with_a_chain_of_its_own_gets_level_nodes_of_its_own_on_each_copy(character_with_props, tmp_path):
    # A sword whose MSFT_lod chain the input has (another tool's levels): its copies kept the
    # input's ids, so that one level node had a base on every motion level's skeleton.
    source, _, _, _ = character_with_props
    builder = GlbBuilder.from_document(GltfDocument(source))
    nodes = builder.json["nodes"]
    sword = next(index for index, node in enumerate(nodes) if node.get("name") == "sword")
    level = builder.append(
        "nodes", {"name": "sword level", "mesh": nodes[sword]["mesh"], "translation": [0.02, 0.08, 0.0]}
    )
    nodes[sword]["extensions"] = {"MSFT_lod": {"ids": [level]}}
    nodes[sword]["extras"] = {"MSFT_screencoverage": [0.3, 0.0]}
    builder.json.setdefault("extensionsUsed", []).append("MSFT_lod")
    chained = tmp_path / "chained.glb"
    builder.save(chained)
    build_character(chained, tmp_path / "lod.glb", [0.5], solver="newton", **QUICK)
    doc = GltfDocument(tmp_path / "lod.glb")
    assert _chain(doc, node_named(doc, "sword")) == ([level], [0.3, 0.0])
    copy = node_named(doc, "sword@motion1")
    (copy_level,), coverages = _chain(doc, copy)
    assert copy_level != level and coverages == [0.3, 0.0]
    assert doc.json["nodes"][copy_level]["mesh"] == doc.json["nodes"][level]["mesh"]
    assert problems(tmp_path / "lod.glb") == []


def test_the_summary_explains_its_errors_once_for_the_character_and_its_props(
    character_with_props, tmp_path, monkeypatch, capsys
):
    import animlod.pipelines.character as pipeline
    from animlod.cli import main

    source, _, report, _ = character_with_props
    monkeypatch.setattr(pipeline, "build_character", lambda *args, **kwargs: report)
    assert main(["character", str(source), "-o", str(tmp_path / "out.glb")]) == 0
    out = capsys.readouterr().out
    assert out.count("Hausdorff") == 1  # one legend, not the character's and simplify's
    assert "error: over their rest pose and every clip's frames" in out


def test_progress_tells_when_the_props_levels_are_collapsed_and_measured(character_with_props):
    # The props' measurement was silent (only the character's geometry said where it stood): on a
    # large prop, the longest stretch of the run.
    _, _, report, lines = character_with_props
    (other,) = report.others
    label = other.label
    at = lines.index(f"{label}: levels of 320 triangles (no clip skins it)")
    assert lines[at + 1].startswith(f"{label}: collapsing over ") and lines[at + 2] == f"{label}: measuring 2 levels"
    (character,) = report.chains  # its geometry levels say when they collapse too
    assert any(line.startswith(f"{character}: collapsing over ") for line in lines[:at])
    # The skeleton's motion levels say when their joints are chosen and each is re-fitted.
    assert "skin 0: joints of 1 of 2 motion levels chosen (trial re-fits)" in lines
    assert any(line.startswith("skin 0: re-fitting motion level 2 (") for line in lines)
