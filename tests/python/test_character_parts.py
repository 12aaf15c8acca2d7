"""A character in parts: a mesh whose skin lists some of the body's joints (a helmet on the head,
Soldier's visor) plays the body's motion levels (pipelines/skin_parts.py, character.py).

It kept its own joints, animated by the input's clips, at every level: where a level froze the
head, the body's head stayed in its key posture and the helmet moved on without it (Soldier's
visor: 7.8 % of the figure's diagonal apart at its 4-joint level).
"""

from __future__ import annotations

import numpy as np
import pygltflib
import pytest

from animlod import synth
from animlod.io import read_lod_chains, write_glb
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines.character import build_character

QUICK = {"frame_budget": 12, "measured_frames": 2}


def _box(centre: np.ndarray, half: float) -> tuple[np.ndarray, np.ndarray]:
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], np.float32)
    faces = [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
             [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]  # fmt: skip
    return (centre + half * corners).astype(np.float32), np.array(faces, np.uint16)


@pytest.fixture(scope="module")
def helmeted(tmp_path_factory):
    """The procedural humanoid walking, with a helmet whose own skin lists Neck and Head (bound
    in the body's pose) and weighs every vertex to Head; its LoD GLB and the build's report."""
    folder = tmp_path_factory.mktemp("parts")
    plain = folder / "humanoid.glb"
    character = synth.humanoid()
    write_glb(plain, character, [synth.humanoid_motion(character.skeleton, "walk")])
    doc = GltfDocument(plain)
    builder = GlbBuilder.from_document(doc)
    nodes = builder.json["nodes"]
    by_name = {node.get("name"): index for index, node in enumerate(nodes)}
    body_skin = builder.json["skins"][0]
    binds = np.asarray(doc.accessor(body_skin["inverseBindMatrices"], "test"), np.float32).reshape(-1, 16)
    slots = [body_skin["joints"].index(by_name[name]) for name in ("Neck", "Head")]
    skin = builder.append(
        "skins", {"joints": [by_name["Neck"], by_name["Head"]], "inverseBindMatrices": builder.add(binds[slots])}
    )
    positions, faces = _box(doc.rest_world_matrix(by_name["Head"])[:3, 3] + [0.0, 0.1, 0.0], 0.12)
    joints = np.zeros((len(positions), 4), np.uint16)
    joints[:, 0] = 1  # Head
    weights = np.zeros((len(positions), 4), np.float32)
    weights[:, 0] = 1.0
    attributes = {"POSITION": builder.add(positions, bounds=True), "JOINTS_0": builder.add(joints),
                  "WEIGHTS_0": builder.add(weights)}  # fmt: skip
    primitive = {"attributes": attributes, "indices": builder.add(faces.reshape(-1, 1))}
    mesh = builder.append("meshes", {"name": "helmet", "primitives": [primitive]})
    helmet = builder.append("nodes", {"name": "helmet", "mesh": mesh, "skin": skin})
    builder.json["scenes"][0]["nodes"].append(helmet)
    source = folder / "helmeted.glb"
    builder.save(source)
    output = folder / "helmeted_lod.glb"
    report = build_character(source, output, [0.5, 0.25, 0.1], solver="newton", **QUICK)
    return output, report


def test_a_helmet_on_the_head_plays_the_bodys_motion_levels(helmeted) -> None:
    output, report = helmeted
    assert "skin 1: its joints belong to skin 0; it plays that skin's motion levels" in report.notes
    chains = {chain.name: chain for chain in read_lod_chains(output)}
    body, helmet = chains["skinned mesh"].levels, chains["helmet"].levels
    assert helmet[0].skeleton.names == ["Neck", "Head"]  # the input, as it was
    frozen_heads = 0
    for body_level, helmet_level in zip(body[1:], helmet[1:]):
        # One skeleton, bound alike and played by the same clips: posed by the same joint matrices.
        assert helmet_level.skeleton.names == body_level.skeleton.names
        np.testing.assert_allclose(helmet_level.mesh.inverse_bind, body_level.mesh.inverse_bind, atol=1e-6)
        for mine, theirs in zip(helmet_level.motions, body_level.motions):
            np.testing.assert_allclose(mine.local_rotations, theirs.local_rotations, atol=1e-6)
            np.testing.assert_allclose(mine.root_positions, theirs.root_positions, atol=1e-6)
        frozen_heads += "Head" not in body_level.skeleton.names
    assert frozen_heads >= 1  # the case that tore the helmet off


def test_the_helmets_levels_share_the_bodys_skins(helmeted) -> None:
    output, _ = helmeted
    nodes = GltfDocument(output).json["nodes"]
    by_name = {node.get("name"): node for node in nodes}
    for level in (1, 2, 3):
        assert by_name[f"helmet_LOD{level}"]["skin"] == by_name[f"skinned mesh_LOD{level}"]["skin"]
    assert by_name["helmet"]["skin"] != by_name["skinned mesh"]["skin"]


def test_a_crowd_poses_the_helmet_at_the_bodys_motion_level(binary, helmeted, tmp_path) -> None:
    # The body's chain and the helmet's choose their levels apart; a crowd draws the finest motion
    # level either chose for both, as for the meshes of one skin: here the body stays at level 0
    # and the helmet would take its coarsest, and MLoD poses exactly what Original poses.
    from animlod.crowd import run_crowd

    output, _ = helmeted
    gltf = pygltflib.GLTF2().load(output)
    for node in gltf.nodes:
        info = (node.extras or {}).get("animlod")
        if info and info.get("level", -1) > 0:
            info["error"] = 1e-9 if node.name.startswith("helmet") else 1e9
    gltf.save(tmp_path / "forced.glb")
    report = run_crowd([tmp_path / "forced.glb"], frames=3, modes="Original,MLoD", pixel_error=1.0, count=12,
                       warmup=2, width=320, height=180)  # fmt: skip
    original, reduced = report.modes["Original"], report.modes["MLoD"]
    assert reduced["drawn"] == original["drawn"] > 0
    assert reduced["joints"] == original["joints"]
