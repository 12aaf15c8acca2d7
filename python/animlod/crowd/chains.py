"""The chain the crowd draws when none is given: the procedural humanoid's LoD GLB."""

from __future__ import annotations

import os
from pathlib import Path


def procedural_chain(path: str | os.PathLike, seed: int = 0) -> Path:
    """Write the procedural humanoid (walk, run and jump clips) as a GLB at ``path``; its path.

    Until the character pipeline (geometry x motion levels in one LoD GLB) is available this
    is a one-level chain, on which every mode draws the same level.
    """
    from .. import synth
    from ..io.gltf import write_glb

    character = synth.humanoid(seed=seed)
    motions = [synth.humanoid_motion(character.skeleton, kind, seed=seed) for kind in synth.KINDS]
    write_glb(path, character, motions)
    return Path(path)
