"""``animlod simplify INPUT -o OUT --ratio 0.5 0.25 0.1``: AQEM levels of detail of an animation."""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from ..io.detect import input_kind, input_stem
from ..model import AnimatedMesh
from . import UserError


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "simplify",
        help="simplify a deforming or skinned mesh over all its frames (AQEM)",
        description=(
            "Build levels of detail of an animated mesh with the animated quadric error metric and motion "
            "features (Yang et al. 2019): one connectivity per level for all frames, every vertex placed "
            "optimally in every frame. OBJ/PLY sequences are written as sequences, NPZ as NPZ, skinned glTF as "
            "GLB with merged skin weights and the input's animations; morph-animated glTF as NPZ (baked frames)."
        ),
    )
    parser.add_argument("input", help="a folder, glob or file of OBJ/PLY frames, an .npz, or a .glb/.gltf")
    parser.add_argument("-o", "--output", required=True, help="folder to write the levels into (created if missing)")
    parser.add_argument("--ratio", type=float, nargs="+", default=[0.5, 0.25, 0.1], help="face ratios of the levels")
    parser.add_argument(
        "--max-error", type=float, default=math.inf, help="stop when the error exceeds this (asset units)"
    )
    parser.add_argument("--no-features", action="store_true", help="ignore motion features (all vertex weights 1)")
    parser.add_argument("--max-frames", type=int, default=0, help="quadrics over K frames chosen to cover the motion")
    parser.add_argument(
        "--placement",
        choices=("optimal", "on_edge"),
        default=None,
        help="optimal: Eq. 5 per frame (default for sequences); on_edge: one point of the edge (default for skins)",
    )
    parser.add_argument("--no-metrics", action="store_true", help="skip the Hausdorff/RMS measurement")
    parser.add_argument(
        "--plot", action="store_true", help="write a PNG of one frame: features in red, levels side by side"
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if any(not 0.0 < ratio <= 1.0 for ratio in args.ratio):
        raise UserError(f"--ratio: every ratio must be in (0, 1], got {args.ratio}")
    kind = input_kind(args.input)
    if kind == "bvh":
        raise UserError(f"{args.input}: a BVH file holds motion only; simplify needs a mesh")
    output = Path(args.output)
    output.mkdir(parents=True, exist_ok=True)
    options = {"max_error": args.max_error, "use_motion_features": not args.no_features, "max_frames": args.max_frames}
    if args.placement:
        options["placement"] = args.placement
    stem = input_stem(args.input)

    if kind == "gltf":
        from ..io.gltf import read_gltf

        scene = read_gltf(args.input)
        if scene.skinned_meshes:
            return _simplify_skinned(args, scene, output, stem, options)
        if not scene.morph_animations:
            raise UserError(f"{args.input}: no skinned or morph-animated mesh to simplify")
        original = scene.morph_animations[0]
    elif kind == "npz":
        from ..io.npz import read_npz

        original = read_npz(args.input)
    else:
        from ..io.meshseq import read_sequence

        original = read_sequence(args.input)

    from ..aqem import simplify_animated

    start = time.perf_counter()
    progress = _ProgressBar("AQEM")
    try:
        result = simplify_animated(original, args.ratio, progress=progress, **options)
    finally:
        progress.close()
    elapsed = time.perf_counter() - start
    rows = []
    for index, level in enumerate(result.levels):
        _write_animated(kind, args.input, output / f"{stem}_lod{index + 1}", level.mesh)
        rows.append(_row(index + 1, level.mesh, level.error, original, args.no_metrics, elapsed))
    _print_summary(original, rows)
    if args.plot:
        _plot(output / f"{stem}_levels.png", original, [level.mesh for level in result.levels], not args.no_features)
    return 0


def _simplify_skinned(args: argparse.Namespace, scene, output: Path, stem: str, options: dict) -> int:
    """Levels of the first skinned mesh over all the scene's animations, written as GLB."""
    from ..aqem import simplify_skinned
    from ..io.gltf import write_glb

    skinned, motions = scene.skinned_meshes[0], scene.motions
    start = time.perf_counter()
    levels = simplify_skinned(skinned, motions, args.ratio, **options)
    elapsed = time.perf_counter() - start
    original = skinned.bake(motions[0]) if motions else AnimatedMesh(skinned.faces, skinned.rest_positions[None])
    # Measured after re-skinning with the merged weights, on the first animation (or the rest pose).
    rows, reskinned = [], []
    for index, level in enumerate(levels):
        write_glb(output / f"{stem}_lod{index + 1}.glb", level.mesh, motions)
        posed = (
            level.mesh.bake(motions[0]) if motions else AnimatedMesh(level.mesh.faces, level.mesh.rest_positions[None])
        )
        reskinned.append(posed)
        rows.append(_row(index + 1, posed, level.error, original, args.no_metrics, elapsed))
    _print_summary(original, rows)
    if args.plot:
        _plot(output / f"{stem}_levels.png", original, reskinned, not args.no_features)
    return 0


def _write_animated(kind: str, source: str, target: Path, mesh: AnimatedMesh) -> None:
    """Write a level in the input's format (NPZ for NPZ and morph-animated glTF)."""
    if kind == "sequence":
        from ..io.meshseq import write_sequence

        files = sorted(Path(source).iterdir()) if Path(source).is_dir() else [Path(source)]
        fmt = "ply" if any(path.suffix.lower() == ".ply" for path in files) else "obj"
        target.mkdir(parents=True, exist_ok=True)
        write_sequence(target, mesh, fmt)
    else:
        from ..io.npz import write_npz

        write_npz(target.with_suffix(".npz"), mesh)


def _row(
    level: int, mesh: AnimatedMesh, error: float, original: AnimatedMesh, skip_metrics: bool, elapsed: float
) -> tuple:
    """One summary row; the surface error compares ``mesh`` with ``original`` frame by frame."""
    hausdorff = rms = "-"
    if not skip_metrics:
        from ..metrics import surface_error

        summary = surface_error(original, mesh, samples=10000).summary()
        hausdorff = f"{summary['hausdorff_mean']:.2e} / {summary['hausdorff_max']:.2e}"
        rms = f"{summary['rms_mean']:.2e} / {summary['rms_max']:.2e}"
    return (level, mesh.face_count, f"{error:.3g}", hausdorff, rms, f"{elapsed:.2f}")


def _print_summary(original: AnimatedMesh, rows: list[tuple]) -> None:
    header = ("level", "faces", "AQEM error", "Hausdorff mean / max", "RMS mean / max", "time s")
    table = [header, (0, original.face_count, "0", "-", "-", "-")] + rows
    widths = [max(len(str(row[column])) for row in table) for column in range(len(header))]
    print("errors relative to the bounding-box diagonal, over frames; time is the whole simplification")
    for row in table:
        print("  ".join(str(value).rjust(width) for value, width in zip(row, widths)))


class _ProgressBar:
    """A tqdm bar fed by the simplifier's progress(done, total) callback; close() when done."""

    def __init__(self, description: str) -> None:
        self.description = description
        self.bar = None

    def __call__(self, done: int, total: int) -> None:
        from tqdm import tqdm

        if self.bar is None:
            self.bar = tqdm(total=total, desc=self.description, unit="collapse", leave=False)
        self.bar.update(min(done, total) - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _plot(path: Path, original: AnimatedMesh, levels: list[AnimatedMesh], show_features: bool) -> None:
    """One frame (the middle) of the original with its motion features in red, then each level."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from ..aqem import motion_features
    from ..io.atomic import atomic_write

    frame = original.frame_count // 2
    red = np.zeros(original.face_count, dtype=bool)
    if show_features:
        in_feature = motion_features(original).vertex_feature >= 0
        red = in_feature[original.faces].any(axis=1)
    meshes = [(original, red, f"original, {original.face_count} faces (features red)")]
    meshes += [(mesh, np.zeros(mesh.face_count, bool), f"{mesh.face_count} faces") for mesh in levels]
    figure = plt.figure(figsize=(4 * len(meshes), 4.5))
    corners = original.frames[frame]
    low, high = corners.min(axis=0), corners.max(axis=0)
    for index, (mesh, highlight, title) in enumerate(meshes):
        axes = figure.add_subplot(1, len(meshes), index + 1, projection="3d")
        triangles = mesh.frames[frame][mesh.faces]
        colors = np.where(highlight[:, None], [0.85, 0.1, 0.1, 1.0], [0.75, 0.75, 0.8, 1.0])
        axes.add_collection3d(
            Poly3DCollection(triangles, facecolors=colors, edgecolors=(0, 0, 0, 0.15), linewidths=0.2)
        )
        axes.set_xlim(low[0], high[0])
        axes.set_ylim(low[1], high[1])
        axes.set_zlim(low[2], high[2])
        axes.set_box_aspect(np.maximum(high - low, 1e-9))
        axes.view_init(elev=90, azim=-90)  # look down -z: x right, y up (the usual glTF/OBJ up axis)
        axes.set_axis_off()
        axes.set_title(title, fontsize=9)
    with atomic_write(path, "wb") as handle:
        figure.savefig(handle, format="png", dpi=100, bbox_inches="tight")
    plt.close(figure)
    print(f"wrote {path}")
