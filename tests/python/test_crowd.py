"""The native crowd benchmark (bench/crowd/animlod_crowd) end to end, under Xvfb: a smoke run on a
hand-built LoD GLB (report parsed, screenshots checked, a level switch seen as the camera backs
away), the Fig. 1 grid and its heat map, and bad input refused with one line.

``make test`` builds the binary and points ANIMLOD_CROWD_BIN at it; elsewhere these tests skip.
"""

from __future__ import annotations

import copy
import os
import shutil
import subprocess
from pathlib import Path

import matplotlib.image
import numpy as np
import pygltflib
import pytest
from crowd_chain import channels_as_pointers, write_hand_built_chain

from animlod.cli import main as cli_main
from animlod.crowd import CrowdError, mode_list, run_crowd, write_heat_map

REQUIRED = ("fps", "frame_ms_p50", "frame_ms_p95", "triangles", "joints", "drawn")
SMALL = {"count": 24, "warmup": 2, "width": 640, "height": 360}


@pytest.fixture(scope="module")
def chain(tmp_path_factory) -> Path:
    return write_hand_built_chain(tmp_path_factory.mktemp("crowd") / "chain.glb")


def _level_pixels(png: Path) -> dict[str, int]:
    """Pixels of each --level-colors tint (chain level 0 green, level 1 yellow) in a screenshot."""
    rgb = matplotlib.image.imread(png)[..., :3].astype(np.float64)
    r, g, b = rgb[..., 0], rgb[..., 1], rgb[..., 2]
    saturated = (rgb.max(axis=-1) - rgb.min(axis=-1) > 0.3) & (b < 0.5 * np.maximum(r, g))
    return {
        "green": int(np.count_nonzero(saturated & (g > 1.5 * r))),
        "yellow": int(np.count_nonzero(saturated & (r > 0.4) & (np.abs(r - g) < 0.2 * r))),
    }


def test_smoke_run_reports_every_mode_and_shows_a_level_switch(binary, chain, tmp_path) -> None:
    near, far = tmp_path / "near.png", tmp_path / "far.png"
    report = run_crowd(
        [chain], frames=12, modes="G+MLoD,Original,GLoD,MLoD,G+MLoD+skip", path="pullback", pixel_error=1.0,
        level_colors=True, screenshots=[(0, near), (11, far)], json_path=tmp_path / "crowd.json", **SMALL,
    )  # fmt: skip
    assert report.renderer
    assert set(report.modes) == {"G+MLoD", "Original", "GLoD", "MLoD", "G+MLoD+skip"}
    for name, mode in report.modes.items():
        assert all(isinstance(mode[key], (int, float)) and mode[key] >= 0 for key in REQUIRED), name
        assert mode["fps"] > 0 and 0 < mode["drawn"] <= SMALL["count"]
        assert mode["measured_frames"] == 12 - 2, name  # the screenshots' frames are out of every mode
    modes = report.modes
    original = modes["Original"]
    assert original["triangles"] == pytest.approx(original["drawn"] * 3664)  # every drawn character at level 0
    assert len(modes["G+MLoD"]["levels"]) == 2 and modes["G+MLoD"]["levels"][1] > 0  # level 1 in use
    # Per drawn character: GLoD draws fewer triangles with every joint, MLoD every triangle with fewer joints.
    per = {name: (m["triangles"] / m["drawn"], m["joints"] / m["drawn"]) for name, m in modes.items()}
    assert per["GLoD"][0] < per["Original"][0] and per["GLoD"][1] == pytest.approx(per["Original"][1])
    assert per["MLoD"][0] == pytest.approx(per["Original"][0]) and per["MLoD"][1] < per["Original"][1]
    assert per["G+MLoD"][0] < per["Original"][0] and per["G+MLoD"][1] < per["Original"][1]
    assert per["G+MLoD+skip"][1] < per["G+MLoD"][1]  # skipped poses are not re-animated
    assert not any(mode["same_work_as_original"] for mode in modes.values())
    levels = report.data["chains"][0]["nodes"][0]["levels"]
    cells = sorted((level["mesh_level"], level["motion_level"], level["chain_level"]) for level in levels)
    assert cells == [(0, 0, 0), (0, 1, -1), (1, 0, -1), (1, 1, 1)]
    assert (tmp_path / "crowd.json").is_file()
    # The screenshots: characters on the background, and the level colours change as the camera backs away.
    pixels_near, pixels_far = _level_pixels(near), _level_pixels(far)
    image = matplotlib.image.imread(near)
    assert image.shape[:2] == (SMALL["height"], SMALL["width"]) and image.std() > 0.02
    assert pixels_near["green"] > 500 and pixels_near["yellow"] > 500
    assert pixels_far["yellow"] > 0 and pixels_far["green"] == 0


def test_a_character_chain_of_unnamed_joints_loads(binary, tmp_path) -> None:
    # animlod names an unnamed joint node<i>, and so do a character chain's reduced skeletons;
    # the crowd names the input's unnamed root alike, so that every level shares it (RiggedFigure's
    # joints are unnamed: its chain was refused).
    from animlod import synth
    from animlod.io import write_glb
    from animlod.pipelines.character import build_character

    character = synth.humanoid()
    write_glb(tmp_path / "named.glb", character, [synth.humanoid_motion(character.skeleton, "walk")])
    gltf = pygltflib.GLTF2().load(tmp_path / "named.glb")
    for joint in gltf.skins[0].joints:
        gltf.nodes[joint].name = None
    gltf.save(tmp_path / "unnamed.glb")
    build_character(tmp_path / "unnamed.glb", tmp_path / "lod.glb", [0.5], solver="newton", frame_budget=12)
    report = run_crowd([tmp_path / "lod.glb"], frames=2, modes="MLoD", **SMALL)
    assert report.modes["MLoD"]["drawn"] > 0


def test_modes_a_one_level_chain_leaves_alike_are_named_as_the_same_work(binary, tmp_path) -> None:
    # A GLB without MSFT_lod gives GLoD and MLoD nothing to choose: their "speed-ups" over Original
    # are the spread of the measurement (the first mode measured at half the others' FPS before
    # every mode warmed up ahead of the first round), and the report says so.
    from animlod import synth
    from animlod.io import write_glb

    character = synth.humanoid()
    write_glb(tmp_path / "plain.glb", character, [synth.humanoid_motion(character.skeleton, "walk")])
    report = run_crowd([tmp_path / "plain.glb"], frames=3, modes="Original,GLoD,MLoD", **SMALL)
    alike = {name: mode["same_work_as_original"] for name, mode in report.modes.items()}
    assert alike == {"Original": False, "GLoD": True, "MLoD": True}
    assert "GLoD, MLoD: the same work per frame as Original" in report.markdown


def test_the_meshes_of_one_character_pose_one_skeleton(binary, chain, tmp_path) -> None:
    # A character in parts (a body and its eyes, BrainStem's meshes) has a chain per mesh on one
    # skin. Each chain chose its own level, so a near part at motion level 0 and a far-off part's
    # coarser level posed two skeletons: MLoD animated more joints than Original.
    gltf = pygltflib.GLTF2().load(chain)
    base = next(i for i, node in enumerate(gltf.nodes) if "MSFT_lod" in (node.extensions or {}))
    (level,) = gltf.nodes[base].extensions["MSFT_lod"]["ids"]
    coarse = copy.deepcopy(gltf.nodes[level])
    coarse.extras["animlod"]["error"] = 1e-9  # this part always takes its coarser level
    gltf.nodes.append(coarse)
    part = copy.deepcopy(gltf.nodes[base])
    part.name, part.extensions = "eyes", {"MSFT_lod": {"ids": [len(gltf.nodes) - 1]}}
    gltf.nodes.append(part)
    gltf.scenes[gltf.scene or 0].nodes.append(len(gltf.nodes) - 1)
    gltf.save(tmp_path / "parts.glb")
    report = run_crowd([tmp_path / "parts.glb"], frames=3, modes="Original,MLoD", pixel_error=1.0, **SMALL)
    original, reduced = report.modes["Original"], report.modes["MLoD"]
    assert reduced["drawn"] == original["drawn"] > 0
    assert reduced["joints"] <= original["joints"] and reduced["palette_joints"] <= original["palette_joints"]


def test_a_chain_named_vrm_loads_as_the_glb_it_is(binary, chain, tmp_path) -> None:
    # animlod writes a VRM avatar's chain as .vrm; the loader took every name but .glb for JSON.
    renamed = tmp_path / "avatar_character.vrm"
    shutil.copyfile(chain, renamed)
    report = run_crowd([renamed], frames=2, modes="Original", **SMALL)
    assert report.modes["Original"]["drawn"] > 0


def test_a_chain_without_scenes_draws_one_level_per_character(binary, chain, tmp_path) -> None:
    # Without scenes every root node is drawn, and a chain's lower levels are roots too: each
    # character drew all its levels at once.
    gltf = pygltflib.GLTF2().load(chain)
    gltf.scene, gltf.scenes = None, []
    gltf.save(tmp_path / "no_scenes.glb")
    reports = [run_crowd([path], frames=2, modes="Original", **SMALL) for path in (chain, tmp_path / "no_scenes.glb")]
    with_scenes, without = (report.modes["Original"] for report in reports)
    assert without["triangles"] / without["drawn"] == with_scenes["triangles"] / with_scenes["drawn"]


def _figure_pixels(image: np.ndarray) -> int:
    """Pixels of untinted characters (light grey) in a screenshot: none where the camera looks
    away from the crowd, as at the end of the default walk through it."""
    rgb = image[..., :3]
    return int(np.count_nonzero((rgb.max(axis=-1) - rgb.min(axis=-1) < 0.06) & (rgb.mean(axis=-1) > 0.3)))


def test_joints_moved_through_animation_pointers_move_alike(binary, chain, tmp_path) -> None:
    # Debian's tinygltf drops every channel without a target node while parsing, so a chain whose
    # clips move the joints through KHR_animation_pointer was refused ("no animation moves its
    # skeleton"); the crowd now resolves the pointers first and draws the same frames.
    pointed = _edited(chain, tmp_path, channels_as_pointers)
    shots = {}
    for name, path in (("nodes", chain), ("pointers", pointed)):
        shots[name] = tmp_path / f"{name}.png"
        run_crowd([path], frames=8, modes="Original", screenshots=[(3, shots[name])], **SMALL)
    nodes, pointers = (matplotlib.image.imread(shots[name]) for name in ("nodes", "pointers"))
    assert _figure_pixels(nodes) > 1000 and np.array_equal(nodes, pointers)


def test_opengl_3_3_with_orphaned_uploads(binary, chain, monkeypatch) -> None:
    """The GL 3.3 core path (no persistent mapping): Mesa asked for a 3.3 context."""
    monkeypatch.setenv("MESA_GL_VERSION_OVERRIDE", "3.3")
    report = run_crowd([chain], frames=3, modes="G+MLoD", extra_args=["--upload", "orphan"], **SMALL)
    assert report.data["palette_upload"] == "orphaned"
    if "Mesa" in report.data["gl_version"]:
        assert report.data["gl_version"].startswith("3.3")
    assert report.modes["G+MLoD"]["fps"] > 0 and report.modes["G+MLoD"]["drawn"] > 0


def test_grid_gives_one_cell_per_level_and_a_heat_map(binary, chain, tmp_path) -> None:
    report = run_crowd([chain], frames=3, grid=True, **SMALL)
    cells = report.data["grid"]
    assert [(c["mesh_level"], c["motion_level"]) for c in cells] == [(0, 0), (0, 1), (1, 0), (1, 1)]
    assert all(c["fps"] > 0 for c in cells)
    assert cells[2]["triangles"] == pytest.approx(cells[0]["triangles"] / 2, rel=0.01)
    assert cells[1]["joints"] < cells[0]["joints"] and cells[3]["joints"] == pytest.approx(cells[1]["joints"])
    write_heat_map(cells, tmp_path / "fig1.png")
    assert matplotlib.image.imread(tmp_path / "fig1.png").shape[0] > 100


def _second_character(gltf: pygltflib.GLTF2) -> None:
    """A copy of every node and skin beside the original (its own skeletons and levels), moved by
    no animation: a scene of two characters, each with its own clips."""
    nodes, skins = len(gltf.nodes), len(gltf.skins)
    for node in copy.deepcopy(gltf.nodes):
        node.children = [child + nodes for child in node.children or []] or None
        node.skin = None if node.skin is None else node.skin + skins
        if node.extensions and "MSFT_lod" in node.extensions:
            node.extensions["MSFT_lod"]["ids"] = [level + nodes for level in node.extensions["MSFT_lod"]["ids"]]
        if node.extras and "animlod_grid" in node.extras:
            node.extras["animlod_grid"] = [[cell + nodes for cell in row] for row in node.extras["animlod_grid"]]
        gltf.nodes.append(node)
    for skin in copy.deepcopy(gltf.skins[:skins]):
        skin.joints = [joint + nodes for joint in skin.joints]
        skin.skeleton = None if skin.skeleton is None else skin.skeleton + nodes
        gltf.skins.append(skin)
    scene = gltf.scenes[gltf.scene or 0]
    scene.nodes += [root + nodes for root in scene.nodes]


def test_a_scene_of_two_characters_draws_both_at_every_level(binary, chain, tmp_path) -> None:
    # The clips are the first character's; the second one's reduced skeletons have no level of
    # them, and the crowd refused the file ("motion level 1 has no animation for clip 'walk'").
    # The second character stands still at every level, as glTF viewers show it.
    two = run_crowd([_edited(chain, tmp_path, _second_character)], frames=2, modes="Original,G+MLoD", **SMALL)
    one = run_crowd([chain], frames=2, modes="Original,G+MLoD", **SMALL)
    for mode in ("Original", "G+MLoD"):
        assert two.modes[mode]["triangles"] > one.modes[mode]["triangles"] > 0


def _edited(chain: Path, tmp_path: Path, edit) -> Path:
    gltf = pygltflib.GLTF2.load(str(chain))
    edit(gltf)
    out = tmp_path / "edited.glb"
    gltf.save_binary(str(out))
    return out


def _no_skin(gltf: pygltflib.GLTF2) -> None:
    for node in gltf.nodes:
        node.skin = None


def _no_animation(gltf: pygltflib.GLTF2) -> None:
    gltf.animations = []


def _other_root(gltf: pygltflib.GLTF2) -> None:
    gltf.nodes[gltf.skins[1].joints[0]].name = "Pelvis"  # the reduced skeleton's root


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_no_skin, "no skinned mesh"),
        (_no_animation, "no animation moves its skeleton"),
        (_other_root, "must share a skeleton root"),
    ],
)
def test_bad_chains_are_refused_with_one_line(binary, chain, tmp_path, edit, message) -> None:
    broken = _edited(chain, tmp_path, edit)
    with pytest.raises(CrowdError, match=message) as caught:
        run_crowd([broken], frames=2, **SMALL)
    assert caught.value.bad_input
    assert str(broken) in str(caught.value)


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (["--modes", "Fast"], "unknown mode 'Fast'"),
        (["--modes", "Original,"], "--modes: empty item in 'Original,'"),
        (["--count", "0"], "--count"),
        (["--path", "up"], "--path"),
    ],
)
def test_bad_arguments_exit_2_with_one_line(binary, chain, arguments, message) -> None:
    completed = subprocess.run([str(binary), str(chain), *arguments], capture_output=True, text=True, check=False)
    assert completed.returncode == 2
    assert completed.stderr.count("\n") == 1 and message in completed.stderr


def test_a_folder_a_missing_file_or_no_gltf_is_one_line(binary, tmp_path) -> None:
    (tmp_path / "empty.glb").write_bytes(b"")
    (tmp_path / "walk.bvh").write_text("HIERARCHY\nROOT Hips\n{\n")
    cases = [
        (tmp_path, "not a regular file"),
        (tmp_path / "missing.glb", "no such file"),
        (tmp_path / "empty.glb", "empty file"),
        (tmp_path / "walk.bvh", "not a glTF character: neither a GLB"),
    ]
    for path, message in cases:
        completed = subprocess.run([str(binary), str(path)], capture_output=True, text=True, check=False)
        assert completed.returncode == 2 and message in completed.stderr and completed.stderr.count("\n") == 1


def test_no_display_is_one_line_and_exit_3(binary, chain) -> None:
    environment = {key: value for key, value in os.environ.items() if key not in ("DISPLAY", "WAYLAND_DISPLAY")}
    completed = subprocess.run([str(binary), str(chain), "--count", "2"], capture_output=True, text=True,
                               env=environment, check=False, timeout=60)  # fmt: skip
    assert completed.returncode == 3
    assert "no display" in completed.stderr and completed.stderr.count("\n") == 1


def test_cli_says_the_machine_has_no_display_with_exit_3(binary, chain, monkeypatch, capsys) -> None:
    monkeypatch.setenv("DISPLAY", ":77")  # set, so no Xvfb is started, and no server behind it
    assert cli_main(["crowd", str(chain), "--count", "2", "--frames", "2"]) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "animlod crowd: error:" in err


def test_cli_refuses_an_unknown_mode_before_running(capsys) -> None:
    assert cli_main(["crowd", "--modes", "Original,Faster"]) == 2
    assert "mode 'Faster'" in capsys.readouterr().err


def test_cli_refuses_a_json_it_could_not_write_before_running(tmp_path, capsys) -> None:
    (tmp_path / "notes.txt").write_text("a file, not a folder")
    assert cli_main(["crowd", "--json", str(tmp_path / "notes.txt" / "crowd.json")]) == 2
    assert f"--json: {tmp_path / 'notes.txt' / 'crowd.json'}: {tmp_path / 'notes.txt'} is not a folder" in (
        capsys.readouterr().err
    )


def test_cli_names_the_element_of_a_truncated_chain_before_running(tmp_path, capsys) -> None:
    # The renderer's loader said only "Invalid glTF binary."; the reader names what is wrong.
    whole = tmp_path / "whole.glb"
    write_hand_built_chain(whole)
    truncated = tmp_path / "truncated.glb"
    truncated.write_bytes(whole.read_bytes()[:200])
    assert cli_main(["crowd", str(truncated), "--count", "2", "--frames", "2"]) == 2
    assert f"{truncated}: GLB header: file is truncated" in capsys.readouterr().err


def test_mode_list() -> None:
    assert mode_list("all") == [
        "Original",
        "GLoD",
        "MLoD",
        "G+MLoD",
        "Original+skip",
        "GLoD+skip",
        "MLoD+skip",
        "G+MLoD+skip",
    ]
    assert mode_list("GLoD,MLoD+skip") == ["GLoD", "MLoD+skip"]
    assert mode_list(["GLoD", "MLoD"], frame_skipping=True) == ["GLoD+skip", "MLoD+skip"]
    with pytest.raises(ValueError, match="'Fast'"):
        mode_list("Fast")


def test_eight_influences_draw_as_the_same_four_in_one_set(binary, tmp_path) -> None:
    # JOINTS_1 / WEIGHTS_1 were dropped (the first four weights renormalised): a file whose
    # influences are spread over both sets must draw as the same influences in one set.
    from gltf_edits import append_accessor, edit_glb

    from animlod import synth
    from animlod.io.gltf import write_glb
    from animlod.io.gltf_document import GltfDocument

    skinned = synth.humanoid(seed=0)
    write_glb(tmp_path / "four.glb", skinned, [synth.humanoid_motion(skinned.skeleton, "walk", cycles=1, seed=0)])

    def spread(gltf, blob) -> None:  # each vertex's largest influence moved to the second set
        attributes = gltf.meshes[0].primitives[0].attributes
        document = GltfDocument(tmp_path / "four.glb")
        for name in ("JOINTS", "WEIGHTS"):
            values = document.accessor(getattr(attributes, f"{name}_0"), name)
            first, second = values.copy(), np.zeros_like(values)
            first[:, 0], second[:, 3] = 0, values[:, 0]
            setattr(attributes, f"{name}_0", append_accessor(gltf, blob, first, "VEC4"))
            setattr(attributes, f"{name}_1", append_accessor(gltf, blob, second, "VEC4"))

    edit_glb(tmp_path / "four.glb", tmp_path / "eight.glb", spread)
    shots = {name: tmp_path / f"{name}.png" for name in ("four", "eight")}
    for name, shot in shots.items():
        run_crowd([tmp_path / f"{name}.glb"], frames=8, modes="Original", screenshots=[(3, shot)], **SMALL)
    four, eight = (matplotlib.image.imread(shot) for shot in shots.values())
    differing = np.count_nonzero(np.abs(four - eight).max(axis=-1) > 0.02) / four[..., 0].size
    assert _figure_pixels(four) > 1000 and differing < 0.001, differing  # blended in another order: edge pixels
