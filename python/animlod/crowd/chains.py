"""LoD GLB chains for the crowd: the procedural humanoid's (the default when none is given), or any
character's, built by ``animlod character`` (geometry levels x motion levels in one GLB)."""

from __future__ import annotations

import os
import shutil
from pathlib import Path


def character_chain(source: str | os.PathLike, output: str | os.PathLike) -> Path | None:
    """Build the LoD GLB of the skinned character ``source`` at ``output`` with the character
    pipeline (``animlod character``); None when this installation has no such command.

    Raises ValueError when the pipeline refuses ``source``.
    """
    from ..cli import COMMAND_MODULES, main

    if "character" not in COMMAND_MODULES:
        return None
    code = main(["character", str(source), "-o", str(output)])
    if code != 0:
        raise ValueError(f"animlod character {source}: failed with exit code {code}")
    return Path(output)


def procedural_chain(path: str | os.PathLike, seed: int = 0) -> Path:
    """The procedural humanoid (walk, run and jump clips) as a LoD GLB at ``path``; its path.

    The humanoid is written to ``<stem>_source.glb`` beside ``path`` and run through
    :func:`character_chain`; where the character pipeline is not available, ``path`` is that
    one-level file, on which every crowd mode draws the same level.
    """
    from .. import synth
    from ..io.gltf import write_glb

    path = Path(path)
    source = path.with_name(f"{path.stem}_source.glb")
    character = synth.humanoid(seed=seed)
    motions = [synth.humanoid_motion(character.skeleton, kind, seed=seed) for kind in synth.KINDS]
    write_glb(source, character, motions)
    if character_chain(source, path) is None:
        shutil.copyfile(source, path)
    return path
