"""``animlod simplify INPUT -o OUT --ratio 0.5 0.25 0.1``: AQEM levels of detail of an animation."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from ..aqem import Preparation
from ..io.detect import GLB_OUTPUT_SUFFIXES, glb_name, input_kind, input_stem
from ..model import AnimatedMesh
from ..options import AqemOptions
from ..pipelines.lod_document import DrawableReport
from ..pipelines.lod_sequence import MEASURED_FRAMES
from . import UserError, add_joint_map_argument, positive_int, print_rows


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "simplify",
        help="simplify a glTF scene or a deforming mesh over all its frames (AQEM)",
        description=(
            "Build levels of detail with the animated quadric error metric and motion features (Yang et al. 2019): "
            "one connectivity per level for all frames. A glTF/GLB goes in whole and comes out as one LoD GLB: "
            "every node, material, texture and animation kept, each drawn mesh's levels attached with MSFT_lod "
            "and MSFT_screencoverage (--separate: one whole GLB per level instead). Any topology is accepted: "
            "seams are welded and kept, non-manifold spots cut and kept in place. OBJ/PLY sequences are written "
            "as sequences and NPZ as NPZ, one per level."
        ),
    )
    parser.add_argument("input", help="a .glb/.gltf/.vrm, an .npz, or a folder, glob or file of OBJ/PLY frames")
    parser.add_argument(
        "-o",
        "--output",
        required=True,
        help="glTF input: the LoD .glb (or .vrm) to write, or a folder for <name>_lod.glb (with --separate: the folder "
        "for the level files); sequences and NPZ: the folder for the levels",
    )
    parser.add_argument("--ratio", type=float, nargs="+", default=[0.5, 0.25, 0.1], help="face ratios of the levels")
    parser.add_argument(
        "--max-error", type=float, default=math.inf, help="stop when the error exceeds this (asset units)"
    )
    parser.add_argument("--no-features", action="store_true", help="ignore motion features (all vertex weights 1)")
    parser.add_argument(
        "--feature-weighting",
        choices=("amplitude", "paper"),
        default=None,
        help="motion features weighted by amplitude (bounded weights where dihedral angles move far above their "
        "spread; the default for sequences and NPZ) or paper (Eq. 6 as published: a feature's vertex count); "
        "glTF inputs use no motion features unless this is given",
    )
    parser.add_argument(
        "--max-frames",
        type=positive_int,
        default=None,
        help="sequences: quadrics over K frames chosen to cover the motion (default: every frame, unless their "
        "quadrics would not fit in memory); glTF: the most frames of all clips that drive the simplification "
        "(default 48)",
    )
    parser.add_argument(
        "--placement",
        choices=("optimal", "on_edge"),
        default=None,
        help="optimal: Eq. 5 per frame (default for sequences and static meshes); on_edge: one point of the "
        "edge (default for skinned and morphed meshes, and for sequences with texture coordinates or vertex "
        "colours, whose values are those of that point)",
    )
    parser.add_argument(
        "--no-tip-quadrics",
        action="store_true",
        help="the paper's quadrics only: no point quadric at needle tips (the ends of legs, beaks and spikes, whose "
        "faces lie nearly parallel to them, then collapse first)",
    )
    parser.add_argument(
        "--fold-limit",
        type=float,
        default=None,
        metavar="DEPTH",
        help="beside Eq. 7's sum over the frames, refuse a collapse that folds a face in any one frame deeper than "
        "DEPTH lengths of its opposite edge (default 1: box limbs, whose flat sides bend in their plane, do not fold "
        "across the bend, and captures' noise, which tips slivers over, does not stall the collapses); 0: no flip in "
        "any frame; inf: Eq. 7 alone, the paper's test",
    )
    parser.add_argument("--separate", action="store_true", help="glTF: one whole GLB per level instead of one LoD GLB")
    parser.add_argument(
        "--clips", nargs="+", default=(), metavar="FILE",
        help="glTF: glTF files of clips on the same rig (an animation library without the mesh), added to the "
        "input's own by node name, and BVH files of its skeleton or of another humanoid's, matched by shape or body "
        "part: they drive the skinned meshes' levels, and the output plays them",
    )  # fmt: skip
    add_joint_map_argument(parser)
    parser.add_argument("--no-metrics", action="store_true", help="sequences: skip the Hausdorff/RMS measurement")
    parser.add_argument(
        "--metric-frames", type=int, default=MEASURED_FRAMES, metavar="K",
        help=f"sequences: measure at most K frames, evenly spaced (default {MEASURED_FRAMES})",
    )  # fmt: skip
    parser.add_argument(
        "--plot", action="store_true", help="write a PNG of one frame: features in red, levels side by side"
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    if any(not 0.0 < ratio <= 1.0 for ratio in args.ratio):
        raise UserError(f"--ratio: every ratio must be in (0, 1], got {args.ratio}")
    if args.metric_frames < 1:
        raise UserError(f"--metric-frames: expected at least 1 frame, got {args.metric_frames}")
    kind = input_kind(args.input)
    if kind == "bvh":
        raise UserError(f"{args.input}: a BVH file holds motion only; simplify needs a mesh")
    options = {"max_error": args.max_error, **feature_options(args)}
    if args.placement:
        options["placement"] = args.placement
    if args.no_tip_quadrics:
        options["tip_quadrics"] = False
    if args.fold_limit is not None:
        if not args.fold_limit >= 0.0:
            raise UserError(f"--fold-limit: expected a depth >= 0 (0, 1, inf), got {args.fold_limit:g}")
        options["fold_limit"] = args.fold_limit
    if kind == "gltf":
        return _simplify_document(args, options)
    if args.clips or args.joint_map:
        option = "--clips" if args.clips else "--joint-map"
        raise UserError(f"{option}: adds glTF clips to a glTF input, not to a {kind} input ({args.input})")
    return _simplify_sequence(args, options)


def _simplify_document(args: argparse.Namespace, options: dict) -> int:
    from ..pipelines import simplify_document

    output = Path(args.output)
    if not args.separate and (output.is_dir() or output.suffix.lower() not in GLB_OUTPUT_SUFFIXES):
        output = output / glb_name(args.input, "_lod")
    frame_budget = {"frame_budget": args.max_frames} if args.max_frames else {}
    report = simplify_document(
        args.input, output, args.ratio, separate=args.separate, clips=args.clips,
        joint_map=args.joint_map, progress=print, **frame_budget,
        **options,
    )  # fmt: skip
    print_drawable_reports(report.drawables)
    for note in report.notes:
        print(f"note: {note}")
    for path in report.outputs:
        print(f"wrote {path}")
    print(f"{report.seconds:.2f} s")
    if args.plot:
        first = report.drawables[0]
        folder = output.parent if not args.separate else output
        _plot(folder / f"{input_stem(args.input)}_levels.png", first.rest_meshes[0], first.rest_meshes[1:], None)
    return 0


def print_drawable_reports(drawables: list[DrawableReport], legend: bool = True) -> None:
    """Each drawable's levels (faces, target, relative error, coverage) and notes, under a legend
    unless the caller printed one."""
    if legend:
        print("errors: max over the rest pose and frames of every clip of the Hausdorff distance, relative to the")
        print("bounding-box diagonal; coverage: the MSFT_screencoverage below which the next level takes over")
    for drawable in drawables:
        renormalised = drawable.renormalised_weights
        print(
            f"{drawable.label} (nodes {drawable.nodes}): {drawable.faces} triangles, {drawable.clips} clips; "
            + _preparation_summary(drawable.preparation)
            + (f", {renormalised} skin weight rows renormalised" if renormalised else "")
        )
        rows = [("level", "faces", "target", "error", "coverage")]
        rows += [
            (level.level, level.faces, level.target_faces, f"{level.relative_error:.2e}", f"{level.coverage:.3g}")
            for level in drawable.levels
        ]
        print_rows(rows, indent="  ")
        for note in drawable.notes:
            print(f"  note: {note}")


def _simplify_sequence(args: argparse.Namespace, options: dict) -> int:
    from ..pipelines.lod_sequence import simplify_sequence

    progress, measuring = _ProgressBar("AQEM", "collapse"), _ProgressBar("measuring", "level")
    try:
        report = simplify_sequence(
            args.input,
            args.output,
            args.ratio,
            measure=not args.no_metrics,
            measured_frames=args.metric_frames,
            progress=progress,
            measuring=measuring,
            max_frames=args.max_frames or 0,  # 0: every frame that fits
            **options,
        )
    finally:
        progress.close()
        measuring.close()
    frame_count = report.original.frame_count
    print(f"{report.original.face_count} triangles, {frame_count} frames; {_preparation_summary(report.preparation)}")
    over = "frames"
    if 0 < report.frames_measured < frame_count:
        measured = report.frames_measured
        over = f"{measured} of the {frame_count} frames, evenly spaced (--metric-frames {frame_count}: all)"
    print(
        "AQEM error: the largest collapse error, asset units; Hausdorff and RMS: relative to the bounding-box"
        f" diagonal, over {over}; time is the whole simplification"
    )
    rows = [("level", "faces", "target", "AQEM error", "Hausdorff mean / max", "RMS mean / max", "time s")]
    faces = report.original.face_count
    rows.append((0, faces, faces, "0", "-", "-", "-"))
    for index, level in enumerate(report.levels, start=1):
        surface = level.surface
        hausdorff = f"{surface['hausdorff_mean']:.2e} / {surface['hausdorff_max']:.2e}" if surface else "-"
        rms = f"{surface['rms_mean']:.2e} / {surface['rms_max']:.2e}" if surface else "-"
        error = f"{level.aqem_error:.3g}"
        rows.append((index, level.faces, level.target_faces, error, hausdorff, rms, f"{report.seconds:.2f}"))
    print_rows(rows)
    if report.frames_used < frame_count and not args.max_frames:
        limit = AqemOptions().quadric_memory_limit / 2**30
        print(
            f"note: quadrics over {report.frames_used} of {frame_count} frames chosen to cover the motion: over "
            f"every frame they would take more than {limit:g} GiB (--max-frames {frame_count} takes them all)"
        )
    for note in report.notes:  # levels short of their targets, and those not written
        print(f"note: {note}")
    if args.plot:
        levels = [_read_level(level.path) for level in report.levels]
        # The weights AQEM used, per input vertex: features found on the raw input would need
        # the manifold surface the simplifier prepares (welded, cut), which scanned meshes lack.
        features = None if args.no_features else report.vertex_weights > 1.0
        _plot(Path(args.output) / f"{input_stem(args.input)}_levels.png", report.original, levels, features)
    return 0


def _preparation_summary(prep: Preparation) -> str:
    """What the simplifier did to the input before simplifying, for the summary line."""
    dropped = prep.degenerate_faces + prep.duplicate_faces
    mirrored = f", {prep.mirrored_faces} two-sided faces mirrored" if prep.mirrored_faces else ""
    return (
        f"welded {prep.welded_vertices} vertices, {prep.seam_vertices} seam positions kept, "
        f"{prep.split_vertices} cut at non-manifold spots, {dropped} degenerate or repeated faces dropped{mirrored}"
    )


def _read_level(path: Path) -> AnimatedMesh:
    if path.suffix == ".npz":
        from ..io.npz import read_npz

        return read_npz(path)
    from ..io.meshseq import read_textured_sequence

    return read_textured_sequence(path)[0]  # its texture coordinates and normals, if any, read as written


class _ProgressBar:
    """A tqdm bar of ``unit``s fed by a progress(done, total) callback; close() when done."""

    def __init__(self, description: str, unit: str) -> None:
        self.description, self.unit = description, unit
        self.bar = None

    def __call__(self, done: int, total: int) -> None:
        from tqdm import tqdm

        if self.bar is None:
            self.bar = tqdm(total=total, desc=self.description, unit=self.unit, leave=False, disable=None)
        self.bar.update(min(done, total) - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _plot(path: Path, original: AnimatedMesh, levels: list[AnimatedMesh], feature_vertices: np.ndarray | None) -> None:
    """One frame (the middle) of the original, the faces touching ``feature_vertices`` (motion
    features, per vertex) in red where given, then each level."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from ..io.atomic import atomic_write

    frame = original.frame_count // 2
    shown = feature_vertices is not None
    red = feature_vertices[original.faces].any(axis=1) if shown else np.zeros(original.face_count, dtype=bool)
    meshes = [(original, red, f"original, {original.face_count} faces" + (" (features red)" if shown else ""))]
    meshes += [(mesh, np.zeros(mesh.face_count, bool), f"{mesh.face_count} faces") for mesh in levels]
    figure = plt.figure(figsize=(4 * len(meshes), 4.5))
    corners = original.frames[frame]
    low, high = corners.min(axis=0), corners.max(axis=0)
    flat = 0.5 * max(float(np.max(high - low)), 1e-9) * (high <= low)  # a planar mesh's third axis
    low, high = low - flat, high + flat
    for index, (mesh, highlight, title) in enumerate(meshes):
        axes = figure.add_subplot(1, len(meshes), index + 1, projection="3d")
        triangles = mesh.frames[min(frame, mesh.frame_count - 1)][mesh.faces]
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


def feature_options(args: argparse.Namespace) -> dict:
    """AQEM's motion-feature options from --no-features and --feature-weighting; empty when neither
    is given, so that each pipeline's default applies."""
    if args.no_features and args.feature_weighting:
        raise UserError("--feature-weighting: cannot be combined with --no-features")
    if args.no_features:
        return {"use_motion_features": False}
    if args.feature_weighting:
        return {"use_motion_features": True, "feature_weighting": args.feature_weighting}
    return {}
