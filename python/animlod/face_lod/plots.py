"""Pictures of face levels: each level with one expression, side by side (PNG, matplotlib Agg).

Meshes are drawn by a small painter's-algorithm renderer: an orthographic view from a chosen
direction, back faces culled, triangles sorted far to near and flat-shaded by one head light,
optionally coloured by region and with the wireframe (as the paper's Figures 9-10).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass
class Panel:
    """One picture: a mesh in one pose, with a title.

    Attributes
    ----------
    positions : (V, 3) positions.
    faces : (M, 3) triangles.
    title : text above the picture.
    face_colours : (M,) region index per face to colour by, or None for grey.
    """

    positions: np.ndarray
    faces: np.ndarray
    title: str
    face_colours: np.ndarray | None = None


def _view_matrix(azimuth_degrees: float) -> np.ndarray:
    """Rows: screen right, screen up, towards the viewer, for a camera turned about +Y."""
    angle = np.radians(azimuth_degrees)
    towards = np.array([np.sin(angle), 0.0, np.cos(angle)])
    right = np.cross([0.0, 1.0, 0.0], towards)
    return np.stack([right, [0.0, 1.0, 0.0], towards])


def draw_mesh(axes, panel: Panel, azimuth_degrees: float = 20.0, wireframe: bool = True) -> None:
    """Draw ``panel`` into matplotlib ``axes``."""
    from matplotlib import colormaps
    from matplotlib.collections import PolyCollection

    view = _view_matrix(azimuth_degrees)
    points = np.asarray(panel.positions, dtype=np.float64) @ view.T
    faces = np.asarray(panel.faces)
    corners = points[faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    visible = (normals[:, 2] > 0.0) & (lengths > 0.0)
    order = np.flatnonzero(visible)[np.argsort(corners[visible, :, 2].mean(axis=1), kind="stable")]
    light = np.array([0.3, 0.5, 1.0]) / np.linalg.norm([0.3, 0.5, 1.0])
    shade = 0.25 + 0.75 * np.clip((normals[order] / lengths[order, None]) @ light, 0.0, 1.0)
    if panel.face_colours is None:
        base = np.full((order.size, 3), 0.82)
    else:
        palette = colormaps["tab20"](np.arange(20))[:, :3]
        base = 0.55 + 0.45 * palette[np.asarray(panel.face_colours)[order] % 20]
    colours = np.clip(base * shade[:, None], 0.0, 1.0)
    edge = (0.0, 0.0, 0.0, 0.25) if wireframe else "face"
    axes.add_collection(
        PolyCollection(corners[order, :, :2], facecolors=colours, edgecolors=edge, linewidths=0.2 if wireframe else 0)
    )
    low, high = points[:, :2].min(axis=0), points[:, :2].max(axis=0)
    pad = 0.04 * float(np.max(high - low))
    axes.set_xlim(low[0] - pad, high[0] + pad)
    axes.set_ylim(low[1] - pad, high[1] + pad)
    axes.set_aspect("equal")
    axes.set_axis_off()
    axes.set_title(panel.title, fontsize=9)


def plot_panels(
    path: str | os.PathLike,
    rows: Sequence[Sequence[Panel]],
    azimuth_degrees: float = 20.0,
    wireframe: bool = True,
    title: str | None = None,
) -> None:
    """Write a PNG grid of panels (one list per row), atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..io.atomic import atomic_write

    row_count = len(rows)
    column_count = max(len(row) for row in rows)
    figure, axes = plt.subplots(row_count, column_count, figsize=(3.2 * column_count, 3.6 * row_count), squeeze=False)
    for r, row in enumerate(rows):
        for c in range(column_count):
            if c < len(row):
                draw_mesh(axes[r][c], row[c], azimuth_degrees, wireframe)
            else:
                axes[r][c].set_axis_off()
    if title:
        figure.suptitle(title, fontsize=11)
    figure.tight_layout()
    with atomic_write(path, "wb") as handle:
        figure.savefig(handle, format="png", dpi=110)
    plt.close(figure)
