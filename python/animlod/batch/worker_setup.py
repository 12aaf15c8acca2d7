"""Set-up of the local cluster's worker processes (Dask's ``distributed.worker.preload``)."""

from __future__ import annotations

import signal


def dask_setup(worker: object) -> None:
    """SIGINT ends the worker process at once and quietly (the system's default action): Ctrl-C
    in a terminal reaches the whole process group, and each worker's KeyboardInterrupt traceback
    would bury the batch's one line; the runner stops the cluster itself."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
