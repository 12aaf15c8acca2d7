"""``animlod motion INPUT -o OUT --levels 8``: motion levels of detail (joint elimination)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..io.detect import input_kind, input_stem
from ..motion_lod.analysis import TRANSLATION_TOLERANCE
from ..motion_lod.chain import SOLVERS
from ..motion_lod.ranking import DEFAULT_RANKING, RANKINGS
from . import UserError, add_joint_map_argument


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "motion",
        help="remove joints from a motion level by level and re-fit the rest (motion LoD)",
        description=(
            "Motion LoD (Sections 4-6 of the motion LoD paper): joint importance from posture error picks the "
            "joints to freeze at their key frames; every frame is re-fitted (E = 0.2 Ed + 0.4 Es + 0.4 Ea) so "
            "that the kept joints stay close to the original with rigid bones. Writes one BVH per level (per clip "
            "and level for a glTF of several) and, for a glTF, one GLB per level with every clip and the skin "
            "moved onto the kept joints (a glTF without skins: its animated node tree is the skeleton, and each "
            "GLB holds the skeleton and the clips)."
        ),
    )
    parser.add_argument(
        "input", help="a .bvh motion, or a .glb/.gltf/.vrm with an animation (of a skinned mesh or of nodes)"
    )
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
        help=f"which joints freeze first, one of {', '.join(RANKINGS)}: refit (default: at each level, the next "
        "joints the other rankings propose, scored by their error after a trial re-fit on 16 frames: the skin's "
        "mean distance for a skinned glTF, the joints' otherwise; the two best choices are carried to the next "
        "level, and the chain whose levels' errors have the lowest product is kept), "
        "importance (Eq. 3 with zero-length bones measured through the joints below them), paper (Eq. 3 as "
        "printed), depth (deepest first), variance (least rotation first), cumulative (least movement of the "
        "whole figure with the joints before it frozen) or spread (least Eq. 3 importance summed over the run of "
        "connected frozen joints a freeze makes)",
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
        "--clip", type=_index_or_name, default=None,
        help="which animation of a glTF file, by index or name; default all of them: as one motion when each "
        "moves other joints (one animation per joint node), else one after another with one skeleton per level "
        "(a BVH per clip and level, every clip in each level's GLB)",
    )  # fmt: skip
    parser.add_argument(
        "--skin", type=_index_or_name, default=None,
        help="in a glTF of several characters, the one whose motion to simplify: its skin by index, or the name of "
        "its skin, mesh or node; default the body whose skin lists the most joints (the others are named in a note)",
    )  # fmt: skip
    parser.add_argument(
        "--clips", nargs="+", default=(), metavar="FILE",
        help="glTF files of clips on the same rig (an animation library without the mesh), added to a glTF "
        "input's own by node name; BVH files of its skeleton or of another humanoid's, matched by shape or body part",
    )  # fmt: skip
    add_joint_map_argument(parser)
    parser.add_argument("--plot", action="store_true", help="write importance, key posture and error charts (PNG)")
    parser.set_defaults(run=run)


class _Progress:
    """tqdm over the default ranking's choice of joints, then over levels and over frames inside
    each level, then over the frames of the skin measurement; without a terminal (a log), one
    line as each of them starts instead."""

    def __init__(self) -> None:
        from functools import partial

        from tqdm import tqdm

        self._tqdm = partial(tqdm, disable=None)  # on a terminal only: in a log, its cursor moves are noise
        self.choice = None
        self.levels = None
        self.frames = None
        self.measure = None

    def chose(self, chosen: int, to_choose: int) -> None:
        if self.choice is None:
            self.choice = self._tqdm(total=to_choose, desc="choosing joints (trial re-fits)", unit="level", position=0)
            self._log(self.choice, f"choosing the joints of {to_choose} levels (trial re-fits)")
        self.choice.update(chosen - self.choice.n)
        if chosen == to_choose:
            self.choice.close()

    def start_level(self, index: int, joints: int, frame_count: int, level_count: int):
        if self.levels is None:
            self.levels = self._tqdm(total=level_count, desc="levels", unit="level", position=0)
        self._end_level()
        # The re-fit reports fractions of frames (a share of each group of points): shown whole.
        self.frames = self._tqdm(total=frame_count, desc=f"level {index} ({joints} joints)", unit="frame",
                                 position=1, leave=False, bar_format=_WHOLE_FRAMES)  # fmt: skip
        self._log(self.frames, f"level {index} of {level_count - 1}: {joints} joints, {frame_count} frames")
        return self.frames.update

    def measured(self, frames: int, frame_count: int) -> None:
        if self.measure is None:
            self._end_level()
            self.levels.close()
            self.measure = self._tqdm(total=frame_count, desc="measuring the skins", unit="frame", position=0)
            self._log(self.measure, f"measuring the skins over {frame_count} frames")
        self.measure.update(frames - self.measure.n)

    @staticmethod
    def _log(bar, line: str) -> None:
        """``line`` on stdout where ``bar`` shows nothing (no terminal): a log of a long run that
        said nothing until its summary."""
        if bar.disable:
            print(line, flush=True)

    def _end_level(self) -> None:
        if self.frames is not None:
            self.frames.close()
            self.levels.update(1)
            self.frames = None

    def close(self) -> None:
        self._end_level()
        for bar in (self.choice, self.levels, self.measure):
            if bar is not None:
                bar.close()


_WHOLE_FRAMES = "{desc}: {percentage:3.0f}%|{bar}| {n:.0f}/{total_fmt} [{elapsed}<{remaining}, {rate_fmt}]"


def _index_or_name(text: str) -> int | str:
    """--clip's and --skin's value: an index when it is a whole number, else a name."""
    try:
        return int(text)
    except ValueError:
        return text


def run(args: argparse.Namespace) -> int:
    from ..pipelines.motion import build_motion_levels

    if args.hard and args.solver == "newton":
        raise UserError("--hard: bone-length equality constraints need an SLSQP solver (slsqp or slsqp-python)")
    if input_kind(args.input) not in ("bvh", "gltf"):
        raise UserError(f"{args.input}: motion LoD needs a .bvh or a skinned .glb/.gltf")
    bars: list[_Progress] = []  # made when the work starts: bad input fails before any bar

    def progress() -> _Progress:
        if not bars:
            bars.append(_Progress())
        return bars[0]

    def on_level(index: int, joints: int, frame_count: int, level_count: int):
        return progress().start_level(index, joints, frame_count, level_count)

    start = time.perf_counter()
    try:
        report = build_motion_levels(
            args.input,
            args.output,
            args.levels,
            joints=args.joints,
            lock=args.lock,
            ranking=args.ranking,
            solver=args.solver,
            penalty=args.penalty,
            workers=args.workers,
            translation_tolerance=args.translation_tolerance,
            weights=args.weights,
            max_frames=args.max_frames,
            clip=args.clip,
            clips=args.clips,
            joint_map=args.joint_map,
            body_skin=args.skin,
            on_level=on_level,
            on_choice=lambda chosen, to_choose: progress().chose(chosen, to_choose),
            on_measure=lambda frames, frame_count: progress().measured(frames, frame_count),
            on_note=lambda text: print(text, file=sys.stderr),
        )
    finally:
        for bar in bars:
            bar.close()
    _print_summary(report.chain, report.floor, report.skin_errors)
    written = sum(len(files) for files in report.files) + 1  # the levels and the manifest
    if args.plot:
        from ..motion_lod.plots import plot_chain

        stem = input_stem(args.input)
        plot_chain(Path(args.output) / f"{stem}_motion_lod.png", report.chain, report.motion.skeleton.names)
        written += 1
    total = time.perf_counter() - start
    levels = sum(level.report.seconds for level in report.chain.levels)
    measuring = f", {report.skin_seconds:.1f} s measuring the skins" if report.skin_errors is not None else ""
    print(
        f"wrote {written} files to {args.output} in {total:.1f} s ({levels:.1f} s re-fitting the levels{measuring}, "
        "the rest reading, analysis and the choice of joints)"
    )
    return 0


def _print_summary(chain, floor, skin_errors) -> None:
    size = chain.figure_size
    leaves = ", as the skin sees them (leaf joints by points of their skin, joints that move none left out)"
    leaves = leaves if skin_errors is not None else ""
    extent = f"figure size {size:.4g} (asset units)"
    if size == 0.0:  # a rig whose joints all sit at one point (a two-joint test skin): max/size has no meaning
        extent = "figure size 0: every joint of the key posture sits at one point, so errors are in asset units only"
    print(f"\n{extent}; errors over every original joint and frame{leaves}")
    if skin_errors is not None:
        print("skin max: the largest distance of a skin vertex from the input's, over every frame")
    if floor.fewest > floor.paper_fewest:
        print(
            f"fewest joints: {floor.fewest} of {floor.total}, above the paper's 8% ({floor.paper_fewest}): "
            f"{floor.explain()} never freeze"
        )
    header = ("level", "joints", "mean err", "max err", "max/size", "bone err", "bone var", "FK resid", "failed", "s")
    header += ("skin max",) if skin_errors is not None else ()
    print(" | ".join(f"{h:>9}" for h in header))
    for index, level in enumerate(chain.levels):
        r = level.report
        cells = (
            index, r.joint_count, f"{r.mean_error:.4g}", f"{r.max_error:.4g}",
            f"{100 * r.max_error / size:.2f}%" if size > 0.0 else "-",
            f"{r.bone_error:.3g}", f"{100 * r.bone_variation:.3f}%", f"{r.fk_residual:.2g}", len(r.failures),
            f"{r.seconds:.1f}",
        )  # fmt: skip
        cells += (f"{skin_errors[index].max():.4g}",) if skin_errors is not None else ()
        print(" | ".join(f"{c!s:>9}" for c in cells))
    failures = [f for level in chain.levels for f in level.report.failures]
    for failure in failures[:10]:
        print(f"frame {failure.frame}: {failure.reason} -> {failure.outcome}")
    if len(failures) > 10:
        print(f"... and {len(failures) - 10} more frames with a failed first solve")
