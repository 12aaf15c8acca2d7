"""Faces from a folder of poses (neutral + expressions) as a blendshape face (glTF faces are
read with their document, :func:`animlod.face_lod.lod_glb.read_gltf_face`).

A pose folder's neutral face is the file named ``neutral``, else the one named
``*reference*`` or ``*neutral*``, else the one named after the folder (``face-poses/face-poses.obj``
beside ``1.obj``, ``4.obj``..., as scanned pose sets ship their rest mesh), else the first in
natural order; every other file is one expression target, and the animation raises and lowers
each in turn.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from ..io.errors import FormatError
from .blendshape import BlendshapeFace, one_at_a_time


def pose_files(folder: str | os.PathLike, neutral: str | None = None) -> list[Path]:
    """The OBJ/PLY files of a pose folder, the neutral face first (see the module notes)."""
    from ..io.meshseq import frame_files

    files = frame_files(folder)
    if len(files) < 2:
        reason = f"holds {len(files)} OBJ/PLY file(s); a neutral face and at least one expression are needed"
        raise FormatError(str(folder), "folder", reason)
    if neutral is not None:
        chosen = [p for p in files if p.name == neutral]
        if not chosen:
            raise FormatError(str(folder), "neutral", f"no file named {neutral!r} in the folder")
    else:
        folder_name = Path(folder).resolve().name.lower()
        chosen = (
            [p for p in files if re.search("reference|neutral", p.name, re.IGNORECASE)]
            or [p for p in files if p.stem.lower() == folder_name]
            or files[:1]
        )
    return [chosen[0]] + [p for p in files if p != chosen[0]]


def read_pose_face(folder: str | os.PathLike, neutral: str | None = None, frames_each: int = 15) -> BlendshapeFace:
    """A folder of OBJ/PLY poses with one connectivity as a blendshape face: one target per
    expression (its positions minus the neutral's), animated one target at a time."""
    from ..io.meshseq import read_sequence

    files = pose_files(folder, neutral)
    sequence = read_sequence(files)
    return BlendshapeFace(
        neutral=sequence.frames[0], faces=sequence.faces, targets=sequence.frames[1:] - sequence.frames[0],
        names=[p.stem for p in files[1:]], weights=one_at_a_time(len(files) - 1, frames_each), fps=30.0,
    )  # fmt: skip
