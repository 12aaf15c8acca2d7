"""Per-vertex colours of OBJ and PLY files (PLY red, green, blue and alpha; an OBJ ``v`` line's
r, g, b and a after x, y, z), kept as the file stores them so that levels write them back alike:
each PLY channel in its own type (uchar 0-255 stay uchar 0-255), an OBJ file's floats as floats."""

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
# An OBJ ``v`` line of six values holds x, y, z, r, g, b (MeshLab, ZBrush, Open3D); of seven,
# x, y, z, r, g, b, a.
OBJ_COLOUR_NAMES = ("r", "g", "b", "a")
# PLY's names of the types a channel may be stored in, by numpy type code: PLY 1.0's original
# names, which every reader knows.
PLY_TYPE_NAMES = {"i1": "char", "u1": "uchar", "i2": "short", "u2": "ushort", "i4": "int", "u4": "uint",
                  "f4": "float", "f8": "double"}  # fmt: skip


@dataclass(frozen=True)
class VertexColours:
    """Colours per vertex, per frame where the frames of a sequence have their own.

    values : (K, V, C) float32, the stored values (K = 1: one colour per vertex for every frame;
        32-bit integer channels beyond 2**24 lose their last bits).
    names : the C channels' names as stored (PLY property names, or :data:`OBJ_COLOUR_NAMES`).
    types : each channel's stored type, a numpy type code without byte order (:data:`PLY_TYPE_NAMES`;
        "u1" for PLY uchar, "f4" for OBJ files).
    """

    values: np.ndarray
    names: tuple[str, ...]
    types: tuple[str, ...]

    def of_frame(self, frame: int, vertices: np.ndarray | None = None) -> VertexColours:
        """The colours of ``frame`` (of its ``vertices`` only, in their order, where given)."""
        values = self.values[frame if len(self.values) > 1 else 0]
        return VertexColours((values if vertices is None else values[vertices])[None], self.names, self.types)

    def same_layout(self, other: VertexColours | None) -> bool:
        """Whether ``other`` stores the same channels in the same types for as many vertices."""
        return (other is not None and (other.names, other.types) == (self.names, self.types)
                and other.values.shape[1:] == self.values.shape[1:])  # fmt: skip

    def layout(self) -> str:
        """The channels and their stored types, as messages name them: "red, green, blue (uchar)"."""
        types = sorted({PLY_TYPE_NAMES[code] for code in self.types})
        return f"{', '.join(self.names)} ({', '.join(types)})"

    def stored(self, path: str | os.PathLike, vertex_count: int) -> list[np.ndarray]:
        """Each channel of this one frame's colours (interpolated values) in its stored type:
        rounded and clipped to an integer type's range; a ValueError naming the file where they
        are not one frame's of ``vertex_count`` vertices, or not finite."""
        values = np.asarray(self.values, np.float64)
        if values.shape != (1, vertex_count, len(self.names)) or not np.isfinite(values).all():
            raise ValueError(f"{os.fspath(path)}: colours: expected (1, {vertex_count}, {len(self.names)}) finite "
                             f"values, got {values.shape}")  # fmt: skip
        channels = []
        for column, code in zip(values[0].T, self.types):
            kind = np.dtype(code)
            if kind.kind != "f":
                limits = np.iinfo(kind)
                column = np.clip(np.rint(column), limits.min, limits.max)
            channels.append(column.astype(kind))
        return channels
