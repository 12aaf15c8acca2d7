"""LoD GLB chains for the crowd: the procedural humanoid's (the default when none is given), or any
character's, built by the character pipeline (geometry levels x motion levels in one GLB)."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

# The motion re-fit the chains use: damped Newton reaches SLSQP's optimum on the same objective
# over ten times faster (bench/bench_motion.py), which keeps `animlod crowd` and the demo quick.
SOLVER = "newton"


def character_chain(
    source: str | os.PathLike, output: str | os.PathLike, progress: Callable[[str], None] | None = None
) -> Path:
    """Build the LoD GLB of the skinned, animated character ``source`` at ``output``; its path.

    :func:`animlod.pipelines.character.build_character` with its default geometry ratios:
    geometry level i with motion level i along the MSFT_lod chain, and every other combination
    in ``extras.animlod_grid`` (what the GLoD and MLoD modes of the crowd draw).

    Raises FormatError (a ValueError) when ``source`` has no skinned mesh with an animation.
    """
    from ..pipelines.character import build_character

    build_character(source, output, solver=SOLVER, progress=progress)
    return Path(output)


def procedural_source(path: str | os.PathLike, seed: int = 0) -> Path:
    """The procedural humanoid (walk, run and jump clips) as a GLB of one level at ``path``, in
    about a second; its path."""
    from .. import synth
    from ..io.gltf import write_glb

    write_glb(path, *synth.humanoid_with_clips(seed))
    return Path(path)


def procedural_chain(path: str | os.PathLike, seed: int = 0, progress: Callable[[str], None] | None = None) -> Path:
    """The procedural humanoid as a LoD GLB at ``path``; its path.

    :func:`procedural_source` is written to ``<stem>_source.glb`` beside ``path`` and made a
    chain by :func:`character_chain`.
    """
    path = Path(path)
    source = procedural_source(path.with_name(f"{path.stem}_source.glb"), seed)
    return character_chain(source, path, progress)
