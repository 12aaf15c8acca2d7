"""Connected components of a graph given as pairs of node indices, in numpy."""

from __future__ import annotations

import numpy as np


def component_labels(node_count: int, pairs: np.ndarray) -> np.ndarray:
    """``(node_count,)`` int64: each node's component, named by its smallest node, where ``pairs
    (P, 2)`` join nodes (label propagation with pointer jumping: a few passes over the pairs)."""
    labels = np.arange(node_count, dtype=np.int64)
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    while True:
        smaller = np.minimum(labels[pairs[:, 0]], labels[pairs[:, 1]])
        updated = labels.copy()
        np.minimum.at(updated, pairs[:, 0], smaller)
        np.minimum.at(updated, pairs[:, 1], smaller)
        updated = updated[updated]
        if np.array_equal(updated, labels):
            return labels
        labels = updated
