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
