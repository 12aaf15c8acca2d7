"""The order of a sequence's frame files, from the numbers in their names."""

from __future__ import annotations

import re
from collections.abc import Iterable
from decimal import Decimal
from pathlib import Path

# A number in a frame name, with its sign where a minus follows a separator.
_NUMBER = re.compile(r"((?:(?<=[._ ])-)?\d+)")
# A name that is a prefix, a frame number (perhaps with a fraction: Houdini's "$FF" writes the
# sub-frame 1.25 as "mesh.1.25.obj") and the extension. The number starts the name or follows a
# separator: "rop_geometry1.1.25.obj" is frame 1.25 of the node rop_geometry1, not 1.1 of one.
_FRAME_NUMBER = re.compile(r"(.*?)(?<![^._ -])((?:(?<=[._ ])-)?\d+(?:\.\d+)?)(\.[^.]*)")


def natural_key(path: Path) -> tuple[list[object], str, str]:
    """Sort key that orders embedded numbers by value (frame2 < frame10) and letters regardless
    of case, the name before its extension (``v2.obj`` before ``v2.1.obj``), then by full path. A
    minus sign after a separator is the number's (``frame.-001.obj``, before frame 0, as Houdini
    numbers frames before the first); after anything else it separates (``mesh-001`` is frame 1)."""
    parts = _NUMBER.split(path.stem)  # text, number, text, ...: the numbers at odd places
    return (
        [int(part) if index % 2 else part.lower() for index, part in enumerate(parts)],
        path.suffix.lower(),
        str(path),
    )


def in_frame_order(paths: Iterable[Path]) -> list[Path]:
    """``paths`` in natural order (:func:`natural_key`), or by the value of a decimal frame number
    where every name is the same prefix, a frame number and the same extension, no two numbers
    equal as decimals, and some whole and some with a fraction (``mesh.1.obj``, ``mesh.1.25.obj``,
    ``mesh.1.5.obj``, as Houdini's ``$FF`` numbers sub-frames) or a fraction of zeros
    (``mesh.1.0.obj``, ``mesh.1.5.obj``, ``mesh.1.25.obj``): sub-frames, which natural order
    would read as 1.25, 1.5, 1. Names that all have a fraction, none of zeros (a shot and its
    frames, ``shot.1.2`` ... ``shot.1.10``), and names equal as decimals (versions ``v2.1`` ...
    ``v2.10``) keep their natural order."""
    paths = sorted(paths, key=natural_key)
    names = [_FRAME_NUMBER.fullmatch(path.name) for path in paths]
    if not all(names) or len({(name[1], name[3].lower()) for name in names}) > 1:
        return paths
    values = [Decimal(name[2]) for name in names]
    fractions = [name[2].partition(".")[2] for name in names]  # "" for a whole number
    whole_and_fractional = any(fractions) and not all(fractions)
    zero_fraction = any(fraction and not fraction.strip("0") for fraction in fractions)  # "1.0"
    if not (whole_and_fractional or zero_fraction) or len(set(values)) < len(values):
        return paths
    return [path for _, path in sorted(zip(values, paths), key=lambda pair: pair[0])]
