"""A skin root with a uniform rest scale (2, as a Blender export of Castle Game Engine's plasma
gun has) that a clip keys at 1 throughout: every joint below the root carries the same
deformation, and the messages must name the root that scales, not whichever of its descendants
float noise set apart (plasma.gltf's clips blamed 'fan' and 'wheels'). A joint that squashes on
its own is still the one named, not the turned children its shear carries into."""

from __future__ import annotations

import numpy as np
import pytest
from gltf_edits import add_scale_channel, append_accessor, edit_glb

from animlod import rotations, synth
from animlod.cli import main
from animlod.io import write_glb
from animlod.io.gltf_document import GltfDocument
from animlod.model import Motion, Skeleton
from animlod.pipelines.character import build_character


@pytest.fixture(scope="module")
def scaled_root(tmp_path_factory):
    """The synthetic humanoid's walk and run, its root Hips at rest scale 2 (the inverse binds
    re-bound to it) and the walk keying the Hips' scale at 1 in every frame."""
    folder = tmp_path_factory.mktemp("scaled_root")
    character = synth.humanoid()
    clips = [synth.humanoid_motion(character.skeleton, kind) for kind in ("walk", "run")]
    write_glb(folder / "humanoid.glb", character, clips)
    doc = GltfDocument(folder / "humanoid.glb")

    def scale_the_root(gltf, blob):
        root = gltf.skins[0].joints[0]
        gltf.nodes[root].scale = [2.0, 2.0, 2.0]
        grow = np.diag([2.0, 2.0, 2.0, 1.0])  # about the root's position, which every joint's rest carries
        grow[:3, 3] = -np.array(gltf.nodes[root].translation)
        binds = doc.accessor(gltf.skins[0].inverseBindMatrices, "test").reshape(-1, 4, 4).transpose(0, 2, 1)
        bound = (binds @ np.linalg.inv(grow)).transpose(0, 2, 1).reshape(-1, 16)  # column-major again
        gltf.skins[0].inverseBindMatrices = append_accessor(gltf, blob, bound.astype(np.float32), "MAT4")
        keys = gltf.accessors[gltf.animations[0].samplers[0].input].count
        add_scale_channel(gltf, blob, root, np.ones((keys, 3)))

    return edit_glb(folder / "humanoid.glb", folder / "scaled_root.glb", scale_the_root)


def test_motion_names_the_root_that_scales(scaled_root, tmp_path, capsys):
    assert main(["motion", str(scaled_root), "--clip", "walk", "-o", str(tmp_path / "motion")]) == 2
    error = capsys.readouterr().err
    assert "animation 'walk': joint 'Hips' scales; motion LoD re-fits rigid motions only" in error


def test_the_character_chain_names_the_root_that_scales(scaled_root, tmp_path):
    report = build_character(scaled_root, tmp_path / "chain.glb", [0.5], frame_budget=12, measured_frames=3)
    assert any("joint 'Hips' scales in its clips" in note for note in report.notes)


def _turning_chain(deformations: np.ndarray, axis: tuple[float, float, float] = (0.3, 1.0, 0.5)) -> Motion:
    """A five-joint chain, each joint turned 40 degrees about ``axis`` from its parent in every
    one of 4 frames, with ``deformations`` (J, 3, 3) in every frame."""
    skeleton = Skeleton([f"j{j}" for j in range(5)], np.arange(-1, 4), np.tile([0.0, 1.0, 0.0], (5, 1)))
    turn = rotations.from_axis_angle(np.array(axis) / np.linalg.norm(axis), np.radians(40.0))
    local = np.broadcast_to(turn, (4, 5, 4))
    return Motion(skeleton, np.zeros((4, 3)), local, 30.0, "clip", None, np.broadcast_to(deformations, (4, 5, 3, 3)))


def test_a_scaled_root_is_named_over_the_float_noise_of_its_descendants():
    """The root's scale seen in each joint's own frame: the same deformation everywhere, but for
    float32 noise, which named the deepest joint here."""
    deformations = np.broadcast_to(0.5 * np.eye(3), (5, 3, 3)).copy()
    deformations[3, 0, 0] -= 2e-7  # 0.5 - 2e-7 strays 2e-7 further from 1
    assert _turning_chain(deformations).deforming_joint() == "j0"


@pytest.mark.parametrize(
    "axis, noise",
    [((0.0, 1.0, 0.0), 2e-7), ((0.3, 1.0, 0.5), 0.0)],
    ids=["turned-about-the-stretch", "sheared-children"],
)
def test_a_joint_that_squashes_is_named_not_the_joints_below_it(axis, noise):
    """j2 stretches along y and thins: children turned about y carry the very same deformation
    (float noise named the deepest), children turned about another axis a shear."""
    deformations = np.broadcast_to(np.eye(3), (5, 3, 3)).copy()
    deformations[2] = np.diag([0.8, 1.4, 0.8])
    turn = rotations.to_matrix(_turning_chain(deformations, axis).local_rotations[0, 1])
    for joint in (3, 4):  # j2's squash as each joint below it sees it in its own frame
        deformations[joint] = turn.T @ deformations[joint - 1] @ turn
    deformations[4, 1, 1] += noise
    assert _turning_chain(deformations, axis).deforming_joint() == "j2"
