"""``animlod crowd [CHAIN.glb ...] --count N --frames K --modes all --json OUT.json``: the native
crowd benchmark (bench/crowd/animlod_crowd) on LoD GLB chains, its table printed."""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

from . import MachineError, UserError, check_output_is_not_input, non_negative_int, positive_int


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
    parser.add_argument("--count", type=positive_int, default=1000, help="characters (default 1000)")
    parser.add_argument("--frames", type=positive_int, default=300, help="measured frames per mode (default 300)")
    parser.add_argument(
        "--warmup", type=non_negative_int, default=10, help="unmeasured frames before each mode (default 10)"
    )
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
    from ..crowd import character_chain, mode_list, procedural_source, write_heat_map
    from ..io.atomic import atomic_write, unwritable

    if args.heat_map and not args.grid:
        raise UserError("--heat-map: needs --grid")
    screenshots = _screenshots(args.screenshot, args.frames)
    outputs = [("--json", args.json, "the report"), ("--heat-map", args.heat_map, "the heat map")]
    outputs += [("--screenshot", png, "the screenshot") for _, png in screenshots]
    for option, target, _ in outputs:
        if target and (reason := unwritable(target)):  # found before the run, not after it
            raise UserError(f"{option}: {target}: {reason}")
    mode_list(args.modes)  # an unknown mode is refused before any chain is built
    chains = [Path(c) for c in args.chains]
    for chain in chains:
        _check_chain(chain)
        for option, target, what in outputs:
            check_output_is_not_input(chain, target, option, what)
    with tempfile.TemporaryDirectory(prefix="animlod_crowd_") as scratch:
        if not chains:
            source = procedural_source(Path(scratch) / "humanoid_source.glb")
            # The chain takes minutes to build: one frame of the humanoid as it is finds a missing
            # binary, no display or a window the binary refuses in seconds, before it.
            _run(
                [source], count=1, frames=1, warmup=0, modes="Original", width=args.width, height=args.height,
                pixel_error=args.pixel_error, level_colors=args.level_colors,
            )  # fmt: skip
            chains = [character_chain(source, Path(scratch) / "humanoid.glb")]
            print(f"chain: the procedural humanoid ({chains[0].name})")
        paths = ["grid"] if args.grid else args.path
        reports = {}
        for index, path in enumerate(paths):
            report = _run(
                chains, count=args.count, frames=args.frames, warmup=args.warmup, modes=args.modes,
                path="nav2" if args.grid else path, width=args.width, height=args.height,
                pixel_error=args.pixel_error, level_colors=args.level_colors, grid=args.grid,
                screenshots=screenshots if index == 0 else (),
            )  # fmt: skip
            if index == 0:  # the binary's stderr is not shown on success: what it read in place of the file
                for loaded in report.data.get("chains", []):
                    for warning in loaded.get("warnings", []):
                        print(f"warning: {loaded['file']}: {warning}", file=sys.stderr)
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


def _screenshots(pairs: list[list[str]], frames: int) -> list[tuple[int, str]]:
    """(measured frame, PNG) of each ``--screenshot FRAME PNG``; UserError for a frame that is not
    one of the ``frames`` measured."""
    screenshots = []
    for frame, png in pairs:
        try:
            number = int(frame)
        except ValueError:
            raise UserError("--screenshot: FRAME must be an integer") from None
        if not 0 <= number < frames:
            raise UserError(f"--screenshot: frame {number} is not among the {frames} measured frames")
        screenshots.append((number, png))
    return screenshots


def _check_chain(chain: Path) -> None:
    """UserError or FormatError (naming the element) for a chain the renderer's loader would take
    without a word or refuse without the element: a folder, a missing file, a malformed glTF, an
    MSFT_lod that lists its own node, a node twice or a fractional id (node 4.7 drawn as node 4),
    screen coverages that are not numbers or rise from one level to the next."""
    from ..io.gltf_document import GltfDocument
    from ..io.gltf_lod import lod_coverages, lod_ids

    if chain.is_dir():
        raise UserError(f"{chain}: is a folder; give the LoD GLB files in it")
    if not chain.is_file():
        raise UserError(f"{chain}: no such file")
    document = GltfDocument(chain)
    for node in range(len(document.json.get("nodes", []))):
        ids = lod_ids(document, node)
        if ids is not None:
            lod_coverages(document, node, ids)


def _run(chains: list[Path], **options):
    """:func:`animlod.crowd.run_crowd`, its errors the CLI's: bad input exits 2, what the machine
    cannot do (no display, the binary missing or crashing) 3."""
    from ..crowd import CrowdError, run_crowd

    try:
        return run_crowd(chains, **options)
    except CrowdError as error:
        raise (UserError if error.bad_input else MachineError)(str(error)) from None
