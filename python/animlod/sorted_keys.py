"""Set operations on integer keys by sorting: numpy's own (``np.unique``, ``np.isin``) hash them,
which took most of the time of the sequence readers' frame matching at 180k triangles."""

from __future__ import annotations

import numpy as np


def distinct(keys: np.ndarray) -> np.ndarray:
    """``keys`` sorted, each once."""
    keys = np.sort(keys)
    first = np.ones(keys.size, dtype=bool)
    first[1:] = keys[1:] != keys[:-1]
    return keys[first]


def among(values: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """(len(values),) bool: whether each of ``values`` is one of ``keys``."""
    if keys.size == 0:
        return np.zeros(np.shape(values), dtype=bool)
    keys = np.sort(keys)
    found = np.minimum(np.searchsorted(keys, values), keys.size - 1)
    return keys[found] == values
