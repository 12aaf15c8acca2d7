"""Asset libraries at scale: every asset of a folder, glob or manifest through its pipeline job
on Dask, a catalogue of the results, reruns that skip what has not changed.

::

    from animlod.batch import read_spec, run_batch
    result = run_batch(read_spec("library/"), "out/library")   # a LocalCluster sized to the machine
    result = run_batch(read_spec("assets.toml"), "/shared/out", scheduler="tcp://farm:8786")

Needs the ``batch`` extra (``pip install animlod[batch]``: dask.distributed and pyarrow).
"""

from .catalogue import read_catalogue
from .jobs import BUILTIN_JOBS, DEFAULT_JOBS, Job, find_job
from .outputs import CATALOGUE, BatchBusy
from .progress import BatchProgress, TqdmProgress
from .runner import BatchResult, SchedulerUnreachable, connect, run_batch
from .spec import AssetSpec, SpecError, read_spec
from .task import run_asset

__all__ = [
    "BUILTIN_JOBS",
    "CATALOGUE",
    "DEFAULT_JOBS",
    "AssetSpec",
    "BatchBusy",
    "BatchProgress",
    "BatchResult",
    "Job",
    "SchedulerUnreachable",
    "SpecError",
    "TqdmProgress",
    "connect",
    "find_job",
    "read_catalogue",
    "read_spec",
    "run_asset",
    "run_batch",
]
