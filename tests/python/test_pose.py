"""The core's clip sampler, forward kinematics and skinning palette (cpp/include/animlod/pose.hpp)
against the Python model: Motion.world_transforms / skin_matrices and io/gltf_keyframes.py."""

from __future__ import annotations

import numpy as np
import pytest

from animlod import _core, rotations, synth
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_keyframes import sample_keyframes
from animlod.io.gltf_skin import SkinRig

TOLERANCE = 1e-5


def _random_track(rng: np.random.Generator, interpolation: str, rotation: bool, keys: int = 9):
    times = np.cumsum(rng.uniform(0.05, 0.4, keys)).astype(np.float32)
    width = 4 if rotation else 3
    shape = (keys, 3, width) if interpolation == "CUBICSPLINE" else (keys, width)
    values = rng.normal(size=shape).astype(np.float32)
    if rotation:
        values = values / np.linalg.norm(values, axis=-1, keepdims=True)
        values[1::2] *= -1.0  # sign flips between keys: the blend must take the short arc
    return times, values


@pytest.mark.parametrize("interpolation", ["LINEAR", "STEP", "CUBICSPLINE"])
@pytest.mark.parametrize("rotation", [False, True])
def test_sampler_matches_the_python_sampler(interpolation: str, rotation: bool) -> None:
    rng = np.random.default_rng(7)
    times, values = _random_track(rng, interpolation, rotation)
    at = np.concatenate([[-1.0, times[0]], rng.uniform(times[0] - 0.1, times[-1] + 0.1, 200), [times[-1], 99.0]])
    at = at.astype(np.float32)
    ours = _core.sample_keyframes(times, values, interpolation, at, rotation=rotation)
    expected = sample_keyframes(times, values, interpolation, at, rotation=rotation)
    if rotation:  # q and -q are one rotation: compare the rotation matrices
        ours, expected = rotations.to_matrix(ours.astype(np.float64)), rotations.to_matrix(expected)
    np.testing.assert_allclose(ours, expected, atol=TOLERANCE, rtol=0)


def test_nlerp_stays_near_slerp_between_close_keys() -> None:
    times = np.array([0.0, 1.0], np.float32)
    values = rotations.from_axis_angle(np.array([[0.0, 0.0, 1.0]] * 2), np.radians([0.0, 10.0])).astype(np.float32)
    at = np.linspace(0.0, 1.0, 41, dtype=np.float32)
    slerp = _core.sample_keyframes(times, values, "LINEAR", at, rotation=True)
    nlerp = _core.sample_keyframes(times, values, "LINEAR", at, rotation=True, blend="nlerp")
    difference = rotations.multiply(rotations.conjugate(slerp), nlerp)
    angle = 2.0 * np.arcsin(np.clip(np.linalg.norm(difference[:, :3], axis=1), 0.0, 1.0))
    assert 0.0 < angle.max() < 1e-4


def test_forward_kinematics_matches_motion_world_transforms() -> None:
    skinned = synth.humanoid(seed=2)
    motion = synth.humanoid_motion(skinned.skeleton, "run", cycles=1, seed=2)
    translations = motion.local_translations().astype(np.float32)
    world = _core.forward_kinematics(motion.skeleton.parents, translations, motion.local_rotations.astype(np.float32))
    assert world.shape == (motion.frame_count, motion.skeleton.joint_count, 4, 4)
    np.testing.assert_allclose(world, motion.world_transforms(), atol=TOLERANCE, rtol=0)
    palette = _core.skin_palette(world, skinned.inverse_bind.astype(np.float32))
    np.testing.assert_allclose(palette, motion.skin_matrices(skinned.inverse_bind), atol=TOLERANCE, rtol=0)
    # The control: a palette of one frame later is not within the tolerance.
    assert np.abs(palette[1:] - motion.skin_matrices(skinned.inverse_bind)[:-1]).max() > 100 * TOLERANCE


def _node_pose_arrays(doc: GltfDocument, rig: SkinRig, animation: int, at: np.ndarray):
    """What the crowd binary does with a glTF skin, in numpy: every joint and ancestor node posed
    through its own TRS (channels sampled by the core), parents first."""
    nodes = sorted({n for joint in rig.joint_nodes for n in [joint, *doc.ancestors(joint)]},
                   key=lambda n: (len(doc.ancestors(n)), n))  # fmt: skip
    index = {node: i for i, node in enumerate(nodes)}
    parents = np.array([index.get(int(doc.parents[n]), -1) for n in nodes], np.int32)
    rest = [doc.rest_trs(n) for n in nodes]
    frames = at.shape[0]
    t = np.stack([np.broadcast_to(r[0], (frames, 3)) for r in rest], axis=1).astype(np.float32)
    r = np.stack([np.broadcast_to(r[1], (frames, 4)) for r in rest], axis=1).astype(np.float32)
    s = np.stack([np.broadcast_to(r[2], (frames, 3)) for r in rest], axis=1).astype(np.float32)
    for number, channel in enumerate(doc.gltf.animations[animation].channels):
        node, path = channel.target.node, channel.target.path
        if node not in index or path not in ("translation", "rotation", "scale"):
            continue
        times, values, interpolation = doc.sampler_keys(animation, channel.sampler, 4 if path == "rotation" else 3,
                                                        f"channel {number}")  # fmt: skip
        sampled = _core.sample_keyframes(times, values, interpolation, at, rotation=path == "rotation")
        {"translation": t, "rotation": r, "scale": s}[path][:, index[node]] = sampled
    return parents, t, r, s, np.array([index[n] for n in rig.joint_nodes[: rig.skin_slots]], np.int32)


@pytest.mark.parametrize("name", ["Soldier.glb", "RiggedFigure.glb", "Monster.glb"])
def test_gltf_palettes_posed_by_the_core_match_the_python_model(data_dir, name: str) -> None:
    """The whole crowd path (node TRS, sampled channels, FK through non-joint ancestors, world @
    inverse bind) gives the palettes of read_skinned's Motion.skin_matrices."""
    path = data_dir / "gltf" / name
    doc = GltfDocument(path)
    skin = next(node.skin for node in doc.gltf.nodes if node.skin is not None and node.mesh is not None)
    rig = SkinRig(doc, skin)
    animation, motion = next((i, m) for i in range(len(doc.gltf.animations)) if (m := rig.motion(doc, i, 30.0)))
    at = doc.animation_frame_times(animation, 30.0).astype(np.float32)
    parents, t, r, s, joint_nodes = _node_pose_arrays(doc, rig, animation, at)
    world = _core.forward_kinematics(parents, t, r, s)
    slots = rig.remap[: rig.skin_slots]  # skeleton joint of each skin slot
    palette = _core.skin_palette(world, rig.inverse_bind[slots].astype(np.float32), joint_nodes)
    # The Python model folds each joint's uniform node scale into its inverse bind (gltf_skin.py).
    folded = rig.inverse_bind.copy()
    folded[:, :3] *= rig.scales[:, None, None]
    expected = motion.skin_matrices(folded)[:, slots]
    scale = max(1.0, float(np.abs(expected[..., :3, 3]).max()))
    np.testing.assert_allclose(palette, expected, atol=TOLERANCE * scale, rtol=0)


def test_bad_pose_input_names_the_element() -> None:
    with pytest.raises(ValueError, match="joint 1"):
        _core.forward_kinematics([-1, 1], np.zeros((1, 2, 3)), np.tile([0, 0, 0, 1.0], (1, 2, 1)))
    with pytest.raises(ValueError, match="zero-length"):
        _core.forward_kinematics([-1, 0], np.zeros((1, 2, 3)), np.zeros((1, 2, 4)))
    with pytest.raises(ValueError, match="key 2"):
        _core.sample_keyframes([0.0, 1.0, 0.5], np.zeros((3, 3)), "LINEAR", [0.2])
    with pytest.raises(ValueError, match="interpolation"):
        _core.sample_keyframes([0.0], np.zeros((1, 3)), "HERMITE", [0.2])
    with pytest.raises(ValueError, match=r"\(N, 3, C\)"):
        _core.sample_keyframes([0.0, 1.0], np.zeros((2, 3)), "CUBICSPLINE", [0.2])
    with pytest.raises(ValueError, match="joint_nodes"):
        _core.skin_palette(np.zeros((1, 2, 4, 4)), np.zeros((1, 4, 4)), [5])
    unit = np.tile([0, 0, 0, 1.0], (2, 2, 1))
    with pytest.raises(ValueError, match="joint 1 has parent 1"):
        _core.clip_forward_kinematics([-1, 1], np.zeros((2, 2, 3)), unit)
    with pytest.raises(ValueError, match=r"rotations: expected shape \(T, J, 4\)"):
        _core.clip_forward_kinematics([-1, 0], np.zeros((2, 2, 3)), unit[:1])
    unit[1, 0, 2] = np.nan
    with pytest.raises(ValueError, match="frame 1, joint 0: non-finite"):
        _core.clip_forward_kinematics([-1, 0], np.zeros((2, 2, 3)), unit)
