"""``animlod face``: the procedural face and blendshape faces end to end, and user mistakes."""

from __future__ import annotations

import copy
import json

import numpy as np
import pygltflib
import pytest
from gltf_edits import append_accessor, edit_glb

from animlod.cli import main
from animlod.face_lod.pipeline import run_face_lod
from animlod.io import write_obj
from animlod.synth import icosphere


def _bulging_poses(folder):
    """A pose folder: a sphere as the neutral face and one expression bulging its top."""
    positions, faces = icosphere(2, 0.1)
    folder.mkdir()
    write_obj(folder / "neutral.obj", positions, faces)
    write_obj(folder / "bulge.obj", positions * (1.0 + 0.2 * np.clip(positions[:, 1:2] / 0.1, 0, 1)), faces)
    return folder


def test_face_procedural_writes_levels_manifest_and_plot(tmp_path, capsys):
    out = tmp_path / "face"
    arguments = ["face", "-o", str(out), "--plot", "--repeats", "1", "--expression", "surprise", "--error-frames", "6"]
    assert main(arguments) == 0
    printed = capsys.readouterr().out
    assert "level | triangles | vertices | animated regions | lattices" in printed
    manifest = json.loads((out / "face_lod.json").read_text())
    levels = manifest["levels"]
    assert [level["triangles"] for level in levels] == sorted([level["triangles"] for level in levels], reverse=True)
    assert levels[0]["error"] < 1e-9 < levels[1]["error"] < levels[2]["error"]
    assert levels[-1]["screen_coverage"] == 0.0 and levels[-1]["active_regions"] == []
    assert "2x2x2" in levels[1]["lattices"].values()
    tree = json.loads((out / "face_lod_animation.json").read_text())["levels"]
    assert tree[-1]["regions"] == [] and len(tree[0]["regions"]) > len(tree[1]["regions"])
    # One LoD GLB: the face with one morph target per MPA and the expressions as a weights clip,
    # its levels attached by MSFT_lod (MPAs a level skips are zero targets there).
    glb = pygltflib.GLTF2().load(str(out / "face_lod.glb"))
    base = glb.nodes[glb.scenes[0].nodes[0]]
    assert len(base.extensions["MSFT_lod"]["ids"]) == len(levels) - 1
    assert base.extras["MSFT_screencoverage"] == [level["screen_coverage"] for level in levels]
    assert len(glb.meshes[0].primitives[0].targets) == len(glb.meshes[0].extras["targetNames"]) >= 12
    assert glb.animations[0].channels[0].target.path == "weights"
    coarsest = glb.nodes[base.extensions["MSFT_lod"]["ids"][-1]]
    assert coarsest.extras["animlod"]["targets"] == []
    png = (out / "face_lod.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10000
    assert not list(out.glob(".*.part"))


def test_face_pose_folder(tmp_path, capsys):
    poses = _bulging_poses(tmp_path / "poses")
    out = str(tmp_path / "out")
    arguments = ["face", str(poses), "-o", out, "--ratio", "0.5", "--repeats", "1", "--error-frames", "4"]
    assert main(arguments) == 0
    printed = capsys.readouterr().out
    assert "1 targets" in printed and "poses_lod.glb" in printed
    # Progress before the long steps: a 100k-vertex head printed nothing for two minutes.
    assert printed.startswith(f"{poses}: building the levels\n{poses}: measuring 2 levels over ")
    assert "neutral face neutral.obj, every other file an expression" in printed  # the choice is said
    manifest = json.loads((tmp_path / "out" / "poses_face_lod.json").read_text())
    assert [level["targets"] for level in manifest["levels"]] == [["bulge"], []]
    # A triangle count the face does not have is named as such, for poses and a glTF face alike
    # (the glTF one said "target_ratios: 15.6 outside (0, 1]").
    for source in (poses, tmp_path / "out" / "poses_lod.glb"):
        assert main(["face", str(source), "-o", str(tmp_path / "again"), "--faces", "5000"]) == 2
        assert "face counts: 5000 outside [1, 320] (the face has 320 triangles)" in capsys.readouterr().err

    # A head of several meshes with targets (face, eyes, teeth): the face is the largest, not the first.
    def eye_first(gltf, blob) -> None:
        eye = copy.deepcopy(gltf.meshes[0])
        eye.name = "eye"
        eye.primitives[0].indices = append_accessor(gltf, blob, np.arange(60, dtype=np.uint32), "SCALAR")
        gltf.meshes.append(eye)
        gltf.nodes.append(pygltflib.Node(name="eye", mesh=len(gltf.meshes) - 1))
        gltf.scenes[0].nodes.insert(0, len(gltf.nodes) - 1)

    head = edit_glb(tmp_path / "out" / "poses_lod.glb", tmp_path / "head.glb", eye_first)
    assert main(["face", str(head), "-o", str(tmp_path / "head"), "--ratio", "0.5", "--repeats", "1"]) == 0
    printed = capsys.readouterr().out
    assert "the face is mesh 0 'face' (320 triangles" in printed and "written unchanged: mesh 2 'eye'" in printed


def test_face_run_that_cannot_write_every_file_writes_none(tmp_path, capsys):
    """The LoD GLB, the manifest(s) and the picture land together: before, each was renamed into
    place as it was written, so a run failing on its last file left the new GLB beside an earlier
    run's manifest, and the error named the hidden temporary."""
    poses = _bulging_poses(tmp_path / "poses")
    out = tmp_path / "out"
    quick = ["--repeats", "1", "--error-frames", "2"]
    assert main(["face", str(poses), "-o", str(out), "--ratio", "0.5", *quick]) == 0
    earlier = {path.name: path.read_bytes() for path in out.iterdir()}
    assert sorted(earlier) == ["poses_face_lod.json", "poses_lod.glb"]
    capsys.readouterr()
    (out / "poses_face_lod.png").mkdir()  # the picture, written last, cannot land
    assert main(["face", str(poses), "-o", str(out), "--ratio", "0.25", "--plot", *quick]) == 2
    assert capsys.readouterr().err == f"animlod face: error: {out / 'poses_face_lod.png'}: Is a directory\n"
    assert {path.name: path.read_bytes() for path in out.iterdir() if path.is_file()} == earlier
    assert sorted(path.name for path in out.iterdir()) == ["poses_face_lod.json", "poses_face_lod.png", "poses_lod.glb"]
    # The procedural face: its GLB and manifest do not land without the active tree's manifest.
    procedural = tmp_path / "procedural"
    (procedural / "face_lod_animation.json").mkdir(parents=True)
    assert main(["face", "-o", str(procedural), *quick]) == 2
    assert f"{procedural / 'face_lod_animation.json'}: Is a directory" in capsys.readouterr().err
    assert [path.name for path in procedural.iterdir()] == ["face_lod_animation.json"]


def test_face_of_fewer_triangles_than_levels(tmp_path, capsys):
    """A 2-triangle pose folder was refused ("target_face_counts: 4 outside [1, 2]", an option
    never given: the levels were made at least 4 triangles) while the same face as a glTF was
    not; both get levels of one triangle, said in a note."""
    poses = tmp_path / "square"
    poses.mkdir()
    square, faces = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float), [[0, 1, 2], [0, 2, 3]]
    write_obj(poses / "neutral.obj", square, faces)
    write_obj(poses / "up.obj", square + [0, 0, 0.5], faces)
    for source in (poses, tmp_path / "out" / "square_lod.glb"):  # the second written by the first run
        assert main(["face", str(source), "-o", str(tmp_path / "out"), "--repeats", "1"]) == 0
        printed = capsys.readouterr().out
        assert "levels 2, 3: no fewer triangles than the level before (2 / 1 / 1 / 1)" in printed
        levels = json.loads((tmp_path / "out" / f"{source.stem}_face_lod.json").read_text())["levels"]
        assert [level["triangles"] for level in levels] == [2, 1, 1, 1]
        assert [level["targets"] for level in levels] == [["up"], ["up"], ["up"], []]


def test_face_user_mistakes_exit_2_with_one_line(tmp_path, capsys):
    poses = tmp_path / "one"
    poses.mkdir()
    write_obj(poses / "only.obj", np.eye(3), [[0, 1, 2]])
    assert main(["face", str(poses), "-o", str(tmp_path / "out")]) == 2
    assert "holds 1 OBJ/PLY file" in capsys.readouterr().err
    assert main(["face", "-o", str(tmp_path / "out"), "--ratio", "0.5", "--faces", "100"]) == 2
    assert "ratios and face_counts: give one of them, not both" in capsys.readouterr().err
    assert main(["face", "-o", str(tmp_path / "out"), "--targets", "1", "0.5"]) == 2
    assert "apply to blendshape faces" in capsys.readouterr().err
    assert main(["face", str(tmp_path / "absent.glb"), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "absent.glb" in err and err.count("\n") == 1


def test_face_gltf_without_morph_targets_is_named(tmp_path, capsys):
    from animlod import synth
    from animlod.io import write_glb

    skinned, _ = synth.bending_cylinder_skinned()
    path = tmp_path / "plain.glb"
    write_glb(path, skinned)
    assert main(["face", str(path), "-o", str(tmp_path / "out")]) == 2
    assert "no mesh has morph targets" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # a refused run leaves no empty output folder


def test_face_unknown_expression(tmp_path, capsys):
    assert main(["face", "-o", str(tmp_path / "out"), "--plot", "--expression", "boredom", "--repeats", "1"]) == 2
    assert "no expression 'boredom'" in capsys.readouterr().err


@pytest.mark.parametrize(
    "options, message",
    [
        ({"repeats": 0}, "repeats: must be at least 1, got 0"),  # ran, and timed every level at inf
        ({"error_frames": -1}, "error_frames: must be at least 1, got -1"),
        ({"ratios": [-0.5]}, r"target_ratios: -0\.500000 outside \(0, 1\]"),  # ran, at 4 triangles
        ({"target_fractions": [1.0, 2.0]}, r"target fraction of level 1: 2\.0 is outside \[0, 1\]"),
    ],
)
def test_face_values_no_face_can_take_are_refused_before_the_work(tmp_path, options, message):
    with pytest.raises(ValueError, match=message):
        run_face_lod(None, tmp_path / "out", **options)
    assert not (tmp_path / "out").exists()
