"""Vertex normals of a triangle mesh, for meshes that come without them."""

from __future__ import annotations

import numpy as np


def vertex_normals(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals ``(V, 3) float32`` of a counter-clockwise mesh (zero for
    a vertex no face uses)."""
    positions = np.asarray(positions, dtype=np.float64)
    corners = positions[faces]
    face_normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])  # length = 2 * area
    normals = np.zeros_like(positions)
    np.add.at(normals, faces.ravel(), np.repeat(face_normals, 3, axis=0))
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return (normals / np.where(length > 0.0, length, 1.0)).astype(np.float32)
