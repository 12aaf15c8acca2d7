"""The core's options as Python classes, and the one way the wrappers take them.

Each ``*Options`` class is the C++ struct of the same name bound field by field (defaults,
docstrings from the header comments; see ``help(animlod.AqemOptions)``). A wrapper such as
:func:`animlod.simplify_animated` takes an ``options`` object, keyword arguments naming its
fields, or both (the keywords change a copy of the object).

List fields (``AqemOptions.target_ratios``, ``target_face_counts``, ``frame_subset``) read as
tuples (the binding's doing). The object holds a C++ vector, so what reading such a field hands
out is a copy: a list there took ``opts.frame_subset.append(3)`` and changed nothing; a tuple has
no ``append`` and says so at once. Change the field by assigning a sequence
(``opts.frame_subset = [0, 3]``, ``opts.target_ratios += (0.25,)``), through ``update`` or by
keyword, and compare it with a tuple (a list never equals one: ``opts.target_ratios == (0.5,)``).
"""

from __future__ import annotations

import copy
from typing import TypeVar

from ._core import (
    AnimationRateOptions,
    AqemOptions,
    FfdFitOptions,
    LodSelectorOptions,
    MotionFeatureOptions,
    MotionRefitOptions,
    PlayerOptions,
    TdagOptions,
)

__all__ = [
    "AnimationRateOptions",
    "AqemOptions",
    "FfdFitOptions",
    "LodSelectorOptions",
    "MotionFeatureOptions",
    "MotionRefitOptions",
    "PlayerOptions",
    "TdagOptions",
    "resolve_options",
]

Options = TypeVar("Options")


def resolve_options(options_type: type[Options], options: Options | None, fields: dict[str, object]) -> Options:
    """``options`` (the struct's defaults when None) with ``fields`` set, as a new object.

    Raises ValueError naming the class for an object of another type, an unknown field or a
    value the field cannot hold.
    """
    if options is None:
        resolved = options_type()
    elif isinstance(options, options_type):
        resolved = copy.copy(options)
    else:
        raise ValueError(f"options: expected {options_type.__name__}, got {type(options).__name__}")
    resolved.update(**fields)
    return resolved
