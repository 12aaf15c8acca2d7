"""LoD GLB chains for the crowd: the procedural humanoid's (the default when none is given), or any
character's: geometry levels x motion levels from ``animlod character`` where this installation
has it, else geometry levels only from the whole-document simplifier."""

from __future__ import annotations

import os
from pathlib import Path

GEOMETRY_RATIOS = (0.5, 0.25, 0.1)


def character_chain(source: str | os.PathLike, output: str | os.PathLike) -> Path:
    """Build the LoD GLB of the skinned character ``source`` at ``output``; its path.

    With the character pipeline (``animlod character``) the chain holds geometry levels times
    motion levels; without it, the geometry levels of
    :func:`animlod.pipelines.lod_document.simplify_document` (50 %, 25 % and 10 % of the
    triangles), on which the MLoD modes draw level 0.

    Raises ValueError (or FormatError) when the pipeline refuses ``source``.
    """
    from ..cli import COMMAND_MODULES, main

    if "character" in COMMAND_MODULES:
        code = main(["character", str(source), "-o", str(output)])
        if code != 0:
            raise ValueError(f"animlod character {source}: failed with exit code {code}")
        return Path(output)
    from ..pipelines.lod_document import simplify_document

    simplify_document(source, output, GEOMETRY_RATIOS)
    return Path(output)


def procedural_chain(path: str | os.PathLike, seed: int = 0) -> Path:
    """The procedural humanoid (walk, run and jump clips) as a LoD GLB at ``path``; its path.

    The humanoid is written to ``<stem>_source.glb`` beside ``path`` and made a chain by
    :func:`character_chain`.
    """
    from .. import synth
    from ..io.gltf import write_glb

    path = Path(path)
    source = path.with_name(f"{path.stem}_source.glb")
    character = synth.humanoid(seed=seed)
    motions = [synth.humanoid_motion(character.skeleton, kind, seed=seed) for kind in synth.KINDS]
    write_glb(source, character, motions)
    return character_chain(source, path)
