"""Seed inputs of the fuzz harnesses, made at fuzz time from the procedural assets and, when
present, the development data (never copied into the repository).

``SEEDS[kind](data_dir)`` returns ``{name: bytes}`` for the SEEDS column of harnesses.txt;
``data_dir`` is None when the development data is absent. Seeds are kept small (at most
MAX_SEED_BYTES), so that every execution stays far below the 1 s timeout: big real files are
cut down (the first vertices and the faces among them, the first frames of a motion).

The C++ kinds encode meshes in the layout documented in tests/fuzz/cpp/fuzz_input.hpp.
"""

from __future__ import annotations

import io
import json
import os
import re
import struct
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

MAX_SEED_BYTES = 120_000
_RAW_FLOATS = 1  # decode_mesh mode bit: float32 coordinates


# ---------------------------------------------------------------------------------------------
# Small meshes shared by several kinds


def _procedural_meshes() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{name: (frames (F, V, 3) float32, faces (M, 3) int32)}``, a few hundred vertices each."""
    from animlod import synth

    meshes = {
        "cylinder": synth.bending_cylinder(frames=4, rings=6, segments=8),
        "bar": synth.twisting_bar(frames=3, rings=4, segments=8),
        "sphere": synth.translating_mesh(frames=2, subdivisions=1),
    }
    result = {name: (mesh.frames, mesh.faces) for name, mesh in meshes.items()}
    # An open strip (boundary edges) and a single triangle: the smallest cases.
    grid = np.array([[x, y, 0.0] for y in range(3) for x in range(3)], np.float32)
    strip = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [3, 4, 7], [3, 7, 6], [4, 5, 8], [4, 8, 7]])
    result["grid"] = (np.stack([grid, grid + [0, 0, 0.5]]), strip.astype(np.int32))
    result["triangle"] = (np.eye(3, dtype=np.float32)[None], np.array([[0, 1, 2]], np.int32))
    return result


def _real_meshes(data_dir: Path | None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Cut-down meshes from the development data: crane (OBJ) and the parrot (morph glTF)."""
    if data_dir is None:
        return {}
    from animlod.io import read_gltf, read_obj

    result = {}
    crane = sorted((data_dir / "meshseq" / "crane").glob("*.obj"))[:2]
    if crane:
        frames = [_crop(*read_obj(path), 150) for path in crane]
        result["crane"] = (np.stack([f[0] for f in frames]), frames[0][1])
    parrot = data_dir / "morph" / "Parrot.glb"
    if parrot.is_file():
        mesh = read_gltf(parrot).morph_animations[0]
        vertices, faces = _crop(mesh.frames[0], mesh.faces, 200)
        result["parrot"] = (mesh.frames[:3, : len(vertices)], faces)
    return result


def _crop(vertices: np.ndarray, faces: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The first ``count`` vertices and the faces among them."""
    return vertices[:count], faces[(faces < count).all(axis=1)]


def _all_meshes(data_dir: Path | None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    return {**_procedural_meshes(), **_real_meshes(data_dir)}


def encode_mesh(frames: np.ndarray, faces: np.ndarray) -> bytes:
    """The decode_mesh layout of fuzz_input.hpp, with raw float32 coordinates."""
    frame_count, vertex_count, _ = frames.shape
    header = struct.pack("<BHHH", _RAW_FLOATS, frame_count - 1, vertex_count - 1, len(faces))
    return header + np.asarray(frames, "<f4").tobytes() + np.asarray(faces, "<u2").tobytes()


# ---------------------------------------------------------------------------------------------
# C++ harnesses


def seeds_mesh(data_dir: Path | None) -> dict[str, bytes]:
    return {name: encode_mesh(*mesh) for name, mesh in _all_meshes(data_dir).items()}


def seeds_features(data_dir: Path | None) -> dict[str, bytes]:
    # flags (boundary_is_feature), threshold 0 (adaptive), min_angle_change ~1 degree
    return {name: bytes([1, 0, 4]) + encode_mesh(*mesh) for name, mesh in _all_meshes(data_dir).items()}


def seeds_aqem(data_dir: Path | None) -> dict[str, bytes]:
    seeds = {}
    variants = {
        # flags, flags2, levels - 1, 4 level bytes, max_frames, max_error, threshold, counts (A | weld off << 2
        # | B << 3), influences - 1
        "default": (0b00010111, 0, 2, [128, 64, 26, 0], 0, 0, 0, 0, 0),
        "on_edge_skin": (0b00110111, 0b00000011, 1, [128, 51, 0, 0], 2, 0, 0, 2, 3),
        "locked_counts": (0b11010011, 0b00010100, 1, [200, 100, 0, 0], 1, 8, 16, 0, 0),
        "groups_morph": (0b00010111, 0b11000001, 0, [128, 0, 0, 0], 0, 0, 0, 0b1001, 0),
        "no_weld": (0b00010111, 0, 0, [100, 0, 0, 0], 0, 0, 0, 0b100, 0),
    }
    for name, mesh in _all_meshes(data_dir).items():
        vertex_count, face_count = mesh[0].shape[1], len(mesh[1])
        for variant, (flags, flags2, levels, sizes, max_frames, max_error, threshold, attrs, k) in variants.items():
            header = bytes([flags, flags2, levels, *sizes, max_frames, max_error, threshold, attrs, k])
            tail = b""
            if flags & 0x40:  # every 7th vertex locked
                tail += bytes(int(v % 7 == 0) for v in range(vertex_count))
            if flags & 0x80:
                tail += bytes([16] * vertex_count)
            if flags2 & 1 and attrs & 3:
                tail += np.arange(vertex_count * (attrs & 3), dtype="<i2").tobytes()
            if flags2 & 2:
                tail += bytes([1, 128, 0, 127] * vertex_count * (k + 1))[: 2 * vertex_count * (k + 1)]
            if flags2 & 0x40 and attrs >> 3:
                tail += (np.arange(vertex_count * (attrs >> 3), dtype="<i2") % 7).tobytes()
            if flags2 & 0x80:
                tail += bytes(f * 4 // max(face_count, 1) for f in range(face_count))
            seeds[f"{name}_{variant}"] = header + encode_mesh(*mesh) + tail
    return seeds


def seeds_lbs(data_dir: Path | None) -> dict[str, bytes]:
    from animlod import synth

    skin, motion = synth.bending_cylinder_skinned(frames=3, rings=4, segments=6)
    matrices = motion.skin_matrices(skin.inverse_bind).astype("<f4").transpose(0, 1, 3, 2)  # column-major
    frame_count, joint_count = matrices.shape[:2]
    vertex_count, influences = skin.joints.shape
    header = struct.pack("<BHBBB", _RAW_FLOATS, vertex_count, influences - 1, joint_count - 1, frame_count - 1)
    weights = np.round(skin.weights * 255).astype(np.uint8)
    body = skin.rest_positions.astype("<f4").tobytes() + skin.joints.astype("<u2").tobytes() + weights.tobytes()
    return {"cylinder": header + body + matrices.tobytes()}


def _int16(values) -> bytes:
    """Numbers in the int16 / 64 coding of FuzzInput::coordinate (rounded to the grid)."""
    return np.clip(np.round(np.asarray(values, np.float64) * 64), -32767, 32767).astype("<i2").tobytes()


def seeds_pose(data_dir: Path | None) -> dict[str, bytes]:
    """Skeletons and clips in the layout of fuzz_pose.cpp (int16 mode): a 3-joint chain with one
    channel of each path and interpolation, and the procedural humanoid's walk (rotations)."""
    from animlod import synth

    def encode(parents, channels, samples, rest_t, rest_r, flags=0b110) -> bytes:
        out = bytes([flags, len(parents) - 1])
        out += bytes(0 if p < 0 else p + 1 for p in parents)  # value % (j + 1) - 1
        out += bytes([len(channels)])
        for path, interpolation, joint, times, values in channels:
            out += bytes([path | interpolation << 2]) + struct.pack("<H", joint) + bytes([len(times)])
            out += _int16([times[0]]) + bytes(int(round((b - a) * 64)) for a, b in zip(times, times[1:]))
            out += _int16(values)
        out += bytes([len(samples) - 1]) + _int16(samples)
        out += _int16(rest_t) + _int16(rest_r)
        if flags & 0b100:
            out += _int16(np.ones((len(parents), 3)))
        return out + bytes([len(parents) - 1]) + bytes(range(len(parents))) + _int16(np.tile(np.eye(4), len(parents)))

    quarter = [0.0, 0.0, 0.7071, 0.7071]
    chain = [
        (1, 0, 1, [0.0, 0.5, 1.0], [[0, 0, 0, 1], quarter, [0, 0, 1, 0]]),  # rotation, linear
        (0, 2, 0, [0.0, 1.0], [[0, 0, 0], [1, 0, 0], [0, 0, 0], [0, 0, 0], [0, 1, 0], [0, 0, 0]]),  # cubic
        (2, 1, 2, [0.25, 0.75], [[1, 1, 1], [2, 2, 2]]),  # scale, step
        (1, 2, 2, [0.0, 1.0], [[0, 0, 0, 0], [0, 0, 0, 1], [0, 0, 0, 0]] * 2),  # rotation, cubic
    ]
    rest_t, rest_r = [[0, 0, 0], [0, 1, 0], [0, 1, 0]], [[0, 0, 0, 1]] * 3
    seeds = {"chain": encode([-1, 0, 1], chain, [-1.0, 0.0, 0.3, 0.5, 1.0, 2.0], rest_t, rest_r)}
    seeds["chain_slerp"] = encode([-1, 0, 1], chain[:1], [0.1, 0.9], rest_t, rest_r, flags=0)
    skeleton = synth.humanoid_skeleton()
    motion = synth.humanoid_motion(skeleton, "walk")
    joints = min(skeleton.joint_count, 32)
    times = [k / 8 for k in range(4)]
    walk = [(1, 0, j, times, motion.local_rotations[:4, j]) for j in range(min(joints, 12))]
    parents = [int(p) for p in skeleton.parents[:joints]]
    seeds["walk"] = encode(parents, walk, [0.0, 0.2, 0.37], skeleton.offsets[:joints], [[0, 0, 0, 1]] * joints)
    return seeds


def seeds_ffd(data_dir: Path | None) -> dict[str, bytes]:
    """Lattices in the layout of fuzz_ffd_lattice.cpp (int16 mode): the face's 3x3x3 and 2x2x2
    lattices over a box around mesh points, weighted and plain, with two lattices displaced."""
    seeds = {}
    for name, (frames, _) in list(_all_meshes(data_dir).items())[:4]:
        points = frames[0][:200].astype(np.float64)
        low, high = points.min(axis=0), points.max(axis=0)
        extent = np.maximum(high - low, 0.25)
        for size, flags in ((3, 0b010), (2, 0b100), (4, 0b000)):
            controls = size**3
            grid = np.stack(np.meshgrid(*[np.linspace(0, 1, size)] * 3, indexing="ij"), -1).reshape(-1, 3)
            out = bytes([flags, size, size, size]) + struct.pack("<H", len(points) - 1)
            out += _int16(low) + _int16(np.diag(extent)) + _int16(points)
            if flags & 0b010:
                out += bytes([32 + (c % 5) * 8 for c in range(controls)])
            out += _int16(low + grid * extent + 0.05)
            # ffd_displace: lattices (size^3, 2^3), 2 frames, vertices alternating, displacements
            out += bytes([1, size, size, size, 2, 2, 2, 1])
            out += struct.pack(f"<{len(points)}H", *[v % 3 for v in range(len(points))])  # 2 -> index 2 % 2 = 0
            total = controls + 8
            out += _int16(np.sin(np.arange(2 * total * 3)) * 0.1)
            if flags & 0b010:
                out += bytes([32] * total)
            out += bytes([0, 0, 1, 16, 16]) + _int16(points + 0.01)
            if flags & 0b100:
                out += _int16(np.zeros((8, 3)))
            if flags & 0b010:
                out += bytes([32] * 12)
            seeds[f"{name}_{size}"] = out
    return seeds


def seeds_refit(data_dir: Path | None) -> dict[str, bytes]:
    """Re-fit problems in the layout of fuzz_motion_refit.cpp (int16 mode): a bent chain of unit
    bones with a branching point, its lengths, a handed group and frozen-joint angles, over 3
    frames of a swaying motion; soft and hard, each solved; and with the branch's children tied to
    each other (a minimal rigid set: a rigid body of the core's reduction)."""
    key = np.array([[0, 0, 0], [0, 1, 0], [0, 2, 0], [1, 2, 0], [-1, 2, 0], [0, 2, 1], [1, 3, 0], [0, 3, 0]], float)
    parents = [-1, 0, 1, 2, 2, 2, 3, 2]
    bones = [(j, parents[j]) for j in range(1, len(key))]
    triples = [(1, 2, 3), (0, 1, 2), (2, 3, 6)]
    cosines = []
    for p, j, c in triples:
        u, v = key[p] - key[j], key[c] - key[j]
        cosines.append(float(u @ v / np.linalg.norm(u) / np.linalg.norm(v)))
    quad = (2, 3, 4, 5)
    volume = float(np.linalg.det(np.stack([key[q] - key[quad[0]] for q in quad[1:]])))
    frames = np.stack([key + np.array([0.1 * t, 0.0, 0.05 * t]) * (np.arange(len(key)) > 1)[:, None] for t in range(3)])
    seeds = {}
    siblings = [(4, 3), (5, 3), (5, 4)]
    cases = (("soft", 0b01011100, bones), ("hard", 0b01011110, bones), ("hard_cold", 0b01111110, bones),
             ("plain", 0b01000000, bones), ("hard_body", 0b01011110, bones + siblings))  # fmt: skip
    for name, flags, pairs in cases:
        lengths = [np.linalg.norm(key[a] - key[b]) for a, b in pairs]
        out = bytes([flags, len(key), 2, len(pairs)])
        out += struct.pack(f"<{2 * len(pairs)}H", *[i for pair in pairs for i in pair])
        out += bytes(int(round(length * 32)) for length in lengths)
        out += bytes([1]) + struct.pack("<2H", 6, 7)  # a coincident pair
        out += bytes([1]) + struct.pack("<4H", *quad) + struct.pack("<b", int(np.clip(volume * 8, -127, 127)))
        out += bytes([len(triples)]) + struct.pack(f"<{3 * len(triples)}H", *[i for t in triples for i in t])
        out += struct.pack(f"<{len(cosines)}b", *[int(round(c * 120)) for c in cosines])
        out += bytes([13, 26, 26, 16, 39, 1]) + _int16(frames)
        if flags & 0b00100000:
            out += _int16(frames)
        seeds[name] = out
    return seeds


def seeds_tdag(data_dir: Path | None) -> dict[str, bytes]:
    """TDAG bodies (fuzz_tdag.cpp wraps them in a valid header and CRC) of small meshes, built
    with several governing meshes, and whole files (flag bit 0)."""
    from animlod.model import AnimatedMesh
    from animlod.tdag import TemporalDag

    seeds = {}
    meshes = list(_procedural_meshes().items()) + list(_real_meshes(data_dir).items())[:1]
    for name, (frames, faces) in meshes:
        mesh = AnimatedMesh(faces, frames, 30.0)
        for governing in ("first", "online"):
            data = TemporalDag.build(mesh, governing=governing).to_bytes()
            seeds[f"{name}_{governing}"] = bytes([0, 4, 0]) + data[20:-4]  # header 20 bytes, CRC 4
        seeds[f"{name}_file"] = bytes([1, 253, 1]) + data
    return seeds


def seeds_crowd_glb(data_dir: Path | None) -> dict[str, bytes]:
    """GLBs split into JSON and BIN for fuzz_crowd_glb.cpp (which writes the container): the
    skinned cylinder as a one-level chain, as a two-level MSFT_lod chain and as that chain with
    KHR_animation_pointer channels, and the small
    skinned characters of the development data; plus a whole file (flag bit 0)."""
    import pygltflib

    def split(glb: bytes) -> bytes:
        json_length = struct.unpack_from("<I", glb, 12)[0]
        body = glb[20 : 20 + json_length]
        bin_chunk = glb[20 + json_length + 8 :] if len(glb) > 20 + json_length else b""
        return bytes([0]) + struct.pack("<I", len(body)) + body + bin_chunk

    cylinder = _small_glb()
    seeds = {"cylinder": split(cylinder), "cylinder_file": bytes([1]) + cylinder}
    gltf = pygltflib.GLTF2.load_from_bytes(cylinder)
    base = next(i for i, node in enumerate(gltf.nodes) if node.mesh is not None and node.skin is not None)
    extras = {"animlod": {"level": 1, "error": 0.01, "mesh_level": 1, "motion_level": 0}}
    level = pygltflib.Node(mesh=gltf.nodes[base].mesh, skin=gltf.nodes[base].skin, extras=extras)
    gltf.nodes.append(level)
    gltf.nodes[base].extensions = {"MSFT_lod": {"ids": [len(gltf.nodes) - 1]}}
    gltf.nodes[base].extras = {"MSFT_screencoverage": [0.5, 0.0], "animlod": {"level": 0, "error": 0.0}}
    gltf.extensionsUsed = [*(gltf.extensionsUsed or []), "MSFT_lod"]
    seeds["cylinder_lod"] = split(b"".join(gltf.save_to_bytes()))
    # The same chain's joints moved through KHR_animation_pointer, plus a pointer at no node
    # (animation_pointers.cpp rewrites them before tinygltf reads the file).
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))  # tests/python
    from crowd_chain import channels_as_pointers

    channels_as_pointers(gltf)
    seeds["cylinder_pointers"] = split(b"".join(gltf.save_to_bytes()))
    for path in (data_dir / "gltf").glob("*.glb") if data_dir else ():
        if path.stat().st_size <= 60_000:
            seeds[path.stem] = split(path.read_bytes())
    return seeds


# ---------------------------------------------------------------------------------------------
# Python readers


def _written(suffix: str, write: Callable[[Path], None]) -> bytes:
    """The bytes a writer produces for a file named ``*suffix``."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"seed{suffix}"
        write(path)
        return path.read_bytes()


def seeds_bvh(data_dir: Path | None) -> dict[str, bytes]:
    from animlod import synth
    from animlod.io import write_bvh
    from animlod.model import Motion

    motion = synth.humanoid_motion(synth.humanoid_skeleton(), "walk")
    short = Motion(motion.skeleton, motion.root_positions[:3], motion.local_rotations[:3], motion.fps, "walk")
    seeds = {"walk": _written(".bvh", lambda path: write_bvh(path, short, precision=3))}
    for path in sorted((data_dir / "bvh").glob("*.bvh")) if data_dir else []:
        text = path.read_bytes()
        seeds[path.stem] = _first_frames(text, 3)
    return seeds


def _first_frames(text: bytes, count: int) -> bytes:
    """A BVH file cut to its first ``count`` MOTION rows (Frames: updated)."""
    head, _, table = text.partition(b"MOTION")
    lines = table.splitlines(keepends=True)
    rows = [line for line in lines[3:] if line.strip()][:count]
    frames = re.sub(rb"\d+", str(len(rows)).encode(), lines[1], count=1)
    return head + b"MOTION" + lines[0] + frames + lines[2] + b"".join(rows)


def seeds_obj(data_dir: Path | None) -> dict[str, bytes]:
    from animlod.io import write_obj

    seeds = {}
    for name, (frames, faces) in _all_meshes(data_dir).items():
        seeds[name] = _written(".obj", lambda path, f=frames, m=faces: write_obj(path, f[0], m))
    # What other exporters write: v/vt/vn corners, negative indices, quads, groups, comments.
    seeds["corners"] = (
        b"# exporter\nmtllib a.mtl\no cube\nv 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
        b"g side\nusemtl red\ns off\nf 1/1/1 2/1/1 3/1/1 4/1/1\n  f -4//1 -2//1 -1//1\n"
    )
    return seeds


def seeds_ply(data_dir: Path | None) -> dict[str, bytes]:
    from animlod.io import write_ply

    seeds = {}
    for name, (frames, faces) in _all_meshes(data_dir).items():
        for binary in (True, False):
            kind = "binary" if binary else "ascii"
            write = lambda path, f=frames, m=faces, b=binary: write_ply(path, f[0], m, binary=b)  # noqa: E731
            seeds[f"{name}_{kind}"] = _written(".ply", write)
    seeds["extras"] = (
        b"ply\nformat ascii 1.0\ncomment x\nelement vertex 3\nproperty float x\nproperty float y\n"
        b"property float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_index\n"
        b"property int flags\nelement edge 0\nproperty int vertex1\nend_header\n0 0 0 1\n1 0 0 2\n0 1 0 3\n3 0 1 2 7\n"
    )
    return seeds


def _small_glb() -> bytes:
    from animlod import synth
    from animlod.io import write_glb

    skin, motion = synth.bending_cylinder_skinned(frames=3, rings=4, segments=6)
    return _written(".glb", lambda path: write_glb(path, skin, [motion]))


def seeds_glb(data_dir: Path | None) -> dict[str, bytes]:
    seeds = {"cylinder": _small_glb()}
    for folder in ("gltf", "morph", "meshseq/Flamingo-morph-glTF") if data_dir else ():
        for path in sorted((data_dir / folder).glob("*.glb")):
            if path.stat().st_size <= MAX_SEED_BYTES:
                seeds[path.stem] = path.read_bytes()
    return seeds


def seeds_gltf(data_dir: Path | None) -> dict[str, bytes]:
    import pygltflib

    glb = pygltflib.GLTF2.load_from_bytes(_small_glb())
    glb.convert_buffers(pygltflib.BufferFormat.DATAURI)
    seeds = {"cylinder": glb.gltf_to_json().encode()}
    for folder in ("gltf", "morph") if data_dir else ():
        for path in sorted((data_dir / folder).glob("*.gltf")):
            if path.stat().st_size <= MAX_SEED_BYTES:
                seeds[path.stem] = path.read_bytes()
    # The JSON structures that break naive readers: deep nesting, references out of range.
    seeds["deep"] = b'{"asset": {"version": "2.0"}, "extras": ' + b"[" * 64 + b"]" * 64 + b"}"
    seeds["dangling"] = json.dumps(
        {"asset": {"version": "2.0"}, "scene": 3, "scenes": [{"nodes": [0]}], "nodes": [{"name": "a"}],
         "animations": [{"channels": [{"sampler": 0, "target": {"node": 9, "path": "rotation"}}], "samplers": []}]}
    ).encode()  # fmt: skip
    return seeds


def seeds_npz(data_dir: Path | None) -> dict[str, bytes]:
    from animlod.io import write_npz
    from animlod.model import AnimatedMesh

    seeds = {}
    for name, (frames, faces) in _all_meshes(data_dir).items():
        seeds[name] = _written(".npz", lambda path, f=frames, m=faces: write_npz(path, AnimatedMesh(m, f, 30.0)))
    # Stored (not deflated) members: mutations then reach numpy's header parser directly.
    buffer = io.BytesIO()
    frames, faces = _procedural_meshes()["triangle"]
    np.savez(buffer, format_version=np.int32(1), faces=faces, frames=frames, fps=np.float64(np.nan))
    seeds["stored"] = buffer.getvalue()
    return seeds


def seeds_manifest(data_dir: Path | None) -> dict[str, bytes]:
    from animlod.io.manifest import write_lod_manifest

    levels = [
        {"files": ["a_lod0.bvh", "a_lod0.glb"], "joints": 41, "error": 0.0},
        {"files": ["a_lod1.bvh"], "joints": 20, "error": 0.012},
    ]
    mesh_levels = [{"file": "c.glb", "faces": 1000, "error": 0.0}, {"file": "c1.glb", "faces": 100, "error": 0.1}]
    return {
        "motion": _written(".json", lambda path: write_lod_manifest(path, "motion", levels)),
        "mesh": _written(".json", lambda path: write_lod_manifest(path, "skinned mesh", mesh_levels)),
    }


SEEDS: dict[str, Callable[[Path | None], dict[str, bytes]]] = {
    "mesh": seeds_mesh,
    "features": seeds_features,
    "aqem": seeds_aqem,
    "lbs": seeds_lbs,
    "pose": seeds_pose,
    "ffd": seeds_ffd,
    "refit": seeds_refit,
    "tdag": seeds_tdag,
    "crowd_glb": seeds_crowd_glb,
    "bvh": seeds_bvh,
    "obj": seeds_obj,
    "ply": seeds_ply,
    "gltf": seeds_gltf,
    "glb": seeds_glb,
    "npz": seeds_npz,
    "manifest": seeds_manifest,
}


def data_dir() -> Path | None:
    """The development data (ANIMLOD_DATA, else ../shared/data beside the checkout), or None."""
    default = Path(__file__).resolve().parents[3] / "shared" / "data"
    folder = Path(os.environ.get("ANIMLOD_DATA", default))
    return folder if folder.is_dir() else None


def write_seeds(kind: str, folder: Path) -> int:
    """Write the seeds of ``kind`` into ``folder`` (emptied first); returns how many."""
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.iterdir():
        old.unlink()
    seeds = {name: data for name, data in SEEDS[kind](data_dir()).items() if len(data) <= MAX_SEED_BYTES}
    for name, data in seeds.items():
        (folder / name).write_bytes(data)
    return len(seeds)
