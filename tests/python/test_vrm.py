"""VRM avatars (.vrm: a binary glTF with VRM's extensions, as VRoid Studio and UniVRM write them)
go through the glTF commands like a .glb, come out under the suffix VRM tools look for, and keep
their extensions pointing at the same nodes."""

from __future__ import annotations

from pathlib import Path

import pytest
from gltf_conformance import problems

from animlod import synth
from animlod.batch.spec import read_spec
from animlod.cli import main
from animlod.io import read_lod_chains
from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf import write_glb
from animlod.io.gltf_document import GltfDocument


@pytest.fixture(scope="module")
def avatar(tmp_path_factory) -> Path:
    """The procedural humanoid and its walk as a VRM 1.0 file: a root VRMC_vrm naming its hips."""
    folder = tmp_path_factory.mktemp("vrm")
    character = synth.humanoid()
    write_glb(folder / "humanoid.glb", character, [synth.humanoid_motion(character.skeleton, "walk")])
    builder = GlbBuilder.from_document(GltfDocument(folder / "humanoid.glb"))
    hips = next(i for i, node in enumerate(builder.json["nodes"]) if node.get("name") == "Hips")
    humanoid = {"humanBones": {"hips": {"node": hips}}}
    builder.json.setdefault("extensions", {})["VRMC_vrm"] = {"specVersion": "1.0", "humanoid": humanoid}
    builder.add_extension_used("VRMC_vrm")
    builder.save(folder / "avatar.vrm")
    return folder / "avatar.vrm"


def _hips_name(path: Path) -> str:
    js = GltfDocument(path).json
    return js["nodes"][js["extensions"]["VRMC_vrm"]["humanoid"]["humanBones"]["hips"]["node"]]["name"]


def test_simplify_writes_a_vrm_that_keeps_the_avatar_extension(avatar, tmp_path) -> None:
    assert main(["simplify", str(avatar), "-o", str(tmp_path), "--ratio", "0.5", "--max-frames", "6"]) == 0
    output = tmp_path / "avatar_lod.vrm"
    assert _hips_name(output) == "Hips"
    assert problems(output) == []
    (chain,) = read_lod_chains(output)
    assert len(chain.levels) == 2


def test_character_writes_the_vrm_it_is_given(avatar, tmp_path) -> None:
    output = tmp_path / "chain.vrm"
    arguments = ["--ratio", "0.5", "--solver", "newton", "--max-frames", "6"]
    assert main(["character", str(avatar), "-o", str(output), *arguments]) == 0
    assert _hips_name(output) == "Hips"
    assert problems(output) == []
    (chain,) = read_lod_chains(output)
    assert chain.levels[1].mesh.face_count < chain.levels[0].mesh.face_count


def test_a_folder_of_avatars_is_a_library(avatar) -> None:
    (asset,) = [spec for spec in read_spec(avatar.parent) if spec.input.endswith(".vrm")]
    assert (asset.name, asset.kind) == ("avatar", "gltf")
