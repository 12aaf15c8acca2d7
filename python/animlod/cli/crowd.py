"""``animlod crowd [CHAIN.glb ...] --count N --frames K --modes all --json OUT.json``: the native
crowd benchmark (bench/crowd/animlod_crowd) on LoD GLB chains, its table printed."""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

from . import MachineError, UserError


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "crowd",
        help="render a crowd of LoD characters natively (instanced GPU skinning) and time each LoD mode",
        description=(
            "Runs animlod_crowd: N characters from LoD GLBs (MSFT_lod chains of geometry x motion levels) on a "
            "height map, each with its own clip and phase, a camera flying along a path, GPU skinning with one "
            "instanced draw per level. Modes: Original (level 0), GLoD (geometry levels), MLoD (motion levels), "
            "G+MLoD (both), each optionally with frame skipping (+skip). Prints frame times, FPS and speed-ups "
            "per mode, measured side by side in one run; without a display it runs under xvfb-run."
        ),
    )
    parser.add_argument("chains", nargs="*", help="LoD GLB files (default: the procedural humanoid)")
    parser.add_argument("--count", type=int, default=1000, help="characters (default 1000)")
    parser.add_argument("--frames", type=int, default=300, help="measured frames per mode (default 300)")
    parser.add_argument("--warmup", type=int, default=10, help="unmeasured frames before each mode (default 10)")
    parser.add_argument(
        "--modes", default="all", help="all, or comma-separated of Original, GLoD, MLoD, G+MLoD, each optionally +skip"
    )
    parser.add_argument(
        "--path", nargs="+", default=["nav1"], choices=("nav1", "nav2", "pullback"),
        help="camera paths: nav1 through the crowd, nav2 over it, pullback away from it (default nav1)",
    )  # fmt: skip
    parser.add_argument("--pixel-error", type=float, default=2.0, help="error budget in pixels for levels (default 2)")
    parser.add_argument("--width", type=int, default=1280, help="window width in pixels (default 1280)")
    parser.add_argument("--height", type=int, default=720, help="window height in pixels (default 720)")
    parser.add_argument("--level-colors", action="store_true", help="tint every character by the level it shows")
    parser.add_argument(
        "--screenshot", nargs=2, action="append", default=[], metavar=("FRAME", "PNG"),
        help="save measured frame FRAME of the first mode on the first path (repeatable)",
    )  # fmt: skip
    parser.add_argument(
        "--grid", action="store_true", help="Fig. 1: FPS of every (mesh, motion) level forced on all characters"
    )
    parser.add_argument("--heat-map", metavar="PNG", help="with --grid: draw the FPS grid as a heat map")
    parser.add_argument("--json", metavar="OUT", help="write the report as JSON")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..crowd import CrowdError, mode_list, procedural_chain, run_crowd, write_heat_map
    from ..io.atomic import atomic_write, unwritable
    from ..io.gltf_document import GltfDocument

    if args.heat_map and not args.grid:
        raise UserError("--heat-map: needs --grid")
    for option, target in (("--json", args.json), ("--heat-map", args.heat_map)):
        if target and (reason := unwritable(target)):  # found before the run, not after it
            raise UserError(f"{option}: {target}: {reason}")
    mode_list(args.modes)  # an unknown mode is refused before any chain is built
    try:
        screenshots = [(int(frame), png) for frame, png in args.screenshot]
    except ValueError:
        raise UserError("--screenshot: FRAME must be an integer") from None
    with tempfile.TemporaryDirectory(prefix="animlod_crowd_") as scratch:
        chains = [Path(c) for c in args.chains]
        for chain in chains:
            if not chain.is_file():
                raise UserError(f"{chain}: no such file")
            GltfDocument(chain)  # a malformed file named with its element here, not by the renderer's loader
        if not chains:
            chains = [procedural_chain(Path(scratch) / "humanoid.glb")]
            print(f"chain: the procedural humanoid ({chains[0].name})")
        paths = ["grid"] if args.grid else args.path
        reports = {}
        for index, path in enumerate(paths):
            try:
                report = run_crowd(
                    chains, count=args.count, frames=args.frames, warmup=args.warmup, modes=args.modes,
                    path="nav2" if args.grid else path, width=args.width, height=args.height,
                    pixel_error=args.pixel_error, level_colors=args.level_colors, grid=args.grid,
                    screenshots=screenshots if index == 0 else (),
                )  # fmt: skip
            except CrowdError as error:
                if not error.bad_input:
                    raise MachineError(str(error)) from None
                raise UserError(str(error)) from None
            if len(paths) > 1:
                print(f"\npath {path}:")
            print(report.markdown, end="")
            reports[path] = report.data
    if args.grid and args.heat_map:
        data = reports["grid"]
        write_heat_map(data["grid"], args.heat_map, title=f"{data['count']} characters, {data['renderer']}")
        print(f"wrote {args.heat_map}")
    if args.json:
        first = reports[paths[0]]
        combined = first if len(paths) == 1 else {**first, "path": paths[0], "paths": reports}
        with atomic_write(args.json, "w") as handle:
            json.dump(combined, handle, indent=1)
        print(f"wrote {args.json}")
    return 0
