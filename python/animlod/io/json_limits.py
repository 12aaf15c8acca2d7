"""JSON from untrusted files with bounded nesting, and JSON written only with finite numbers.

``json.loads`` recurses once per nesting level; a file of 100,000 ``[`` raises RecursionError
(or, in a deeper call stack, exhausts it). animlod's JSON documents (glTF, LoD manifests) need a
handful of levels, so anything nested deeper than :data:`MAX_JSON_DEPTH` is refused before it is
parsed, with a FormatError naming the file and the byte where the limit is crossed.

Python's ``json`` writes NaN and infinities as ``NaN`` and ``Infinity``, which JSON does not
have: a glTF or manifest holding one is refused by every strict reader. :func:`finite_json_text`
refuses them instead, naming where the first one is.
"""

from __future__ import annotations

import json
import os
from typing import Any

import numpy as np

from .errors import FormatError

# glTF's deepest schema path is ~6 levels; extras and extensions may nest more, not 100 deeper.
MAX_JSON_DEPTH = 100


def json_depth_exceeded(data: bytes, limit: int = MAX_JSON_DEPTH) -> int | None:
    """Byte offset where brackets outside strings first nest deeper than ``limit``, or None.

    Linear in the size of ``data`` and vectorised: a quote preceded by an odd run of
    backslashes is escaped; the others open and close strings, inside which brackets do not
    count. (A regular expression for strings is quadratic on an unterminated string full of
    escaped quotes.) Unbalanced brackets and bad strings are left for the parser to report.
    """
    codes = np.frombuffer(data, dtype=np.uint8)
    if not codes.size:
        return None
    position = np.arange(codes.size)
    backslash = codes == ord("\\")
    # Length of the run of backslashes just before each byte.
    last_other = np.maximum.accumulate(np.where(backslash, -1, position))
    run_before = np.concatenate(([0], position[:-1] - last_other[:-1]))
    quote = (codes == ord('"')) & (run_before % 2 == 0)
    inside = (np.cumsum(quote) - quote) % 2 == 1  # after an opening quote, before its closing one
    opening = np.isin(codes, (ord("["), ord("{"))) & ~inside
    closing = np.isin(codes, (ord("]"), ord("}"))) & ~inside
    depth = np.cumsum(opening.astype(np.int64) - closing)
    deepest = np.flatnonzero(depth > limit)
    return int(deepest[0]) if deepest.size else None


def load_json(path: str | os.PathLike, data: bytes, element: str = "JSON") -> Any:
    """Parse ``data`` (UTF-8, a BOM allowed) read from ``path``; FormatError for invalid or too
    deeply nested JSON, naming ``element`` and the byte or line."""
    offset = json_depth_exceeded(data)
    if offset is not None:
        reason = f"nests deeper than {MAX_JSON_DEPTH} levels (at byte {offset}); refused before parsing"
        raise FormatError(path, element, reason)
    try:
        return json.loads(data.decode("utf-8-sig"))
    except UnicodeDecodeError as error:
        raise FormatError(path, element, f"not UTF-8 text (byte {error.start})") from None
    except json.JSONDecodeError as error:
        reason = f"invalid JSON at line {error.lineno} column {error.colno}: {error.msg}"
        raise FormatError(path, element, reason) from None
    except RecursionError:  # a deep stack of callers; the depth check above makes this rare
        raise FormatError(path, element, "nests too deeply to parse") from None


def finite_json_text(document: Any, **dumps_options: Any) -> str:
    """``json.dumps(document, **dumps_options)``; ValueError naming the JSON pointer of the first
    number that is not finite (``/nodes/3/extras/animlod/error``) instead of writing it."""
    try:
        return json.dumps(document, allow_nan=False, **dumps_options)
    except ValueError:
        pointer = _non_finite_pointer(document, "")
        if pointer is None:
            raise
        raise ValueError(f"JSON {pointer or '/'}: not a finite number (JSON has no NaN or infinity)") from None


def _non_finite_pointer(value: Any, pointer: str) -> str | None:
    """The JSON pointer of the first non-finite float within ``value``, or None."""
    if isinstance(value, float):
        return None if np.isfinite(value) else pointer
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list | tuple) else ()
    for key, item in items:
        found = _non_finite_pointer(item, f"{pointer}/{key}")
        if found is not None:
            return found
    return None
