"""BVH files as capture libraries and exporters write them, beyond test_io_bvh's hand-written ones.

Each test builds its input in tmp_path in the dialect it names.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from animlod import rotations
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


# A small figure: root, a spine chain ending in an End Site, and a two-joint leg; 4 frames.
_PARENTS = [-1, 0, 1, 2, 0, 4]
_OFFSETS = [[0.0, 90.0, 0.0], [0.0, 10.0, 1.0], [0.0, 30.0, 0.0], [0.0, 12.0, 0.0], [9.0, -5.0, 0.0], [0.0, -40.0, 2.0]]
_END_SITES = [False, False, False, True, False, False]
_LEGACY_NAMES = ["Hips", "Spine", "Head", "Head_End", "LeftUpLeg", "LeftLeg"]


def _dialect_text(dialect: str) -> tuple[str, list[str]]:
    """The figure's clip written as ``dialect`` writes it, and the joint names a reader should find."""
    rng = np.random.default_rng(7)
    frames = 4
    angles = np.radians(rng.uniform(-80.0, 80.0, (frames, len(_PARENTS), 3)))
    local = rotations.from_euler(angles, "ZXY")
    root = np.array(_OFFSETS[0]) + rng.uniform(-5.0, 5.0, (frames, 3))
    names = {
        "biped": ["Bip01", "Bip01 Spine", "Bip01 Head", "Bip01 HeadNub", "Bip01 L Thigh", "Bip01 L Calf"],
        "mixamo": [f"mixamorig:{name}" for name in _LEGACY_NAMES],
    }.get(dialect, _LEGACY_NAMES)
    order = {"lafan1": "XYZ", "neuron": "YXZ", "rotation_first": "ZYX"}.get(dialect, "ZXY")
    fmt = "{:.6e}" if dialect == "scientific" else "{:.9f}"
    indent = "  " if dialect == "mixamo" else "\t"
    lines, columns = ["HIERARCHY"], []

    def block(joint: int, depth: int) -> None:
        pad, brace = indent * depth, " {" if dialect == "brace_same_line" else ""
        offset = " ".join(fmt.format(v) for v in _OFFSETS[joint])
        if _END_SITES[joint]:
            label = "End Site" + (f" {names[joint]}" if dialect == "biped" else "")
            lines.extend([pad + label + brace] + ([] if brace else [pad + "{"]) + [f"{pad}{indent}OFFSET {offset}"])
            lines.append(pad + "}")
            return
        keyword = "ROOT" if joint == 0 else "JOINT"
        lines.extend([f"{pad}{keyword} {names[joint]}{brace}"] + ([] if brace else [pad + "{"]))
        lines.append(f"{pad}{indent}OFFSET {offset}")
        position = [f"{axis}position" for axis in "XYZ"] if joint == 0 or dialect == "lafan1" else []
        rotation = [f"{axis}rotation" for axis in order]
        channels = rotation + position if dialect == "rotation_first" else position + rotation
        lines.append(f"{pad}{indent}CHANNELS {len(channels)} {' '.join(channels)}")
        euler = np.degrees(rotations.to_euler(local[:, joint], order))
        translation = root if joint == 0 else np.broadcast_to(_OFFSETS[joint], (frames, 3))
        for channel in channels:
            axis = "XYZ".index(channel[0])
            columns.append(translation[:, axis] if channel.endswith("position") else euler[:, order.index(channel[0])])
        for child in (c for c, p in enumerate(_PARENTS) if p == joint):
            block(child, depth + 1)
        lines.append(pad + "}")

    block(0, 0)
    frame_time = "3.333333e-02" if dialect == "scientific" else "0.033333"
    lines += ["MOTION", f"Frames: {frames}", f"Frame Time: {frame_time}"]
    separator = "\t" if dialect == "tabs_and_trailing" else " "
    lines += [separator.join(fmt.format(v) for v in row) for row in np.stack(columns, axis=1)]
    if dialect == "tabs_and_trailing":
        lines = [line + " \t" for line in lines] + ["", "", ""]
    newline = "\r\n" if dialect == "biped" else "\n"
    expected = [name if not end else f"{names[p]}_End" for name, end, p in zip(names, _END_SITES, _PARENTS)]
    return newline.join(lines) + newline, expected


DIALECTS = [
    "biped",
    "mixamo",
    "lafan1",
    "neuron",
    "rotation_first",
    "scientific",
    "tabs_and_trailing",
    "brace_same_line",
]


@pytest.mark.parametrize("dialect", DIALECTS)
def test_exporter_dialects_read_as_the_same_motion(tmp_path: Path, dialect: str) -> None:
    # 3ds Max Biped: names with spaces, named End Sites, CRLF. Mixamo: "mixamorig:" names, two-space
    # indents. LAFAN1: six channels on every joint, XYZ. Perception Neuron: YXZ. Some exporters:
    # rotation channels before position ones, %e numbers, tab-separated rows, trailing blanks,
    # "JOINT Name {" on one line.
    reference_text, _ = _dialect_text("legacy")
    (tmp_path / "reference.bvh").write_text(reference_text, encoding="utf-8", newline="")
    reference = read_bvh(tmp_path / "reference.bvh")
    text, names = _dialect_text(dialect)
    (tmp_path / "clip.bvh").write_text(text, encoding="utf-8", newline="")
    motion = read_bvh(tmp_path / "clip.bvh")
    expected_names = names if dialect != "biped" else names[:3] + ["Bip01 HeadNub"] + names[4:]
    assert motion.skeleton.names == expected_names
    assert motion.fps == 30.0
    np.testing.assert_allclose(motion.world_positions(), reference.world_positions(), atol=1e-4)
    # The levels' writer and reader keep the names as read.
    write_bvh(tmp_path / "out.bvh", motion)
    written = read_bvh(tmp_path / "out.bvh")
    assert [n for n, e in zip(written.skeleton.names, _END_SITES) if not e] == [
        n for n, e in zip(expected_names, _END_SITES) if not e
    ]
    np.testing.assert_allclose(written.world_positions(), motion.world_positions(), atol=1e-4)
