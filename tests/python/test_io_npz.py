"""NPZ archives of AnimatedMesh: exact round trips, the stored keys, bad archives."""

from __future__ import annotations

import struct
import zipfile
from pathlib import Path

import numpy as np
import pytest

from animlod.io import FormatError, read_npz, write_npz
from animlod.io.npz import FORMAT_VERSION
from animlod.model import AnimatedMesh

FACES = np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32)


def _mesh(fps: float | None) -> AnimatedMesh:
    frames = np.random.default_rng(3).normal(size=(5, 4, 3)).astype(np.float32)
    return AnimatedMesh(FACES, frames, fps=fps)


@pytest.mark.parametrize("fps", [30.0, None])
def test_round_trip_is_exact(tmp_path: Path, fps: float | None) -> None:
    mesh = _mesh(fps)
    write_npz(tmp_path / "mesh.npz", mesh)
    back = read_npz(tmp_path / "mesh.npz")
    np.testing.assert_array_equal(back.frames, mesh.frames)
    np.testing.assert_array_equal(back.faces, mesh.faces)
    assert back.fps == fps
    assert back.frames.dtype == np.float32 and back.faces.dtype == np.int32


def test_archive_keys(tmp_path: Path) -> None:
    write_npz(tmp_path / "mesh.npz", _mesh(24.0))
    with np.load(tmp_path / "mesh.npz") as archive:
        assert sorted(archive.files) == ["faces", "format_version", "fps", "frames"]
        assert int(archive["format_version"]) == FORMAT_VERSION


def test_a_write_failing_part_way_keeps_the_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "mesh.npz"
    write_npz(path, _mesh(24.0))
    old = path.read_bytes()

    def write_a_header_then_fail(handle, **arrays) -> None:
        handle.write(b"PK\x03\x04 half an archive")
        raise OSError("disk full")

    monkeypatch.setattr(np, "savez", write_a_header_then_fail)
    with pytest.raises(OSError, match="disk full"):
        write_npz(path, _mesh(30.0))
    assert path.read_bytes() == old
    assert [entry.name for entry in tmp_path.iterdir()] == ["mesh.npz"]


def _save(tmp_path: Path, **arrays: np.ndarray) -> Path:
    keys = {"format_version": np.int32(1), "faces": FACES, "frames": _mesh(None).frames, "fps": np.float64(30.0)}
    keys.update(arrays)
    path = tmp_path / "bad.npz"
    np.savez(path, **{key: value for key, value in keys.items() if value is not None})
    return path


@pytest.mark.parametrize(
    ("arrays", "message"),
    [
        ({"frames": None}, "key 'frames': missing"),
        ({"format_version": None}, "key 'format_version': missing"),
        ({"format_version": np.int32(2)}, "key 'format_version': unsupported version 2"),
        ({"frames": np.zeros((4, 3), np.float32)}, "key 'frames': expected float (F, V, 3), got float32 (4, 3)"),
        ({"faces": np.zeros((2, 4), np.int32)}, "key 'faces': expected integer (M, 3), got int32 (2, 4)"),
        ({"faces": FACES.astype(np.float32)}, "key 'faces': expected integer (M, 3), got float32 (2, 3)"),
        ({"fps": np.float64(-1.0)}, "key 'fps': must be positive or NaN, got -1.0"),
        ({"faces": FACES + 2}, "mesh: faces: face 0 [2, 3, 4] has an index outside [0, 4)"),
        ({"frames": np.full((1, 4, 3), np.nan, np.float32)}, "mesh: frames: non-finite value"),
    ],
)
def test_bad_archive(tmp_path: Path, arrays: dict, message: str) -> None:
    path = _save(tmp_path, **arrays)
    with pytest.raises(FormatError) as caught:
        read_npz(path)
    assert str(caught.value).startswith(f"{path}: {message}")


def test_not_an_archive(tmp_path: Path) -> None:
    path = tmp_path / "text.npz"
    path.write_text("hello")
    with pytest.raises(FormatError, match="archive: not a readable npz archive"):
        read_npz(path)


@pytest.mark.parametrize("damage", [b"\xff" * 8, b"\x00" * 8])
def test_damaged_compressed_member(tmp_path: Path, damage: bytes) -> None:
    path = tmp_path / "mesh.npz"  # deflated, as other writers (and animlod before 2026-12-06) write
    mesh = _mesh(24.0)
    np.savez_compressed(path, format_version=np.int32(1), faces=mesh.faces, frames=mesh.frames, fps=np.float64(24.0))
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as archive:
        local_header = archive.getinfo("frames.npy").header_offset
    name_length, extra_length = struct.unpack("<HH", data[local_header + 26 : local_header + 30])
    start = local_header + 30 + name_length + extra_length  # the member's deflate stream
    data[start : start + len(damage)] = damage
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match="archive: not a readable npz archive .*decompressing"):
        read_npz(path)


def test_damaged_stored_member(tmp_path: Path) -> None:
    path = tmp_path / "mesh.npz"  # write_npz stores its members: damage shows in their checksum
    write_npz(path, _mesh(24.0))
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as archive:
        member = archive.getinfo("frames.npy")
        assert member.compress_type == zipfile.ZIP_STORED
    name_length, extra_length = struct.unpack("<HH", data[member.header_offset + 26 : member.header_offset + 30])
    start = member.header_offset + 30 + name_length + extra_length + member.file_size - 8  # the last positions
    data[start : start + 8] = b"\xff" * 8
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match=r"archive: not a readable npz archive \(BadZipFile: Bad CRC-32"):
        read_npz(path)


def test_member_with_an_unknown_compression_method(tmp_path: Path) -> None:
    path = tmp_path / "mesh.npz"
    write_npz(path, _mesh(24.0))
    data = bytearray(path.read_bytes())
    # zipfile takes the method from the central directory entry, whose 46-byte header precedes the name.
    central_header = data.rfind(b"frames.npy") - 46
    assert data[central_header : central_header + 4] == b"PK\x01\x02"
    data[central_header + 10 : central_header + 12] = struct.pack("<H", 99)  # method 99: AE-x encryption
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match="archive: not a readable npz archive .*compression method"):
        read_npz(path)
