"""How `animlod character` names the clips of its motion levels and says whose skeleton each one
poses (pipelines/character.py), so that a runtime choosing clips by name or by their extras plays
each skeleton's own."""

from __future__ import annotations

from pathlib import Path

import pytest
from simplify_inputs import two_bone_tube

from animlod.cli import main
from animlod.io import write_glb
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines.character import build_character

QUICK = {"frame_budget": 12, "measured_frames": 2}


def _one_character(folder: Path) -> Path:
    """The two-bone tube bending its elbow, as animlod writes it: one skin, one animation."""
    skinned, motion = two_bone_tube(12)
    motion.name = "bend"
    path = folder / "tube.glb"
    write_glb(path, skinned, [motion])
    return path


def _doubled(source: Path, target: Path) -> Path:
    """``source`` with a copy of its scene's node trees beside them (the meshes shared, skins of
    their own over the copied joints), the animations driving both, as a file of two characters
    of one rig is."""
    builder = GlbBuilder.from_document(GltfDocument(source))
    js = builder.json
    nodes = js["nodes"]
    copies: dict[int, int] = {}

    def copy_tree(node: int) -> int:
        copies[node] = len(nodes)
        nodes.append({key: value for key, value in nodes[node].items() if key != "children"})
        nodes[copies[node]]["children"] = [copy_tree(child) for child in nodes[node].get("children", [])]
        return copies[node]

    js["scenes"][0]["nodes"] += [copy_tree(root) for root in list(js["scenes"][0]["nodes"])]
    for copy in (copies[node] for node in copies if "skin" in nodes[node]):
        skin = js["skins"][nodes[copy]["skin"]]
        js["skins"].append({**skin, "joints": [copies[joint] for joint in skin["joints"]]})
        if "skeleton" in skin:
            js["skins"][-1]["skeleton"] = copies[skin["skeleton"]]
        nodes[copy]["skin"] = len(js["skins"]) - 1
    for animation in js["animations"]:
        animation["channels"] += [
            {**channel, "target": {**channel["target"], "node": copies[channel["target"]["node"]]}}
            for channel in animation["channels"]
            if channel["target"].get("node") in copies
        ]
    builder.save(target)
    return target


def _level_clips(doc: GltfDocument) -> list[dict]:
    return [animation for animation in doc.json["animations"] if "animlod" in animation.get("extras", {})]


def _posed_by_clips_of_their_skin(doc: GltfDocument) -> None:
    """Every level node at a motion level m >= 1 finds, among the level clips of m whose
    extras.animlod.skins hold its chain's input skin, one per input clip, each posing the level
    node's own skeleton (its channels on that skin's joints)."""
    nodes = doc.json["nodes"]
    for base in (node for node in nodes if "animlod_grid" in node.get("extras", {})):
        for row in base["extras"]["animlod_grid"]:
            for level_node in row[1:]:
                motion_level = nodes[level_node]["extras"]["animlod"]["motion_level"]
                joints = set(doc.json["skins"][nodes[level_node]["skin"]]["joints"])
                chosen = [
                    clip
                    for clip in _level_clips(doc)
                    if clip["extras"]["animlod"]["motion_level"] == motion_level
                    and base["skin"] in clip["extras"]["animlod"]["skins"]
                ]
                assert sorted(clip["extras"]["animlod"]["clip"] for clip in chosen) == [0], base["name"]
                assert all(channel["target"]["node"] in joints for clip in chosen for channel in clip["channels"])


def test_one_skeletons_level_clips_keep_their_names(tmp_path: Path) -> None:
    # The common case, which README documents: `<clip>@motion<m>`, and the extras name its skin.
    output = tmp_path / "lod.glb"
    build_character(_one_character(tmp_path), output, [0.5], solver="newton", **QUICK)
    doc = GltfDocument(output)
    clips = _level_clips(doc)
    assert [clip["name"] for clip in clips] == ["bend@motion1"]
    assert clips[0]["extras"]["animlod"] == {"clip": 0, "motion_level": 1, "skins": [0]}
    _posed_by_clips_of_their_skin(doc)


def test_two_skeletons_driven_by_one_clip_get_level_clips_of_distinct_names_saying_their_skin(
    tmp_path: Path,
) -> None:
    """Two characters animated by one animation got two level clips both named `bend@motion1`,
    their extras the same {clip, motion_level}: a runtime choosing by name or by those extras
    could play one skeleton's clip on the other's level (which then stood still)."""
    output = tmp_path / "lod.glb"
    two = _doubled(_one_character(tmp_path), tmp_path / "two.glb")
    report = build_character(two, output, [0.5], solver="newton", **QUICK)
    assert len(report.chains) == 2
    doc = GltfDocument(output)
    clips = _level_clips(doc)
    assert [clip["name"] for clip in clips] == ["bend@skin0@motion1", "bend@skin1@motion1"]
    assert [clip["extras"]["animlod"]["skins"] for clip in clips] == [[0], [1]]
    _posed_by_clips_of_their_skin(doc)


def test_two_dev_characters_driven_by_one_clip_get_distinct_level_clips(data_dir: Path, tmp_path: Path) -> None:
    # The hunt's shape on a real file: the figure and a copy of its whole node tree beside it.
    source = data_dir / "gltf" / "RiggedFigure.glb"
    if not source.exists():
        pytest.skip(f"{source} not available")
    output = tmp_path / "lod.glb"
    build_character(_doubled(source, tmp_path / "two.glb"), output, [0.5, 0.25], solver="newton", **QUICK)
    doc = GltfDocument(output)
    names = [clip["name"] for clip in _level_clips(doc)]
    assert len(names) == 4 and len(set(names)) == 4
    _posed_by_clips_of_their_skin(doc)


def test_motion_names_the_second_character_it_leaves_out(tmp_path: Path) -> None:
    """`animlod motion` takes one skeleton: the second character's mesh was counted among meshes
    "on other joints, bound in another pose or with unnamed morph targets", three reasons for one."""
    from animlod.pipelines.motion import build_motion_levels

    source = _doubled(_one_character(tmp_path), tmp_path / "pair.glb")
    report = build_motion_levels(source, tmp_path / "levels", levels=2)
    (note,) = [note for note in report.notes if "not in the levels' GLBs" in note]
    assert note.endswith("skinned mesh not in the levels' GLBs: node 5 'skinned mesh' (on another skeleton) "
                         "(`--skin` picks another character; `animlod character` takes every skin)")  # fmt: skip


def test_motion_takes_the_character_skin_picks(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`--skin` picks the other character of a file of two: until 2026-12-07 `motion` took the body
    whose skin lists the most joints, and the other could not have motion levels of its own."""
    builder = GlbBuilder.from_document(GltfDocument(_doubled(_one_character(tmp_path), tmp_path / "pair.glb")))
    builder.json["nodes"][5]["name"] = "Body2"  # the second figure's skinned node, as Blender names objects
    source = tmp_path / "named.glb"
    builder.save(source)
    for skin in ("1", "Body2"):
        assert main(["motion", str(source), "-o", str(tmp_path / skin), "--levels", "2", "--skin", skin]) == 0
        assert "not in the levels' GLBs: node 2 'skinned mesh' (on another skeleton)" in capsys.readouterr().err
    assert main(["motion", str(source), "-o", str(tmp_path / "other"), "--skin", "hat"]) == 2
    assert capsys.readouterr().err.strip() == (
        f"animlod motion: error: {source}: skin 'hat': not in the file (skinned meshes use skins: 0, 1)"
    )
    assert not (tmp_path / "other").exists()
