"""Skins of rigid parts for the tests: each part's points follow one joint alone."""

from __future__ import annotations

import numpy as np

from animlod.model import Skeleton, SkinnedMesh


def rigid_skin(skeleton: Skeleton, parts: list[tuple[int, np.ndarray]], faces: np.ndarray | None = None) -> SkinnedMesh:
    """A skin of ``parts`` (joint, points), each following its joint alone, bound in the rest
    pose; ``faces`` None: a strip through every vertex (a GLB keeps only vertices in faces)."""
    positions = np.concatenate([points for _, points in parts]).astype(np.float32)
    joints = np.zeros((len(positions), 4), np.int32)
    joints[:, 0] = np.concatenate([np.full(len(points), joint) for joint, points in parts])
    weights = np.zeros((len(positions), 4), np.float32)
    weights[:, 0] = 1.0
    faces = np.arange(len(positions) - 2)[:, None] + [0, 1, 2] if faces is None else faces
    return SkinnedMesh(positions, faces, joints, weights, np.linalg.inv(skeleton.rest_world_transforms()), skeleton)
