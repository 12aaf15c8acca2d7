"""BVH reading and writing: conventions on hand-written files, round trips, real clips, bad input."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from animlod import rotations
from animlod.io import FormatError, read_bvh, read_bvh_with_layout, write_bvh
from animlod.model import Motion, Skeleton

# Root with 6 channels, a 3-channel joint A (Z-X-Y intrinsic), an End Site, and a 6-channel
# non-root joint B whose position channels replace its OFFSET. Line endings are mixed on purpose.
SMALL_BVH = (
    "HIERARCHY\r\n"
    "ROOT Hips\r\n"
    "{\n"
    "\tOFFSET 0 0 0\r\n"
    "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "\tJOINT A\r\n"
    "\t{\n"
    "\t\tOFFSET 0 1 0\n"
    "\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n"
    "\t\tEnd Site\n"
    "\t\t{\n"
    "\t\t\tOFFSET 0 2 0\n"
    "\t\t}\n"
    "\t}\n"
    "\tJOINT B\n"
    "\t{\n"
    "\t\tOFFSET 5 0 0\n"
    "\t\tCHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation\n"
    "\t}\n"
    "}\n"
    "MOTION\r\n"
    "Frames: 2\r\n"
    "Frame Time: .0333333\r\n"
    "1 2 3 0 0 0 0 0 0 5 0 0 0 0 0\r\n"
    "1 2 3 90 0 0 90 90 0 7 0 0 0 0 0\n"
)


def _write(tmp_path: Path, text: str, name: str = "clip.bvh") -> Path:
    path = tmp_path / name
    path.write_bytes(text.encode())
    return path


def test_reads_hierarchy_channels_and_end_sites(tmp_path: Path) -> None:
    motion = read_bvh(_write(tmp_path, SMALL_BVH))
    skeleton = motion.skeleton
    assert skeleton.names == ["Hips", "A", "A_End", "B"]
    assert skeleton.parents.tolist() == [-1, 0, 1, 0]
    assert skeleton.end_sites.tolist() == [False, False, True, False]
    np.testing.assert_array_equal(skeleton.offsets, [[0, 0, 0], [0, 1, 0], [0, 2, 0], [5, 0, 0]])
    np.testing.assert_array_equal(motion.root_positions, [[1, 2, 3], [1, 2, 3]])
    assert motion.fps == 30.0
    assert motion.name == "clip"
    # B's position channel moves it to x=7 in frame 1, so per-frame translations are kept.
    assert motion.joint_translations is not None
    np.testing.assert_array_equal(motion.joint_translations[:, 3], [[5, 0, 0], [7, 0, 0]])


def test_a_file_converted_to_crlf_twice_reads_like_the_original(tmp_path: Path) -> None:
    # CR CR LF: a blank line after every line, between MOTION, Frames: and Frame Time: too.
    twice = read_bvh(_write(tmp_path, SMALL_BVH.replace("\n", "\r\n"), "twice.bvh"))
    once = read_bvh(_write(tmp_path, SMALL_BVH))
    assert twice.skeleton.names == once.skeleton.names and twice.fps == once.fps
    np.testing.assert_array_equal(twice.local_rotations, once.local_rotations)
    np.testing.assert_array_equal(twice.joint_translations, once.joint_translations)
    message = _read_error(tmp_path, SMALL_BVH.replace("\n", "\r\n").replace("Frames: 2", "Frames: x"))
    assert "line 27: expected 'Frames: N', found 'Frames: x'" in message  # as an editor counts


def test_a_byte_order_mark_is_no_part_of_the_hierarchy(tmp_path: Path) -> None:
    marked = tmp_path / "marked.bvh"
    marked.write_bytes(b"\xef\xbb\xbf" + SMALL_BVH.encode())
    once = read_bvh(_write(tmp_path, SMALL_BVH))
    np.testing.assert_array_equal(read_bvh(marked).local_rotations, once.local_rotations)


@pytest.mark.parametrize("case", [str.lower, str.title], ids=["lower", "title"])
def test_keywords_in_any_case_read_like_upper_case(tmp_path: Path, case: Callable[[str], str]) -> None:
    # Some exporters write "hierarchy", "root", "offset", "end site", "frames:"; Blender reads them.
    # Joint names (Hips, A, B) stay as written; channel names were already read in any case.
    keywords = r"HIERARCHY|ROOT|JOINT|OFFSET|CHANNELS|End Site|MOTION|Frames:|Frame Time:|[XYZ](?:position|rotation)"
    text = re.sub(keywords, lambda match: case(match.group()), SMALL_BVH)
    assert "root Hips" in text if case is str.lower else "Root Hips" in text
    cased, upper = read_bvh(_write(tmp_path, text, "cased.bvh")), read_bvh(_write(tmp_path, SMALL_BVH))
    assert cased.skeleton.names == upper.skeleton.names == ["Hips", "A", "A_End", "B"]
    assert cased.fps == upper.fps
    for name in ("root_positions", "local_rotations", "joint_translations"):
        np.testing.assert_array_equal(getattr(cased, name), getattr(upper, name))
    np.testing.assert_array_equal(cased.skeleton.offsets, upper.skeleton.offsets)
    np.testing.assert_array_equal(cased.skeleton.parents, upper.skeleton.parents)
    np.testing.assert_array_equal(cased.skeleton.end_sites, upper.skeleton.end_sites)


def test_keywords_match_ascii_case_only(tmp_path: Path) -> None:
    # U+017F LATIN SMALL LETTER LONG S upper-cases to "S"; it spells no keyword.
    message = _read_error(tmp_path, SMALL_BVH.replace("End Site", "End \u017fite"))
    assert message.endswith("line 10: expected 'Site', found '\u017fite'")
    message = _read_error(tmp_path, SMALL_BVH.replace("Frames: 2", "Frame\u017f: 2"))
    assert message.endswith("line 22: expected 'Frames: N', found 'Frame\u017f: 2'")


def test_a_hinge_with_one_rotation_channel_reads_like_three_with_zeros(tmp_path: Path) -> None:
    def clip(knee_channels: str, knee_values: list[str]) -> str:
        rows = [f"0 1 0 0 0 0 {value}" for value in knee_values]
        return (
            "HIERARCHY\nROOT Hip\n{\n\tOFFSET 0 1 0\n"
            "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
            f"\tJOINT Knee\n\t{{\n\t\tOFFSET 0 -0.5 0\n\t\tCHANNELS {knee_channels}\n"
            "\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 -0.5 0\n\t\t}\n\t}\n}\n"
            f"MOTION\nFrames: {len(rows)}\nFrame Time: 0.1\n" + "\n".join(rows) + "\n"
        )

    hinge = read_bvh(_write(tmp_path, clip("1 Xrotation", ["10", "-35"]), "hinge.bvh"))
    full = read_bvh(_write(tmp_path, clip("3 Zrotation Xrotation Yrotation", ["0 10 0", "0 -35 0"]), "full.bvh"))
    np.testing.assert_allclose(hinge.local_rotations, full.local_rotations, atol=1e-15)
    message = _read_error(tmp_path, clip("2 Xrotation Xrotation", ["1 2", "3 4"]))
    assert "joint 'Knee': channels ['Xrotation', 'Xrotation'] must name each axis once" in message


def test_euler_angles_follow_the_written_channel_order(tmp_path: Path) -> None:
    world = read_bvh(_write(tmp_path, SMALL_BVH)).world_positions()
    # Frame 0: no rotation.
    np.testing.assert_allclose(world[0], [[1, 2, 3], [1, 3, 3], [1, 5, 3], [6, 2, 3]], atol=1e-12)
    # Frame 1: the root turns 90 degrees about Z, so A's offset (0, 1, 0) points along -X and
    # B (translated by its channels to (7, 0, 0)) lands at +Y. A rotates Rz(90) @ Rx(90) (the
    # written order): its end site offset (0, 2, 0) -> Rx -> (0, 0, 2) -> Rz -> (0, 0, 2).
    np.testing.assert_allclose(world[1], [[1, 2, 3], [0, 2, 3], [0, 2, 5], [1, 9, 3]], atol=1e-12)


def test_no_joint_translations_when_channels_equal_offsets(tmp_path: Path) -> None:
    text = SMALL_BVH.replace("1 2 3 90 0 0 90 90 0 7 0 0", "1 2 3 90 0 0 90 90 0 5 0 0")
    assert read_bvh(_write(tmp_path, text)).joint_translations is None


def test_root_without_position_channels_stays_at_its_offset(tmp_path: Path) -> None:
    text = (
        "HIERARCHY\nROOT Hips\n{\n  OFFSET 1 2 3\n  CHANNELS 3 Yrotation Xrotation Zrotation\n"
        "  End Site Nose\n  {\n    OFFSET 0 0 1\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 0.5\n\n0 0 0\n90 0 0  \n\n"
    )
    motion = read_bvh(_write(tmp_path, text))
    assert motion.skeleton.names == ["Hips", "Nose"]
    assert motion.fps == 2.0
    np.testing.assert_array_equal(motion.root_positions, [[1, 2, 3], [1, 2, 3]])
    np.testing.assert_allclose(motion.world_positions()[:, 1], [[1, 2, 4], [2, 2, 3]], atol=1e-12)


@pytest.mark.parametrize(("frame_time", "fps"), [("0.008333", 120.0), (".04", 25.0), ("0.0123456", 1 / 0.0123456)])
def test_frame_time_gives_fps(tmp_path: Path, frame_time: str, fps: float) -> None:
    motion = read_bvh(_write(tmp_path, SMALL_BVH.replace(".0333333", frame_time)))
    assert motion.fps == pytest.approx(fps, rel=1e-12)


def _hand_made_motion(seed: int, animated_translation: bool) -> Motion:
    """A 6-joint tree (two branches, one end site) with random rotations and root motion."""
    rng = np.random.default_rng(seed)
    frame_count = 7
    skeleton = Skeleton(
        ["root", "spine", "head", "head_End", "arm", "hand"],
        [-1, 0, 1, 2, 1, 4],
        [[0.5, 1.0, -0.2], [0, 1, 0], [0, 0.6, 0.1], [0, 0.3, 0], [0.4, 0.5, 0], [0.7, 0, 0]],
        end_sites=[False, False, False, True, False, False],
    )
    local = rotations.normalize(rng.normal(size=(frame_count, 6, 4)))
    translations = None
    if animated_translation:
        translations = np.repeat(skeleton.offsets[None], frame_count, axis=0)
        translations[:, 4] += rng.normal(scale=0.1, size=(frame_count, 3))
    return Motion(skeleton, rng.normal(size=(frame_count, 3)), local, fps=24.0, joint_translations=translations)


@pytest.mark.parametrize("order", ["XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"])
@pytest.mark.parametrize("animated_translation", [False, True])
def test_round_trip_preserves_world_positions(tmp_path: Path, order: str, animated_translation: bool) -> None:
    motion = _hand_made_motion(seed=len(order) + ord(order[0]), animated_translation=animated_translation)
    path = tmp_path / "round.bvh"
    write_bvh(path, motion, rotation_order=order)
    back = read_bvh(path)
    assert back.skeleton.names == motion.skeleton.names
    assert back.skeleton.parents.tolist() == motion.skeleton.parents.tolist()
    assert back.skeleton.end_sites.tolist() == motion.skeleton.end_sites.tolist()
    assert back.fps == motion.fps
    np.testing.assert_allclose(back.skeleton.offsets, motion.skeleton.offsets, atol=5e-7)
    # 6 decimals of degrees and of length units: FK agrees to about 1e-6.
    np.testing.assert_allclose(back.world_positions(), motion.world_positions(), atol=1e-5)
    assert (back.joint_translations is not None) == animated_translation
    channel_lines = [line.split()[1] for line in path.read_text().splitlines() if "CHANNELS" in line]
    expected = ["6", "3", "3", "6" if animated_translation else "3", "3"]  # the end site has none
    assert channel_lines == expected


def test_float_noise_on_translations_is_no_animated_translation(tmp_path: Path) -> None:
    """A glTF clip whose one joint translates (a node between joints turning) gives every joint
    per-frame translations, composed through the nodes with 1e-18 of float noise: the end site's
    was refused as "an end site with animated translation; BVH cannot store it". Noise the
    written digits cannot show is no translation."""
    motion = _hand_made_motion(seed=5, animated_translation=True)
    noise = np.random.default_rng(5).normal(scale=1e-18, size=motion.joint_translations.shape)
    noisy = Motion(motion.skeleton, motion.root_positions, motion.local_rotations, motion.fps,
                   joint_translations=motion.joint_translations + noise)  # fmt: skip
    write_bvh(tmp_path / "noisy.bvh", noisy)
    channel_lines = [
        line.split()[1] for line in (tmp_path / "noisy.bvh").read_text().splitlines() if "CHANNELS" in line
    ]
    assert channel_lines == ["6", "3", "3", "6", "3"]  # the translating joint keeps its own
    np.testing.assert_allclose(read_bvh(tmp_path / "noisy.bvh").world_positions(), motion.world_positions(), atol=1e-5)


def test_a_tiny_skeleton_keeps_its_precision_through_a_round_trip(tmp_path: Path) -> None:
    motion = _hand_made_motion(seed=3, animated_translation=False)
    s = motion.skeleton
    tiny = Motion(
        Skeleton(s.names, s.parents, 1e-4 * s.offsets, end_sites=s.end_sites),
        1e-4 * motion.root_positions,
        motion.local_rotations,
        motion.fps,
    )
    write_bvh(tmp_path / "tiny.bvh", tiny)
    back = read_bvh(tmp_path / "tiny.bvh")
    size = np.abs(s.offsets).max() * 1e-4
    np.testing.assert_allclose(back.world_positions(), tiny.world_positions(), atol=1e-5 * size)


MIXED_ORDERS_BVH = (
    "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n"
    "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n"
    "\tJOINT Spine\n\t{\n\t\tOFFSET 0 1 0\n\t\tCHANNELS 3 Yrotation Xrotation Zrotation\n"
    "\t\tJOINT Hinge\n\t\t{\n\t\t\tOFFSET 0 1 0\n\t\t\tCHANNELS 1 Xrotation\n"
    "\t\t\tEnd Site\n\t\t\t{\n\t\t\t\tOFFSET 0 0.5 0\n\t\t\t}\n\t\t}\n\t}\n}\n"
    "MOTION\nFrames: 2\nFrame Time: 0.5\n"
    "1.5 2 3 10 -20 30 40 50 -60 70\n"
    "1 2 3 -170 80 -120 -35 -5 175 -10\n"
)


def test_a_motion_written_in_its_files_rotation_orders_keeps_its_channel_values(tmp_path: Path) -> None:
    """read_bvh_with_layout gives each joint's rotation order as written (the one-channel hinge has none:
    written in the default ZXY), and write_bvh writes them back: the same channels and, for angles
    in Euler's principal range, the same values."""
    source = _write(tmp_path, MIXED_ORDERS_BVH)
    orders = read_bvh_with_layout(source)[1].rotation_orders
    assert orders == {"Hips": "ZYX", "Spine": "YXZ"}
    write_bvh(tmp_path / "back.bvh", read_bvh(source), rotation_order=orders)
    text = (tmp_path / "back.bvh").read_text()
    channels = [line.split()[2:] for line in text.splitlines() if "CHANNELS" in line]
    assert channels[:2] == [["Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation"],
                            ["Yrotation", "Xrotation", "Zrotation"]]  # fmt: skip
    rows = np.loadtxt(text.split("Frame Time: 0.5\n")[1].splitlines())
    expected = np.loadtxt(MIXED_ORDERS_BVH.split("Frame Time: 0.5\n")[1].splitlines())
    np.testing.assert_allclose(rows[:, :9], expected[:, :9], atol=1e-6)


def _root_block(name: str, child: str, offset: str) -> str:
    """A ROOT block with six channels, one child of three and its end site."""
    return (
        f"ROOT {name}\n{{\n\tOFFSET {offset}\n"
        "\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
        f"\tJOINT {child}\n\t{{\n\t\tOFFSET 0 1 0\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n"
        "\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 1 0\n\t\t}\n\t}\n}\n"
    )


def _bvh_text(blocks: list[str], rows: list[str]) -> str:
    return "HIERARCHY\n" + "".join(blocks) + f"MOTION\nFrames: {len(rows)}\nFrame Time: 0.5\n" + "\n".join(rows) + "\n"


def test_several_roots_read_as_one_skeleton_below_a_joint_of_their_own(tmp_path: Path) -> None:
    """Two ROOTs (a performer and a prop, or two performers): each moves as its file alone would,
    below a joint at the origin named Roots (Roots1 here, as the file has a joint Roots). Such
    files were refused."""
    actor, prop = _root_block("Actor", "Roots", "0 0 0"), _root_block("Prop", "Tip", "5 0 0")
    actor_rows = ["1 2 3 10 20 30 40 0 0", "2 2 3 15 25 35 45 5 0"]
    prop_rows = ["-1 0 0 0 90 0 0 0 30", "-2 0 1 0 80 0 0 0 20"]
    both = _write(tmp_path, _bvh_text([actor, prop], [f"{a} {p}" for a, p in zip(actor_rows, prop_rows)]), "both.bvh")
    motion = read_bvh(both)
    assert motion.skeleton.names[:2] == ["Roots1", "Actor"] and motion.skeleton.parents[[1, 4]].tolist() == [0, 0]
    assert read_bvh_with_layout(both)[1].roots == ["Actor", "Prop"]
    np.testing.assert_array_equal(motion.root_positions, 0.0)
    for block, rows, joints in ((actor, actor_rows, slice(1, 4)), (prop, prop_rows, slice(4, 7))):
        alone = read_bvh(_write(tmp_path, _bvh_text([block], rows), "alone.bvh"))
        np.testing.assert_allclose(motion.world_positions()[:, joints], alone.world_positions(), atol=1e-12)
    write_bvh(tmp_path / "back.bvh", motion)
    np.testing.assert_allclose(read_bvh(tmp_path / "back.bvh").world_positions(), motion.world_positions(), atol=1e-5)


def test_write_rejects_bad_rotation_order(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="rotation_order"):
        write_bvh(tmp_path / "x.bvh", _hand_made_motion(0, False), rotation_order="XXY")


def test_a_write_failing_part_way_keeps_the_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "x.bvh"
    path.write_text("old content")

    def write_some_rows_then_fail(handle, table, **kwargs) -> None:
        handle.write("0.0 1.0 2.0\n")
        raise OSError("disk full")

    monkeypatch.setattr(np, "savetxt", write_some_rows_then_fail)
    with pytest.raises(OSError, match="disk full"):
        write_bvh(path, _hand_made_motion(0, False))
    assert path.read_text() == "old content"
    assert [p.name for p in tmp_path.iterdir()] == ["x.bvh"]


def _chain_bvh(depth: int) -> str:
    """A root and ``depth - 1`` nested joints, each one unit above its parent, then an End Site."""
    opening = "".join(
        f"JOINT j{index}\n{{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n" for index in range(1, depth)
    )
    root = (
        "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    )
    end_site = "End Site\n{\nOFFSET 0 1 0\n}\n"
    motion = f"MOTION\nFrames: 1\nFrame Time: 0.04\n{' '.join(['0'] * (3 + 3 * depth))}\n"
    return root + opening + end_site + "}\n" * depth + motion


def test_deeply_nested_chain_reads_and_writes(tmp_path: Path) -> None:
    depth = 3000  # far past Python's default recursion limit of 1000
    motion = read_bvh(_write(tmp_path, _chain_bvh(depth)))
    assert motion.skeleton.joint_count == depth + 1
    assert motion.skeleton.parents.tolist() == list(range(-1, depth))
    assert motion.skeleton.names[-1] == f"j{depth - 1}_End"
    write_bvh(tmp_path / "back.bvh", motion)
    back = read_bvh(tmp_path / "back.bvh")
    assert back.skeleton.parents.tolist() == motion.skeleton.parents.tolist()
    np.testing.assert_array_equal(back.skeleton.offsets, motion.skeleton.offsets)


# --- real clips (SOURCES.md) ---------------------------------------------------------------

REAL_CLIPS = [
    # file, joints (without end sites), end sites, frames, fps, has animated non-root translation
    ("131_01.bvh", 31, 7, 994, 120.0, False),
    ("dataset-1_run_proud_001.bvh", 22, 5, 141, 30.0, True),
]


@pytest.mark.parametrize(("name", "joints", "end_sites", "frames", "fps", "translated"), REAL_CLIPS)
def test_real_clip_loads_with_documented_stats(
    data_dir: Path, name: str, joints: int, end_sites: int, frames: int, fps: float, translated: bool
) -> None:
    motion = read_bvh(data_dir / "bvh" / name)
    assert motion.skeleton.joint_count - int(motion.skeleton.end_sites.sum()) == joints
    assert int(motion.skeleton.end_sites.sum()) == end_sites
    assert motion.frame_count == frames
    assert motion.fps == fps
    assert (motion.joint_translations is not None) == translated


def test_cmu_clip_first_frame_values(data_dir: Path) -> None:
    motion = read_bvh(data_dir / "bvh" / "131_01.bvh")
    np.testing.assert_array_equal(motion.root_positions[0], [5.23, 16.9002, -33.8986])
    np.testing.assert_array_equal(motion.skeleton.offsets[2], [1.24777, -1.64261, 0.71711])
    # Root channels "Zrotation Yrotation Xrotation" = -5.4029 9.8098 10.4956 degrees.
    expected = rotations.from_euler(np.radians([-5.4029, 9.8098, 10.4956]), "ZYX")
    np.testing.assert_allclose(motion.local_rotations[0, 0], expected, atol=1e-15)


def _axis_matrix(axis: str, degrees: float) -> np.ndarray:
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    i, j = {"X": (1, 2), "Y": (2, 0), "Z": (0, 1)}[axis]
    m = np.eye(4)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def test_bandai_forward_kinematics_matches_a_matrix_reference(data_dir: Path) -> None:
    """Every Bandai joint has "Xposition Yposition Zposition Zrotation Xrotation Yrotation":
    world = parent @ T(position channels) @ Rz @ Rx @ Ry, built here from elementary matrices."""
    path = data_dir / "bvh" / "dataset-1_run_proud_001.bvh"
    motion = read_bvh(path)
    frame = 57
    row = np.array(path.read_text().split("Frame Time:")[1].splitlines()[1 + frame].split(), dtype=float).reshape(-1, 6)
    joints = np.flatnonzero(~motion.skeleton.end_sites)
    world = {}
    for values, joint in zip(row, joints):
        local = np.eye(4)
        local[:3, 3] = values[:3]
        local = local @ _axis_matrix("Z", values[3]) @ _axis_matrix("X", values[4]) @ _axis_matrix("Y", values[5])
        parent = motion.skeleton.parents[joint]
        world[joint] = local if parent < 0 else world[parent] @ local
    expected = np.array([world[joint][:3, 3] for joint in joints])
    np.testing.assert_allclose(motion.world_positions()[frame, joints], expected, atol=1e-9)


@pytest.mark.parametrize("name", [clip[0] for clip in REAL_CLIPS])
def test_real_clip_round_trip(data_dir: Path, tmp_path: Path, name: str) -> None:
    motion = read_bvh(data_dir / "bvh" / name)
    write_bvh(tmp_path / name, motion)
    back = read_bvh(tmp_path / name)
    assert back.skeleton.names == motion.skeleton.names
    extent = np.ptp(motion.world_positions().reshape(-1, 3), axis=0).max()
    np.testing.assert_allclose(back.world_positions(), motion.world_positions(), atol=1e-6 * extent)


# --- bad input --------------------------------------------------------------------------------


def _read_error(tmp_path: Path, text: str) -> str:
    with pytest.raises(FormatError) as caught:
        read_bvh(_write(tmp_path, text))
    message = str(caught.value)
    assert message.startswith(str(tmp_path / "clip.bvh") + ": ")
    return message


def test_truncated_motion_table(tmp_path: Path) -> None:
    message = _read_error(tmp_path, SMALL_BVH.replace("Frames: 2", "Frames: 3"))
    assert "line 26 (frame 2): Frames: says 3 but the MOTION table has 2 rows" in message


def test_more_rows_than_frames_are_all_read_with_a_warning(tmp_path: Path) -> None:
    expected = read_bvh(_write(tmp_path, SMALL_BVH))
    with pytest.warns(UserWarning, match=r"clip.bvh: Frames: says 1 but the MOTION table has 2 rows; read all 2"):
        motion = read_bvh(_write(tmp_path, SMALL_BVH.replace("Frames: 2", "Frames: 1")))
    np.testing.assert_array_equal(motion.local_rotations, expected.local_rotations)
    np.testing.assert_array_equal(motion.root_positions, expected.root_positions)


def test_row_with_wrong_channel_count(tmp_path: Path) -> None:
    message = _read_error(tmp_path, SMALL_BVH.replace("7 0 0 0 0 0", "7 0 0 0 0"))
    assert "line 25 (frame 1): expected 15 channel values, found 14" in message


@pytest.mark.parametrize("bad", ["nan", "inf", "-Infinity"])
def test_non_finite_value_names_joint_and_channel(tmp_path: Path, bad: str) -> None:
    message = _read_error(tmp_path, SMALL_BVH.replace("90 90 0 7", f"90 {bad} 0 7"))
    assert "line 25 (frame 1), joint 'A' Xrotation: value" in message and "is not finite" in message


def test_value_that_is_not_a_number(tmp_path: Path) -> None:
    message = _read_error(tmp_path, SMALL_BVH.replace("90 90 0 7", "90 9O 0 7"))
    assert "line 25 (frame 1), joint 'A' Xrotation: '9O' is not a number" in message


def test_missing_closing_brace(tmp_path: Path) -> None:
    text = SMALL_BVH.replace("\t\t}\n\t}\n", "\t\t}\n", 1)
    message = _read_error(tmp_path, text)
    assert "'}' closing joint 'Hips' (opened on line 2)" in message


def test_unknown_keyword_in_joint(tmp_path: Path) -> None:
    message = _read_error(tmp_path, SMALL_BVH.replace("\t\tOFFSET 5 0 0", "\t\tOFFSET 5 0 0\n\t\tSCALE 1 1 1"))
    assert "line 18: unexpected 'SCALE' in joint 'B'" in message


def test_unknown_channel_name(tmp_path: Path) -> None:
    message = _read_error(tmp_path, SMALL_BVH.replace("Xrotation Yrotation\n\t\tEnd", "Xrotation Wrotation\n\t\tEnd"))
    assert "line 9: joint 'A': unknown channel 'Wrotation'" in message


def test_channel_count_larger_than_names(tmp_path: Path) -> None:
    message = _read_error(tmp_path, SMALL_BVH.replace("CHANNELS 3 Zrotation", "CHANNELS 4 Zrotation"))
    assert "joint 'A'" in message


def test_a_joint_name_keeps_the_spaces_written_inside_it(tmp_path: Path) -> None:
    # "Left  Shoulder" was read, and written back, as "Left Shoulder".
    text = SMALL_BVH.replace("JOINT A", "JOINT Left  Shoulder").replace("\tJOINT B", "\tJOINT  B\t x  ")
    motion = read_bvh(_write(tmp_path, text))
    assert motion.skeleton.names[1:4:2] == ["Left  Shoulder", "B\t x"]
    write_bvh(tmp_path / "again.bvh", motion)
    assert read_bvh(tmp_path / "again.bvh").skeleton.names == motion.skeleton.names


def test_duplicate_joint_name(tmp_path: Path) -> None:
    assert "joint name 'A' is used twice" in _read_error(tmp_path, SMALL_BVH.replace("JOINT B", "JOINT A"))


def test_missing_motion_section(tmp_path: Path) -> None:
    assert "no MOTION section" in _read_error(tmp_path, SMALL_BVH.split("MOTION")[0])


def test_not_a_bvh_file(tmp_path: Path) -> None:
    assert "line 1: expected 'HIERARCHY', found 'ply'" in _read_error(tmp_path, "ply\nformat ascii 1.0\n")


@pytest.mark.parametrize("frame_time", ["1e-320", "0", "-0.1", "inf", "nan", "x"])
def test_frame_time_without_a_finite_rate(tmp_path: Path, frame_time: str) -> None:
    message = _read_error(tmp_path, SMALL_BVH.replace(".0333333", frame_time))
    assert (
        f"line 23: expected 'Frame Time: SECONDS' > 0 with a finite frame rate, found 'Frame Time: {frame_time}'"
        in message
    )


def test_channel_count_that_is_a_non_ascii_digit(tmp_path: Path) -> None:
    message = _read_error(tmp_path, SMALL_BVH.replace("CHANNELS 3 Zrotation", "CHANNELS ³ Zrotation"))
    assert "line 9: joint 'A': channel count '³' is not a whole number" in message


def test_unicode_space_inside_a_value_is_not_a_separator(tmp_path: Path) -> None:
    value = "9\u00a00"  # a no-break space, which str.split() would split on
    message = _read_error(tmp_path, SMALL_BVH.replace("90 90 0 7", f"90 {value} 0 7"))
    assert f"line 25 (frame 1), joint 'A' Xrotation: {value!r} is not a number" in message
