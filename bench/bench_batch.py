"""`animlod batch` on Dask: a generated asset library through 1 and 2 local workers, against the
same jobs called directly, and what 16 workers would give.

Run: ``.venv/bin/python bench/bench_batch.py [--assets 200]`` (needs the ``batch`` extra).

The library (a TOML manifest with per-asset options, written to a temporary folder): in every
ten assets, four skinned bending cylinders (GLB, 10 to 38 rings), three twisting bars (NPZ),
one bending cylinder as a folder of OBJ frames, one procedural humanoid with a walk and a run
(GLB; seed varies height and girth) and one procedural face animation (NPZ); seeds and sizes
vary from asset to asset. The small glTF files of the development data are added when present.

- direct: every asset's job called in this process, one after the other (``find_job(...)``,
  the function the workers call); the sum of their wall times;
- batch, 1 and 2 workers: ``run_batch(..., force=True)`` on a LocalCluster of that many
  single-threaded worker processes, wall time. Before the clock starts, this process and every
  worker run one asset of each kind (imports and first calls are paid once per process, as on a
  farm whose workers live long); the cluster's start-up and that warm-up are given apart;
- Dask overhead per asset: (1-worker wall time - the sum of the jobs' own times measured on the
  worker) / assets, and over the mean job time: what scheduling, transfers, the records and the
  catalogue add; the jobs' time on the worker against the direct calls is printed beside it
  (workers run one thread each, and the machine may be shared: the load average is printed),
  and a no-op task's submit and result on the 1-worker cluster, for scale (the runner's path
  from one asset to the next holds part of such a round trip: the finished task's notice and
  the next submission);
- peak memory: the largest peak resident set of each worker process (``ru_maxrss``);
- rerun: the same batch again, unchanged (every asset fingerprinted and skipped);
- 16 workers: the measured 1-worker job times plus the measured overhead per asset, handed out
  largest input first (as the runner submits them) to 16 simulated workers.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table, stopwatch

from animlod import synth
from animlod.batch import connect, read_spec, run_batch
from animlod.batch.fingerprint import fingerprint
from animlod.batch.jobs import find_job
from animlod.io import write_glb
from animlod.io.meshseq import write_sequence
from animlod.io.npz import write_npz

# Job options of the generated assets: a few drive and measured frames per clip.
GLTF_OPTIONS = "frame_budget = 12\nmeasured_frames = 4\n"
DEV_FILES = ["gltf/RiggedFigure.glb", "gltf/SimpleSkin.gltf", "morph/Stork.glb", "morph/Parrot.glb"]


def generate(root: Path, count: int) -> Path:
    """Write ``count`` procedural assets (and the small dev files) under ``root``; the manifest."""
    entries = []
    for index in range(count):
        slot = index % 10
        if slot < 4:
            rings = 10 + 4 * ((index // 10 + slot) % 8)
            skin, motion = synth.bending_cylinder_skinned(frames=12, rings=rings, segments=12 + 2 * slot)
            path = root / "characters" / f"cylinder_{index:03d}.glb"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_glb(path, skin, [motion])
            entries.append((path, GLTF_OPTIONS))
        elif slot < 7:
            mesh = synth.twisting_bar(frames=10, rings=12 + 2 * (index % 7), segments=8 + 8 * (slot - 4))
            path = root / "bars" / f"bar_{index:03d}.npz"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_npz(path, mesh)
            entries.append((path, ""))
        elif slot == 7:
            path = root / "sequences" / f"tube_{index:03d}"
            write_sequence(path, synth.bending_cylinder(frames=6, rings=10 + index % 6, segments=10), "obj")
            entries.append((path, ""))
        elif slot == 8:
            character = synth.humanoid(seed=index)
            motions = [synth.humanoid_motion(character.skeleton, style) for style in ("walk", "run")]
            path = root / "characters" / f"humanoid_{index:03d}.glb"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_glb(path, character, motions)
            entries.append((path, GLTF_OPTIONS))
        else:
            face = synth.face(seed=index)
            path = root / "faces" / f"face_{index:03d}.npz"
            path.parent.mkdir(parents=True, exist_ok=True)
            write_npz(path, synth.face_animation(face, seconds=0.4, seed=index))
            entries.append((path, ""))
    for name in DEV_FILES:
        if (DATA_DIR / name).is_file():
            entries.append((DATA_DIR / name, GLTF_OPTIONS))
    manifest = root / "library.toml"
    blocks = []
    for path, options in entries:
        name = path.relative_to(root).with_suffix("").as_posix() if path.is_relative_to(root) else f"dev/{path.stem}"
        blocks.append(f'[[assets]]\ninput = "{path}"\nname = "{name}"\n{options}')
    manifest.write_text("\n".join(blocks))
    return manifest


def warm_up(assets: list, folder: str) -> None:
    """Run the first asset of each job and input kind once into ``folder``: the imports and
    first calls that a long-lived worker (or this process) pays once, not per asset."""
    seen = set()
    for asset in assets:
        if (asset.job, asset.kind) not in seen:
            seen.add((asset.job, asset.kind))
            find_job(asset.job).function()(asset.input, Path(folder) / asset.name, **asset.options)


def _nothing(value: int) -> int:
    return value


def round_trip_ms(client, repeats: int = 50) -> float:
    """Mean milliseconds of a no-op task's submit and result on ``client``'s cluster."""
    client.submit(_nothing, -1, pure=False).result()
    with stopwatch() as elapsed:
        for value in range(repeats):
            client.submit(_nothing, value, pure=False).result()
    return 1000 * elapsed[0] / repeats


def simulate(times: list[float], workers: int) -> float:
    """Makespan of ``times`` handed in order to whichever of ``workers`` is free first."""
    free = [0.0] * workers
    for seconds in times:
        slot = min(range(workers), key=free.__getitem__)
        free[slot] += seconds
    return max(free)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--assets", type=int, default=200, help="generated assets (default %(default)s)")
    args = parser.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="bench_batch_"))
    with stopwatch() as made:
        manifest = generate(scratch / "library", args.assets)
    assets = read_spec(manifest)
    print(f"\n{len(assets)} assets generated in {made[0]:.1f} s; {os.cpu_count()} cores on this machine")

    load_before = os.getloadavg()[0]
    warm_up(assets, os.fspath(scratch / "warm"))
    direct: dict[str, float] = {}
    for asset in assets:
        with stopwatch() as elapsed:
            find_job(asset.job).function()(asset.input, scratch / "direct" / asset.name, **asset.options)
        direct[asset.name] = elapsed[0]
    direct_sum = sum(direct.values())
    loads = {0: os.getloadavg()[0]}  # 1-minute load average after each run: the machine may be shared

    runs, round_trip = {}, 0.0
    for workers in (1, 2):
        with stopwatch() as started:
            client, cluster = connect(workers=workers)
            client.run(warm_up, assets, os.fspath(scratch / f"warm{workers}"))
        try:
            result = run_batch(assets, scratch / f"out{workers}", client=client, force=True)
            if workers == 1:
                round_trip = round_trip_ms(client)
        finally:
            client.close()
            cluster.close()
        runs[workers] = (result, started[0])
        loads[workers] = os.getloadavg()[0]

    one, two = runs[1][0], runs[2][0]
    failed = [record["name"] for result in (one, two) for record in result.records if record["status"] != "ok"]
    count = len(assets)
    inside = {record["name"]: record.get("seconds") or 0.0 for record in one.records}
    worker_sum = sum(inside.values())
    overhead = (one.seconds - worker_sum) / count  # scheduling, transfer, records, catalogue
    rows = [
        ("direct (one process)", "", f"{direct_sum:.1f}", "", f"{direct_sum / count:.3f}", "", f"{loads[0]:.1f}"),
        ("batch, 1 worker", f"{runs[1][1]:.1f}", f"{one.seconds:.1f}", "1.00", f"{one.seconds / count:.3f}",
         f"{overhead:.3f} s ({100 * overhead / (worker_sum / count):.1f} %)", f"{loads[1]:.1f}"),
        ("batch, 2 workers", f"{runs[2][1]:.1f}", f"{two.seconds:.1f}", f"{one.seconds / two.seconds:.2f}",
         f"{two.seconds / count:.3f}", "", f"{loads[2]:.1f}"),
    ]  # fmt: skip
    print_table(
        f"Batch of {count} assets (wall seconds)",
        ("run", "cluster start s", "wall s", "speed-up", "s per asset", "Dask overhead per asset", "load after"),
        rows,
    )
    if failed:
        print(f"\nfailed assets: {', '.join(sorted(set(failed)))}")
    print(
        f"\nDask overhead per asset: (1-worker wall - the jobs' own time on the worker) / assets. The jobs took "
        f"{worker_sum:.1f} s on the worker against {direct_sum:.1f} s called directly "
        f"({100 * (worker_sum - direct_sum) / direct_sum:+.1f} %: one thread per worker, and whatever else ran on "
        f"the machine: 1-minute load average {load_before:.1f} at the start, then as in the table). A no-op "
        f"task's submit and result on the 1-worker cluster: {round_trip:.1f} ms (for scale: the runner's path "
        f"from one asset to the next holds part of such a round trip)."
    )

    peaks: dict[str, float] = {}
    for result in (one, two):
        for record in result.records:
            worker = record.get("worker") or "?"
            peaks[worker] = max(peaks.get(worker, 0.0), record.get("peak_rss_mb") or 0.0)
    print_table(
        "Peak resident memory per worker process",
        ("run", "worker", "peak MB"),
        [(f"{len({r.get('worker') for r in result.records})} worker(s)", worker, f"{peaks[worker]:.0f}")
         for result in (one, two) for worker in sorted({r.get("worker") for r in result.records})],
    )  # fmt: skip

    with stopwatch() as rerun:
        again = run_batch(assets, scratch / "out1")
    print(f"\nrerun, nothing changed: {again.skipped} of {count} skipped, {again.ran} run, {rerun[0]:.2f} s")

    sizes = {asset.name: fingerprint(asset)[1] for asset in assets}
    order = sorted(inside, key=lambda name: -sizes[name])
    per_asset = [inside[name] + max(overhead, 0.0) for name in order]
    rows = []
    for workers in (1, 2, 16):
        makespan = simulate(per_asset, workers)
        ideal = sum(per_asset) / workers
        rows.append((workers, f"{makespan:.1f}", f"{ideal:.1f}", f"{max(per_asset):.1f}",
                     f"{simulate(per_asset, 1) / makespan:.2f}"))  # fmt: skip
    print_table(
        "Projection from the measured per-asset times (largest input first, list scheduling)",
        ("workers", "makespan s", "sum / workers s", "longest asset s", "speed-up"),
        rows,
    )
    if os.environ.get("BENCH_BATCH_DEBUG"):
        for name in inside:
            print(f"{name}: direct {direct[name]:.2f} s, worker {inside[name]:.2f} s")
    longest = max(inside, key=inside.__getitem__)
    print(f"\nlongest asset: {longest} ({inside[longest]:.1f} s)")


if __name__ == "__main__":
    main()
