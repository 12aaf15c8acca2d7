"""Reading (and OBJ writing) speed of the file formats on the real development data (../shared/data).

Run: ``.venv/bin/python bench/bench_io.py``. Each row is the best of a few runs; inputs that
are absent are skipped. The crane sequence is also converted to binary PLY and NPZ in a
temporary folder, to show what the faster containers buy over OBJ text, and written as a
textured OBJ sequence (texture coordinates and normals, as exporters write one). Every dev glTF is parsed
into its checked document (io/gltf_decode.py builds pygltflib's object model), with pygltflib's
own loader (dataclasses_json) as the peer.
"""

from __future__ import annotations

import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np
from devdata import DATA_DIR
from table import print_table, stopwatch

from animlod.io import read_bvh, read_npz, read_sequence, read_textured_sequence, write_npz, write_sequence
from animlod.io.gltf_document import GltfDocument
from animlod.io.meshseq import SequenceTexture
from animlod.model import AnimatedMesh
from animlod.normals import Shading

REPEATS = 3


def best_time(action: Callable[[], object]) -> tuple[float, object]:
    """Shortest wall time of ``REPEATS`` runs of ``action`` and its last result."""
    times = []
    for _ in range(REPEATS):
        with stopwatch() as elapsed:
            result = action()
        times.append(elapsed[0])
    return min(times), result


def main() -> None:
    rows = []
    for name in ("131_01.bvh", "dataset-1_run_proud_001.bvh"):
        path = DATA_DIR / "bvh" / name
        if not path.is_file():
            print(f"skipped {path}: not found")
            continue
        seconds, motion = best_time(lambda path=path: read_bvh(path))
        end_sites = int(motion.skeleton.end_sites.sum())
        size = f"{motion.skeleton.joint_count - end_sites} joints + {end_sites} end sites, {motion.frame_count} frames"
        rows.append((f"read BVH {name}", size, seconds * 1e3, motion.frame_count / seconds))
    crane = DATA_DIR / "meshseq" / "crane"
    if crane.is_dir():
        seconds, mesh = best_time(lambda: read_sequence(crane))
        size = f"{mesh.vertex_count} vertices, {mesh.face_count} faces, {mesh.frame_count} frames"
        rows.append(("read OBJ sequence crane/", size, seconds * 1e3, mesh.frame_count / seconds))
        with tempfile.TemporaryDirectory() as folder:
            seconds, _ = best_time(lambda: write_textured_crane(Path(folder) / "textured", mesh))
            rows.append(("write textured OBJ sequence (crane)", size, seconds * 1e3, mesh.frame_count / seconds))
            seconds, _ = best_time(lambda: read_textured_sequence(Path(folder) / "textured"))
            rows.append(("read textured OBJ sequence (crane)", size, seconds * 1e3, mesh.frame_count / seconds))
            write_sequence(Path(folder) / "ply", mesh, fmt="ply")
            write_npz(Path(folder) / "crane.npz", mesh)
            seconds, _ = best_time(lambda: read_sequence(Path(folder) / "ply"))
            rows.append(("read binary PLY sequence (crane)", size, seconds * 1e3, mesh.frame_count / seconds))
            seconds, _ = best_time(lambda: read_npz(Path(folder) / "crane.npz"))
            rows.append(("read NPZ (crane)", size, seconds * 1e3, mesh.frame_count / seconds))
    else:
        print(f"skipped {crane}: not found")
    rows += gltf_rows()
    print_table("File reading and writing (best of 3)", ["case", "size", "time (ms)", "frames/s"], rows)


def write_textured_crane(folder: Path, mesh: AnimatedMesh) -> None:
    """The crane as an exporter writes a textured sequence: every frame's ``v`` and ``vn`` lines
    its own, its ``vt`` lines (a planar projection of the first frame) and ``f v/vt/vn`` corners
    the same in every file."""
    first = mesh.frames[0]
    span = np.ptp(first[:, :2], axis=0)
    uvs = ((first[:, :2] - first[:, :2].min(axis=0)) / np.where(span > 0, span, 1)).astype(np.float32)
    points = np.arange(mesh.vertex_count, dtype=np.int32)
    write_sequence(folder, mesh, texture=SequenceTexture(uvs, points), shading=Shading(np.pi, False))


def gltf_rows() -> list[tuple]:
    """Parsing every dev glTF: animlod's checked document against pygltflib's own loader."""
    import warnings

    import pygltflib

    rows = []
    for path in sorted(p for folder in ("gltf", "morph") for p in (DATA_DIR / folder).glob("*.gl*")):
        seconds, doc = best_time(lambda path=path: GltfDocument(path))
        size = f"{len(doc.gltf.accessors)} accessors, {path.stat().st_size / 1e6:.1f} MB"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # pygltflib warns about unknown chunks
            peer, _ = best_time(lambda path=path: pygltflib.GLTF2.load(str(path)))
        rows.append((f"parse glTF {path.name} (animlod)", size, seconds * 1e3, "-"))
        rows.append((f"parse glTF {path.name} (pygltflib.GLTF2.load)", size, peer * 1e3, "-"))
    return rows


if __name__ == "__main__":
    main()
