"""``animlod info FILE``: what a BVH, glTF, frame sequence or NPZ holds."""

from __future__ import annotations

import argparse
import glob
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..io.detect import assets_in, input_kind, is_pattern, unread_models_note
from ..io.meshseq import is_frame_name
from ..model import AnimatedMesh, Motion
from ..pipelines.humanoid_roles import naming_label

if TYPE_CHECKING:
    from ..io.gltf_document import GltfDocument


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "info",
        help="describe a BVH, glTF/GLB, OBJ/PLY sequence or NPZ file, or a .tdag or LoD manifest animlod wrote",
        description="Print what a file holds: joints, frames, fps, vertices, faces, skins, animations, morph targets.",
    )
    parser.add_argument(
        "path",
        help="a .bvh, .glb/.gltf/.vrm, .npz file, an OBJ/PLY file, a folder of frames or of assets "
        "(model files and frame folders, found as batch finds them), a glob, or animlod's own .tdag "
        "file or <name>_*lod.json manifest",
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Describe each asset; in a library an unreadable one is named with its reason and the rest
    still listed (exit code 2 if any was unreadable)."""
    written = _own_output(args.path)
    if written is not None:
        kind, lines = written
        print(f"{args.path}: {kind}")
        for line in lines:
            print(f"  {line}")
        return 0
    paths = _models(args.path)
    unreadable = 0
    for path in paths:
        kind = input_kind(path)
        try:
            lines = _describe(kind, path)
        except (ValueError, OSError) as error:
            if len(paths) == 1:
                raise
            lines, unreadable = [f"error: {error}"], unreadable + 1
        print(f"{path}: {kind}")
        for line in lines:
            print(f"  {line}")
    unread = unread_models_note(Path(args.path)) if Path(args.path).is_dir() else None
    if unread:
        print(f"note: {args.path}: left out {unread}")
    if unreadable:
        print(f"animlod info: {unreadable} of {len(paths)} assets could not be read", file=sys.stderr)
        return 2
    return 0


def _own_output(path: str) -> tuple[str, list[str]] | None:
    """(kind, lines) for a file animlod writes that is no input of its commands: a .tdag file
    or a LoD manifest; None for anything else. FormatError naming the file and element."""
    suffix = Path(path).suffix.lower()
    if suffix == ".tdag":
        from ..tdag import TemporalDag

        dag = TemporalDag.load(path)
        backs = int(dag.two_sided.sum())
        stored = ", ".join(f"{count} {name.replace('_', ' ')}" for name, count in dag.stored_counts.items())
        return "tdag", [
            f"frames: {dag.frame_count}, vertices: {dag.vertex_count}, faces: {dag.face_count}"
            + (f" ({backs} of them two-sided)" if backs else ""),
            f"collapses: {dag.collapse_count}; stored {stored}; {Path(path).stat().st_size} bytes",
        ]
    if suffix == ".json":
        from ..io.manifest import read_lod_manifest

        manifest = read_lod_manifest(path)
        lines = [f"{len(manifest['levels'])} levels of a {manifest['kind'].replace('_', ' ')} chain"]
        for index, level in enumerate(manifest["levels"]):
            sizes = ", ".join(f"{level[key]} {key}" for key in ("faces", "triangles", "joints") if key in level)
            files = ", ".join(level.get("files", []))
            lines.append(f"level {index}: {sizes + '; ' if sizes else ''}error {level['error']:.4g}: {files}")
        return "LoD manifest", lines
    return None


def _models(path: str) -> list[str]:
    """``path`` itself, or for a folder every asset in and below it that ``animlod batch`` would
    take: model files and frame folders (a folder of OBJ/PLY frames alone is one sequence); for a
    glob, its matches, as ``batch`` takes them, unless they are all OBJ/PLY frames (one sequence)."""
    if is_pattern(path):
        matches = sorted(glob.glob(path, recursive=True))
        return matches if not all(is_frame_name(Path(match).name) for match in matches) else [path]
    if not Path(path).is_dir():
        return [path]
    return [str(asset) for asset in assets_in(Path(path))] or [path]


def _describe(kind: str, path: str) -> list[str]:
    if kind == "bvh":
        from ..io.bvh import read_bvh_with_layout

        motion, layout = read_bvh_with_layout(path)
        lines = _motion_lines(motion)
        if len(layout.roots) > 1:  # read below a joint of their own, which the file does not have
            lines.insert(1, f"ROOTs: {', '.join(layout.roots)}, below {motion.skeleton.names[0]!r} at the origin")
        return lines
    if kind == "npz":
        from ..io.npz import read_npz

        return _animated_lines(read_npz(path))
    if kind == "sequence":
        from ..io.meshseq import level_format, normals_fit, read_textured_sequence, sequence_paths

        mesh, texture, shading, colours, materials, points = read_textured_sequence(path)
        lines = _animated_lines(mesh)
        if points is not None:  # the mesh has a vertex per position and texture coordinate or material
            positions = np.unique(points).size  # an OBJ's; a PLY's vertices have their own
            counts = f"{positions}, {mesh.vertex_count}" if positions != mesh.vertex_count else f"{positions}"
            textured = " with their texture coordinates" if texture is not None else ""
            lines[0] = f"vertices: {counts}{textured}, triangles: {mesh.face_count}"
        paths = sequence_paths(path)
        if shading is not None:
            kind = {0.0: "flat", np.pi: "smooth"}.get(shading.crease, "smooth with hard edges")
            inward = ", pointing against the faces' winding" if shading.inward else ""
            if normals_fit(level_format(paths), shading):
                fate = "rebuilt on each level"
            else:
                fate = "not written to the levels (PLY files: one normal per vertex)"
            lines[0] += f"; normals: {kind}{inward}, {fate}"
        if colours is not None:
            changing = ", each frame's own" if len(colours.values) > 1 else ""
            lines[0] += f"; vertex colours: {colours.layout()}{changing}"
        if materials is not None:
            libraries = f" from {', '.join(materials.libraries)}" if materials.libraries else ""
            lines[0] += f"; materials: {', '.join(materials.names)}{libraries}"
        names = [frame.name for frame in paths]
        if len(names) > 1:  # the order the frames are read in: a stray file shows at an end
            lines[-1] += f", {names[0]} .. {names[-1]}"
        return lines
    return _document_lines(path)


def _document_lines(path: str) -> list[str]:
    """Every drawn (mesh, skin) pair with its primitives, every animation, and LoD chains."""
    from ..io.gltf_document import GltfDocument
    from ..io.gltf_drawable import mesh_label, points_and_lines_meshes, read_drawables
    from ..io.gltf_lod import lod_coverages, lod_ids

    doc = GltfDocument(path)
    drawables = read_drawables(doc)
    lines = [
        f"{len(doc.json.get('nodes', []))} nodes, {len(doc.json.get('meshes', []))} meshes, "
        f"{len(doc.json.get('materials', []))} materials, {len(doc.json.get('textures', []))} textures, "
        f"{len(doc.json.get('skins', []))} skins, {len(doc.json.get('animations', []))} animations"
        + (f", sampled at {doc.sample_rate():g} fps" if doc.json.get("animations") else "")
    ]
    materials = doc.json.get("materials", [])
    for drawable in drawables:
        geometry = drawable.geometry
        lines.append(
            f"{drawable.label}, drawn by nodes {drawable.nodes}: {len(geometry.positions)} vertices, "
            f"{len(geometry.faces)} triangles, {len(drawable.clips)} clips"
        )
        for primitive in geometry.primitives:
            source = doc.json["meshes"][drawable.mesh_index]["primitives"][primitive.index]
            material = source.get("material")
            name = materials[material].get("name", "") if material is not None and material < len(materials) else ""
            lines.append(
                f"  primitive {primitive.index}: {primitive.vertex_count} vertices, {len(primitive.faces)} triangles, "
                f"{', '.join(primitive.attributes)}"
                + (f", {len(primitive.targets)} morph targets" if primitive.targets else "")
                + ("" if material is None else f", material {material} {name!r}")
            )
        if geometry.other_primitives:
            lines.append(f"  primitives {geometry.other_primitives}: points or lines")
        if drawable.skinned is not None:
            skeleton = drawable.skinned.skeleton
            naming = naming_label(skeleton.names)
            lines.append(
                f"  skin: {skeleton.joint_count} joints, {drawable.skinned.joints.shape[1]} influences per vertex"
                + (f", {naming}" if naming else "")
            )
            if drawable.weight_breaks.vertices:  # what a LoD GLB's level 0 rewrites
                lines.append(f"  {drawable.weight_breaks.describe()}; read normalised")
    for mesh, nodes in points_and_lines_meshes(doc).items():
        lines.append(f"{mesh_label(doc, mesh)}, drawn by nodes {nodes}: points or lines only")
    if doc.gltf.animations and not doc.gltf.skins:
        lines += _node_tree_lines(doc)
    for index, animation in enumerate(doc.gltf.animations or []):
        doc.animation_frame_times(index, 30.0)  # refuses a clip too long to sample
        extras = animation.extras.get("animlod") if isinstance(animation.extras, dict) else None
        level = (
            f", motion level {extras['motion_level']}" if isinstance(extras, dict) and "motion_level" in extras else ""
        )
        lines.append(
            f"{doc.animation_label(index)}: {len(animation.channels or [])} channels, "
            f"{doc.animation_duration(index):.2f} s{level}"
        )
    if idle := doc.idle_weight_channels_note():
        lines.append(idle)
    for index in range(len(doc.json.get("nodes", []))):
        ids = lod_ids(doc, index)
        if ids is not None:
            coverages = lod_coverages(doc, index, ids)
            shown = "none" if coverages[0] is None else ", ".join(f"{coverage:.4g}" for coverage in coverages)
            lines.append(f"LoD chain on {doc.node_label(index)}: levels at nodes {[index, *ids]}, coverage {shown}")
    return lines


def _node_tree_lines(doc: GltfDocument) -> list[str]:
    """The skeleton ``motion`` reads from a file without skins, its animated node tree, if any
    (``motion`` says why there is none)."""
    from ..io.errors import FormatError
    from ..io.gltf_skin import SkinRig

    try:
        rig = SkinRig(doc, None)
    except FormatError:
        return []
    skeleton = rig.skeleton
    line = f"no skin; animated node tree: {skeleton.joint_count} joints, root {skeleton.names[0]!r}"
    return [line + (f"; other animated trees: {', '.join(rig.trees_left_out)}" if rig.trees_left_out else "")]


def _motion_lines(motion: Motion) -> list[str]:
    skeleton = motion.skeleton
    end_sites = int(np.count_nonzero(skeleton.end_sites))
    naming = naming_label([name for name, end in zip(skeleton.names, skeleton.end_sites) if not end])
    return [
        f"joints: {skeleton.joint_count - end_sites} (+{end_sites} end sites), root {skeleton.names[0]!r}"
        + (f", {naming}" if naming else ""),
        f"frames: {motion.frame_count} at {motion.fps:g} fps ({motion.duration:.2f} s)",
    ]


def _animated_lines(mesh: AnimatedMesh) -> list[str]:
    fps = f" at {mesh.fps:g} fps" if mesh.fps else ""
    return [f"vertices: {mesh.vertex_count}, triangles: {mesh.face_count}", f"frames: {mesh.frame_count}{fps}"]
