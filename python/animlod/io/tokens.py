"""Vectorised helpers for whitespace-separated text tables (BVH MOTION rows, OBJ and ASCII PLY bodies).

Counting tokens line by line in Python is a loop over frames or vertices; these work on the
bytes of the whole table at once.
"""

from __future__ import annotations

import numpy as np

_WHITESPACE = np.frombuffer(b" \t\r\n\v\f", dtype=np.uint8)


def tokens_per_line(data: bytes) -> np.ndarray:
    """Number of whitespace-separated tokens on each ``\\n``-separated line of ``data``.

    Returns ``(L,) int64`` where ``L = data.count(b"\\n") + 1``; entry ``i`` is for line ``i``.
    """
    codes = np.frombuffer(data, dtype=np.uint8)
    space = np.isin(codes, _WHITESPACE)
    token_start = ~space & np.concatenate(([True], space[:-1]))
    newline = codes == ord("\n")
    line_of_byte = np.cumsum(newline) - newline
    return np.bincount(line_of_byte[token_start], minlength=int(newline.sum()) + 1)


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
