"""Per-vertex colours of OBJ and PLY files (PLY red, green, blue and alpha; an OBJ ``v`` line's
r, g, b after x, y, z), kept as the file stores them so that levels write them back alike: a
PLY file's uchar 0-255 stay uchar 0-255, an OBJ file's 0-1 floats stay floats."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

# A PLY vertex's colour under the names exporters give it (MeshLab, Open3D and Blender write red,
# green, blue; older tools diffuse_*); the first set whose three colour channels a file has is
# read, with its alpha where the file has one.
PLY_COLOUR_NAMES = (
    ("red", "green", "blue", "alpha"),
    ("diffuse_red", "diffuse_green", "diffuse_blue", "diffuse_alpha"),
)
# An OBJ ``v`` line of six values holds x, y, z, r, g, b (MeshLab, ZBrush, Open3D).
OBJ_COLOUR_NAMES = ("r", "g", "b")


@dataclass(frozen=True)
class VertexColours:
    """Colours per vertex, per frame where the frames of a sequence have their own.

    values : (K, V, C) float32, the stored values (K = 1: one colour per vertex for every frame).
    names : the C channels' names as stored (PLY property names, or :data:`OBJ_COLOUR_NAMES`).
    type_code : how they are stored, a numpy type code without byte order ("u1" for PLY uchar,
        "f4" for float and for OBJ files).
    """

    values: np.ndarray
    names: tuple[str, ...]
    type_code: str

    def of_frame(self, frame: int, vertices: np.ndarray | None = None) -> VertexColours:
        """The colours of ``frame`` (of its ``vertices`` only, in their order, where given)."""
        values = self.values[frame if len(self.values) > 1 else 0]
        return VertexColours((values if vertices is None else values[vertices])[None], self.names, self.type_code)

    def same_layout(self, other: VertexColours | None) -> bool:
        """Whether ``other`` stores the same channels in the same type for as many vertices."""
        return (other is not None and other.names == self.names and other.type_code == self.type_code
                and other.values.shape[1:] == self.values.shape[1:])  # fmt: skip

    def stored(self, values: np.ndarray) -> np.ndarray:
        """``values`` (interpolated colours of this layout) as the file type holds them: rounded
        and clipped to an integer type's range, else float32."""
        kind = np.dtype(self.type_code)
        if kind.kind == "f":
            return values.astype(np.float32)
        limits = np.iinfo(kind)
        return np.clip(np.rint(values), limits.min, limits.max).astype(kind)

    def checked(self, path: str | os.PathLike, vertex_count: int) -> VertexColours:
        """These colours if they are one frame's, of ``vertex_count`` vertices and finite; else a
        ValueError naming the file."""
        values = np.asarray(self.values)
        if values.shape != (1, vertex_count, len(self.names)) or not np.isfinite(values).all():
            raise ValueError(f"{os.fspath(path)}: colours: expected (1, {vertex_count}, {len(self.names)}) finite "
                             f"values, got {values.shape}")  # fmt: skip
        return self
