"""What a glTF document draws, as animlod simplifies it: one :class:`Drawable` per (mesh, skin)
pair used by a node, with every animation that moves it.

A drawable holds its mesh's triangle primitives (node-local, :mod:`.gltf_mesh`), the rest
transform that places them in the world, and, when skinned, the world-space
:class:`~animlod.model.SkinnedMesh` of :mod:`.gltf_read` with its skin as an animlod skeleton.
Each animation that moves the skin or the mesh's morph weights becomes a :class:`Clip`, so that
the drawable's posed frames can be produced for any clip: skinning after morphing, as glTF does.
"""

from __future__ import annotations

import dataclasses
import os
import warnings
from dataclasses import dataclass, field

import numpy as np
import pygltflib

from ..model import Motion, SkinnedMesh, morphed
from .gltf_document import GltfDocument
from .gltf_mesh import SINGULAR_DETERMINANT, TRIANGLES, MeshGeometry, read_mesh_geometry, transform_points
from .gltf_read import from_first_key, morph_weight_tracks, node_weights, skinned_mesh_of_node
from .gltf_skin import SkinRig
from .stored_weights import UnitSumBreaks, stored_unit_sum_breaks

_POINTS_AND_LINES = range(4)  # primitive modes POINTS, LINES, LINE_LOOP, LINE_STRIP


@dataclass
class Clip:
    """One animation as it moves a drawable.

    Attributes
    ----------
    index : the animation's index in the document.
    name : its name ("" when unnamed).
    frame_count : T, samples at the drawable's fps from ``start_frame``.
    motion : the skeleton's motion (skinned drawables; the rest pose held when the animation
        moves only morph weights), or None.
    morph_weights : (T, N) morph weights, or None when the animation does not drive them.
    start_frame : the frame at or just before the animation's first key
        (GltfDocument.animation_start_frame), where the clip's frames start: frame k is at
        ``(start_frame + k) / fps``. A clip keyed late on a timeline (Blender keeps an action's
        frame numbers) holds its first key's pose before it; those frames are left out.
    """

    index: int
    name: str
    frame_count: int
    motion: Motion | None = None
    morph_weights: np.ndarray | None = None
    start_frame: int = 0


@dataclass
class Drawable:
    """A (mesh, skin) pair of a document and what animates it.

    Attributes
    ----------
    mesh_index, skin_index : the glTF mesh and skin (None when unskinned).
    nodes : the nodes that draw this pair (instances).
    label : "mesh 0 'Body' with skin 0" for messages.
    geometry : the triangle primitives, node-local.
    world : (4, 4) rest world transform of the first node, less ``placement``; positions below are
        in world space shifted by ``-placement``.
    placement : (3,) the first node's world position for an unskinned mesh (zero when skinned:
        a skin places it). Taken out of ``world`` so that float32 positions keep the precision of
        the stored ones: a mesh placed a million units out had its world positions, and the levels
        written back from them, on float32's 0.0625-unit grid there.
    skinned : the world-space skinned mesh (joints in skeleton order), or None.
    rig : the skin as a skeleton, or None.
    clips : the animations that move this drawable.
    default_weights : (N,) morph weights the first node shows where no animation drives them
        (glTF's node or mesh ``weights``), or None without morph targets.
    weight_breaks : the vertices whose stored skin weights break glTF's unit sum
        (:func:`~animlod.io.stored_weights.stored_unit_sum_breaks`, as ``animlod info`` reports
        them and level 0 of a LoD GLB rewrites them).
    """

    mesh_index: int
    skin_index: int | None
    nodes: list[int]
    label: str
    geometry: MeshGeometry
    world: np.ndarray
    placement: np.ndarray = field(default_factory=lambda: np.zeros(3))
    skinned: SkinnedMesh | None = None
    rig: SkinRig | None = None
    clips: list[Clip] = field(default_factory=list)
    default_weights: np.ndarray | None = None
    weight_breaks: UnitSumBreaks = UnitSumBreaks(0, 0.0)

    @property
    def morph_targets(self) -> np.ndarray | None:
        """(N, V, 3) float32 morph position deltas in the space of :meth:`bind_positions`, or None:
        the stored deltas themselves (no copy) under a node without rotation or scale."""
        targets = self.geometry.targets
        if targets is None or np.array_equal(self.world[:3, :3], np.eye(3)):
            return targets
        return (targets @ self.world[:3, :3].T).astype(np.float32)

    def bind_positions(self) -> np.ndarray:
        """(V, 3) float32 bind shape: POSITION under the node's rest world transform (morph
        weights 0). The space of ``skinned.rest_positions`` and of the vertices a writer stores."""
        return transform_points(self.world, self.geometry.positions).astype(np.float32)

    def rest_positions(self) -> np.ndarray:
        """(V, 3) float32 world positions a viewer shows with no animation playing (morph targets
        at ``default_weights``): a skinned mesh posed by its skeleton's rest pose
        (SkinnedMesh.rest_pose, which can differ from the bind shape in pose and scale: Xbot.glb's
        is 100x), the bind shape otherwise. Sizes and errors are taken on this one."""
        if self.skinned is not None:
            return self.skinned.rest_pose()
        return morphed(self.bind_positions(), self.morph_targets, self.default_weights)

    def rest_morph_targets(self) -> np.ndarray | None:
        """(N, V, 3) morph deltas as they move :meth:`rest_positions`, or None."""
        return self.morph_targets if self.skinned is None else self.skinned.rest_pose_morph_targets()

    def clip_frames(self, clip: Clip, frames: np.ndarray | None = None) -> np.ndarray:
        """(T', V, 3) world positions of the drawable in the given frames of ``clip`` (all when None)."""
        frames = np.arange(clip.frame_count) if frames is None else np.asarray(frames)
        weights = None if clip.morph_weights is None else clip.morph_weights[frames]
        if self.skinned is not None:
            motion = clip.motion.take_frames(frames)
            return self.skinned.bake(motion, weights).frames
        weights = self.default_weights if weights is None else weights
        return morphed(self.bind_positions(), self.morph_targets, weights, len(frames))


def read_drawables(doc: GltfDocument, fps: float | None = None) -> list[Drawable]:
    """Every (mesh, skin) pair drawn by a node of ``doc``, in order of first use, with its clips
    sampled at ``fps`` (None: at the rate of their keys, :meth:`GltfDocument.sample_rate`). Nodes
    that are lower levels of an MSFT_lod chain are alternates of their base node, not drawables
    of their own. Raises FormatError naming the element for anything it cannot read."""
    fps = doc.sample_rate(fps)
    alternates = doc.alternate_nodes()
    pairs: dict[tuple[int, int | None], list[int]] = {}
    for index, node in enumerate(doc.gltf.nodes or []):
        if node.mesh is not None and index not in alternates:
            mesh = doc.item("meshes", node.mesh, doc.node_label(index))
            if node.skin is not None:
                doc.item("skins", node.skin, doc.node_label(index))
            if not points_and_lines_only(mesh):
                pairs.setdefault((node.mesh, node.skin), []).append(index)
    rigs: dict[int, SkinRig] = {}
    motions: dict[tuple[int, int], Motion | None] = {}  # (skin, animation): sampled once per skin
    drawables = []
    for (mesh_index, skin_index), nodes in pairs.items():
        label = mesh_label(doc, mesh_index) + ("" if skin_index is None else f" with skin {skin_index}")
        geometry = read_mesh_geometry(doc, mesh_index, skinned=skin_index is not None)
        nodes, world = _placed_first(doc, nodes)
        placement = np.zeros(3)
        if skin_index is None:
            placement, world[:3, 3] = world[:3, 3].copy(), 0.0
        drawable = Drawable(mesh_index, skin_index, nodes, label, geometry, world, placement)
        if geometry.targets is not None:
            drawable.default_weights = node_weights(doc, nodes[0], geometry.default_weights)
        if skin_index is not None:
            if skin_index not in rigs:
                rigs[skin_index] = SkinRig(doc, skin_index)
            drawable.rig = rigs[skin_index]
            drawable.skinned = skinned_mesh_of_node(doc, nodes[0], drawable.rig, geometry, world)
            drawable.weight_breaks = stored_unit_sum_breaks(doc, mesh_index)
        drawable.clips = _clips(doc, drawable, fps, motions)
        drawables.append(drawable)
    return drawables


def read_document_drawables(path: str | os.PathLike, fps: float | None = None) -> tuple[GltfDocument, list[Drawable]]:
    """The parsed document at ``path`` and its drawables."""
    doc = GltfDocument(path)
    return doc, read_drawables(doc, fps)


def on_rig(doc: GltfDocument, drawable: Drawable, rig: SkinRig, fps: float = 30.0) -> Drawable:
    """``drawable`` (skinned) read again on ``rig``, a rig of its skin with extra joints
    (SkinRig): its skinned mesh over that skeleton and its clips sampled on it."""
    with warnings.catch_warnings():  # its weights warned when it was first read
        warnings.simplefilter("ignore")
        skinned = skinned_mesh_of_node(doc, drawable.nodes[0], rig, drawable.geometry, drawable.world)
    moved = dataclasses.replace(drawable, rig=rig, skinned=skinned)
    moved.clips = _clips(doc, moved, fps, {})
    return moved


def mesh_label(doc: GltfDocument, mesh_index: int) -> str:
    """``mesh 0 'Body'`` (``mesh 0`` when unnamed), for messages."""
    name = doc.gltf.meshes[mesh_index].name
    return f"mesh {mesh_index}" + (f" {name!r}" if name else "")


def points_and_lines_only(mesh: pygltflib.Mesh) -> bool:
    """Whether every primitive of ``mesh`` draws points or lines (a point cloud, a wireframe
    helper): there is nothing to simplify, and the mesh stays as it is. A mesh without
    primitives, or with one of an unknown mode, is read_mesh_geometry's to refuse."""
    modes = [TRIANGLES if primitive.mode is None else primitive.mode for primitive in mesh.primitives or []]
    return bool(modes) and all(mode in _POINTS_AND_LINES for mode in modes)


def points_and_lines_meshes(doc: GltfDocument) -> dict[int, list[int]]:
    """The meshes of points and lines only (:func:`points_and_lines_only`) that nodes draw: mesh
    index -> the nodes, in node order."""
    drawn: dict[int, list[int]] = {}
    for index, node in enumerate(doc.gltf.nodes or []):
        if node.mesh is not None and points_and_lines_only(doc.item("meshes", node.mesh, doc.node_label(index))):
            drawn.setdefault(node.mesh, []).append(index)
    return drawn


def _placed_first(doc: GltfDocument, nodes: list[int]) -> tuple[list[int], np.ndarray]:
    """``nodes`` with the first whose rest world transform is invertible moved to the front, and
    that transform: the space the drawable is read, simplified and measured in. A node at zero
    scale is valid glTF (an instance hidden at rest, a prop that pops in by an animated scale)
    and draws nothing at rest; where every node is at zero scale, the mesh is taken in its own
    space (identity), which a skinned mesh shows anyway: skinning ignores its node's transform."""
    for position, node in enumerate(nodes):
        world = doc.rest_world_matrix(node)
        if abs(np.linalg.det(world[:3, :3])) >= SINGULAR_DETERMINANT:
            return [node, *nodes[:position], *nodes[position + 1 :]], world
    return nodes, np.eye(4)


def _clips(
    doc: GltfDocument, drawable: Drawable, fps: float, motions: dict[tuple[int, int], Motion | None]
) -> list[Clip]:
    """Clips of every animation that moves the drawable's skin or its first node's morph weights;
    ``motions`` holds each (skin, animation) sampled so far, shared by the meshes of one skin."""
    targets = drawable.geometry.targets
    tracks = {} if targets is None else dict(morph_weight_tracks(doc, drawable.nodes[0], len(targets), fps))
    clips = []
    for index, animation in enumerate(doc.gltf.animations or []):
        motion = None
        if drawable.rig is not None:
            key = (drawable.skin_index, index)
            if key not in motions:
                motions[key] = drawable.rig.motion(doc, index, fps)
            motion = motions[key]
        weights = tracks.get(index)
        if motion is None and weights is None:
            continue
        motion, weights, start = from_first_key(doc, index, fps, motion, weights)
        frame_count = motion.frame_count if motion is not None else len(weights)
        if motion is None and drawable.rig is not None:
            motion = drawable.rig.skeleton.rest_motion(frame_count, fps)
        clips.append(Clip(index, animation.name or "", frame_count, motion, weights, start))
    return clips
