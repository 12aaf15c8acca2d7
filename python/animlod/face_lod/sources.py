"""Faces from files: a glTF mesh with morph targets, or a folder of poses (neutral + expressions).

Both become a :class:`~animlod.face_lod.blendshape.BlendshapeFace`. A glTF face is the first
node (in node order) whose mesh has morph targets, placed by its node's world transform; its
animation is every clip that drives the node's morph weights, sampled at ``fps`` and played one
after the other (a file without such a clip gets each target raised and lowered in turn). A pose
folder's neutral face is the file named ``neutral``, else the one named ``*reference*`` or
``*neutral*``, else the first in natural order; every other file is one expression target.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ..io.errors import FormatError
from .blendshape import BlendshapeFace, one_at_a_time


def read_gltf_face(path: str | os.PathLike, fps: float = 30.0, frames_each: int = 15) -> BlendshapeFace:
    """The first morph-target mesh of a .glb/.gltf file as a blendshape face.

    Raises FormatError naming the file and element when no mesh has morph targets or the file
    is malformed (a target whose vertex count differs from its primitive's is reported by the
    glTF reader, naming the primitive and the target).
    """
    from ..io.gltf_document import GltfDocument
    from ..io.gltf_keyframes import sample_keyframes
    from ..io.gltf_mesh import read_mesh_geometry, transform_points

    doc = GltfDocument(path)
    for node_index, node in enumerate(doc.gltf.nodes or []):
        if node.mesh is None:
            continue
        mesh = doc.item("meshes", node.mesh, doc.node_label(node_index))
        if not any(primitive.targets for primitive in mesh.primitives or []):
            continue
        geometry = read_mesh_geometry(doc, node.mesh, skinned=False)
        world = doc.rest_world_matrix(node_index)
        faces = geometry.faces[:, ::-1] if np.linalg.det(world[:3, :3]) < 0.0 else geometry.faces
        count = len(geometry.targets)
        tracks = []
        for a, animation in enumerate(doc.gltf.animations or []):
            for c, channel in enumerate(animation.channels or []):
                target = channel.target
                if target is None or target.node != node_index or target.path != "weights":
                    continue
                element = f"{doc.animation_label(a)} channel {c}"
                times, values, interpolation = doc.sampler_keys(a, channel.sampler, count, element)
                tracks.append(sample_keyframes(times, values, interpolation, doc.animation_frame_times(a, fps)))
        weights = np.concatenate(tracks) if tracks else one_at_a_time(count, frames_each)
        names = geometry.target_names or [f"target_{index}" for index in range(count)]
        try:
            return BlendshapeFace(
                neutral=transform_points(world, geometry.positions),
                faces=faces,
                targets=geometry.targets @ world[:3, :3].T,
                names=names,
                weights=weights,
                fps=fps,
                uvs=geometry.uvs,
            )
        except ValueError as error:
            raise doc.fail(f"mesh {node.mesh}", str(error)) from None
    raise doc.fail("meshes", "no mesh has morph targets, so there is no blendshape face to simplify")


def _natural_key(path: Path) -> list[object]:
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


def pose_files(folder: str | os.PathLike, neutral: str | None = None) -> list[Path]:
    """The OBJ/PLY files of a pose folder, the neutral face first (see the module notes)."""
    from ..io.meshseq import MESH_SUFFIXES

    folder = Path(folder)
    files = sorted((p for p in folder.iterdir() if p.suffix.lower() in MESH_SUFFIXES), key=_natural_key)
    if len(files) < 2:
        reason = f"holds {len(files)} OBJ/PLY file(s); a neutral face and at least one expression are needed"
        raise FormatError(str(folder), "folder", reason)
    if neutral is not None:
        chosen = [p for p in files if p.name == neutral]
        if not chosen:
            raise FormatError(str(folder), "neutral", f"no file named {neutral!r} in the folder")
    else:
        chosen = [p for p in files if re.search("reference|neutral", p.name, re.IGNORECASE)] or files[:1]
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
