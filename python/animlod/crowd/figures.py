"""Fig. 1 of the motion LoD paper from a crowd grid run: FPS per (motion level, mesh level) cell."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np


def write_heat_map(grid: Sequence[dict], path: str | os.PathLike, title: str = "") -> None:
    """Write a PNG heat map of FPS over mesh levels (columns) and motion levels (rows).

    Parameters
    ----------
    grid : the ``"grid"`` list of an ``animlod_crowd --grid`` JSON report: cells with
        ``mesh_level``, ``motion_level``, ``fps``, ``triangles`` and ``joints`` (per frame).
    path : output PNG, written atomically.
    title : figure title (the run's character count and renderer, say).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io.atomic import atomic_write

    if not grid:
        raise ValueError("grid: no cell to draw")
    mesh_levels = sorted({int(cell["mesh_level"]) for cell in grid})
    motion_levels = sorted({int(cell["motion_level"]) for cell in grid})
    fps = np.full((len(motion_levels), len(mesh_levels)), np.nan)
    for cell in grid:
        fps[motion_levels.index(int(cell["motion_level"])), mesh_levels.index(int(cell["mesh_level"]))] = cell["fps"]
    figure, axes = plt.subplots(figsize=(1.2 * len(mesh_levels) + 3, 0.9 * len(motion_levels) + 2))
    image = axes.imshow(np.ma.masked_invalid(fps), cmap="viridis", origin="lower", aspect="auto")
    for (row, column), value in np.ndenumerate(fps):
        if np.isfinite(value):
            axes.text(column, row, f"{value:.1f}", ha="center", va="center", color="white", fontsize=9)
    axes.set_xticks(range(len(mesh_levels)), [str(level) for level in mesh_levels])
    axes.set_yticks(range(len(motion_levels)), [str(level) for level in motion_levels])
    axes.set_xlabel("mesh level (fewer triangles to the right)")
    axes.set_ylabel("motion level (fewer joints upwards)")
    axes.set_title(title or "crowd FPS per level (Fig. 1)")
    figure.colorbar(image, ax=axes, label="FPS")
    figure.tight_layout()
    with atomic_write(path, "wb") as handle:
        figure.savefig(handle, format="png", dpi=110)
    plt.close(figure)
