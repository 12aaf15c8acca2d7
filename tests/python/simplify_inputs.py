"""Small procedural inputs for the simplification tests (numpy only, deterministic)."""

from __future__ import annotations

import numpy as np

from animlod.model import AnimatedMesh, Motion, Skeleton, SkinnedMesh


def tube(
    rings: int = 16, segments: int = 12, length: float = 2.0, radius: float = 0.2
) -> tuple[np.ndarray, np.ndarray]:
    """Open tube along x in [-length/2, length/2]: positions (rings*segments, 3), faces facing out."""
    x = np.linspace(-length / 2, length / 2, rings)
    phi = 2 * np.pi * np.arange(segments) / segments
    positions = np.stack(
        np.broadcast_arrays(x[:, None], radius * np.cos(phi)[None], radius * np.sin(phi)[None]), axis=-1
    ).reshape(-1, 3)
    ring, seg = np.meshgrid(np.arange(rings - 1), np.arange(segments), indexing="ij")
    a = ring * segments + seg
    b = ring * segments + (seg + 1) % segments
    c, d = a + segments, b + segments
    faces = np.concatenate([np.stack([a, d, c], -1).reshape(-1, 3), np.stack([a, b, d], -1).reshape(-1, 3)])
    return positions.astype(np.float32), faces.astype(np.int32)


def bending_tube(frames: int = 6, bend: float = 1.2, rings: int = 16, segments: int = 12) -> AnimatedMesh:
    """The tube bending at x = 0 like an elbow: frame f turns the x > 0 half by f * bend / (F - 1)."""
    positions, faces = tube(rings, segments)
    blend = np.clip(positions[:, 0] / 0.2 + 0.5, 0.0, 1.0)
    angles = np.linspace(0.0, bend, frames)[:, None] * blend[None]
    cos, sin = np.cos(angles), np.sin(angles)
    x, y, z = positions.T
    stacked = np.stack([cos * x - sin * y, sin * x + cos * y, np.broadcast_to(z, angles.shape)], axis=-1)
    return AnimatedMesh(faces, stacked.astype(np.float32))


def ellipsoid(frames: int = 4, rings: int = 14, segments: int = 20) -> AnimatedMesh:
    """Closed latitude-longitude sphere stretching along x over the frames, faces facing out."""
    theta = np.pi * np.arange(1, rings) / rings
    phi = 2 * np.pi * np.arange(segments) / segments
    body = np.stack(
        [
            np.outer(np.sin(theta), np.cos(phi)),
            np.outer(np.sin(theta), np.sin(phi)),
            np.outer(np.cos(theta), np.ones_like(phi)),
        ],
        axis=-1,
    ).reshape(-1, 3)
    unit = np.concatenate([[[0, 0, 1]], body, [[0, 0, -1]]])
    south = len(unit) - 1
    ring, seg = np.meshgrid(np.arange(rings - 2), np.arange(segments), indexing="ij")
    a = 1 + ring * segments + seg
    b = 1 + ring * segments + (seg + 1) % segments
    c, d = a + segments, b + segments
    top_a, top_b = 1 + np.arange(segments), 1 + (np.arange(segments) + 1) % segments
    bottom_a, bottom_b = top_a + (rings - 2) * segments, top_b + (rings - 2) * segments
    faces = np.concatenate(
        [
            np.stack([np.zeros(segments, int), top_a, top_b], -1),
            np.stack([a, c, d], -1).reshape(-1, 3),
            np.stack([a, d, b], -1).reshape(-1, 3),
            np.stack([np.full(segments, south), bottom_b, bottom_a], -1),
        ]
    )
    scale = np.stack([1 + 0.5 * np.arange(frames), np.ones(frames), 1 - 0.3 * np.arange(frames) / frames], -1)
    return AnimatedMesh(faces, (unit[None] * scale[:, None]).astype(np.float32))


def tube_with_bow_tie_and_fin() -> AnimatedMesh:
    """:func:`bending_tube` (2 frames) with a closed tetrahedron touching it at vertex 0 only (a
    bow tie) and a fin: one more face on the tube's edge (0, 13)."""
    mesh = bending_tube(frames=2)
    apex = mesh.frames[:, :1] + np.array([-0.5, 0.0, 0.0], np.float32)
    fin = mesh.frames[:, :1] + np.array([0.0, 0.0, 0.4], np.float32)
    frames = np.concatenate([mesh.frames, apex, apex + [[[0, 0.3, 0]]], apex + [[[0, 0, 0.3]]], fin], axis=1)
    a, b, c, tip = 192, 193, 194, 195
    faces = np.concatenate([mesh.faces, [[0, b, a], [0, c, b], [0, a, c], [a, b, c], [0, 13, tip]]])
    return AnimatedMesh(faces, frames)


def two_bone_tube(frames: int = 8) -> tuple[SkinnedMesh, Motion]:
    """The tube skinned to two joints (root at x = -1, elbow at x = 0) and a motion bending the
    elbow by up to 90 degrees about z."""
    positions, faces = tube()
    skeleton = Skeleton(["root", "elbow"], [-1, 0], [[-1.0, 0, 0], [1.0, 0, 0]])
    elbow_weight = np.clip(positions[:, 0] / 0.4 + 0.5, 0.0, 1.0)
    joints = np.tile(np.array([[1, 0]], np.int32), (len(positions), 1))
    weights = np.stack([elbow_weight, 1 - elbow_weight], -1)
    inverse_bind = np.linalg.inv(skeleton.rest_world_transforms())
    u = np.uv = positions[:, :2] * 0.5 + 0.5
    skinned = SkinnedMesh(positions, faces, joints, weights, inverse_bind, skeleton, uvs=u)
    angle = np.linspace(0, np.pi / 2, frames)
    rotations = np.zeros((frames, 2, 4))
    rotations[:, :, 3] = 1.0
    rotations[:, 1, 2] = np.sin(angle / 2)
    rotations[:, 1, 3] = np.cos(angle / 2)
    motion = Motion(skeleton, np.tile([[-1.0, 0, 0]], (frames, 1)), rotations, fps=30.0)
    return skinned, motion


def twisting_cylinder(frames: int = 5) -> tuple[AnimatedMesh, np.ndarray]:
    """A cylinder (axis y) at rest, and ``(frames, V, 3)`` frames that twist it about its axis from
    that rest pose (up to 1.2 radians at the top), which keeps every surface point's height."""
    from animlod import synth

    rest = synth.bending_cylinder(frames=1, rings=16, segments=16)
    turns = np.linspace(0.0, 1.2, frames)[:, None] * (rest.frames[0][:, 1] - rest.frames[0][:, 1].min())
    x, y, z = rest.frames[0].T
    twisted = np.stack([np.cos(turns) * x - np.sin(turns) * z, np.broadcast_to(y, turns.shape),
                        np.sin(turns) * x + np.cos(turns) * z], axis=-1)  # fmt: skip
    return rest, twisted


def wrapped_texture(mesh: AnimatedMesh) -> tuple[np.ndarray, np.ndarray]:
    """Cylindrical texture coordinates of :func:`twisting_cylinder`'s rest mesh: ``uvs (T, 2)``,
    u the angle about the axis and v the height, and each triangle corner's index into them
    ``(M, 3)``; the faces across u = 0 take u + 1, a seam."""
    rest = mesh.frames[0]
    u = np.arctan2(rest[:, 2], rest[:, 0]) / (2 * np.pi) % 1.0
    v = (rest[:, 1] - rest[:, 1].min()) / np.ptp(rest[:, 1])
    corner_u = u[mesh.faces]
    wraps = np.ptp(corner_u, axis=1) > 0.5
    corner_u = np.where(wraps[:, None] & (corner_u < 0.5), corner_u + 1.0, corner_u)
    uvs, corners = np.unique(np.stack([corner_u, v[mesh.faces]], axis=2).reshape(-1, 2), axis=0, return_inverse=True)
    return uvs.astype(np.float32), corners.reshape(-1, 3).astype(np.int32)


def directed_edges_unique(faces: np.ndarray) -> bool:
    """True when no directed edge appears twice: the faces form an oriented manifold."""
    directed = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    return len(np.unique(directed, axis=0)) == len(directed)
