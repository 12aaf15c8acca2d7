"""How many threads the C++ core's parallel loops may take, process-wide.

Every parallel loop of the core (AQEM, skinning, distances, the motion re-fit's frames) takes at
most :func:`thread_limit` threads: every core by default, fewer once capped here or by the
environment variable ``ANIMLOD_THREADS`` (read before the core's first parallel loop). A process that runs
several jobs side by side caps it so that the jobs do not each take every core; ``animlod batch``
does so on its workers. Results never depend on it.
"""

from __future__ import annotations

import os
import warnings

from . import _core

ENVIRONMENT_VARIABLE = "ANIMLOD_THREADS"


def set_thread_limit(threads: int) -> None:
    """Caps the core's threads at ``threads`` (0: every core again). ValueError below 0."""
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 0:
        raise ValueError(f"threads: must be a whole number >= 0 (0: every core), got {threads!r}")
    _core.set_thread_limit(threads)


def thread_limit() -> int:
    """The threads a parallel loop of the core may take now (the cap, at most the cores, at least 1)."""
    return _core.thread_limit()


def environment_sets_limit() -> bool:
    """Whether ``ANIMLOD_THREADS`` sets the core's starting cap (set to a whole number, which the
    core reads; another value is ignored)."""
    return bool(os.environ.get(ENVIRONMENT_VARIABLE)) and not _core.thread_environment_ignored()


def _check_environment() -> None:
    """A warning for an ``ANIMLOD_THREADS`` the core ignores (it reads whole numbers only)."""
    if _core.thread_environment_ignored():
        value = os.environ.get(ENVIRONMENT_VARIABLE)
        warnings.warn(
            f"{ENVIRONMENT_VARIABLE}={value!r} is not a whole number of threads; ignored, the core uses every core",
            stacklevel=2,
        )


_check_environment()
