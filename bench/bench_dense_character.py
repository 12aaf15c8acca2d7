"""A dense skinned character through ``animlod motion``: where the time goes, and the skin
measurement of its levels against the numpy bakes it replaced.

Run: ``.venv/bin/python bench/bench_dense_character.py`` (part of ``make bench``). Xbot.glb
(../shared/data/gltf; skipped when absent) with its triangles split in four twice (175k
vertices, 333k triangles; a new vertex takes the four largest of its edge's ends' skin weights,
halved) and its walk repeated 40 times (1,200 frames; 1,470 with its 6 other clips), written to a
temporary GLB. Rows: ``build_motion_levels`` (what ``animlod motion`` runs) with 8 levels, its
seconds; then the summary's "skin max" column, the largest distance of a level's skin from the
input's in each frame, measured for those 8 levels by ``SkinnedMesh.distance_maxima`` (the core,
every frame, nothing stored: what ``animlod motion`` runs) and by baking both skins' frames and
taking numpy's norms (the code before 2026-12-05, in chunks of 4M positions), in the same run,
with whether the two agree bit for bit. Wall and CPU seconds (all threads of this process).
``--write GLB`` only writes the dense character, to time the commands on it.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table, wall_and_cpu

from animlod.io import read_skinned, write_glb
from animlod.model import Motion, SkinnedMesh
from animlod.pipelines.motion import _read_input, build_motion_levels

XBOT = DATA_DIR / "gltf" / "Xbot.glb"
SPLITS = 2
WALK_REPEATS = 40
LEVELS = 8


def split_in_four(skin: SkinnedMesh) -> SkinnedMesh:
    """``skin`` with each triangle split into four at its edges' midpoints (UVs halfway too)."""
    faces = skin.faces
    sides = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    edges, side_edge = np.unique(np.sort(sides, axis=1), axis=0, return_inverse=True)
    a, b = edges[:, 0], edges[:, 1]
    joints = np.concatenate([skin.joints[a], skin.joints[b]], axis=1)
    weights = 0.5 * np.concatenate([skin.weights[a], skin.weights[b]], axis=1)
    largest = np.argsort(-weights, axis=1, kind="stable")[:, : skin.joints.shape[1]]
    midpoint = len(skin.rest_positions) + side_edge.reshape(3, -1)  # (3 sides, M): the vertex on each side
    ab, bc, ca = midpoint
    f0, f1, f2 = faces.T
    return SkinnedMesh(
        np.concatenate([skin.rest_positions, 0.5 * (skin.rest_positions[a] + skin.rest_positions[b])]),
        np.concatenate(
            [np.stack(corners, axis=1) for corners in ((f0, ab, ca), (ab, f1, bc), (ca, bc, f2), (ab, bc, ca))]
        ),
        np.concatenate([skin.joints, np.take_along_axis(joints, largest, axis=1)]),
        np.concatenate([skin.weights, np.take_along_axis(weights, largest, axis=1)]),
        skin.inverse_bind,
        skin.skeleton,
        uvs=None if skin.uvs is None else np.concatenate([skin.uvs, 0.5 * (skin.uvs[a] + skin.uvs[b])]),
    )


def dense_xbot(path: Path) -> str:
    """Writes the dense Xbot to ``path``; its size."""
    skin, motions = read_skinned(XBOT)
    for _ in range(SPLITS):
        skin = split_in_four(skin)
    walk = next(motion for motion in motions if motion.name == "walk")
    clips = [Motion.concatenate([walk] * WALK_REPEATS, "long_walk")] + [m for m in motions if m is not walk]
    write_glb(path, skin, clips)
    frames = sum(clip.frame_count for clip in clips)
    return f"{skin.vertex_count} vertices, {skin.face_count} triangles, {len(clips)} clips, {frames} frames"


def numpy_distances(skin: SkinnedMesh, motion: Motion, others: list[tuple[SkinnedMesh, Motion]]) -> np.ndarray:
    """The skin distances as measured before the core kernel: both skins baked, numpy's norms."""
    chunk = max(1, 4_000_000 // skin.vertex_count)
    out = np.empty((len(others), motion.frame_count), np.float32)
    for start in range(0, motion.frame_count, chunk):
        frames = slice(start, min(start + chunk, motion.frame_count))
        original = skin.bake(motion.take_frames(frames)).frames
        for row, (other, played) in enumerate(others):
            posed = other.bake(played.take_frames(frames)).frames
            out[row, frames] = np.linalg.norm(posed - original, axis=-1).max(axis=1)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", metavar="GLB", type=Path, help="only write the dense character to GLB")
    args = parser.parse_args()
    if not XBOT.is_file():
        print(f"skipped: {XBOT} not found")
        return
    if args.write:
        print(f"{args.write}: {dense_xbot(args.write)}")
        return
    with tempfile.TemporaryDirectory() as folder:
        source = Path(folder) / "dense_xbot.glb"
        size = dense_xbot(source)
        report, wall, cpu = wall_and_cpu(lambda: build_motion_levels(source, Path(folder) / "levels", LEVELS))
        rows = [("build_motion_levels, 8 levels (animlod motion)", wall, cpu, "-")]
        motion, _, skin, _ = _read_input(source, None, (), None, lambda note: None)
    others = [(level.skin, level.motion) for level in report.chain.levels]
    core, wall, cpu = wall_and_cpu(lambda: skin.distance_maxima(motion, others))
    peer, peer_wall, peer_cpu = wall_and_cpu(lambda: numpy_distances(skin, motion, others))
    same = "yes" if np.array_equal(core.view(np.uint32), peer.view(np.uint32)) else "NO"
    rows.append((f"skin distances of its {len(others)} levels, core (SkinnedMesh.distance_maxima)", wall, cpu, same))
    rows.append((f"skin distances of its {len(others)} levels, numpy bakes (peer)", peer_wall, peer_cpu, same))
    print_table(f"Dense character: {size}", ("case", "wall s", "CPU s", "bit for bit"), rows)


if __name__ == "__main__":
    main()
