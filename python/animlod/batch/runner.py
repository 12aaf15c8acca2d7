"""Run a batch on Dask: every asset through its job on a worker, the catalogue kept up to date.

- Cluster: a ``distributed.LocalCluster`` sized to the machine (one single-threaded worker
  process per core, memory split evenly) unless a client or a scheduler address is given; the
  same code runs on any Dask cluster whose workers share the output folder's file system.
- One asset per worker at a time: workers have one thread, and the runner submits an asset only
  when a thread is free (see :func:`_run_pending`), so that a worker's memory holds one asset
  and a worker's death is counted against the asset that caused it alone.
- Failures: a job that fails comes back as a failed record (:func:`animlod.batch.task.run_asset`);
  a worker that dies (a crash in native code, the memory limit) is restarted by its nanny and
  the asset is tried once more on another worker, then marked failed (``allowed-failures`` 1).
- Reruns: an asset whose fingerprint (inputs, job, options, version) matches the record in its
  output folder is not submitted; its rows are carried into the new catalogue.
- A run that stops early (no scheduler, Ctrl-C) keeps in the catalogue the assets it did not
  collect as their records on disk say (an earlier run's, or one a worker finished meanwhile).
- Order: largest inputs first, so that a long asset does not start last.
"""

from __future__ import annotations

import logging
import os
import secrets
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from ..io.detect import read_asset_record
from .catalogue import record_rows, write_catalogue
from .fingerprint import fingerprint
from .outputs import CATALOGUE, clear_staging, earlier_assets, output_lock, prepare_output
from .progress import BatchProgress
from .spec import AssetSpec
from .task import describe_error, run_asset

if TYPE_CHECKING:
    from distributed import Client, LocalCluster

# How a LocalCluster and the scheduler behave for a batch (see the module docstring).
CLUSTER_CONFIG = {
    "distributed.scheduler.allowed-failures": 1,
    "distributed.scheduler.worker-saturation": 1.0,
    "distributed.worker.preload": ["animlod.batch.worker_setup"],
}
# Least time between two rewrites of the catalogue while assets finish (seconds).
CATALOGUE_INTERVAL = 2.0


class SchedulerUnreachable(ConnectionError):
    """No Dask scheduler answered at the given address within the time allowed."""


@dataclass
class BatchResult:
    """What a batch did: one record per asset, in the spec's order (see :func:`run_asset`)."""

    output: Path
    catalogue: Path
    records: list[dict]
    ran: int
    skipped: int
    failed: int
    seconds: float
    workers: int
    notes: list[str] = field(default_factory=list)


def connect(
    scheduler: str | None = None, workers: int | None = None, timeout: float = 10.0
) -> tuple[Client, LocalCluster | None]:
    """A Dask client: to ``scheduler`` (``tcp://HOST:PORT``), waiting at most ``timeout`` seconds,
    or to a new LocalCluster of ``workers`` single-threaded processes (default: one per core).

    Returns (client, cluster or None); the caller closes both. Raises SchedulerUnreachable.
    """
    import dask
    from distributed import Client, LocalCluster

    if scheduler is not None:
        _check_address(scheduler)
        try:
            return Client(scheduler, timeout=timeout, set_as_default=False), None
        except (OSError, TimeoutError) as error:
            reason = " ".join(str(error).split())
            message = f"{scheduler}: no Dask scheduler answered within {timeout:g} s ({reason})"
            raise SchedulerUnreachable(message) from None
    count = workers or os.cpu_count() or 1
    with dask.config.set(CLUSTER_CONFIG):
        cluster = LocalCluster(
            n_workers=count,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",
            silence_logs=logging.ERROR,
        )
    return Client(cluster, set_as_default=False), cluster


def _check_address(scheduler: str) -> None:
    """SchedulerUnreachable for an address no scheduler can have (checked before a Client is
    made: one made from such an address fails late and leaves a closing traceback behind)."""
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, location = parse_address(scheduler)
        port = parse_host_port(location)[1] if scheme in ("tcp", "tls") else 1
        reason = None if 0 < port < 65536 else "the port must be 1-65535"
    except ValueError as error:
        reason = str(error)
    if reason:
        raise SchedulerUnreachable(f"{scheduler}: not a scheduler address like tcp://HOST:PORT ({reason})")


def run_batch(
    assets: Sequence[AssetSpec],
    output: str | os.PathLike,
    *,
    client: Client | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    connect_timeout: float = 10.0,
    force: bool = False,
    progress: BatchProgress | None = None,
) -> BatchResult:
    """Run every asset of ``assets`` into ``output``; write ``output/catalogue.parquet``.

    Parameters
    ----------
    assets : from :func:`animlod.batch.read_spec`.
    output : the batch's folder (created; FileExistsError when it is a file).
    client : a ``distributed.Client`` to use (left open); otherwise one is made by :func:`connect`
        from ``scheduler``, ``workers`` and ``connect_timeout`` and closed at the end.
    force : run every asset, even those unchanged since the last run.
    progress : receives progress (see :class:`BatchProgress`).

    Returns the :class:`BatchResult`; a failed asset is a record with status "failed", never an
    exception. Raises SchedulerUnreachable, BatchBusy (another batch writes into ``output``).
    """
    started = time.perf_counter()
    progress = progress or BatchProgress()
    root = prepare_output(output).resolve()
    with output_lock(root):
        clear_staging(root)  # attempts of a killed earlier run
        records: dict[str, dict] = {}
        ran_flags: dict[str, bool] = {}
        earlier: dict[str, dict] = {}  # records on disk of the assets still to run
        pending: list[tuple[AssetSpec, str, int]] = []
        for asset in assets:
            try:
                digest, size = fingerprint(asset)
            except OSError as error:
                records[asset.name] = _failed(asset, "", describe_error(error, asset.input))
                ran_flags[asset.name] = True
                continue
            previous = read_asset_record(root / asset.name)
            if not force and previous is not None and _unchanged(previous, digest, root):
                records[asset.name], ran_flags[asset.name] = previous, False
                continue
            pending.append((asset, digest, size))
            if previous is not None:
                earlier[asset.name] = previous
        skipped = sum(1 for flag in ran_flags.values() if not flag)
        notes: list[str] = []
        worker_count = 0
        progress.start(len(pending), skipped)
        try:
            if pending:
                owned = None
                if client is None:
                    client, owned = connect(scheduler, workers, connect_timeout)
                try:
                    _wait_for_a_worker(client, scheduler, connect_timeout)
                    worker_count, notes = _check_workers(client)
                    _run_pending(client, pending, root, records, ran_flags, progress, assets, earlier)
                finally:
                    if owned is not None:
                        client.close()
                        owned.close()
        finally:
            progress.close()
            on_disk = {
                asset.name: read_asset_record(root / asset.name) for asset in assets if asset.name not in records
            }
            _write(root, assets, records, ran_flags, on_disk)
            clear_staging(root)
        others = earlier_assets(root, {asset.name for asset in assets})
        if others:
            shown = ", ".join(others[:5]) + (f" and {len(others) - 5} more" if len(others) > 5 else "")
            notes.append(f"{root}: {len(others)} asset folder{'s' if len(others) > 1 else ''} of earlier runs "
                         f"not in this batch ({shown}): left as they are, and out of the catalogue")  # fmt: skip
    ordered = [records[asset.name] for asset in assets if asset.name in records]
    failed = sum(1 for record in ordered if record["status"] != "ok")
    ran = sum(1 for asset in assets if ran_flags.get(asset.name))
    return BatchResult(
        root, root / CATALOGUE, ordered, ran, skipped, failed, time.perf_counter() - started, worker_count, notes
    )


def _run_pending(
    client, pending, root: Path, records: dict, ran_flags: dict, progress: BatchProgress, assets, earlier: dict
) -> None:
    """Run ``pending`` (largest first), collect records as they finish, keep the catalogue (the
    assets not collected yet as ``earlier`` records them).

    At most one asset per worker thread is in the cluster at a time: the next is submitted as one
    finishes. Handing a worker a second asset while it runs one would put both in memory, and
    when the first kills the worker process Dask counts the death against both (its
    ``allowed-failures``), so an innocent asset could be marked failed.
    """
    from collections import deque

    from distributed import as_completed

    topic = f"animlod-batch-{secrets.token_hex(6)}"

    def on_event(event) -> None:
        message = event[1] if isinstance(event, tuple) else event
        if isinstance(message, dict):
            progress.asset_event(str(message.get("asset")), message.get("fraction"), str(message.get("message", "")))

    client.subscribe_topic(topic, on_event)
    waiting = deque(sorted(pending, key=lambda item: -item[2]))
    futures: dict = {}  # the assets in the cluster, submitted and not yet collected
    running = as_completed(loop=client.loop)
    submitted = 0

    def submit_while_free() -> None:
        nonlocal submitted
        sharing = _threads_by_host(client)  # read each time: a cluster may grow or shrink
        while waiting and len(futures) < max(1, sum(sharing.values())):
            asset, digest, _size = waiting.popleft()
            key = f"animlod-{submitted}-{topic}"
            future = client.submit(run_asset, asset, os.fspath(root), digest, topic, sharing, key=key, pure=False)
            futures[future] = (asset, digest)
            running.add(future)
            submitted += 1

    last_write = time.monotonic()
    try:
        submit_while_free()
        for future in running:
            asset, digest = futures.pop(future)
            # The next asset goes out before this one's record is fetched: the worker is free
            # now, and the fetch (a round trip to the worker) overlaps the next asset's run.
            submit_while_free()
            try:
                record = future.result()
            except Exception as error:
                record = _failed(asset, digest, _lost(error, asset))
            # Released at once: a record held on a worker that dies later would be recomputed.
            future.release()
            records[asset.name], ran_flags[asset.name] = record, True
            progress.asset_done(record)
            if time.monotonic() - last_write >= CATALOGUE_INTERVAL:
                _write(root, assets, records, ran_flags, earlier)
                last_write = time.monotonic()
    except BaseException:
        client.cancel(list(futures))
        raise
    finally:
        client.unsubscribe_topic(topic)


def _threads_by_host(client) -> dict[str, int]:
    """Worker threads in the cluster now, by host (a synchronous client asks the scheduler each
    time): each runs an asset, and an asset's core loops share the host's cores with the others."""
    sharing: dict[str, int] = {}
    for worker in _workers(client).values():
        host = str(worker.get("host", ""))
        sharing[host] = sharing.get(host, 0) + int(worker.get("nthreads", 1))
    return sharing


def _workers(client) -> dict:
    """The scheduler's workers (address -> info), every one of them."""
    info = client.scheduler_info(n_workers=-1) if _takes_n_workers(client) else client.scheduler_info()
    return info.get("workers", {})


def _lost(error: BaseException, asset: AssetSpec) -> dict:
    from distributed import KilledWorker

    if isinstance(error, KilledWorker):
        reason = (
            "its worker process died each time it was tried (a crash in native code or the memory limit; "
            "the scheduler's allowed-failures, 1 on a local cluster); the other assets went on"
        )
        return {"file": asset.input, "element": "worker", "reason": reason, "traceback": None}
    return describe_error(error, asset.input)


def _failed(asset: AssetSpec, digest: str, error: dict) -> dict:
    from datetime import datetime, timezone

    return {
        "name": asset.name,
        "job": asset.job,
        "input": asset.input,
        "fingerprint": digest,
        "status": "failed",
        "result": None,
        "error": error,
        "worker": None,
        "finished": datetime.now(timezone.utc).isoformat(timespec="milliseconds"),
    }


def _unchanged(record: dict, digest: str, root: Path) -> bool:
    """Whether an earlier record is for the same fingerprint and its outputs are all there."""
    if record.get("status") != "ok" or record.get("fingerprint") != digest or not record.get("result"):
        return False
    return _standing(record, root)


def _standing(record: dict, root: Path) -> bool:
    """Whether a record on disk still describes its folder: a whole record whose outputs are all
    there (a failed one has none)."""
    if not all(isinstance(record.get(key), str) for key in ("name", "job", "input", "status")):
        return False
    result = record.get("result") or {}
    return all((root / record["name"] / path).exists() for path in result.get("outputs", []))


def _wait_for_a_worker(client, scheduler: str | None, timeout: float) -> None:
    """SchedulerUnreachable when the cluster has no worker after ``timeout`` seconds (a
    scheduler started without workers would otherwise hold the batch forever)."""
    try:
        client.wait_for_workers(1, timeout=timeout)
    except TimeoutError:
        where = scheduler or "the local cluster"
        raise SchedulerUnreachable(f"{where}: the scheduler has no worker after {timeout:g} s") from None


def _check_workers(client) -> tuple[int, list[str]]:
    """How many workers there are, and a note when some run several assets at once."""
    workers = _workers(client)
    threads = [int(worker.get("nthreads", 1)) for worker in workers.values()]
    notes = []
    if any(count > 1 for count in threads):
        notes.append(
            f"some workers have up to {max(threads)} threads and run as many assets at once (memory: one asset per "
            "thread); start them with --nthreads 1 for one asset per worker"
        )
    return len(workers), notes


def _takes_n_workers(client) -> bool:
    import inspect

    return "n_workers" in inspect.signature(client.scheduler_info).parameters


def _write(root: Path, assets: Sequence[AssetSpec], records: dict, ran_flags: dict, on_disk: dict) -> None:
    """The catalogue: each asset's record of this run, else its record ``on_disk`` if it stands."""
    rows = []
    for asset in assets:
        if asset.name in records:
            rows += record_rows(records[asset.name], ran_flags.get(asset.name, True))
        elif (record := on_disk.get(asset.name)) is not None and _standing(record, root):
            rows += record_rows(record, False)
    write_catalogue(root / CATALOGUE, rows)
