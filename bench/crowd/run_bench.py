"""The motion LoD paper's Table 2 and Fig. 1 with the native crowd benchmark (``make bench-crowd``).

For the procedural humanoid and Soldier.glb from the development data (each made a LoD GLB of
geometry x motion levels by ``animlod character``), ``animlod_crowd`` renders N characters along
Nav1 (through the crowd) and Nav2 (over it) in every mode, side by side in one run per path:

1. Table 2: FPS per mode and path and the speed-up over Original (the paper: 1.8x GLoD, 2.6x
   MLoD, 3.2x G+MLoD on Nav1; 2.4x G+MLoD on Nav2), with and without frame skipping.
2. Where the time goes per mode: CPU animation (selection, sampling, FK, palettes), upload,
   draw submission (llvmpipe shades vertices inside the draw call), swap, GPU timer queries;
   triangles and joints per frame.
3. 10,000 characters rendered at all (a few frames, Original and G+MLoD+skip on Nav2).
4. Fig. 1: every (mesh level, motion level) forced on all characters, FPS per cell, as JSON and
   a heat map PNG.

Run: ``.venv/bin/python bench/crowd/run_bench.py [--count N] [--frames K] [--quick]``; JSON
reports, screenshots and heat maps go to out/bench-crowd/.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from devdata import DATA_DIR
from table import print_table

from animlod.crowd import character_chain, procedural_chain, run_crowd, write_heat_map
from animlod.io.atomic import atomic_write

PAPER = {"nav1": {"GLoD": 1.8, "MLoD": 2.6, "G+MLoD": 3.2}, "nav2": {"G+MLoD": 2.4}}
MODES = ("Original", "GLoD", "MLoD", "G+MLoD")


def chains(out: Path, count: int, real_count: int, reuse: bool, which: list[str]) -> list[tuple[str, Path, int]]:
    """(label, LoD GLB, characters): the procedural humanoid (3,664 triangles) and Soldier.glb
    (11,376 triangles, so fewer of them for a measurable Original). ``reuse`` keeps chains
    already in ``out`` (building them takes minutes)."""
    humanoid, soldier_chain = out / "humanoid_lod.glb", out / "Soldier_lod.glb"
    result = []
    if "humanoid" in which:
        if not (reuse and humanoid.exists()):
            procedural_chain(humanoid, progress=print)
        result.append(("procedural humanoid", humanoid, count))
    soldier = DATA_DIR / "gltf" / "Soldier.glb"
    if "soldier" in which and not soldier.exists():
        print(f"{soldier}: not found (set ANIMLOD_DATA), skipped")
    if "soldier" in which and soldier.exists():
        if not (reuse and soldier_chain.exists()):
            character_chain(soldier, soldier_chain, progress=print)
        result.append(("Soldier.glb", soldier_chain, real_count))
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=1000, help="procedural humanoids for Table 2 (default 1000)")
    parser.add_argument("--real-count", type=int, default=300, help="Soldiers for Table 2 (default 300)")
    parser.add_argument("--frames", type=int, default=30, help="measured frames per mode (default 30)")
    parser.add_argument("--rounds", type=int, default=3, help="path segments the modes take turns on (default 3)")
    parser.add_argument("--big-count", type=int, default=10000, help="the 'rendered at all' run (default 10000)")
    parser.add_argument("--out", type=Path, default=Path("out/bench-crowd"))
    parser.add_argument("--reuse-chains", action="store_true", help="keep the LoD GLBs already in --out")
    parser.add_argument("--chains", nargs="+", choices=("humanoid", "soldier"), default=["humanoid", "soldier"])
    parser.add_argument("--quick", action="store_true", help="100 characters, 10 frames, no 10,000 run")
    args = parser.parse_args()
    if args.quick:
        args.count, args.real_count, args.frames, args.big_count, args.rounds = 100, 50, 10, 0, 1
    args.out.mkdir(parents=True, exist_ok=True)
    for label, chain, count in chains(args.out, args.count, args.real_count, args.reuse_chains, args.chains):
        stem = chain.stem
        reports = {}
        for path in ("nav1", "nav2"):
            shot = [(args.frames // 2, args.out / f"{stem}_{path}.png")]
            reports[path] = run_crowd(
                [chain], count=count, frames=args.frames, rounds=args.rounds, warmup=3, modes="all", path=path,
                json_path=args.out / f"{stem}_{path}.json", screenshots=shot,
            )  # fmt: skip
        data = reports["nav1"].data
        levels = data["chains"][0]["nodes"][0]["levels"]
        chain_levels = sum(level["chain_level"] >= 0 for level in levels)
        heading = f"{label}: {chain.name}, {chain_levels} chain levels ({len(levels)} grid cells), {count} characters"
        print(f"\n## {heading}, {data['renderer']}")
        rows = []
        for path, report in reports.items():
            modes = report.modes
            for skip in ("", "+skip"):
                row = [path + (" (frame skipping)" if skip else "")]
                for mode in MODES:
                    entry = modes[mode + skip]
                    row.append(f"{entry['fps']:.2f} ({entry['speedup']:.2f}x)")
                rows.append(row)
            rows.append([f"{path}: paper"] + [f"{PAPER[path].get(mode, '-')}x" if mode != "Original" else "1x"
                                              for mode in MODES])  # fmt: skip
        print_table(f"Table 2 ({label}): FPS (speed-up over Original)", ["path", *MODES], rows)
        columns = ["path", "mode", "frame ms p50", "p95", "drawn", "triangles", "joints animated", "CPU anim ms",
                   "upload ms", "submit ms", "swap ms", "GPU ms"]  # fmt: skip
        rows = [
            [path, name, m["frame_ms_p50"], m["frame_ms_p95"], m["drawn"], m["triangles"], m["joints"],
             m["cpu_animation_ms"], m["upload_ms"], m["submit_ms"], m["swap_ms"], m["gpu_ms"]]
            for path, report in reports.items() for name, m in report.modes.items()
        ]  # fmt: skip
        print_table(f"Where the time goes ({label})", columns, rows)
        if args.big_count and label == "procedural humanoid":  # once is enough, and the lightest
            big = run_crowd([chain], count=args.big_count, frames=3, warmup=1, modes="Original,G+MLoD+skip",
                            path="nav2", json_path=args.out / f"{stem}_{args.big_count}.json")  # fmt: skip
            print_table(f"{args.big_count} characters on Nav2 ({label})", ["mode", "FPS", "drawn", "triangles"],
                        [[n, m["fps"], m["drawn"], m["triangles"]] for n, m in big.modes.items()])  # fmt: skip
        grid = run_crowd([chain], count=count, frames=max(args.frames // 3, 3), grid=True,
                         json_path=args.out / f"{stem}_grid.json")  # fmt: skip
        cells = grid.data["grid"]
        write_heat_map(cells, args.out / f"{stem}_fig1.png", title=f"{label}: {count} characters, FPS")
        rows = [[c["mesh_level"], c["motion_level"], c["triangles"], c["joints"], c["fps"]] for c in cells]
        columns = ["mesh level", "motion level", "triangles / frame", "joints / frame", "FPS"]
        print_table(f"Fig. 1 ({label}): every level on all {count} characters (Nav2 at its midpoint)", columns, rows)
        with atomic_write(args.out / f"{stem}_summary.json", "w") as handle:
            json.dump({p: r.data for p, r in reports.items()}, handle, indent=1)


if __name__ == "__main__":
    main()
