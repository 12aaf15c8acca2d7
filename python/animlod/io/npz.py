"""Compressed NumPy archive (.npz) for an AnimatedMesh: the fastest way to store a baked sequence.

Keys: ``format_version`` (int, currently 1), ``faces (M, 3) int32``, ``frames (F, V, 3)
float32`` and ``fps`` (a float, NaN when the mesh has no frame rate; an integer is read too).
"""

from __future__ import annotations

import math
import os
import struct
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ..model import AnimatedMesh
from .atomic import atomic_write
from .errors import FormatError

FORMAT_VERSION = 1
_KEYS = ("format_version", "faces", "frames", "fps")
# Largest ratio of uncompressed to compressed size that deflate can reach (about 1032:1).
_MAX_DEFLATE_RATIO = 1032
_NPY_HEADER_READERS = {(1, 0): np.lib.format.read_array_header_1_0, (2, 0): np.lib.format.read_array_header_2_0}
_MAX_NPY_HEADER = 10_000  # numpy's own default limit of a header's size


def write_npz(path: str | os.PathLike, mesh: AnimatedMesh) -> None:
    """Write ``mesh`` with ``np.savez``, atomically. Stored, not deflated: float positions
    deflate by about a tenth, and deflating took 35x as long as storing (a dense capture's level
    of 1.1 GB: 52.8 s against 1.5 s, and reading it back 12.9 s)."""
    with atomic_write(path, "wb") as handle:
        np.savez(
            handle,
            format_version=np.int32(FORMAT_VERSION),
            faces=mesh.faces,
            frames=mesh.frames,
            fps=np.float64(np.nan if mesh.fps is None else mesh.fps),
        )


def read_npz(path: str | os.PathLike) -> AnimatedMesh:
    """Read an AnimatedMesh written by :func:`write_npz`.

    Every member's .npy header is checked before its array is allocated: the shape must need
    exactly the bytes the member holds, and the member no more bytes than its compressed size
    can expand to, so a few hostile bytes cannot make the reader allocate gigabytes.

    Raises
    ------
    FormatError
        If the file is not an npz archive, lacks a key, has a newer format version, or holds
        arrays of the wrong shape or values the mesh rejects (NaN, face index out of range).
    """
    path = Path(path)
    try:
        # A damaged member fails while it is decompressed: zlib.error, EOFError, or BadZipFile for
        # its CRC; zipfile raises RuntimeError (NotImplementedError) for encrypted or unknown
        # compression, ValueError and struct.error for damaged records.
        with zipfile.ZipFile(path) as archive:
            arrays = {key: _member_array(path, archive, key) for key in _KEYS if f"{key}.npy" in archive.namelist()}
    except (zipfile.BadZipFile, zlib.error, OSError, EOFError, ValueError, RuntimeError, struct.error) as error:
        if isinstance(error, FormatError):
            raise
        raise FormatError(path, "archive", f"not a readable npz archive ({type(error).__name__}: {error})") from None
    missing = [key for key in _KEYS if key not in arrays]
    if missing:
        raise FormatError(path, f"key {missing[0]!r}", f"missing (an animlod npz has {', '.join(_KEYS)})")
    version, faces, frames, fps = (arrays[key] for key in _KEYS)
    checks = [
        ("format_version", version.shape == () and _holds(version, np.integer), "an integer"),
        ("frames", frames.ndim == 3 and frames.shape[2] == 3 and _holds(frames, np.floating), "float (F, V, 3)"),
        ("faces", faces.ndim == 2 and faces.shape[1] == 3 and _holds(faces, np.integer), "integer (M, 3)"),
        # np.savez(..., fps=30) stores an integer: as clear a rate as 30.0.
        ("fps", fps.shape == () and (_holds(fps, np.floating) or _holds(fps, np.integer)), "a float (NaN for none)"),
    ]
    for key, valid, expected in checks:
        if not valid:
            raise FormatError(path, f"key {key!r}", f"expected {expected}, got {arrays[key].dtype} {arrays[key].shape}")
    if not 1 <= int(version) <= FORMAT_VERSION:
        reason = f"unsupported version {int(version)}; this reader knows 1 to {FORMAT_VERSION}"
        raise FormatError(path, "key 'format_version'", reason)
    fps = np.float64(fps)
    if not (np.isnan(fps) or (np.isfinite(fps) and fps > 0)):
        raise FormatError(path, "key 'fps'", f"must be positive or NaN, got {float(fps)}")
    try:
        return AnimatedMesh(faces, frames, fps=None if np.isnan(fps) else float(fps))
    except ValueError as error:
        raise FormatError(path, "mesh", str(error)) from None


def _member_array(path: Path, archive: zipfile.ZipFile, key: str) -> np.ndarray:
    """The array of member ``key.npy``, its header checked against the member's size first."""
    info = archive.getinfo(f"{key}.npy")
    element = f"key {key!r}"
    # Deflate expands at most ~1032:1; a member claiming more is damaged or a bomb.
    if info.file_size > _MAX_DEFLATE_RATIO * info.compress_size + 1024:
        reason = f"member claims {info.file_size} bytes from {info.compress_size} compressed bytes"
        raise FormatError(path, element, reason)
    with archive.open(info) as member:
        try:
            version = np.lib.format.read_magic(member)
            read_header = _NPY_HEADER_READERS.get(version)
            if read_header is None:
                raise FormatError(path, element, f"unknown .npy version {version}")
            shape, fortran_order, dtype = read_header(member, max_header_size=_MAX_NPY_HEADER)
        except (ValueError, SyntaxError, TypeError) as error:
            raise FormatError(path, element, f"not a .npy array ({error})") from None
        if any(extent < 0 for extent in shape):
            raise FormatError(path, element, f"header declares a negative extent in shape {shape}")
        if dtype.hasobject or dtype.itemsize == 0:
            raise FormatError(path, element, f"dtype {dtype} is not a plain numeric type")
        header_bytes = member.tell()
        count = math.prod(shape)
        if count * dtype.itemsize != info.file_size - header_bytes:
            reason = (
                f"header declares shape {shape} of {dtype} ({count * dtype.itemsize} bytes), "
                f"the member holds {info.file_size - header_bytes}"
            )
            raise FormatError(path, element, reason)
        data = member.read()
    if len(data) != count * dtype.itemsize:
        raise FormatError(path, element, f"member ends after {len(data)} of {count * dtype.itemsize} bytes")
    array = np.frombuffer(data, dtype=dtype)
    return array.reshape(shape[::-1]).T if fortran_order else array.reshape(shape)


def _holds(array: np.ndarray, kind: type) -> bool:
    """Whether ``array``'s dtype is a kind of ``kind`` (np.integer, np.floating)."""
    return bool(np.issubdtype(array.dtype, kind))
