"""``fold_limit`` (``--fold-limit``): beside the paper's Eq. 7, which sums each face's orientation
over the frames, no collapse may fold a face in any one frame deeper than the limit, in lengths
of the face's edge opposite the moved corner. Under the sum alone a face may flip in a few
frames where it keeps its area in the others: a flat side that stays in its plane while the limb
under it bends costs no quadric error, so its triangles fold across the bend in the bent frames
(found on a Blender export of a box-limbed character). Refusing every flip (a limit of 0)
stalls the collapses on noisy captures, whose noise tips slivers over in some frame; noise flips
stay shallow, so the default limit of one edge length keeps both."""

from __future__ import annotations

import math

import numpy as np
import pytest

from animlod import simplify_animated
from animlod.cli import main
from animlod.io.meshseq import read_sequence, write_sequence
from animlod.metrics import surface_error
from animlod.model import AnimatedMesh
from animlod.synth import humanoid, humanoid_motion, kicking_box_leg


def _hausdorff(mesh: AnimatedMesh, level: AnimatedMesh) -> float:
    return surface_error(mesh, level).summary()["hausdorff_max"]


def test_the_default_keeps_a_bending_box_sides_from_folding():
    mesh = kicking_box_leg()
    default = simplify_animated(mesh, (0.5, 0.25))
    paper = simplify_animated(mesh, (0.5, 0.25), fold_limit=math.inf)
    strict = simplify_animated(mesh, (0.5, 0.25), fold_limit=0.0)
    for ours, summed, unflipped in zip(default.levels, paper.levels, strict.levels):
        assert ours.mesh.face_count == summed.mesh.face_count == unflipped.mesh.face_count
        summed_error = _hausdorff(mesh, summed.mesh)
        assert summed_error > 0.05  # Eq. 7 alone: folded across the knee in the bent frames
        assert _hausdorff(mesh, ours.mesh) < 0.1 * summed_error
        assert _hausdorff(mesh, unflipped.mesh) < 0.1 * summed_error


def test_noise_that_tips_slivers_over_does_not_stall_the_default():
    # The synth walk with noise of 2e-3 of the diagonal: refusing every flip leaves the 10%
    # level at over twice its faces; the default reaches it as Eq. 7 alone does.
    figure = humanoid()
    walk = figure.bake(humanoid_motion(figure.skeleton, "walk"))
    frames = walk.frames[np.linspace(0, walk.frame_count - 1, 12).round().astype(int)]
    diagonal = np.linalg.norm(np.ptp(frames[0], axis=0))
    noise = np.random.default_rng(0).normal(scale=2e-3 * diagonal, size=frames.shape)
    noisy = AnimatedMesh(walk.faces, (frames + noise).astype(np.float32))
    target = round(0.1 * noisy.face_count)
    counts = {limit: simplify_animated(noisy, (0.1,), fold_limit=limit).levels[0].mesh.face_count
              for limit in (0.0, 1.0, math.inf)}  # fmt: skip
    assert counts[0.0] > 2 * target
    assert counts[1.0] == counts[math.inf] == target


def test_the_command_line_option_reaches_the_simplifier(tmp_path):
    write_sequence(tmp_path / "leg", kicking_box_leg(), "obj")
    errors = {}
    for option in ([], ["--fold-limit", "inf"], ["--fold-limit", "0"]):
        out = tmp_path / f"out{'_'.join(option)}"
        assert main(["simplify", str(tmp_path / "leg"), "-o", str(out), "--ratio", "0.5", "--no-metrics", *option]) == 0
        errors[tuple(option)] = _hausdorff(read_sequence(tmp_path / "leg"), read_sequence(out / "leg_lod1"))
    paper = errors[("--fold-limit", "inf")]
    assert errors[()] < 0.1 * paper
    assert errors[("--fold-limit", "0")] < 0.1 * paper


@pytest.mark.parametrize("value", ["-1", "nan"])
def test_a_negative_fold_limit_is_refused_in_one_line(tmp_path, value, capsys):
    write_sequence(tmp_path / "leg", kicking_box_leg(), "obj")
    assert main(["simplify", str(tmp_path / "leg"), "-o", str(tmp_path / "out"), f"--fold-limit={value}"]) == 2
    message = f"animlod simplify: error: --fold-limit: expected a depth >= 0 (0, 1, inf), got {value}"
    assert capsys.readouterr().err.strip() == message
    assert not (tmp_path / "out").exists()


def test_the_library_refuses_a_negative_fold_limit():
    with pytest.raises(ValueError, match="fold_limit: must be >= 0"):
        simplify_animated(kicking_box_leg(), (0.5,), fold_limit=-1.0)
