"""``animlod info FILE``: what a BVH, glTF, frame sequence or NPZ holds."""

from __future__ import annotations

import argparse

import numpy as np

from ..io.detect import input_kind
from ..model import AnimatedMesh, Motion, SkinnedMesh


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "info",
        help="describe a BVH, glTF/GLB, OBJ/PLY sequence or NPZ file",
        description="Print what a file holds: joints, frames, fps, vertices, faces, skins, animations, morph targets.",
    )
    parser.add_argument("path", help="a .bvh, .glb/.gltf, .npz file, an OBJ/PLY file, a folder of frames or a glob")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    kind = input_kind(args.path)
    print(f"{args.path}: {kind}")
    for line in _describe(kind, args.path):
        print(f"  {line}")
    return 0


def _describe(kind: str, path: str) -> list[str]:
    if kind == "bvh":
        from ..io.bvh import read_bvh

        return _motion_lines(read_bvh(path))
    if kind == "npz":
        from ..io.npz import read_npz

        return _animated_lines(read_npz(path))
    if kind == "sequence":
        from ..io.meshseq import read_sequence

        return _animated_lines(read_sequence(path))
    from ..io.gltf import read_gltf

    scene = read_gltf(path)
    lines: list[str] = []
    for index, skinned in enumerate(scene.skinned_meshes):
        lines.append(f"skinned mesh {index}:")
        lines += [f"  {line}" for line in _skinned_lines(skinned)]
    for index, motion in enumerate(scene.motions):
        lines.append(f"animation {index} {motion.name!r}:")
        lines += [f"  {line}" for line in _motion_lines(motion)]
    for index, mesh in enumerate(scene.morph_animations):
        lines.append(f"morph animation {index}:")
        lines += [f"  {line}" for line in _animated_lines(mesh)]
    for index, mesh in enumerate(scene.static_meshes):
        lines.append(f"static mesh {index}: {mesh.vertex_count} vertices, {mesh.face_count} triangles")
    return lines or ["no meshes, skins or animations"]


def _motion_lines(motion: Motion) -> list[str]:
    skeleton = motion.skeleton
    end_sites = int(np.count_nonzero(skeleton.end_sites))
    return [
        f"joints: {skeleton.joint_count - end_sites} (+{end_sites} end sites), root {skeleton.names[0]!r}",
        f"frames: {motion.frame_count} at {motion.fps:g} fps ({motion.duration:.2f} s)",
    ]


def _animated_lines(mesh: AnimatedMesh) -> list[str]:
    fps = f" at {mesh.fps:g} fps" if mesh.fps else ""
    return [f"vertices: {mesh.vertex_count}, triangles: {mesh.face_count}", f"frames: {mesh.frame_count}{fps}"]


def _skinned_lines(skinned: SkinnedMesh) -> list[str]:
    lines = [
        f"vertices: {skinned.vertex_count}, triangles: {skinned.face_count}",
        f"skin: {skinned.skeleton.joint_count} joints, {skinned.joints.shape[1]} influences per vertex",
        f"uvs: {'yes' if skinned.uvs is not None else 'no'}, normals: {'yes' if skinned.normals is not None else 'no'}",
    ]
    if skinned.morph_targets is not None:
        lines.append(f"morph targets: {len(skinned.morph_targets)}")
    return lines
