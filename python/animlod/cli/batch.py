"""``animlod batch SPEC -o OUT``: every asset of a folder, glob or manifest through its job on Dask."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..io.detect import unread_models_note
from . import UserError, positive_int


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "batch",
        help="run a library of assets (folder, glob or TOML/JSON manifest) on Dask, with a Parquet catalogue",
        description=(
            "Turn every asset of SPEC into its levels with the pipelines (simplify for glTF, NPZ and OBJ/PLY "
            "sequences, motion for BVH, or the job a manifest names), one asset per Dask worker at a time: a "
            "LocalCluster with one worker per core, or the cluster at --scheduler (its workers must see OUT at "
            "the same path). Each asset's files appear in OUT/<name>/ whole or not at all; OUT/catalogue.parquet "
            "has one row per asset and level (triangles, joints, errors, time, worker; the file, element and "
            "reason of a failure), rewritten as assets finish. A failed asset never stops the others; a rerun "
            "skips assets whose inputs, job and options are unchanged (content hash). Exit code 1 when an asset "
            "failed, 2 for a bad spec or option."
        ),
    )
    parser.add_argument(
        "spec", help="a folder of assets, a quoted glob ('lib/**/*.glb'), or a .toml/.json manifest (see README)"
    )
    parser.add_argument("-o", "--output", required=True, help="the batch's output folder (created if missing)")
    parser.add_argument(
        "--job", help="job for every asset of a folder or glob (simplify, character, motion, face, module:function)"
    )
    parser.add_argument(
        "--set", action="append", default=[], metavar="OPTION=VALUE", dest="options",
        help="a job option for every asset, VALUE in JSON (--set ratios=[0.5,0.2] --set solver=newton); "
        "a manifest's own options win",
    )  # fmt: skip
    parser.add_argument("--workers", type=positive_int, help="local worker processes (default: one per core)")
    parser.add_argument(
        "--scheduler", metavar="tcp://HOST:PORT", help="use this Dask scheduler instead of a local cluster"
    )
    parser.add_argument(
        "--connect-timeout", type=float, default=10.0, metavar="SECONDS",
        help="how long to wait for --scheduler to answer (default %(default)g s)",
    )  # fmt: skip
    parser.add_argument(
        "--force", action="store_true", help="redo every asset, even those unchanged since the last run"
    )
    parser.set_defaults(run=run)


def _options(pairs: list[str]) -> dict:
    options = {}
    for pair in pairs:
        name, equals, text = pair.partition("=")
        if not equals or not name:
            raise UserError(f"--set: expected OPTION=VALUE, got {pair!r}")
        try:
            options[name] = json.loads(text)
        except ValueError:
            options[name] = text  # a bare word: a string (--set solver=newton)
    return options


def run(args: argparse.Namespace) -> int:
    from ..batch.spec import read_spec
    from ..batch.task import WARNING_NOTE

    if args.workers is not None and args.scheduler:
        raise UserError("--workers: sizes the local cluster; a --scheduler cluster has its own workers")
    if args.connect_timeout <= 0:
        raise UserError(f"--connect-timeout: must be > 0, got {args.connect_timeout}")
    assets = read_spec(args.spec, job=args.job, options=_options(args.options))
    unread = unread_models_note(Path(args.spec)) if Path(args.spec).is_dir() else None
    try:
        import distributed  # noqa: F401
        import pyarrow  # noqa: F401
    except ImportError as error:
        raise UserError(f"animlod batch needs the batch extra (pip install 'animlod[batch]'): {error}") from None
    from ..batch import SchedulerUnreachable, TqdmProgress, run_batch

    try:
        result = run_batch(
            assets,
            args.output,
            scheduler=args.scheduler,
            workers=args.workers,
            connect_timeout=args.connect_timeout,
            force=args.force,
            progress=TqdmProgress(args.workers or 4),
        )
    except SchedulerUnreachable as error:
        raise UserError(f"--scheduler: {error}") from None
    for note in [*result.notes, *([f"{args.spec}: left out {unread}"] if unread else [])]:
        print(f"note: {note}")
    warned = [(record["name"], note) for record in result.records if record["status"] == "ok"
              for note in record["result"]["notes"] if note.startswith(WARNING_NOTE)]  # fmt: skip
    for name, note in warned[:20]:
        print(f"warning {name}: {note.removeprefix(WARNING_NOTE)}")
    if len(warned) > 20:
        print(f"... and {len(warned) - 20} more warnings (see each asset's record)")
    failures = [record for record in result.records if record["status"] != "ok"]
    for record in failures[:20]:
        error = record["error"]
        where = ": ".join(part for part in (error["file"], error["element"]) if part)
        print(f"failed {record['name']}: {where}: {error['reason']}")
    if len(failures) > 20:
        print(f"... and {len(failures) - 20} more failed assets (see the catalogue)")
    on = f" on {result.workers} workers" if result.workers else ""
    print(
        f"{len(result.records)} assets: {result.ran} run, {result.skipped} unchanged and skipped, {result.failed} "
        f"failed; {result.seconds:.1f} s{on}; catalogue {result.catalogue}"
    )
    return 1 if failures else 0
