"""Compressed NumPy archive (.npz) for an AnimatedMesh: the fastest way to store a baked sequence.

Keys: ``format_version`` (int, currently 1), ``faces (M, 3) int32``, ``frames (F, V, 3)
float32`` and ``fps`` (a float, NaN when the mesh has no frame rate).
"""

from __future__ import annotations

import os
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ..model import AnimatedMesh
from .atomic import atomic_write
from .errors import FormatError

FORMAT_VERSION = 1
_KEYS = ("format_version", "faces", "frames", "fps")


def write_npz(path: str | os.PathLike, mesh: AnimatedMesh) -> None:
    """Write ``mesh`` with ``np.savez_compressed``, atomically."""
    with atomic_write(path, "wb") as handle:
        np.savez_compressed(
            handle,
            format_version=np.int32(FORMAT_VERSION),
            faces=mesh.faces,
            frames=mesh.frames,
            fps=np.float64(np.nan if mesh.fps is None else mesh.fps),
        )


def read_npz(path: str | os.PathLike) -> AnimatedMesh:
    """Read an AnimatedMesh written by :func:`write_npz`.

    Raises
    ------
    FormatError
        If the file is not an npz archive, lacks a key, has a newer format version, or holds
        arrays of the wrong shape or values the mesh rejects (NaN, face index out of range).
    """
    path = Path(path)
    try:
        # A plain .npy file gives an ndarray, which is no context manager: TypeError. A damaged
        # member fails while it is decompressed: zlib.error, EOFError, or BadZipFile for its CRC;
        # zipfile raises RuntimeError (NotImplementedError) for encrypted or unknown compression.
        with np.load(path, allow_pickle=False) as archive:
            arrays = {key: archive[key] for key in _KEYS if key in archive.files}
    except (zipfile.BadZipFile, zlib.error, OSError, EOFError, ValueError, TypeError, RuntimeError) as error:
        raise FormatError(path, "archive", f"not a readable npz archive ({error})") from None
    missing = [key for key in _KEYS if key not in arrays]
    if missing:
        raise FormatError(path, f"key {missing[0]!r}", f"missing (an animlod npz has {', '.join(_KEYS)})")
    version, faces, frames, fps = (arrays[key] for key in _KEYS)
    checks = [
        ("format_version", version.shape == () and _holds(version, np.integer), "an integer"),
        ("frames", frames.ndim == 3 and frames.shape[2] == 3 and _holds(frames, np.floating), "float (F, V, 3)"),
        ("faces", faces.ndim == 2 and faces.shape[1] == 3 and _holds(faces, np.integer), "integer (M, 3)"),
        ("fps", fps.shape == () and _holds(fps, np.floating), "a float (NaN for none)"),
    ]
    for key, valid, expected in checks:
        if not valid:
            raise FormatError(path, f"key {key!r}", f"expected {expected}, got {arrays[key].dtype} {arrays[key].shape}")
    if not 1 <= int(version) <= FORMAT_VERSION:
        reason = f"unsupported version {int(version)}; this reader knows 1 to {FORMAT_VERSION}"
        raise FormatError(path, "key 'format_version'", reason)
    if not (np.isnan(fps) or (np.isfinite(fps) and fps > 0)):
        raise FormatError(path, "key 'fps'", f"must be positive or NaN, got {float(fps)}")
    try:
        return AnimatedMesh(faces, frames, fps=None if np.isnan(fps) else float(fps))
    except ValueError as error:
        raise FormatError(path, "mesh", str(error)) from None


def _holds(array: np.ndarray, kind: type) -> bool:
    """Whether ``array``'s dtype is a kind of ``kind`` (np.integer, np.floating)."""
    return bool(np.issubdtype(array.dtype, kind))
