"""Smooth scalar curves of time or phase that drive the procedural animations."""

from __future__ import annotations

import numpy as np


def bump(u: np.ndarray, start: float, stop: float) -> np.ndarray:
    """``sin^2`` window: 0 outside ``[start, stop]``, 1 in the middle, smooth (C1) at both ends."""
    s = np.clip((np.asarray(u, dtype=np.float64) - start) / (stop - start), 0.0, 1.0)
    return np.sin(np.pi * s) ** 2


def raised(phase: np.ndarray, peak: float, sharpness: int) -> np.ndarray:
    """Periodic pulse in [0, 1] peaking at ``phase == peak``; higher ``sharpness`` is narrower."""
    return (0.5 + 0.5 * np.cos(np.asarray(phase, dtype=np.float64) - peak)) ** sharpness
