"""Regions grown from motion, for faces without region labels."""

from __future__ import annotations

import numpy as np
import pytest

from animlod import synth
from animlod.face_lod.grow import GrowOptions, grow_regions, motion_of_frames, motion_of_targets


@pytest.fixture(scope="module")
def head():
    model = synth.face()
    return model, synth.face_animation(model, seconds=1.5, fps=20)


def _connected(faces: np.ndarray, members: np.ndarray) -> bool:
    """Whether the vertices ``members`` form one piece through edges among themselves."""
    inside = np.zeros(faces.max() + 1, bool)
    inside[members] = True
    edges = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    edges = edges[inside[edges[:, 0]] & inside[edges[:, 1]]]
    reached = {int(members[0])}
    frontier = [int(members[0])]
    neighbours: dict[int, list[int]] = {}
    for a, b in edges.tolist():
        neighbours.setdefault(a, []).append(b)
        neighbours.setdefault(b, []).append(a)
    while frontier:
        vertex = frontier.pop()
        for other in neighbours.get(vertex, []):
            if other not in reached:
                reached.add(other)
                frontier.append(other)
    return len(reached) == len(members)


def test_regions_grown_from_the_talking_head_separate_still_and_moving_parts(head):
    model, animation = head
    regions = grow_regions(motion_of_frames(animation.frames), model.faces)
    assert "static" in regions.names and len(regions.names) >= 4
    static = regions.vertex_regions == regions.index("static")
    # What face_animation never moves (ears, nose, upper teeth, scalp) is static.
    still = np.isin(model.vertex_regions, [model.region_names.index(n) for n in synth.STILL_REGIONS])
    assert np.all(static[still])
    # The lips, mouth and lower teeth move: they are not static (parts of the jaw near its hinge
    # and the poles of the eyeballs hardly move, and may be).
    moving = model.region_mask("lip_lower") | model.region_mask("mouth") | model.region_mask("teeth_lower")
    assert not np.any(static[moving])
    # Every moving region is one connected piece of at least min_vertices vertices.
    for index, name in enumerate(regions.names):
        members = np.flatnonzero(regions.vertex_regions == index)
        if name != "static":
            assert len(members) >= GrowOptions().min_vertices and _connected(model.faces, members), name
    assert regions.vertex_importance()[static].max() < regions.vertex_importance()[~static].min()


def test_regions_from_targets_and_a_face_that_does_not_move(head):
    model, animation = head
    targets = (animation.frames[[5, 15]] - animation.frames[0]).astype(np.float32)
    regions = grow_regions(motion_of_targets(targets, np.array([1.0, 0.5])), model.faces, GrowOptions(region_count=3))
    assert len(regions.names) >= 2
    with pytest.raises(ValueError, match="no vertex moves"):
        grow_regions(np.zeros((len(model.positions), 6)), model.faces)


def test_a_face_without_labels_is_offered_grown_ones(head):
    from animlod.face_lod import FaceRig

    model, animation = head
    with pytest.raises(ValueError, match="region labels: the face has none.*grow_regions"):
        FaceRig(model.positions, model.faces, None)
    regions = grow_regions(motion_of_frames(animation.frames), model.faces)
    rig = FaceRig(model.positions, model.faces, regions)  # the grown labels make a rig
    assert set(rig.lattices) == set(regions.names)


_SQUARE = np.array([[0, 1, 2], [0, 2, 3]])


@pytest.mark.parametrize(
    "features, faces, message",
    [
        (None, [[0, 1, 2], [0, 2, 9]], r"faces: face 1 \[0, 2, 9\] has an index outside \[0, 4\)"),  # IndexError before
        (None, [[0, 1, 2], [0, -1, 3]], r"faces: face 1 \[0, -1, 3\] has an index outside"),  # the last vertex before
        (None, [[0, 1, 2], [0, 2.5, 3]], r"faces: face 1 \[0.0, 2.5, 3.0\] has an index that is not a whole number"),
        (None, [[0, 1, 2, 3]], r"faces: expected shape \(M, 3\), got \(1, 4\)"),  # read as other triangles before
        (np.ones((4, 4)), _SQUARE, r"features: expected shape \(V, D\) with D a multiple of 3, got \(4, 4\)"),
        (np.full((4, 6), np.nan), _SQUARE, r"features: non-finite value at index \(0, 0\)"),  # "no vertex moves"
    ],
)
def test_grow_regions_names_the_bad_face_or_feature(features, faces, message):
    if features is None:
        features = np.random.default_rng(0).normal(size=(4, 6))
    with pytest.raises(ValueError, match=message):
        grow_regions(features, faces)
