"""Minimum Perceptible Actions, expressions and MPA animations (seeds/004, Section 3.2.1, Figures 3-4).

The animation system has three levels of control: an expression ("smile") is a weighted set of
MPAs; an MPA ("raise_eyebrows") is a set of control-point displacements over one or more
regions, scaled by an intensity; the deformation level moves the regions' vertices by rational
FFD. An animation is MPA intensities over time.

Shapes: ``N`` MPAs, ``T`` animation frames, ``(l, m, n)`` control points per axis.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass
class Mpa:
    """A Minimum Perceptible Action.

    Attributes
    ----------
    name : e.g. "raise_eyebrows".
    displacements : region name -> (l, m, n, 3) float64 control-point displacements at
        intensity 1, asset units, for that region's lattice (3x3x3 by default).
    """

    name: str
    displacements: dict[str, np.ndarray]

    @property
    def regions(self) -> list[str]:
        return list(self.displacements)


@dataclass
class Expression:
    """A named, weighted set of MPAs (Figure 4: the MPAs of "smile").

    Attributes
    ----------
    name : e.g. "smile".
    intensities : MPA name -> intensity (1 is the MPA as defined; negative reverses it).
    """

    name: str
    intensities: dict[str, float]


@dataclass
class MpaAnimation:
    """MPA intensities over time.

    Attributes
    ----------
    mpa_names : N names, the columns of ``intensities``.
    intensities : (T, N) float64.
    fps : frames per second.
    """

    mpa_names: list[str]
    intensities: np.ndarray
    fps: float

    def __post_init__(self) -> None:
        self.intensities = np.asarray(self.intensities, dtype=np.float64)
        if self.intensities.ndim != 2 or self.intensities.shape[1] != len(self.mpa_names):
            raise ValueError(
                f"MPA animation: intensities of shape {self.intensities.shape}, expected (T, {len(self.mpa_names)})"
            )
        if not np.all(np.isfinite(self.intensities)):
            frame = int(np.argwhere(~np.isfinite(self.intensities))[0, 0])
            raise ValueError(f"MPA animation: frame {frame} has a non-finite intensity")
        if not (np.isfinite(self.fps) and self.fps > 0):
            raise ValueError(f"MPA animation: fps must be positive, got {self.fps}")

    @property
    def frame_count(self) -> int:
        return int(self.intensities.shape[0])


def expression_intensities(expression: Expression, mpa_names: Sequence[str]) -> np.ndarray:
    """(N,) intensities of ``expression`` in the order of ``mpa_names``; ValueError naming the
    expression and the MPA if it uses one that is not in the list."""
    result = np.zeros(len(mpa_names))
    for name, value in expression.intensities.items():
        if name not in mpa_names:
            raise ValueError(f"expression {expression.name!r}: no MPA named {name!r}")
        result[list(mpa_names).index(name)] = value
    return result


def expression_sequence(
    expressions: Sequence[Expression], mpa_names: Sequence[str], seconds_each: float = 1.0, fps: float = 30.0
) -> MpaAnimation:
    """An animation that plays every expression in turn: each rises from neutral to full
    intensity and back (a smooth bump over ``seconds_each``), so a frame holds at most one."""
    if not expressions:
        raise ValueError("expression sequence: no expressions")
    per = max(3, round(seconds_each * fps))
    phase = np.arange(per) / (per - 1)
    envelope = 0.5 - 0.5 * np.cos(2.0 * np.pi * phase)  # sin^2(pi x): 0 -> 1 -> 0, smooth, exact 0 at the ends
    rows = [envelope[:, None] * expression_intensities(expression, mpa_names)[None] for expression in expressions]
    return MpaAnimation(list(mpa_names), np.concatenate(rows), fps)
