"""``animlod character CHARACTER.glb -o OUT.glb``: geometry x motion levels in one LoD GLB."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..io.detect import GLB_OUTPUT_SUFFIXES, glb_name, input_kind
from . import UserError, add_joint_map_argument, non_negative_int, positive_int, print_rows
from .simplify import feature_options, print_drawable_reports


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "character",
        help="skinned glTF character -> geometry x motion LoD chain in one GLB",
        description=(
            "Build the paper's per-character chain: AQEM geometry levels of every skinned mesh (over all its "
            "clips) times motion levels of its skeleton (joints frozen by importance, every clip re-fitted with "
            "SLSQP, skin weights of frozen joints moved to their kept ancestors). Level i combines geometry "
            "level i and motion level i; every other combination is written too (extras.animlod_grid). Meshes "
            "no clip skins (props, static meshes) get levels of their own, as simplify gives them. The "
            "input document stays whole; a viewer without MSFT_lod shows level 0."
        ),
    )
    parser.add_argument(
        "input", help="a .glb/.gltf/.vrm with a skinned mesh and at least one animation (its own or --clips')"
    )
    parser.add_argument(
        "-o", "--output", required=True, help="the LoD .glb (or .vrm) to write, or a folder for <name>_character.glb"
    )
    parser.add_argument(
        "--ratio", type=float, nargs="+", default=[0.5, 0.25, 0.1], help="face ratios of levels 1, 2, ..."
    )
    parser.add_argument("--solver", choices=("slsqp", "newton"), default="slsqp", help="motion re-fit (default slsqp)")
    parser.add_argument(
        "--workers", type=non_negative_int, default=0,
        help="threads of the motion analysis and re-fit; 0: every core (the default)",
    )  # fmt: skip
    parser.add_argument("--no-features", action="store_true", help="ignore motion features in AQEM (the default)")
    parser.add_argument(
        "--feature-weighting",
        choices=("amplitude", "paper"),
        default=None,
        help="use AQEM's motion features with this weighting (see animlod simplify --help)",
    )
    parser.add_argument(
        "--max-frames", type=positive_int, default=48, help="frames of all clips that drive AQEM (default 48)"
    )
    parser.add_argument(
        "--clips", nargs="+", default=(), metavar="FILE",
        help="glTF files of clips on the same rig (an animation library without the mesh, such as Mixamo's "
        "'without skin' downloads), added to the character's own by node name; BVH files of its skeleton or of "
        "another humanoid's (CMU, Bandai-Namco), matched by shape or body part",
    )  # fmt: skip
    add_joint_map_argument(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..pipelines.character import build_character

    if any(not 0.0 < ratio <= 1.0 for ratio in args.ratio):
        raise UserError(f"--ratio: every ratio must be in (0, 1], got {args.ratio}")
    if input_kind(args.input) != "gltf":
        raise UserError(f"{args.input}: animlod character needs a .glb, .gltf or .vrm")
    output = Path(args.output)
    if output.is_dir() or output.suffix.lower() not in GLB_OUTPUT_SUFFIXES:
        output = output / glb_name(args.input, "_character")
    report = build_character(
        args.input,
        output,
        args.ratio,
        solver=args.solver,
        workers=args.workers,
        clips=args.clips,
        joint_map=args.joint_map,
        frame_budget=args.max_frames,
        **feature_options(args),
        progress=print,
    )
    print("error: max over frames of every clip of the Hausdorff distance to the input (reduced skin, re-fitted")
    print("clips), relative to the bounding-box diagonal; coverage: where the next level takes over")
    for label, levels in report.chains.items():
        print(label)
        rows = [("level", "faces", "joints", "error", "coverage")]
        rows += [(lv.level, lv.faces, lv.joints, f"{lv.relative_error:.2e}", f"{lv.coverage:.3g}") for lv in levels]
        print_rows(rows, indent="  ")
    if report.others:
        print("meshes no clip skins, with levels of their own (props, static meshes; their copies on each motion")
        print("level's skeleton have the same levels); error: over their rest pose and every clip's frames")
        print_drawable_reports(report.others, legend=False)
    for note in report.notes:
        print(f"note: {note}")
    print(
        f"wrote {report.output} (motion levels {report.motion_seconds:.1f} s, geometry {report.geometry_seconds:.1f} s)"
    )
    return 0
