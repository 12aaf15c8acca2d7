"""input_kind: which reader a CLI path needs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from animlod.io import FormatError
from animlod.io.detect import assets_in, input_kind, unread_models_note


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("a.bvh", "bvh"),
        ("a.glb", "gltf"),
        ("a.GLTF", "gltf"),
        ("a.npz", "npz"),
        ("a.obj", "sequence"),
        ("a.PLY", "sequence"),
    ],
)
def test_kind_follows_the_suffix(tmp_path: Path, name: str, kind: str) -> None:
    (tmp_path / name).write_bytes(b"")
    assert input_kind(tmp_path / name) == kind


def test_folders_and_globs_are_sequences(tmp_path: Path) -> None:
    (tmp_path / "frame_1.obj").write_bytes(b"")
    assert input_kind(tmp_path) == "sequence"
    assert input_kind(str(tmp_path / "frame_*.obj")) == "sequence"


def test_unknown_missing_or_unmatched_paths(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_bytes(b"")
    with pytest.raises(FormatError, match=r"notes.txt: file: unknown type .txt; expected .bvh, .glb"):
        input_kind(tmp_path / "notes.txt")
    with pytest.raises(FormatError, match="file: does not exist"):
        input_kind(tmp_path / "gone.bvh")
    with pytest.raises(FormatError, match="pattern: matches no file"):
        input_kind(str(tmp_path / "*.ply"))


def test_a_folder_of_models_without_frames_names_them(tmp_path: Path) -> None:
    # `animlod simplify FOLDER` on a folder holding one .glb said "no .obj or .ply frame found".
    (tmp_path / "bird.glb").write_bytes(b"")
    (tmp_path / "notes.txt").write_bytes(b"")
    with pytest.raises(FormatError, match=r"folder: holds no .obj or .ply frame but bird.glb: pass one of them"):
        input_kind(tmp_path)
    (tmp_path / "bird_0001.obj").write_bytes(b"")
    assert input_kind(tmp_path) == "sequence"


def test_a_folder_of_frame_folders_names_them(tmp_path: Path) -> None:
    for name in ("b_walk", "a_run", "c_jump", "d_idle"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "frame_0001.ply").write_bytes(b"")
    with pytest.raises(FormatError, match=r"holds no .obj or .ply frame but a_run, b_walk, c_jump and more: pass one"):
        input_kind(tmp_path)


_TRIANGLE = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
_QUAD = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n"


def test_a_folder_of_separate_meshes_is_a_library_not_a_sequence(tmp_path: Path) -> None:
    # Props as loose OBJ/PLY files (an asset pack; assimp's OBJ test folder): each an asset of
    # batch and info, where the whole folder was one sequence that failed at its second file.
    props = tmp_path / "props"
    props.mkdir()
    (props / "rock_2.obj").write_bytes(_QUAD)
    (props / "rock_10.obj").write_bytes(_TRIANGLE)
    (props / "tree.obj").write_bytes(_QUAD)
    assert list(assets_in(tmp_path)) == [props / "rock_2.obj", props / "rock_10.obj", props / "tree.obj"]
    with pytest.raises(
        FormatError, match=r"props: folder: holds 3 separate meshes \(rock_2.obj, rock_10.obj, tree.obj"
    ):
        input_kind(props)


def test_numbered_frames_stay_one_sequence_when_one_of_them_differs(tmp_path: Path) -> None:
    # A broken frame of a numbered sequence (beside its rest mesh) is the sequence's error, not a
    # library of one-frame assets; unnumbered poses with one connectivity are one sequence too.
    frames = tmp_path / "gallop"
    frames.mkdir()
    for index in range(3):
        (frames / f"horse-{index:02d}.obj").write_bytes(_QUAD)
    (frames / "horse-03.obj").write_bytes(_TRIANGLE)
    (frames / "horse-reference.obj").write_bytes(_QUAD)
    poses = tmp_path / "poses"
    poses.mkdir()
    for name in ("neutral", "smile", "frown"):
        (poses / f"{name}.obj").write_bytes(_QUAD)
    assert list(assets_in(tmp_path)) == [frames, poses]
    assert input_kind(frames) == input_kind(poses) == "sequence"


def test_model_formats_animlod_does_not_read_are_named_not_passed_over(tmp_path: Path, capsys) -> None:
    from animlod.cli import main

    library = tmp_path / "library"
    (library / "props").mkdir(parents=True)
    (library / "hero.fbx").write_bytes(b"")
    (library / "props" / "crate.dae").write_bytes(b"")
    (library / "props" / ".hidden.fbx").write_bytes(b"")
    note = "2 model files in formats animlod does not read (1 .dae, 1 .fbx); convert to glTF first"
    assert note in unread_models_note(library)
    with pytest.raises(FormatError, match=re.escape(f"folder: holds no .obj or .ply frame, but {note}")):
        input_kind(library)
    with pytest.raises(FormatError, match=r"hero.fbx: file: unknown type .fbx; expected .*; convert to glTF first"):
        input_kind(library / "hero.fbx")
    (library / "props" / "box.obj").write_bytes(_QUAD)
    assert main(["info", str(library)]) == 0
    assert f"note: {library}: left out {note}" in capsys.readouterr().out
    (library / "hero.fbx").unlink()
    assert "1 model file in a format animlod does not read (.dae); convert" in unread_models_note(library)
    (library / "props" / "crate.dae").unlink()
    assert unread_models_note(library) is None
