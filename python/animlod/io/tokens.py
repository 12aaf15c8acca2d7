"""Vectorised helpers for whitespace-separated text tables (BVH MOTION rows, OBJ and ASCII PLY bodies).

Counting tokens line by line in Python is a loop over frames or vertices; these work on the
bytes of the whole table at once.
"""

from __future__ import annotations

import warnings

import numpy as np

_IS_SPACE = np.zeros(256, dtype=bool)
_IS_SPACE[list(b" \t\r\n\v\f")] = True
_IS_INTEGER_CHARACTER = np.zeros(256, dtype=bool)
_IS_INTEGER_CHARACTER[list(b"0123456789+-")] = True


def _token_layout(data: bytes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``data``'s bytes, whether each is white space, and the offset of every whitespace-separated
    token (a byte that is not space after one that is, or at the start)."""
    codes = np.frombuffer(data, dtype=np.uint8)
    space = _IS_SPACE[codes]
    return codes, space, np.flatnonzero(~space & np.concatenate(([True], space[:-1])))


def tokens_per_line(data: bytes) -> np.ndarray:
    """Number of whitespace-separated tokens on each ``\\n``-separated line of ``data``.

    Returns ``(L,) int64`` where ``L = data.count(b"\\n") + 1``; entry ``i`` is for line ``i``.
    """
    codes, _, token_starts = _token_layout(data)
    line_starts = np.concatenate(([0], np.flatnonzero(codes == ord("\n")) + 1, [codes.size + 1]))
    return np.diff(np.searchsorted(token_starts, line_starts)).astype(np.int64)


def token_starts(data: bytes) -> np.ndarray:
    """The offset of every whitespace-separated token of ``data``: ``(T,) int64``, ascending."""
    return _token_layout(data)[2]


def integer_tokens(data: bytes) -> np.ndarray:
    """Whether each whitespace-separated token of ``data`` is written with ASCII digits and signs
    only (``12``, ``-3``; not ``3.0`` or ``1e3``), as an integer table must be: ``(N,) bool``."""
    codes, space, token_starts = _token_layout(data)
    if not token_starts.size:
        return np.zeros(0, dtype=bool)
    # A token's run reaches to the next token's start; the spaces after it are no other character.
    return ~np.logical_or.reduceat(~(space | _IS_INTEGER_CHARACTER[codes]), token_starts)


def parse_all(data: bytes, dtype: type) -> np.ndarray | None:
    """Every whitespace-separated token of ``data`` as ``dtype``, in one pass of numpy's C parser
    (ten times as fast as converting an array of byte-string tokens); None when a token does not
    parse, or an integer reaches the type's limit (the parser saturates), so that the caller
    finds and names it token by token."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", DeprecationWarning)  # numpy < 2 warns where 2 raises
            values = np.fromstring(data.decode("ascii"), dtype=dtype, sep=" ")
    except (ValueError, DeprecationWarning, UnicodeDecodeError):
        return None
    if values.dtype.kind == "i" and values.size:
        limits = np.iinfo(values.dtype)
        if values.max() == limits.max or values.min() == limits.min:
            return None
    return values


def parses(token: str | bytes, dtype: type) -> bool:
    """Whether numpy converts ``token`` to ``dtype``, as it does a whole table of such tokens.

    False for malformed text and for integers too large for ``dtype``; used after a bulk
    ``astype`` failed, to find the token to name in the error.
    """
    try:
        np.array([token]).astype(dtype)
    except (ValueError, OverflowError):
        return False
    return True
