"""BVH files as capture libraries and exporters write them, beyond test_io_bvh's hand-written ones.

Each test builds its input in tmp_path in the dialect it names.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from animlod.io import FormatError, read_bvh, write_bvh

# Two joints whose names differ only outside ASCII (as MikuMikuDance-derived files name them).
JAPANESE_BVH = (
    "HIERARCHY\n"
    "ROOT \u30bb\u30f3\u30bf\u30fc\n"  # センター
    "{\n"
    "\tOFFSET 0 0 0\n"
    "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "\tJOINT \u5de6\u8db3\n"  # 左足
    "\t{\n"
    "\t\tOFFSET 1 -1 0\n"
    "\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n"
    "\t\tEnd Site\n"
    "\t\t{\n"
    "\t\t\tOFFSET 0 -4 0\n"
    "\t\t}\n"
    "\t}\n"
    "\tJOINT \u53f3\u8db3\n"  # 右足
    "\t{\n"
    "\t\tOFFSET -1 -1 0\n"
    "\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n"
    "\t\tEnd Site\n"
    "\t\t{\n"
    "\t\t\tOFFSET 0 -4 0\n"
    "\t\t}\n"
    "\t}\n"
    "}\n"
    "MOTION\n"
    "Frames: 2\n"
    "Frame Time: 0.033333\n"
    "0 10 0 0 0 0 10 0 0 -10 0 0\n"
    "0 10 1 0 5 0 20 0 0 -20 0 0\n"
)
NAMES = ["\u30bb\u30f3\u30bf\u30fc", "\u5de6\u8db3", "\u5de6\u8db3_End", "\u53f3\u8db3", "\u53f3\u8db3_End"]


def test_shift_jis_joint_names_read_as_their_characters(tmp_path: Path) -> None:
    # Japanese tools (MikuMikuDance converters) write Shift-JIS. Decoded as UTF-8 with
    # replacement, 左足 and 右足 both became "\ufffd\ufffd" and the file was refused as naming a
    # joint twice.
    path = tmp_path / "mmd.bvh"
    path.write_bytes(JAPANESE_BVH.encode("shift_jis"))
    motion = read_bvh(path)
    assert motion.skeleton.names == NAMES
    reference = tmp_path / "utf8.bvh"
    reference.write_bytes(JAPANESE_BVH.encode("utf-8"))
    np.testing.assert_array_equal(motion.world_positions(), read_bvh(reference).world_positions())
    # Written back (as UTF-8), the names survive a round trip.
    write_bvh(tmp_path / "out.bvh", motion)
    assert read_bvh(tmp_path / "out.bvh").skeleton.names == NAMES


def test_names_in_a_single_byte_code_page_stay_distinct(tmp_path: Path) -> None:
    # 3ds Max on a European Windows writes its code page: "Bip01 Épaule" and "Bip01 Èpaule"
    # are two joints, not one name written twice.
    text = JAPANESE_BVH.replace(NAMES[1], "Bip01 \u00c9paule").replace(NAMES[3], "Bip01 \u00c8paule")
    path = tmp_path / "max.bvh"
    path.write_bytes(text.replace(NAMES[0], "Bip01").encode("cp1252"))
    names = read_bvh(path).skeleton.names
    assert len(set(names)) == len(names) == 5
    assert names[0] == "Bip01"


def test_a_utf16_file_with_a_byte_order_mark_reads_like_utf8(tmp_path: Path) -> None:
    # PowerShell's "> file.bvh" and Notepad's "Unicode" save write UTF-16 with a byte order mark.
    reference = tmp_path / "utf8.bvh"
    reference.write_bytes(JAPANESE_BVH.encode("utf-8"))
    expected = read_bvh(reference)
    for encoding in ("utf-16-le", "utf-16-be"):
        path = tmp_path / f"{encoding}.bvh"
        bom = b"\xff\xfe" if encoding.endswith("le") else b"\xfe\xff"
        path.write_bytes(bom + JAPANESE_BVH.replace("\n", "\r\n").encode(encoding))
        motion = read_bvh(path)
        assert motion.skeleton.names == NAMES
        np.testing.assert_array_equal(motion.local_rotations, expected.local_rotations)


def test_a_frame_time_in_scientific_notation_gives_the_rate_it_was_rounded_from(tmp_path: Path) -> None:
    # numpy.savetxt's "%e" and C's "%e" write 1/120 s as 8.333333e-03: nine digits after the
    # point, as many as 0.008333333, which reads as 120 fps; the rate was 120.0000048.
    for written in ("8.333333e-03", "8.333333E-03", "0.008333333"):
        path = tmp_path / "clip.bvh"
        path.write_text(JAPANESE_BVH.replace("0.033333", written), encoding="utf-8")
        assert read_bvh(path).fps == 120.0, written
    path.write_text(JAPANESE_BVH.replace("0.033333", "1.23456e-02"), encoding="utf-8")
    assert read_bvh(path).fps == 1 / 0.0123456  # no integer rate rounds to it


def test_a_prop_of_one_joint_writes_its_motion_as_the_one_level(tmp_path: Path, capsys) -> None:
    # A camera or prop clip: one ROOT with an End Site. Nothing can freeze; the note counts "1 joint".
    from animlod.cli import main

    path = tmp_path / "camera.bvh"
    path.write_text(
        "HIERARCHY\nROOT Camera\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
        "Yrotation\n\tEnd Site\n\t{\n\t\tOFFSET 0 0 -10\n\t}\n}\nMOTION\nFrames: 3\nFrame Time: 0.04\n"
        "0 100 0 0 0 0\n5 100 0 0 10 0\n10 100 0 0 20 0\n",
        encoding="utf-8",
    )
    out = tmp_path / "out"
    assert main(["motion", str(path), "-o", str(out), "--levels", "8"]) == 0
    assert "nothing can freeze (1 joint, all kept: root)" in capsys.readouterr().err
    written = read_bvh(out / "camera_lod0.bvh")
    np.testing.assert_allclose(written.world_positions(), read_bvh(path).world_positions(), atol=1e-6)


def test_an_end_site_gives_way_to_a_joint_written_later_with_its_generated_name(tmp_path: Path) -> None:
    # A joint "A" with an End Site and then a JOINT named "A_End" (as a rig with tip joints named
    # <parent>_End writes them): the End Site, named A_End by the reader, was taken for a first
    # use of that name and the file was refused as naming a joint twice.
    text = (
        "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
        "Yrotation\n\tJOINT A\n\t{\n\t\tOFFSET 0 1 0\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n"
        "\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 1 0\n\t\t}\n"
        "\t\tJOINT A_End\n\t\t{\n\t\t\tOFFSET 1 0 0\n\t\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n\t\t}\n\t}\n}\n"
        "MOTION\nFrames: 1\nFrame Time: 0.04\n0 0 0 0 0 0 0 0 0 0 0 0\n"
    )
    path = tmp_path / "tips.bvh"
    path.write_text(text, encoding="utf-8")
    skeleton = read_bvh(path).skeleton
    assert skeleton.names == ["Hips", "A", "A_End1", "A_End"]
    assert skeleton.end_sites.tolist() == [False, False, True, False]
    # Two joints of one name are still refused.
    path.write_text(text.replace("JOINT A_End", "JOINT A"), encoding="utf-8")
    with pytest.raises(FormatError, match="line 14: joint name 'A' is used twice"):
        read_bvh(path)
