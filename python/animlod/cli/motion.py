"""``animlod motion INPUT -o OUT --levels 8``: motion levels of detail (joint elimination)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..io.detect import input_kind, input_stem
from ..motion_lod.analysis import TRANSLATION_TOLERANCE
from ..motion_lod.chain import SOLVERS
from ..motion_lod.ranking import DEFAULT_RANKING, RANKINGS
from . import UserError


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "motion",
        help="remove joints from a motion level by level and re-fit the rest (motion LoD)",
        description=(
            "Motion LoD (Sections 4-6 of the motion LoD paper): joint importance from posture error picks the "
            "joints to freeze at their key frames; every frame is re-fitted (E = 0.2 Ed + 0.4 Es + 0.4 Ea) so "
            "that the kept joints stay close to the original with rigid bones. Writes one BVH per level and, "
            "for a skinned glTF, one GLB per level with the skin moved onto the kept joints."
        ),
    )
    parser.add_argument("input", help="a .bvh motion, or a .glb/.gltf with a skinned mesh and an animation")
    parser.add_argument("-o", "--output", required=True, help="folder to write the levels into (created if missing)")
    parser.add_argument(
        "--levels", type=int, default=None,
        help="number of levels, from every joint down to the fewest possible (the paper's 100..8%% of the joints "
        "where the skeleton allows); default 8, or as many as the skeleton allows",
    )  # fmt: skip
    parser.add_argument("--joints", type=int, nargs="+", help="joint counts of the levels instead of --levels")
    parser.add_argument("--lock", nargs="+", default=[], metavar="JOINT", help="joints never to freeze")
    parser.add_argument(
        "--ranking", default=DEFAULT_RANKING, metavar="NAME",
        help=f"which joints freeze first, one of {', '.join(RANKINGS)}: importance (Eq. 3 with zero-length bones "
        "measured through the joints below them, default), paper (Eq. 3 as printed), depth (deepest first) or "
        "variance (least rotation first)",
    )  # fmt: skip
    parser.add_argument(
        "--solver",
        choices=SOLVERS,
        default=SOLVERS[0],
        help="slsqp: nlopt SLSQP per frame in the C++ core on every core (default); slsqp-python: the same in "
        "Python (the reference, slower); newton: damped Newton on the penalty objective (no hard constraints)",
    )
    constraints = parser.add_mutually_exclusive_group()
    constraints.add_argument(
        "--hard", action="store_true",
        help="hold bone lengths as equality constraints (the default with the SLSQP solvers)",
    )  # fmt: skip
    constraints.add_argument(
        "--penalty", action="store_true",
        help="hold bone lengths only through the string error Es (the paper's E; the default with newton)",
    )  # fmt: skip
    parser.add_argument(
        "--workers", type=int, default=0,
        help="threads of the core's solve, or processes of the Python solvers; 0: every core (slsqp), one process "
        "(others)",
    )  # fmt: skip
    parser.add_argument(
        "--translation-tolerance", type=float, default=TRANSLATION_TOLERANCE, metavar="FRACTION",
        help="a joint whose translation moves by more than this fraction of its bone length translates and "
        "never freezes (default %(default)g); smaller moves are float noise or held at the key frame",
    )  # fmt: skip
    parser.add_argument(
        "--weights", type=float, nargs=3, default=(0.2, 0.4, 0.4), metavar=("ALPHA", "BETA", "GAMMA"),
        help="weights of the distance, string and angle errors (Eq. 5)",
    )  # fmt: skip
    parser.add_argument("--max-frames", type=int, default=600, help="frames motion analysis looks at, at most")
    parser.add_argument(
        "--clip", type=int, default=None,
        help="which animation of a glTF file (index); default the first, or all of them as one motion when each "
        "moves other joints (one animation per joint node)",
    )  # fmt: skip
    parser.add_argument("--plot", action="store_true", help="write importance, key posture and error charts (PNG)")
    parser.set_defaults(run=run)


class _Progress:
    """tqdm over levels, and over frames inside each level."""

    def __init__(self, level_count: int) -> None:
        from tqdm import tqdm

        self._tqdm = tqdm
        self.levels = tqdm(total=level_count, desc="levels", unit="level", position=0)
        self.frames = None

    def start_level(self, index: int, joints: int, frame_count: int):
        if self.frames is not None:
            self.frames.close()
            self.levels.update(1)
        self.frames = self._tqdm(total=frame_count, desc=f"level {index} ({joints} joints)", unit="frame",
                                 position=1, leave=False)  # fmt: skip
        return self.frames.update

    def close(self) -> None:
        if self.frames is not None:
            self.frames.close()
            self.levels.update(1)
        self.levels.close()


def run(args: argparse.Namespace) -> int:
    from ..motion_lod.chain import build_motion_chain, joint_floor
    from ..motion_lod.objective import Weights
    from ..motion_lod.refit import SlsqpOptions

    if args.hard and args.solver == "newton":
        raise UserError("--hard: bone-length equality constraints need an SLSQP solver (slsqp or slsqp-python)")
    if args.workers < 0:
        raise UserError(f"--workers: must be at least 0, got {args.workers}")
    if args.ranking not in RANKINGS:
        raise UserError(f"--ranking: no ranking named {args.ranking!r} (choose from {', '.join(RANKINGS)})")
    motion, skin = _read_input(args)
    try:
        analysis, counts = _plan_levels(args, motion)
    except ValueError as error:  # the skeleton or the level request: name the file they concern
        raise UserError(f"{args.input}: {error}") from None
    floor = joint_floor(motion, analysis)
    if floor.possible_levels == 1:
        print(
            f"{args.input}: nothing can freeze ({floor.total} joints, all kept: {floor.explain()}); "
            "writing one level, the input's motion",
            file=sys.stderr,
        )
    progress = _Progress(len(counts))
    try:
        chain = build_motion_chain(
            motion,
            counts,
            weights=Weights(*args.weights),
            solver=args.solver,
            slsqp_options=SlsqpOptions(hard_constraints=args.solver != "newton" and not args.penalty),
            workers=args.workers,
            skin=skin,
            on_level=lambda index, joints: progress.start_level(index, joints, motion.frame_count),
            analysis=analysis,
        )
    finally:
        progress.close()

    output = Path(args.output)
    output.mkdir(parents=True, exist_ok=True)
    stem = input_stem(args.input)
    from ..io.bvh import write_bvh
    from ..io.manifest import write_lod_manifest

    rows = []
    for index, level in enumerate(chain.levels):
        files = [f"{stem}_lod{index}.bvh"]
        write_bvh(output / files[0], level.motion)
        if level.skin is not None:
            from ..io.gltf import write_glb

            files.append(f"{stem}_lod{index}.glb")
            write_glb(output / files[1], level.skin, [level.motion])
        rows.append({"files": files, "joints": level.report.joint_count, "error": level.report.max_error})
    # The runtime's level chooser: each level's largest joint position error in asset units.
    write_lod_manifest(output / f"{stem}_motion_lod.json", "motion", rows)
    _print_summary(chain, floor)
    if args.plot:
        from ..motion_lod.plots import plot_chain

        plot_chain(output / f"{stem}_motion_lod.png", chain, motion.skeleton.names)
    return 0


def _read_input(args: argparse.Namespace):
    """The motion to simplify and, for a skinned glTF, its skin."""
    kind = input_kind(args.input)
    if kind == "bvh":
        from ..io.bvh import read_bvh

        return read_bvh(args.input), None
    if kind == "gltf":
        from ..io.gltf import read_skinned

        skin, motions = read_skinned(args.input)
        if not motions:
            raise UserError(f"{args.input}: the skinned mesh has no animation to simplify")
        if args.clip is None:
            from ..motion_lod.clips import merge_split_clips

            merged = merge_split_clips(motions)
            if merged is not None:
                print(f"{args.input}: its {len(motions)} animations each move other joints: simplifying them as one "
                      "motion (use --clip to take one)", file=sys.stderr)  # fmt: skip
                return merged, skin
            return motions[0], skin
        if not 0 <= args.clip < len(motions):
            raise UserError(f"--clip: {args.input} has {len(motions)} animations, got index {args.clip}")
        return motions[args.clip], skin
    raise UserError(f"{args.input}: motion LoD needs a .bvh or a skinned .glb/.gltf")


def _plan_levels(args: argparse.Namespace, motion):
    """The motion analysis and the joint counts of the levels (ValueError on a bad request)."""
    from ..motion_lod.analysis import analyze_motion
    from ..motion_lod.chain import joint_floor, level_joint_counts

    analysis = analyze_motion(
        motion,
        locked=args.lock,
        max_frames=args.max_frames,
        translation_tolerance=args.translation_tolerance,
        ranking=args.ranking,
    )
    floor = joint_floor(motion, analysis)
    if args.joints:
        return analysis, level_joint_counts(motion, analysis, args.joints)
    if floor.possible_levels == 1:  # every joint stays: one level, said in run()
        return analysis, [floor.total]
    levels = args.levels if args.levels is not None else min(8, floor.possible_levels)
    return analysis, level_joint_counts(motion, analysis, levels)


def _print_summary(chain, floor) -> None:
    size = chain.figure_size
    print(f"\nfigure size {size:.4g} (asset units); errors over every original joint and frame")
    if floor.fewest > floor.paper_fewest:
        print(
            f"fewest joints: {floor.fewest} of {floor.total}, above the paper's 8% ({floor.paper_fewest}): "
            f"{floor.explain()} never freeze"
        )
    header = ("level", "joints", "mean err", "max err", "max/size", "bone err", "bone var", "FK resid", "failed", "s")
    print(" | ".join(f"{h:>9}" for h in header))
    for index, level in enumerate(chain.levels):
        r = level.report
        cells = (
            index, r.joint_count, f"{r.mean_error:.4g}", f"{r.max_error:.4g}", f"{100 * r.max_error / size:.2f}%",
            f"{r.bone_error:.3g}", f"{100 * r.bone_variation:.3f}%", f"{r.fk_residual:.2g}", len(r.failures),
            f"{r.seconds:.1f}",
        )  # fmt: skip
        print(" | ".join(f"{c!s:>9}" for c in cells))
    failures = [f for level in chain.levels for f in level.report.failures]
    for failure in failures[:10]:
        print(f"frame {failure.frame}: {failure.reason} -> {failure.outcome}")
    if len(failures) > 10:
        print(f"... and {len(failures) - 10} more frames with a failed first solve")
