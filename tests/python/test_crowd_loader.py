"""The crowd binary's glTF reader (bench/crowd/lod_asset.cpp) on hand-written GLBs: every skin
influence set read, vertices without skin weight on their first joint, default and animated morph
weights drawn, damaged MSFT_lod chains refused.

Each GLB is a 2 m strip of 10 vertices skinned to a chain of three joints (root, mid, top), bent
at a constant angle by its one clip, so that a screenshot shows the skin and two files that skin
alike draw the same pixels. The binary is run directly (under xvfb-run without a display); the
tests skip where it is not built (``make test`` sets ANIMLOD_CROWD_BIN).
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
from pathlib import Path

import matplotlib.image
import numpy as np
import pygltflib
import pytest

ROWS = np.linspace(0.0, 2.0, 5)
POSITIONS = np.array([[x, y, 0.0] for y in ROWS for x in (-0.2, 0.2)], np.float32)  # (10, 3)
FACES = np.array([[2 * r, 2 * r + 1, 2 * r + 3, 2 * r, 2 * r + 3, 2 * r + 2] for r in range(4)], np.uint16)
FACES = FACES.reshape(-1, 1)  # (24, 1) indices of the 4 rows' quads
BONE = np.where(POSITIONS[:, 1] < 0.6, 0, np.where(POSITIONS[:, 1] < 1.3, 1, 2))  # (10,) joint of each row
JOINT_HEIGHTS = (0.0, 0.67, 1.33)  # root, mid, top; further joints are children of mid at its place
_TYPES = {1: "SCALAR", 3: "VEC3", 4: "VEC4", 16: "MAT4"}
_COMPONENTS = {np.dtype(np.float32): 5126, np.dtype(np.uint16): 5123, np.dtype(np.uint32): 5125}


Skin = dict[int, tuple[np.ndarray, np.ndarray]]  # n -> JOINTS_n, WEIGHTS_n (V, 4)


def influence_sets(joints: np.ndarray, weights: np.ndarray) -> Skin:
    """(V, 4k) joints and weights as k JOINTS_n / WEIGHTS_n sets."""
    return {s // 4: (joints[:, s : s + 4], weights[:, s : s + 4]) for s in range(0, joints.shape[1], 4)}


def rigid_skin(sets: int = 1, in_set: int = 0) -> Skin:
    """Each vertex wholly on its row's joint, written in set `in_set` of `sets`."""
    joints, weights = np.zeros((10, 4 * sets), np.uint16), np.zeros((10, 4 * sets), np.float32)
    joints[:, 4 * in_set], weights[:, 4 * in_set] = BONE, 1.0
    return influence_sets(joints, weights)


class Glb:
    """A glTF document as a dict with one binary buffer, written as a GLB."""

    def __init__(self) -> None:
        self.json: dict = {"asset": {"version": "2.0"}, "bufferViews": [], "accessors": []}
        self.blob = bytearray()

    def view(self, values: np.ndarray) -> int:
        self.blob.extend(b"\0" * (-len(self.blob) % 4))
        self.json["bufferViews"].append({"buffer": 0, "byteOffset": len(self.blob), "byteLength": values.nbytes})
        self.blob.extend(np.ascontiguousarray(values).tobytes())
        return len(self.json["bufferViews"]) - 1

    def accessor(self, values: np.ndarray, sparse: bool = False) -> int:
        """An accessor of (N, C) `values`; `sparse` stores only the non-zero rows (as Blender writes shape keys)."""
        accessor = {"componentType": _COMPONENTS[values.dtype], "count": len(values), "type": _TYPES[values.shape[1]]}
        if sparse:
            rows = np.flatnonzero(np.any(values != 0, axis=1)).astype(np.uint16)
            accessor["sparse"] = {
                "count": len(rows),
                "indices": {"bufferView": self.view(rows), "componentType": 5123},
                "values": {"bufferView": self.view(values[rows])},
            }
        else:
            accessor["bufferView"] = self.view(values)
        if values.shape[1] == 3:
            accessor["min"], accessor["max"] = values.min(axis=0).tolist(), values.max(axis=0).tolist()
        self.json["accessors"].append(accessor)
        return len(self.json["accessors"]) - 1

    def write(self, path: Path) -> Path:
        self.blob.extend(b"\0" * (-len(self.blob) % 4))
        self.json["buffers"] = [{"byteLength": len(self.blob)}]
        text = json.dumps(self.json).encode()
        text += b" " * (-len(text) % 4)
        chunks = struct.pack("<II", len(text), 0x4E4F534A) + text  # JSON
        chunks += struct.pack("<II", len(self.blob), 0x004E4942) + self.blob  # BIN
        path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)
        return path


def strip(
    path: Path,
    skin: Skin,
    extra_joints: int = 0,
    normals: np.ndarray | None = None,
    targets: list[dict[str, np.ndarray]] | None = None,
    sparse_targets: bool = False,
    mesh_weights: list | None = None,
    node_weights: list | None = None,
    lod_ids: list | None = None,
    coverages: list | None = None,
    positions: np.ndarray = POSITIONS,
    weight_keys: tuple[str, np.ndarray] | None = None,
) -> Path:
    """The strip as a GLB: `skin` its JOINTS_n / WEIGHTS_n, `extra_joints` more joints at
    mid; `lod_ids` the base node's MSFT_lod ids, of which id 4 + extra_joints is a level node
    drawing the same mesh (the node after the joints); `weight_keys` (interpolation, outputs
    (2 or 6, T)) a channel of the clip setting the strip's morph weights, keys at 0 and 1 s."""
    glb = Glb()
    attributes = {"POSITION": glb.accessor(positions)}
    if normals is not None:
        attributes["NORMAL"] = glb.accessor(normals)
    for n, (joints, weights) in skin.items():
        attributes[f"JOINTS_{n}"] = glb.accessor(joints.astype(np.uint16))
        attributes[f"WEIGHTS_{n}"] = glb.accessor(weights.astype(np.float32))
    primitive = {"attributes": attributes, "indices": glb.accessor(FACES)}
    if targets:
        primitive["targets"] = [{name: glb.accessor(d, sparse_targets) for name, d in t.items()} for t in targets]
    mesh = {"primitives": [primitive]}
    if mesh_weights is not None:
        mesh["weights"] = mesh_weights
    extra = list(range(4, 4 + extra_joints))
    nodes = [
        {"name": "strip", "mesh": 0, "skin": 0},
        {"name": "root", "children": [2]},
        {"name": "mid", "translation": [0, 0.67, 0], "children": [3, *extra]},
        {"name": "top", "translation": [0, 0.66, 0]},
        *({"name": f"extra{j}"} for j in extra),
    ]
    if node_weights is not None:
        nodes[0]["weights"] = node_weights
    if lod_ids is not None:
        nodes.append({"name": "strip L1", "mesh": 0, "skin": 0, "extras": {"animlod": {"error": 0.1, "mesh_level": 1}}})
        nodes[0]["extensions"] = {"MSFT_lod": {"ids": lod_ids}}
        glb.json["extensionsUsed"] = ["MSFT_lod"]
    if coverages is not None:
        nodes[0]["extras"] = {"MSFT_screencoverage": coverages}
    heights = [*JOINT_HEIGHTS, *(JOINT_HEIGHTS[1] for _ in extra)]
    inverse_binds = np.tile(np.eye(4, dtype=np.float32).reshape(1, 16), (len(heights), 1))
    inverse_binds[:, 13] = [-y for y in heights]  # column-major: the translation's y
    bent = [0.0, 0.0, np.sin(0.4), np.cos(0.4)]  # mid turned 0.8 rad about z at every key
    clip = {
        "input": glb.accessor(np.array([[0.0], [1.0]], np.float32)),
        "output": glb.accessor(np.array([bent, bent], np.float32)),
    }
    samplers, channels = [clip], [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}]
    if weight_keys is not None:
        interpolation, outputs = weight_keys
        times, values = glb.accessor(np.array([[0.0], [1.0]], np.float32)), glb.accessor(outputs.reshape(-1, 1))
        samplers.append({"input": times, "output": values, "interpolation": interpolation})
        channels.append({"sampler": 1, "target": {"node": 0, "path": "weights"}})
    glb.json.update(
        scene=0,
        scenes=[{"nodes": [0, 1]}],
        nodes=nodes,
        meshes=[mesh],
        skins=[{"joints": [1, 2, 3, *extra], "inverseBindMatrices": glb.accessor(inverse_binds)}],
        animations=[{"name": "bend", "samplers": samplers, "channels": channels}],
    )
    return glb.write(path)


def run(binary: Path, glb: Path, *arguments: str, display: bool = True) -> subprocess.CompletedProcess:
    """The binary on `glb`, 1 character near the camera; under xvfb-run where there is no display."""
    command = [str(binary), str(glb), "--count", "1", "--frames", "2", "--warmup", "0", "--modes", "Original"]
    command += ["--path", "pullback", "--width", "320", "--height", "240", *arguments]
    if display and not os.environ.get("DISPLAY"):
        command = ["xvfb-run", "-a", "-s", "-screen 0 640x480x24", *command]
    return subprocess.run(command, capture_output=True, text=True, check=False, timeout=120)


def screenshot(binary: Path, glb: Path) -> np.ndarray:
    """Frame 0 of the strip (the nearest), RGB."""
    shot = glb.with_suffix(".png")
    completed = run(binary, glb, "--screenshot", "0", str(shot))
    assert completed.returncode == 0, completed.stderr
    return matplotlib.image.imread(shot)[..., :3]


def report(binary: Path, glb: Path) -> tuple[dict, str]:
    """The JSON report's entry of `glb` and the binary's stderr."""
    out = glb.with_suffix(".json")
    completed = run(binary, glb, "--json", str(out))
    assert completed.returncode == 0, completed.stderr
    return json.loads(out.read_text())["chains"][0], completed.stderr


def differing_pixels(a: np.ndarray, b: np.ndarray) -> int:
    return int(np.count_nonzero(np.abs(a - b).max(axis=-1) > 0.05))


def strip_pixels(image: np.ndarray) -> int:
    """Pixels of the grey strip (the sky is blue, the ground green)."""
    return int(np.count_nonzero(image.max(axis=-1) - image.min(axis=-1) < 0.05))


def test_every_influence_set_is_read(binary, tmp_path) -> None:
    # JOINTS_2 / WEIGHTS_2 were ignored: weights only in the third set were refused ("no positive
    # skin weight"), and a quarter of each vertex's weight there was dropped.
    base = screenshot(binary, strip(tmp_path / "base.glb", rigid_skin()))
    assert strip_pixels(base) > 500
    last = screenshot(binary, strip(tmp_path / "last.glb", rigid_skin(sets=3, in_set=2)))
    assert differing_pixels(base, last) == 0
    # Half on the row's joint, a quarter on the top joint (in the third set), a quarter on the root
    # spread over ten slots: at most 3 joints a vertex, as the same weights in one set.
    joints, weights = np.zeros((10, 12), np.uint16), np.zeros((10, 12), np.float32)
    joints[:, 0], weights[:, 0] = BONE, 0.5
    weights[:, 1:11] = 0.025
    joints[:, 11], weights[:, 11] = 2, 0.25
    twelve = screenshot(binary, strip(tmp_path / "twelve.glb", influence_sets(joints, weights)))
    merged = np.zeros((10, 3), np.float32)
    np.add.at(merged, (np.arange(10), BONE), 0.5)
    merged[:, 0] += 0.25
    merged[:, 2] += 0.25
    four_joints = np.tile(np.array([0, 1, 2, 0], np.uint16), (10, 1))
    four_weights = np.pad(merged, ((0, 0), (0, 1)))
    four = screenshot(binary, strip(tmp_path / "four.glb", influence_sets(four_joints, four_weights)))
    assert differing_pixels(base, four) > 10  # the control: these weights bend the strip otherwise
    assert differing_pixels(twelve, four) == 0


def test_more_influences_than_the_gpu_holds_keep_the_largest_weights_with_a_warning(binary, tmp_path) -> None:
    # 9 joints a vertex: the row's joint 0.6, then eight joints at mid with 0.1 (in the third set,
    # which was dropped silently) down to 0.02. The GPU holds 8: the smallest (ties: the later
    # joint) goes and the rest is renormalised, as the same 8 written in two sets draw; said once
    # for the mesh although two level nodes draw it.
    extra = [0.1, 0.08, 0.06, 0.05, 0.04, 0.03, 0.02, 0.02]  # joints 3 to 10
    joints, weights = np.zeros((10, 12), np.uint16), np.zeros((10, 12), np.float32)
    joints[:, 0], weights[:, 0] = BONE, 0.6
    joints[:, 1:8], weights[:, 1:8] = np.arange(4, 11), extra[1:]
    joints[:, 8], weights[:, 8] = 3, extra[0]
    nine = strip(tmp_path / "nine.glb", influence_sets(joints, weights), extra_joints=8, lod_ids=[12])
    entry, stderr = report(binary, nine)
    warning = (f"animlod_crowd: warning: {nine}: level 0 (node 0 'strip') mesh 0: 10 vertices have more than 8 skin "
               "influences; the GPU skinning keeps the 8 largest weights of each, renormalised")  # fmt: skip
    assert stderr.count("warning") == 1 and warning in stderr.splitlines()
    assert entry["warnings"] == [warning.split(f"{nine}: ", 1)[1]]
    kept_joints = np.concatenate([BONE[:, None], np.tile(np.arange(3, 10), (10, 1))], axis=1)
    kept_weights = np.tile(np.array([0.6, *extra[:7]], np.float32) / 0.98, (10, 1))
    eight = strip(tmp_path / "eight.glb", influence_sets(kept_joints, kept_weights), extra_joints=8)
    unmoved = strip(tmp_path / "unmoved.glb", rigid_skin(), extra_joints=8)
    shots = {name: screenshot(binary, glb) for name, glb in (("nine", nine), ("eight", eight), ("unmoved", unmoved))}
    assert differing_pixels(shots["eight"], shots["unmoved"]) > 10  # the control: the joints at mid move it
    assert differing_pixels(shots["nine"], shots["eight"]) == 0
    assert "warning" not in report(binary, eight)[1]


def test_default_morph_weights_are_drawn(binary, tmp_path) -> None:
    # A target that lifts the top row 1 m and turns the normals, on by default (a Blender shape key
    # left on): the strip was drawn and measured at its base shape, 2 m tall.
    lift = np.zeros_like(POSITIONS)
    lift[POSITIONS[:, 1] > 1.9, 1] = 1.0
    facing = np.tile(np.array([0.0, 0.0, 1.0], np.float32), (10, 1))
    turned = np.tile(np.array([0.0, 0.8, 0.6], np.float32), (10, 1))
    target = [{"POSITION": lift, "NORMAL": turned - facing}]
    skin = rigid_skin()
    heights = {}
    for name, options in {
        "mesh": {"mesh_weights": [1.0]},
        "half": {"mesh_weights": [0.5]},
        "node": {"mesh_weights": [1.0], "node_weights": [0.0]},  # a node's weights override its mesh's
        "sparse": {"mesh_weights": [1.0], "sparse_targets": True},
    }.items():
        glb = strip(tmp_path / f"{name}.glb", skin, normals=facing, targets=target, **options)
        heights[name] = report(binary, glb)[0]["height"]
    assert heights == pytest.approx({"mesh": 3.0, "half": 2.5, "node": 2.0, "sparse": 3.0})
    # Drawn as the same shape written without a target, its normals turned too.
    baked = screenshot(binary, strip(tmp_path / "baked.glb", skin, normals=turned, positions=POSITIONS + lift))
    morph = strip(tmp_path / "morph.glb", skin, normals=facing, targets=target, mesh_weights=[1.0])
    morphed = screenshot(binary, morph)
    unlit = screenshot(binary, strip(tmp_path / "unlit.glb", skin, normals=facing, positions=POSITIONS + lift))
    assert differing_pixels(baked, unlit) > 100  # the control: the normals change the shading
    assert differing_pixels(morphed, baked) == 0


def _push_and_turn() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A target pushing the top two rows 0.5 m towards the camera and turning every normal:
    (push, facing, turned) (10, 3). It leaves the strip's height, which places the camera, as it is."""
    push = np.zeros_like(POSITIONS)
    push[POSITIONS[:, 1] > 1.4, 2] = 0.5
    facing = np.tile(np.array([0.0, 0.0, 1.0], np.float32), (10, 1))
    turned = np.tile(np.array([0.0, 0.8, 0.6], np.float32), (10, 1))
    return push, facing, turned


@pytest.mark.parametrize(
    ("interpolation", "weight"),
    [("LINEAR", [[1.0], [1.0]]), ("STEP", [[1.0], [1.0]]), ("CUBICSPLINE", [[0.0], [1.0], [0.0]] * 2)],
)
def test_a_clip_of_morph_weights_is_played(binary, tmp_path, interpolation, weight) -> None:
    # The clip holds the target at 1 over a default weight of 0 (at every clip time, so that the
    # character's random phase does not matter): the crowd drew the default weights only, as if
    # the clip had no weights channel.
    push, facing, turned = _push_and_turn()
    skin = rigid_skin()
    keys = (interpolation, np.array(weight, np.float32))
    target = [{"POSITION": push, "NORMAL": turned - facing}]
    played = strip(tmp_path / "played.glb", skin, normals=facing, targets=target, mesh_weights=[0.0], weight_keys=keys)
    baked = screenshot(binary, strip(tmp_path / "baked.glb", skin, normals=turned, positions=POSITIONS + push))
    unmorphed = screenshot(binary, strip(tmp_path / "unmorphed.glb", skin, normals=facing))
    shot = screenshot(binary, played)
    assert differing_pixels(baked, unmorphed) > 100  # the control: the target shows
    assert differing_pixels(shot, baked) == 0


def test_a_clip_of_morph_weights_overrides_the_default_weights(binary, tmp_path) -> None:
    # Weights 0 over a default of 1: the clip's weights are drawn, not the node's (a shape key left
    # on in the file, which the clip turns off).
    push, facing, turned = _push_and_turn()
    skin = rigid_skin()
    target = [{"POSITION": push, "NORMAL": turned - facing}]
    played = strip(tmp_path / "played.glb", skin, normals=facing, targets=target, node_weights=[1.0],
                   weight_keys=("LINEAR", np.zeros((2, 1), np.float32)))  # fmt: skip
    unmorphed = screenshot(binary, strip(tmp_path / "unmorphed.glb", skin, normals=facing))
    shown = screenshot(binary, strip(tmp_path / "shown.glb", skin, normals=facing, targets=target, node_weights=[1.0]))
    assert differing_pixels(shown, unmorphed) > 100  # the control: the default weight shows without the clip
    assert differing_pixels(screenshot(binary, played), unmorphed) == 0


def test_a_weights_channel_of_the_wrong_size_is_refused_with_one_line(binary, tmp_path) -> None:
    push, _, _ = _push_and_turn()
    glb = strip(tmp_path / "short.glb", rigid_skin(), targets=[{"POSITION": push}] * 2,
                weight_keys=("LINEAR", np.zeros((3, 1), np.float32)))  # fmt: skip
    completed = run(binary, glb, display=False)
    assert completed.returncode == 2 and completed.stderr.count("\n") == 1
    assert "animation 0 'bend' channel 1: output holds 3 numbers for 2 keys of 2 morph weights" in completed.stderr


def test_vertices_without_skin_weight_follow_their_first_joint_with_a_warning(binary, tmp_path) -> None:
    # glTF forbids them, but Blender before 2.90 and Maya2glTF write the vertices no bone deforms
    # with all-zero weights; three.js, Blender's importer and animlod's reader move them with their
    # first listed joint. The crowd refused the file ("vertex 8 has no positive skin weight").
    skin = rigid_skin()
    joints, weights = skin[0]
    unweighted = weights.copy()
    unweighted[8:] = 0.0  # the top row, on joint 2 (top) first
    glb = strip(tmp_path / "unweighted.glb", {0: (joints, unweighted)})
    entry, stderr = report(binary, glb)
    warning = (
        f"animlod_crowd: warning: {glb}: level 0 (node 0 'strip') mesh 0 primitive 0: 2 of 10 vertices (first: 8) "
        "have no positive skin weight; they follow their first listed joint, as three.js and Blender do"
    )
    assert warning in stderr.splitlines() and stderr.count("warning") == 1
    assert entry["warnings"] == [warning.split(f"{glb}: ", 1)[1]]
    on_root = joints.copy()
    on_root[8:, 0] = 0
    rooted = screenshot(binary, strip(tmp_path / "rooted.glb", {0: (on_root, weights)}))
    rigid = screenshot(binary, strip(tmp_path / "rigid.glb", skin))
    assert differing_pixels(rigid, rooted) > 10  # the control: the top row on another joint
    assert differing_pixels(screenshot(binary, glb), rigid) == 0


@pytest.mark.parametrize(
    ("options", "reason"),
    [
        ({"lod_ids": [0]}, "node 0 'strip': MSFT_lod id 0 (0) is the node itself"),
        ({"lod_ids": [4, 4]}, "node 0 'strip': MSFT_lod id 1 (4) repeats an earlier id"),
        ({"lod_ids": [4.7]}, "node 0 'strip': MSFT_lod id 0 (4.7) is not a node: ids are node indices below 5"),
        ({"lod_ids": ["4"]}, "node 0 'strip': MSFT_lod id 0 ('4') is not a node"),
        ({"lod_ids": [4], "coverages": ["big", "small"]}, "MSFT_screencoverage value 0 ('big') is not a number"),
        ({"lod_ids": [4], "coverages": [-1, -2]}, "level 0 has coverage -1.000000, expected a finite value >= 0"),
        ({"lod_ids": [4], "coverages": [0.1, 0.5]}, "MSFT_screencoverage must not increase"),
        (
            {"targets": [{"POSITION": np.ones((10, 3), np.float32)}], "mesh_weights": [1.0, 0.0]},
            "has 1 morph targets for 2 default morph weights",
        ),
    ],
)
def test_damaged_chains_and_morph_weights_are_refused_with_one_line(binary, tmp_path, options, reason) -> None:
    # Accepted before: the base node as its own level, a node twice, 4.7 read as node 4, string
    # coverages read as 0, negative or increasing coverages (the selector assumes them valid); and
    # default morph weights that do not match the targets, ignored while targets were.
    glb = strip(tmp_path / "damaged.glb", rigid_skin(), **options)
    out = tmp_path / "report.json"
    completed = run(binary, glb, "--json", str(out), display=False)  # refused before any window opens
    assert completed.returncode == 2
    assert completed.stderr.count("\n") == 1 and completed.stderr.startswith(f"animlod_crowd: error: {glb}: ")
    assert reason in completed.stderr
    assert not out.exists()


def test_influence_sets_numbered_with_a_gap_are_refused(binary, tmp_path) -> None:
    skin = rigid_skin(sets=2)
    glb = strip(tmp_path / "gap.glb", {0: skin[0], 2: skin[1]})  # no JOINTS_1 / WEIGHTS_1
    completed = run(binary, glb, display=False)
    assert completed.returncode == 2 and completed.stderr.count("\n") == 1
    assert "mesh 0 primitive 0: numbers its JOINTS_n / WEIGHTS_n sets with a gap" in completed.stderr


def test_an_accessor_count_near_2_to_the_64_is_refused(binary, tmp_path) -> None:
    # 2^62 VEC4 elements: the sizes wrapped to 0 and the reader wrote past its buffer (exit 139).
    glb = strip(tmp_path / "huge.glb", rigid_skin())
    data = glb.read_bytes()
    length = struct.unpack("<I", data[12:16])[0]
    document = json.loads(data[20 : 20 + length])
    document["accessors"][1]["count"] = 2**62  # JOINTS_0
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + length :]
    glb.write_bytes(struct.pack("<4sIIII", b"glTF", 2, 20 + len(text) + len(rest), len(text), 0x4E4F534A) + text + rest)
    completed = run(binary, glb, display=False)
    assert completed.returncode == 2 and completed.stderr.count("\n") == 1
    assert "JOINTS_0 accessor 1: count 4611686018427387904 is more than animlod_crowd reads" in completed.stderr


def _on_a_still_joint(gltf, blob, weights_channel: bool) -> None:
    """A morph-animated bird (no skin) bound wholly to one joint that its first clip holds at rest,
    so that the crowd takes it; without `weights_channel` that clip no longer sets the weights."""
    from gltf_edits import append_accessor

    node = next(i for i, n in enumerate(gltf.nodes) if n.mesh is not None)
    for primitive in gltf.meshes[gltf.nodes[node].mesh].primitives:
        count = gltf.accessors[primitive.attributes.POSITION].count
        primitive.attributes.JOINTS_0 = append_accessor(gltf, blob, np.zeros((count, 4), np.uint16), "VEC4")
        weights = np.tile(np.array([1.0, 0.0, 0.0, 0.0], np.float32), (count, 1))
        primitive.attributes.WEIGHTS_0 = append_accessor(gltf, blob, weights, "VEC4")
    gltf.nodes.append(pygltflib.Node(name="still joint"))
    gltf.scenes[gltf.scene or 0].nodes.append(len(gltf.nodes) - 1)
    gltf.skins.append(pygltflib.Skin(joints=[len(gltf.nodes) - 1]))
    gltf.nodes[node].skin = len(gltf.skins) - 1
    animation = gltf.animations[0]
    if not weights_channel:
        animation.channels = []
    times = animation.samplers[0].input
    rest = np.tile(np.array([0.0, 0.0, 0.0, 1.0], np.float32), (gltf.accessors[times].count, 1))
    animation.samplers.append(pygltflib.AnimationSampler(input=times, output=append_accessor(gltf, blob, rest, "VEC4")))
    target = pygltflib.AnimationChannelTarget(node=len(gltf.nodes) - 1, path="rotation")
    animation.channels.append(pygltflib.AnimationChannel(sampler=len(animation.samplers) - 1, target=target))


def test_the_morph_clips_of_the_development_birds_play(binary, data_dir, tmp_path) -> None:
    # The development files whose clips set morph weights (three.js' parrot and stork, 12 and 13
    # targets of POSITION deltas, LINEAR) have no skin; bound to a joint held still, they drew the
    # same frame whether their clip set the weights or not.
    from gltf_edits import edit_glb

    birds = sorted((data_dir / "morph").glob("*.glb"))
    assert birds
    for bird in birds:
        shots = {}
        for played in (True, False):
            glb = tmp_path / f"{bird.stem}_{'played' if played else 'still'}.glb"
            edit_glb(bird, glb, lambda gltf, blob, played=played: _on_a_still_joint(gltf, blob, played))
            shots[played] = screenshot(binary, glb)
        assert strip_pixels(shots[False]) > 100, bird.name  # the bird is in view
        assert differing_pixels(shots[True], shots[False]) > 100, bird.name
