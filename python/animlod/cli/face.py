"""``animlod face [INPUT] -o OUT``: levels of detail of an animated face (facial LoD)."""

from __future__ import annotations

import argparse

from . import UserError


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "face",
        help="levels of detail of an animated face: geometry, animated regions, lattices, blendshapes",
        description=(
            "Facial LoD (seeds/004). Without INPUT: the procedural head, animated by MPAs on 3x3x3 rational FFD "
            "lattices per region, simplified by AQEM with region-group importance over its expressions; each "
            "level animates only the regions of its active-tree level and uses 2x2x2 lattices where the geometry "
            "already lost as much. With a .glb/.gltf with morph targets, or a folder of OBJ/PLY poses (the "
            "neutral face named *neutral*/*reference*, else after its folder, else the first; then the "
            "expressions): targets ranked by the largest displacement they cause, the least important pruned per "
            "level, the mesh simplified with the kept targets carried. Writes one LoD GLB (the levels attached by "
            "MSFT_lod, with morph targets), a JSON manifest and a table of sizes, time per frame and surface error "
            "against the full face; the files land together, or none if the run fails."
        ),
    )
    parser.add_argument("input", nargs="?", help="a .glb/.gltf with morph targets or a folder of poses "
                        "(default: the procedural face)")  # fmt: skip
    parser.add_argument("-o", "--output", required=True, help="folder to write the levels into (created if missing)")
    parser.add_argument(
        "--ratio",
        type=float,
        nargs="+",
        help="triangle fractions of the levels after the full face "
        "(default: the paper's 1533/2313 and 357/2313 for the procedural face; 0.5 0.25 0.1 else)",
    )
    parser.add_argument("--faces", type=int, nargs="+", help="triangle counts of the levels instead of --ratio")
    parser.add_argument("--targets", type=float, nargs="+", metavar="FRACTION",
                        help="blendshape faces: fraction of morph targets kept at each level, the full face included "
                        "(default: a level drops the targets that move the face less than its geometric error, and "
                        "the coarsest level keeps none)")  # fmt: skip
    parser.add_argument("--neutral", help="pose folders: file name of the neutral face")
    parser.add_argument("--expression", help="expression (procedural face) or morph target to show with --plot")
    parser.add_argument("--plot", action="store_true", help="write a PNG of every level showing one expression")
    parser.add_argument("--repeats", type=int, default=3, help="timing runs per frame; the fastest is kept")
    parser.add_argument(
        "--error-frames",
        type=int,
        default=24,
        help="animation frames the surface error is measured on, evenly spaced (default 24); the frame where "
        "each target (MPA for the procedural face) has its largest weight is measured too",
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..face_lod.pipeline import run_face_lod

    if args.input is None and (args.targets or args.neutral):
        raise UserError("--targets and --neutral: apply to blendshape faces (give an INPUT)")
    result = run_face_lod(
        args.input,
        args.output,
        ratios=args.ratio,
        face_counts=args.faces,
        target_fractions=args.targets,
        neutral=args.neutral,
        plot=args.plot,
        expression=args.expression,
        repeats=args.repeats,
        error_frames=args.error_frames,
        progress=print,
    )
    for note in result.notes:
        print(note)
    print(" | ".join(result.columns))
    for row in result.rows:
        print(" | ".join(f"{value:.4g}" if isinstance(value, float) else str(value) for value in row))
    for path in result.files:
        print(f"wrote {path}")
    return 0
