"""File formats: BVH, glTF 2.0 / GLB, OBJ and PLY frame sequences, NPZ."""

from .errors import FormatError

__all__ = ["FormatError"]
