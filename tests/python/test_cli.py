"""The animlod command line: info on every format, demo end to end, exit code 2 on user mistakes."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from bvh_edits import with_a_second_root

from animlod import AnimatedMesh, Motion, Skeleton, rotations
from animlod.cli import main
from animlod.io.bvh import write_bvh
from animlod.io.npz import write_npz


def _small_motion() -> Motion:
    skeleton = Skeleton(
        ["hips", "leg", "leg_End"], [-1, 0, 1], [[0, 1, 0], [0, -0.5, 0], [0, -0.5, 0]], end_sites=[False, False, True]
    )
    local = rotations.identity((4, 3))
    local[:, 1] = rotations.from_axis_angle(np.array([1.0, 0, 0]), np.linspace(0, 0.5, 4))
    return Motion(skeleton, np.tile([0.0, 1.0, 0.0], (4, 1)), local, fps=24.0)


def test_info_bvh(tmp_path, capsys):
    path = tmp_path / "clip.bvh"
    write_bvh(path, _small_motion())
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "joints: 2 (+1 end sites), root 'hips'" in out
    assert "frames: 4 at 24 fps" in out
    assert "ROOTs" not in out
    # Two ROOTs: the file's own are named beside the joint read above them.
    two = with_a_second_root(path, tmp_path / "two.bvh", {"ROOT hips": "ROOT prop", "JOINT leg": "JOINT tip"})
    assert main(["info", str(two)]) == 0
    assert "ROOTs: hips, prop, below 'Roots' at the origin" in capsys.readouterr().out


def test_version(capsys):
    import animlod

    assert main(["--version"]) == 0 and capsys.readouterr().out == f"animlod {animlod.__version__}\n"


def test_info_on_what_animlod_writes(tmp_path, capsys):
    """A .tdag file and a LoD manifest: `info` refused them as unknown types."""
    from animlod.io.manifest import write_lod_manifest

    frames = np.random.default_rng(1).normal(size=(2, 4, 3))
    write_npz(tmp_path / "quad.npz", AnimatedMesh([[0, 1, 2], [0, 2, 3]], frames, fps=10.0))
    assert main(["tdag", "build", str(tmp_path / "quad.npz"), "-o", str(tmp_path / "quad.tdag")]) == 0
    write_lod_manifest(tmp_path / "clip_motion_lod.json", "motion",
                       [{"files": ["clip_lod0.bvh"], "joints": 20, "error": 0.0},
                        {"files": ["clip_lod1.bvh"], "joints": 9, "error": 0.25}])  # fmt: skip
    capsys.readouterr()
    assert main(["info", str(tmp_path / "quad.tdag")]) == 0
    assert "frames: 2, vertices: 4, faces: 2" in capsys.readouterr().out
    assert main(["info", str(tmp_path / "clip_motion_lod.json")]) == 0
    out = capsys.readouterr().out
    assert "2 levels of a motion chain" in out and "level 1: 9 joints; error 0.25: clip_lod1.bvh" in out


def test_info_npz(tmp_path, capsys):
    path = tmp_path / "mesh.npz"
    frames = np.random.default_rng(0).normal(size=(3, 4, 3))
    write_npz(path, AnimatedMesh([[0, 1, 2], [0, 2, 3]], frames, fps=10.0))
    assert main(["info", str(path)]) == 0
    assert "vertices: 4, triangles: 2" in capsys.readouterr().out


def test_info_on_a_folder_of_models_describes_each(tmp_path, capsys):
    # It took such a folder for a sequence of frames ("no .obj or .ply frame found").
    write_bvh(tmp_path / "a.bvh", _small_motion())
    write_npz(tmp_path / "b.npz", AnimatedMesh([[0, 1, 2]], np.eye(3)[None], fps=10.0))
    assert main(["info", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert f"{tmp_path / 'a.bvh'}: bvh" in out and f"{tmp_path / 'b.npz'}: npz" in out


def test_info_on_a_glob_of_models_describes_each_and_of_frames_one_sequence(tmp_path, capsys):
    # A glob of models, as `batch` takes it, was read as a frame glob: "expected one of .obj, .ply".
    from animlod.io.meshseq import write_sequence

    write_bvh(tmp_path / "a.bvh", _small_motion())
    write_bvh(tmp_path / "b.bvh", _small_motion())
    assert main(["info", str(tmp_path / "*.bvh")]) == 0
    out = capsys.readouterr().out
    assert f"{tmp_path / 'a.bvh'}: bvh" in out and f"{tmp_path / 'b.bvh'}: bvh" in out
    write_sequence(tmp_path / "walk", AnimatedMesh([[0, 1, 2]], np.tile(np.eye(3), (2, 1, 1)), fps=10.0))
    assert main(["info", str(tmp_path / "walk" / "*.obj")]) == 0
    assert "frames: 2, frame_0000.obj .. frame_0001.obj" in capsys.readouterr().out


def test_info_on_a_library_names_an_unreadable_asset_and_lists_the_rest(tmp_path, capsys):
    # It stopped at the first unreadable asset with its error, so the assets after it were never listed.
    (tmp_path / "a_broken.bvh").write_text("HIERARCHY\nROOT hips\n")
    write_bvh(tmp_path / "b.bvh", _small_motion())
    assert main(["info", str(tmp_path)]) == 2
    captured = capsys.readouterr()
    assert f"{tmp_path / 'a_broken.bvh'}: bvh\n  error: {tmp_path / 'a_broken.bvh'}" in captured.out
    assert f"{tmp_path / 'b.bvh'}: bvh\n  joints: 2" in captured.out
    assert captured.err.strip() == "animlod info: 1 of 2 assets could not be read"
    assert main(["info", str(tmp_path / "a_broken.bvh")]) == 2  # one file: its error alone, as before
    captured = capsys.readouterr()
    assert captured.out == "" and len(captured.err.strip().splitlines()) == 1


def test_info_on_a_folder_of_frame_folders_describes_each_sequence(tmp_path, capsys):
    # A library of sequences (../shared/data/meshseq) exited 2 with "no .obj or .ply frame found".
    from animlod.io.meshseq import write_sequence

    mesh = AnimatedMesh([[0, 1, 2]], np.tile(np.eye(3), (2, 1, 1)), fps=10.0)
    for name in ("walk", "run"):
        write_sequence(tmp_path / "library" / name, mesh)
    write_bvh(tmp_path / "library" / "clips" / "a.bvh", _small_motion())
    assert main(["info", str(tmp_path / "library")]) == 0
    out = capsys.readouterr().out
    for asset, kind in (("clips/a.bvh", "bvh"), ("run", "sequence"), ("walk", "sequence")):
        assert f"{tmp_path / 'library' / asset}: {kind}" in out
    assert out.count("vertices: 3, triangles: 1") == 2
    # The first and last file in reading order: a stray file beside the frames shows at an end.
    assert out.count("frames: 2, frame_0000.obj .. frame_0001.obj") == 2


def test_info_into_a_pipe_closed_early_exits_quietly(tmp_path):
    # `animlod info DIR | head -1`: the reader leaves; not an error of the input.
    for index in range(200):
        write_bvh(tmp_path / f"clip{index:03d}.bvh", _small_motion())
    command = [sys.executable, "-c", "import sys; from animlod.cli import main; sys.exit(main(sys.argv[1:]))"]
    info = subprocess.Popen([*command, "info", str(tmp_path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    info.stdout.readline()
    info.stdout.close()
    assert info.wait(timeout=120) == 141
    assert info.stderr.read() == b""


def test_info_real_files(data_dir, capsys):
    assert main(["info", str(data_dir / "bvh" / "131_01.bvh")]) == 0
    # The naming that BVH clips of other humanoids are matched through, body part by body part.
    assert "joints: 31 (+7 end sites), root 'Hips', CMU naming (23 of 23 body parts)" in capsys.readouterr().out
    assert main(["info", str(data_dir / "bvh" / "dataset-1_run_proud_001.bvh")]) == 0
    assert "root 'joint_Root', Unity naming (21 of 23 body parts)" in capsys.readouterr().out
    assert main(["info", str(data_dir / "gltf" / "Soldier.glb")]) == 0
    out = capsys.readouterr().out
    assert out.count(" with skin ") == 2 and "'Walk'" in out and "2 materials, 2 textures" in out
    assert main(["info", str(data_dir / "gltf" / "Xbot.glb")]) == 0
    out = capsys.readouterr().out
    assert "'Mesh' with skin 0" in out and "'Mesh.001' with skin 0" in out and "Beta_Joints_MAT" in out
    assert "skin: 67 joints, 4 influences per vertex, Mixamo naming (22 of 23 body parts)" in out
    # a folder holding one model file describes that file
    assert main(["info", str(data_dir / "meshseq" / "Flamingo-morph-glTF")]) == 0
    assert "14 morph targets" in capsys.readouterr().out
    assert main(["info", str(data_dir / "meshseq" / "crane")]) == 0
    assert "vertices: 10002, triangles: 20000" in capsys.readouterr().out
    # a folder of sequence folders describes each sequence and model below it
    assert main(["info", str(data_dir / "meshseq")]) == 0
    out = capsys.readouterr().out
    assert "crane: sequence" in out and "face-poses: sequence" in out and "Flamingo.glb: gltf" in out
    # simplify reads a folder as frames: one holding a model names it instead of "no frame found"
    assert main(["simplify", str(data_dir / "meshseq" / "Flamingo-morph-glTF"), "-o", "unused"]) == 2
    assert "holds no .obj or .ply frame but Flamingo.glb: pass one of them" in capsys.readouterr().err
    assert main(["simplify", str(data_dir / "meshseq"), "-o", "unused"]) == 2
    assert "but Flamingo-morph-glTF/Flamingo.glb, crane, face-poses: pass one" in capsys.readouterr().err


@pytest.mark.parametrize(
    "name, content, message",
    [
        ("missing.bvh", None, "does not exist"),
        ("notes.txt", b"hello", "unknown type .txt"),
        ("broken.bvh", b"HIERARCHY\nROOT hips\n{\n", "broken.bvh"),
    ],
)
def test_user_mistakes_exit_2_with_one_line(tmp_path, capsys, name, content, message):
    path = tmp_path / name
    if content is not None:
        path.write_bytes(content)
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_an_output_that_is_the_input_file_is_refused_before_anything_is_written(tmp_path, capsys):
    # `animlod simplify hero.glb -o hero.glb` replaced the file it read with its LoD GLB.
    from animlod import synth
    from animlod.io import write_glb

    character = synth.humanoid()
    source = tmp_path / "hero.glb"
    write_glb(source, character, [synth.humanoid_motion(character.skeleton, "walk", cycles=1)])
    before = source.read_bytes()
    for command in ("simplify", "character"):
        assert main([command, str(source), "-o", str(tmp_path / "." / "hero.glb")]) == 2
        err = capsys.readouterr().err
        assert "hero.glb: is the input file; write the levels to another file" in err and err.count("\n") == 1
    assert source.read_bytes() == before


def test_demo_writes_the_character_and_its_lod_glb(tmp_path, capsys):
    from animlod.io import read_lod_chains
    from animlod.io.gltf import read_skinned

    assert main(["demo", "-o", str(tmp_path)]) == 0
    skinned, motions = read_skinned(tmp_path / "character.glb")
    assert skinned.skeleton.joint_count >= 30
    assert [m.name for m in motions] == ["walk", "run", "jump"]
    (chain,) = read_lod_chains(tmp_path / "character_lod.glb")
    faces = [level.mesh.face_count for level in chain.levels]
    assert faces[0] == skinned.face_count and faces == sorted(faces, reverse=True) and len(faces) == 4
    joints = [level.skeleton.joint_count for level in chain.levels]
    assert joints == sorted(joints, reverse=True) and joints[-1] < joints[0]
    errors = [level.error for level in chain.levels]
    assert errors[0] == 0.0 and errors == sorted(errors)
    assert all(len(level.motions) == 3 for level in chain.levels)
    assert (tmp_path / "summary.txt").read_text().startswith("character.glb:")


@pytest.mark.parametrize(
    "relative, expected",
    [("frames/*.obj", "frames"), ("frames", "frames"), ("frames/", "frames"), ("clip.bvh", "clip")],
)
def test_input_stem_names_outputs_after_the_input(tmp_path, monkeypatch, relative, expected):
    from animlod.io.detect import input_stem

    (tmp_path / "frames").mkdir()
    monkeypatch.chdir(tmp_path)
    assert input_stem(relative) == expected


def test_animlod_debug_shows_the_traceback(tmp_path, monkeypatch):
    monkeypatch.setenv("ANIMLOD_DEBUG", "1")
    with pytest.raises(ValueError, match="does not exist"):
        main(["info", str(tmp_path / "missing.bvh")])


def test_an_interrupted_demo_leaves_the_earlier_outputs_as_they_were(tmp_path, monkeypatch):
    # The new seed's character.glb was written beside the earlier run's character_lod.glb and
    # summary.txt when the minutes-long chain build was interrupted.
    earlier = {name: f"earlier {name}" for name in ("character.glb", "character_lod.glb", "summary.txt")}
    for name, text in earlier.items():
        (tmp_path / name).write_text(text)

    def interrupted(*arguments, **keywords):
        raise KeyboardInterrupt

    monkeypatch.setattr("animlod.pipelines.character.build_character", interrupted)
    assert main(["demo", "-o", str(tmp_path), "--seed", "5"]) == 130
    assert {path.name: path.read_text() for path in tmp_path.iterdir()} == earlier


def test_demo_names_a_negative_seed(tmp_path, capsys):
    assert main(["demo", "-o", str(tmp_path), "--seed", "-1"]) == 2
    assert "--seed: must be >= 0, got -1" in capsys.readouterr().err
