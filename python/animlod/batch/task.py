"""What runs on a worker: one asset through its job, into a staging folder, then published.

:func:`run_asset` never raises for a problem of the asset: a failed job comes back as a record
with ``status = "failed"`` and the file, element and reason, so that one asset never stops the
others. Only the death of the worker process itself (a crash in native code, the memory limit)
is left to Dask, which reschedules the asset once and then reports it (see the runner).
"""

from __future__ import annotations

import os
import resource
import socket
import time
import traceback
import warnings
from datetime import datetime, timezone
from pathlib import Path
from typing import TYPE_CHECKING

from ..io.errors import FormatError
from ..threads import environment_sets_limit, set_thread_limit
from .jobs import find_job
from .outputs import discard, publish, staging_folder
from .spec import AssetSpec

if TYPE_CHECKING:
    from ..pipelines.result import Progress

# Least time between two progress events of one asset (seconds): enough for a live bar, few
# enough messages that the scheduler does not notice them.
PROGRESS_INTERVAL = 0.25
# How an asset's notes begin for a warning a reader gave while its job ran.
WARNING_NOTE = "warning: "


def run_asset(
    asset: AssetSpec, root: str, fingerprint: str, topic: str | None = None, sharing: dict[str, int] | None = None
) -> dict:
    """Run ``asset``'s job into ``root/<asset.name>``; the record of what happened.

    On a Dask worker the core's loops take this process's cores divided by the worker threads
    on its host (``sharing``: host -> worker threads, from the scheduler; a host missing from it
    counts this worker's threads alone), so that assets running side by side do not each take
    every core (:func:`animlod.set_thread_limit`; the result does not depend on it), unless the
    worker's environment sets ANIMLOD_THREADS.

    The record (JSON values): name, job, input, fingerprint, status ("ok" or "failed"), result
    (:meth:`AssetResult.to_dict` with outputs relative to the asset's folder; ok only), error
    ({"file", "element", "reason", "traceback"}; failed only), worker, peak_rss_mb (the worker
    process's peak resident memory so far), started and finished (ISO 8601, UTC), seconds.
    """
    started = time.perf_counter()
    record: dict = {
        "name": asset.name,
        "job": asset.job,
        "input": asset.input,
        "fingerprint": fingerprint,
        "worker": _worker_name(),
        "started": _now(),
    }
    staging = None
    try:
        folder = Path(root)
        staging = staging_folder(folder, asset.name)
        job = find_job(asset.job).function()
        _share_cores(sharing)
        # The readers' warnings (a texture not found, a BVH's frame count one short) go with the
        # asset's notes, not to the worker's stderr. Exact on single-threaded workers, as the
        # local cluster's are: catch_warnings is process-wide.
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")
            result = job(asset.input, staging, progress=_progress(topic, asset.name), **asset.options)
        result.notes += [WARNING_NOTE + " ".join(str(warning.message).split()) for warning in caught]
        record.update(status="ok", result=result.to_dict(relative_to=staging), error=None)
        _finish(record, started)
        publish(staging, folder, asset.name, record)
        staging = None
    except Exception as error:
        record.update(status="failed", result=None, error=describe_error(error, asset.input))
        _finish(record, started)
    finally:
        if staging is not None:
            discard(staging)
    return record


def describe_error(error: BaseException, source: str) -> dict:
    """{"file", "element", "reason", "traceback"} of a failed job: a FormatError's own parts;
    an OSError's file and the system's reason; another ValueError (the data model and the core
    name the element: ``"faces[3]: index 99 out of range"``) the input and that element; any
    other exception is a bug, given with its type and traceback."""
    if isinstance(error, FormatError):
        return {"file": error.path, "element": error.element, "reason": error.reason, "traceback": None}
    if isinstance(error, OSError):
        file = error.filename if error.filename is not None else source
        return {"file": os.fspath(file), "element": "file", "reason": error.strerror or str(error), "traceback": None}
    message = " ".join(str(error).split()) or type(error).__name__
    if isinstance(error, ValueError):
        head, _, rest = message.partition(": ")
        if rest and " " not in head:
            return {"file": source, "element": head, "reason": rest, "traceback": None}
        return {"file": source, "element": "", "reason": message, "traceback": None}
    trace = "".join(traceback.format_exception(type(error), error, error.__traceback__))
    return {"file": source, "element": "", "reason": f"{type(error).__name__}: {message}", "traceback": trace}


def _finish(record: dict, started: float) -> None:
    record["finished"] = _now()
    record["seconds"] = time.perf_counter() - started
    record["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds")


def _worker_name() -> str:
    """The Dask worker's address, or host:pid outside Dask."""
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return f"{socket.gethostname()}:{os.getpid()}"


def _share_cores(sharing: dict[str, int] | None) -> None:
    """Caps the core's threads at this worker's share of its host's cores (nothing outside Dask,
    or where the worker's environment sets ANIMLOD_THREADS to a cap the core takes: the user's
    cap stands)."""
    if environment_sets_limit():
        return
    try:
        from distributed import get_worker
        from distributed.comm.addressing import get_address_host

        worker = get_worker()
    except (ImportError, ValueError):
        return
    threads = (sharing or {}).get(get_address_host(worker.address)) or worker.state.nthreads
    set_thread_limit(max(1, (os.cpu_count() or 1) // max(1, threads)))


def _progress(topic: str | None, name: str) -> Progress | None:
    """A job progress callback that sends (asset, fraction, message) events to the client,
    at most one per PROGRESS_INTERVAL; None outside Dask or without a topic."""
    if topic is None:
        return None
    try:
        from distributed import get_worker

        worker = get_worker()
    except (ImportError, ValueError):
        return None
    last = [0.0]

    def send(fraction: float | None, message: str) -> None:
        now = time.monotonic()
        if now - last[0] >= PROGRESS_INTERVAL:
            last[0] = now
            worker.log_event(topic, {"asset": name, "fraction": fraction, "message": message})

    return send
