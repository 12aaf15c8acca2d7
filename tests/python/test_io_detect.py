"""input_kind: which reader a CLI path needs."""

from __future__ import annotations

from pathlib import Path

import pytest

from animlod.io import FormatError
from animlod.io.detect import input_kind


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
