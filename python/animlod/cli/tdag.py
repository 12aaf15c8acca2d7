"""``animlod tdag build|query|play``: the TDAG of a deforming mesh (Shamir and Pascucci 2001)."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from . import UserError, positive_int, print_rows


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "tdag",
        help="temporal and spatial level of detail of a deforming mesh (TDAG)",
        description=(
            "Build a TDAG (temporal DAG with time-tagged fields and a per-frame affine/residual split) of a "
            "deforming mesh, query a frame at a tolerance, or play the frames and measure the three temporal "
            "approximation levels. Tolerances and errors are in asset units (or, with --relative, fractions of "
            "frame 0's bounding-box diagonal); a query's mesh is within its tolerance of the input frame."
        ),
    )
    commands = parser.add_subparsers(dest="tdag_command", required=True, metavar="ACTION")

    build = commands.add_parser("build", help="build a .tdag file from a sequence, an .npz or an animated glTF")
    build.add_argument("input", help="a folder, glob or file of OBJ/PLY frames, an .npz, or a .glb/.gltf")
    build.add_argument("-o", "--output", required=True, help="the .tdag file to write")
    build.add_argument(
        "--governing",
        default="first",
        help="collapse order: first, average, aqem, online, or a frame number (default first)",
    )
    build.add_argument(
        "--history-weight", type=float, default=1.0, help="lambda of --governing online (0: each frame its own order)"
    )
    build.add_argument("--base", choices=("first", "average"), default="first", help="base mesh of the affine split")
    build.add_argument("--no-inversion-check", action="store_true", help="allow collapses that flip a face")
    build.add_argument(
        "--no-weld", action="store_true", help="keep seam copies of a position apart (they become borders)"
    )
    build.set_defaults(run=run_build)

    query = commands.add_parser("query", help="write one frame at a tolerance as OBJ/PLY")
    query.add_argument("tdag", help="a .tdag file")
    query.add_argument("--frame", type=int, required=True, help="frame to extract")
    size = query.add_mutually_exclusive_group(required=True)
    size.add_argument("--tolerance", type=float, help="asset units (see --relative)")
    size.add_argument(
        "--faces", type=int, help="instead of a tolerance: the finest mesh of at most this many faces (at --frame)"
    )
    query.add_argument("--relative", action="store_true", help="tolerance as a fraction of the bounding-box diagonal")
    query.add_argument("-o", "--output", required=True, help="the .obj or .ply file to write")
    query.add_argument(
        "--level",
        type=int,
        choices=(1, 2, 3),
        default=3,
        help="temporal approximation: 1 affine only, 2 + residuals, 3 + cut update (default 3)",
    )
    query.add_argument("--from-frame", type=int, default=None, help="levels 1-2: the previous cut's frame")
    query.add_argument("--camera", type=float, nargs=3, metavar=("X", "Y", "Z"), help="view-dependent tolerance")
    query.add_argument("--pixels", type=float, default=1.0, help="with --camera: screen-space tolerance in pixels")
    query.add_argument("--focal", type=float, default=1000.0, help="with --camera: focal length in pixels")
    query.add_argument(
        "--plot", action="store_true", help="also write <output>_tolerances.png: the frame at 1/4, 1 and 4 x tolerance"
    )
    query.set_defaults(run=run_query)

    play = commands.add_parser("play", help="walk the frames and measure the three approximation levels")
    play.add_argument("tdag", help="a .tdag file")
    play.add_argument("--tolerance", type=float, required=True, help="asset units (see --relative)")
    play.add_argument("--relative", action="store_true", help="tolerance as a fraction of the bounding-box diagonal")
    play.add_argument("--first-frame", type=int, default=0)
    play.add_argument("--frames", type=positive_int, default=None, help="frames to walk after the first (default: all)")
    play.set_defaults(run=run_play)


def _governing(text: str) -> str | int:
    from ..tdag import GOVERNING_CHOICES

    if text in GOVERNING_CHOICES:
        return text
    try:
        return int(text)
    except ValueError:
        raise UserError(
            f"--governing: expected {', '.join(GOVERNING_CHOICES)} or a frame number, got {text!r}"
        ) from None


def read_animation(path: str):
    """The deforming mesh of ``path``: OBJ/PLY frames, an NPZ, or a glTF's first morph-animated
    mesh without a skin (baked frames, under its node's animation) or its body's skinned mesh
    baked with its first clip, skin and morph weights as the clip moves them (the drawable reader's
    clips; a clip of morph weights alone holds the skeleton at rest)."""
    from ..io.detect import input_kind

    kind = input_kind(path)
    if kind == "bvh":
        raise UserError(f"{path}: a BVH file holds motion only; a TDAG needs a deforming mesh")
    if kind == "npz":
        from ..io.npz import read_npz

        return read_npz(path)
    if kind == "sequence":
        from ..io.meshseq import read_sequence

        return read_sequence(path)
    from ..io.gltf_document import GltfDocument
    from ..io.gltf_drawable import read_drawables
    from ..io.gltf_read import body_node, read_unskinned_meshes

    doc = GltfDocument(path)
    morph_animations, _ = read_unskinned_meshes(doc)
    if morph_animations:
        mesh, others = morph_animations[0], len(morph_animations) - 1
        taken = "the first morph-animated mesh and clip"
    else:
        animated = [drawable for drawable in read_drawables(doc) if drawable.skinned is not None and drawable.clips]
        if not animated:
            raise UserError(f"{path}: no morph-animated mesh and no animated skinned mesh to build a TDAG of")
        body = body_node(doc, [drawable.nodes[0] for drawable in animated])
        drawable = next(drawable for drawable in animated if drawable.nodes[0] == body)
        clip = drawable.clips[0]
        mesh = drawable.skinned.bake(clip.motion, clip.morph_weights)
        others = sum(len(drawable.clips) for drawable in animated) - 1
        taken = f"the body's skinned mesh baked with its first clip, {clip.name or 'unnamed'!r}"
    if others:  # a TDAG is one mesh over one run of frames
        print(f"note: {path}: the TDAG is of {taken}; {others} other (mesh, clip) pair{'s' if others > 1 else ''} "
              "left out", file=sys.stderr)  # fmt: skip
    return mesh


def run_build(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from ..tdag import TemporalDag

    governing = _governing(args.governing)
    mesh = read_animation(args.input)
    bar = tqdm(total=mesh.frame_count, desc="TDAG", unit="frame", leave=False, disable=None)

    def progress(done: int, total: int) -> None:
        bar.update(done - bar.n)

    try:
        dag = TemporalDag.build(
            mesh,
            governing,
            history_weight=args.history_weight,
            affine_base=args.base,
            check_inversion=not args.no_inversion_check,
            weld=not args.no_weld,
            progress=progress,
        )
    finally:
        bar.close()
    raw = mesh.frames.size * 4
    counts = mesh.frame_count, mesh.vertex_count, mesh.face_count
    del mesh  # the input frames, no longer needed: freed before the save
    start = time.perf_counter()
    size = dag.save(args.output)
    save_seconds = time.perf_counter() - start
    report = dag.report
    average, median = report.quality_measure()
    print(f"wrote {args.output}")
    rows = [
        (
            "frames, vertices, faces",
            f"{counts[0]}, {counts[1]}, {counts[2]} (TDAG: {dag.vertex_count} welded vertices, {dag.face_count} faces)",
        ),
        ("governing", f"{dag.governing}" + (f" (lambda {args.history_weight:g})" if dag.governing == "online" else "")),
        ("collapses (nodes), per frame", f"{dag.collapse_count}, {report.collapse_counts.mean():.0f}"),
        (
            "build s (affine, hierarchy, fields)",
            f"{report.seconds:.3f} ({report.seconds_affine:.3f}, {report.seconds_hierarchy:.3f}, "
            f"{report.seconds_fields:.3f}); {report.seconds / counts[0] * 1e3:.1f} ms per frame",
        ),
        ("file bytes / raw float32 frames", f"{size} / {raw} = {size / raw:.3f} (written in {save_seconds:.3f} s)"),
        ("Figure 6 measure: average, median", f"{average:.4g}, {median:.4g} (squared asset units)"),
    ]
    width = max(len(name) for name, _ in rows)
    for name, value in rows:
        print(f"  {name.ljust(width)}  {value}")
    return 0


def _tolerance(dag, value: float, relative: bool) -> float:
    if not (value >= 0.0 and math.isfinite(value)):
        raise UserError(f"--tolerance: must be a finite number >= 0, got {value}")
    if not relative:
        return value
    corners = dag.frame_positions(0)
    return value * float(np.linalg.norm(corners.max(axis=0) - corners.min(axis=0)))


def _load(path: str):
    from ..tdag import TemporalDag

    return TemporalDag.load(path)


def _check_frame(dag, path: str, option: str, frame: int) -> None:
    if not 0 <= frame < dag.frame_count:
        raise UserError(f"{path}: {option} {frame} outside the frames 0 to {dag.frame_count - 1}")


def run_query(args: argparse.Namespace) -> int:
    from ..io.meshseq import write_mesh

    # Combinations of options are refused before any work: nothing is written for a refused query.
    if args.faces is not None and (args.camera is not None or args.relative):
        raise UserError("--faces: sets the tolerance itself; drop " + ("--camera" if args.camera else "--relative"))
    if args.plot and args.camera is not None:
        raise UserError("--plot: draws tolerances, not a view; drop --camera")
    output = Path(args.output)
    if output.suffix.lower() not in (".obj", ".ply"):
        raise UserError(f"{output}: expected an .obj or .ply output")
    dag = _load(args.tdag)
    _check_frame(dag, args.tdag, "--frame", args.frame)
    if args.from_frame is not None:
        _check_frame(dag, args.tdag, "--from-frame", args.from_frame)
    # Levels 1-2 keep the cut of an earlier frame (and its face count).
    start = args.from_frame if args.from_frame is not None else max(args.frame - 1, 0)
    cut_frame = args.frame if args.level == 3 else start
    if args.faces is None:
        tolerance = _tolerance(dag, args.tolerance, args.relative)
    else:
        tolerance = dag.tolerance_for_faces(cut_frame, args.faces)
    if args.camera is not None:
        mesh = dag.query_view(args.frame, args.camera, args.pixels, args.focal)
    elif args.level == 3:
        mesh = dag.query(args.frame, tolerance)
    else:
        dag.query(start, tolerance)
        mesh = dag.advance(args.frame, args.level)
    what = f"tolerance {tolerance:.4g}"
    if args.faces is not None:  # a budget below the coarsest cut gets that cut, which is over it
        within = mesh.face_count <= args.faces
        what += f" (for at most {args.faces} faces)" if within else f" (the coarsest cut, over {args.faces} faces)"
    if args.camera is not None:
        what = f"view from {tuple(args.camera)}, {args.pixels:g} px at focal {args.focal:g}"
    elif args.level != 3:
        what += f", level {args.level} from the cut of frame {start}"
    write_mesh(output, mesh.positions, mesh.faces)
    backs = int(np.count_nonzero(dag.two_sided))  # a two-sided face is one face of the TDAG, two of the mesh
    print(
        f"wrote {output}: frame {args.frame}, {what}: {mesh.vertex_count} vertices, {mesh.face_count} faces "
        f"(input {dag.vertex_count}, {dag.face_count + backs}), error bound {mesh.error_bound:.4g}"
    )
    if args.plot:
        from ..tdag import plot_tolerances

        picture = output.with_name(f"{output.stem}_tolerances.png")
        plot_tolerances(dag, args.frame, [tolerance / 4, tolerance, tolerance * 4], picture)
        print(f"wrote {picture}")
    return 0


def run_play(args: argparse.Namespace) -> int:
    dag = _load(args.tdag)
    tolerance = _tolerance(dag, args.tolerance, args.relative)
    # The walk starts at --first-frame and measures the frames after it: none after it would print
    # a table of zeros measured over nothing.
    _check_frame(dag, args.tdag, "--first-frame", args.first_frame)
    if args.first_frame == dag.frame_count - 1:
        raise UserError(
            f"{args.tdag}: --first-frame {args.first_frame} leaves no frame to play after it "
            f"(the TDAG holds {dag.frame_count} frame{'s' if dag.frame_count > 1 else ''}); use tdag query"
        )
    report = dag.play(tolerance, args.first_frame, args.frames)
    print(f"{report.frames} frames from frame {args.first_frame}, tolerance {tolerance:.4g} (asset units)")
    header = ("level", "ms per frame (mean / max)", "error mean / max", "vertices", "faces")
    names = ["1 affine", "2 residual", "3 cut update", "fresh query"]
    rows = [header]
    for name, stats in zip(names, [*report.levels, report.full_query]):
        rows.append(
            (
                name,
                f"{stats.mean_seconds * 1e3:.3f} / {stats.max_seconds * 1e3:.3f}",
                f"{stats.mean_error:.4g} / {stats.max_error:.4g}",
                f"{stats.mean_vertices:.0f}",
                f"{stats.mean_faces:.0f}",
            )
        )
    print_rows(rows)
    print(
        f"level 3: {report.mean_splits:.1f} splits and {report.mean_collapses:.1f} collapses per frame; "
        f"walk {report.sequential_seconds_per_frame * 1e3:.3f} ms per frame on one thread, "
        f"{report.double_buffered_seconds_per_frame * 1e3:.3f} ms double-buffered"
    )
    return 0
