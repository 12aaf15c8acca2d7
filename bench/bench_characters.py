"""Whole glTF characters: animlod's LoD levels against meshoptimizer at equal triangle counts.

Run: ``.venv/bin/python bench/bench_characters.py [--quick]`` (needs the ``bench`` extra).

For every glTF file of ../shared/data/gltf and ../shared/data/morph, the procedural humanoid
(written to a GLB first) and each of its drawables, at 50%, 25% and 10% of the triangles:

- animlod: the levels of ``animlod.pipelines.simplify_document`` (AQEM over the rest pose,
  every morph target and frames of every clip, primitives together, seams kept);
- meshoptimizer: ``meshoptimizer.simplify`` on each primitive of the rest pose (its seam-aware
  simplifier, target_error 1), the same share of each primitive's triangles; its levels keep
  a subset of the input's vertices, so they are re-skinned (or re-morphed) with those vertices'
  own weights.

Both are measured the same way: the symmetric Hausdorff distance over surface samples, the max
over frames spread over every clip (and the rest pose), relative to the rest pose's
bounding-box diagonal. "ratio" is animlod's error over meshoptimizer's (the goal: <= 0.75 at
25% and 10%). Where meshoptimizer stops above the target (seams, locked vertices), the table
gives the triangles it reached, and the ratio compares at those counts.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table, stopwatch

from animlod import synth
from animlod.io import write_glb
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_drawable import Drawable, read_drawables
from animlod.metrics import hausdorff_distance
from animlod.model import AnimatedMesh, spread_frames
from animlod.pipelines.drawable_levels import posed_frames, simplify_drawable

RATIOS = (0.5, 0.25, 0.1)
MEASURED_FRAMES = 16  # per clip
SAMPLES = 10000


def inputs(scratch: Path) -> list[Path]:
    files = sorted((DATA_DIR / "gltf").glob("*.gl*")) + sorted((DATA_DIR / "morph").glob("*.gl*"))
    humanoid = synth.humanoid()
    motions = [synth.humanoid_motion(humanoid.skeleton, style) for style in ("walk", "run")]
    write_glb(scratch / "procedural_humanoid.glb", humanoid, motions)
    return [scratch / "procedural_humanoid.glb", *files]


def measured_frames(drawable: Drawable) -> list[AnimatedMesh]:
    """The input's frames the error is taken over: the rest pose, then frames of every clip."""
    faces = drawable.geometry.faces
    frames = [AnimatedMesh(faces, drawable.rest_positions()[None])]
    for clip in drawable.clips:
        frames.append(AnimatedMesh(faces, drawable.clip_frames(clip, spread_frames(clip.frame_count, MEASURED_FRAMES))))
    return frames


def worst_error(originals: list[AnimatedMesh], levels: list[AnimatedMesh]) -> float:
    worst = 0.0
    for original, level in zip(originals, levels):
        worst = hausdorff_distance(original, level, samples=SAMPLES, at_least=worst)
    return worst


def meshopt_faces(drawable: Drawable, ratio: float) -> np.ndarray:
    """meshoptimizer's triangles (input vertex indices) at ``ratio`` of each primitive."""
    import meshoptimizer

    rest = drawable.bind_positions()
    starts = drawable.geometry.vertex_starts
    kept = []
    for k, primitive in enumerate(drawable.geometry.primitives):
        indices = primitive.faces.ravel().astype(np.uint32)
        destination = np.zeros_like(indices)
        target = 3 * max(1, round(ratio * len(primitive.faces)))
        positions = np.ascontiguousarray(rest[starts[k] : starts[k + 1]])
        count = meshoptimizer.simplify(destination, indices, positions, target_index_count=target, target_error=1.0)
        kept.append(destination[:count].reshape(-1, 3).astype(np.int64) + starts[k])
    return np.concatenate(kept)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="skip the files over 20k triangles")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        for path in inputs(Path(scratch)):
            drawables = read_drawables(GltfDocument(path))
            for drawable in drawables:
                faces = len(drawable.geometry.faces)
                if args.quick and faces > 20000:
                    continue
                with stopwatch() as elapsed:
                    ours = simplify_drawable(drawable, RATIOS)
                originals = measured_frames(drawable)
                size = ours.size
                for ratio, level in zip(RATIOS, ours.levels):
                    our_faces = level.simplified.mesh.face_count
                    level_faces = level.simplified.mesh.faces
                    posed = [AnimatedMesh(level_faces, level.rest_positions()[None])]
                    posed += [AnimatedMesh(level_faces, _posed(drawable, level, clip)) for clip in drawable.clips]
                    our_error = worst_error(originals, posed) / size
                    theirs = meshopt_faces(drawable, ratio)
                    their_posed = [AnimatedMesh(theirs, original.frames) for original in originals]
                    their_error = worst_error(originals, their_posed) / size
                    rows.append(
                        (
                            path.name,
                            drawable.label,
                            faces,
                            f"{ratio:.0%}",
                            our_faces,
                            our_error,
                            len(theirs),
                            their_error,
                            our_error / their_error if their_error > 0 else float("nan"),
                            elapsed[0],
                        )
                    )
                    print(rows[-1], flush=True)
    print_table(
        "animlod LoD levels against meshoptimizer (max-over-frames Hausdorff / rest diagonal)",
        (
            "file",
            "drawable",
            "triangles",
            "target",
            "animlod triangles",
            "animlod error",
            "meshopt triangles",
            "meshopt error",
            "ratio",
            "animlod s (all levels)",
        ),
        rows,
    )


def _posed(drawable: Drawable, level, clip) -> np.ndarray:
    return posed_frames(drawable, level, clip, spread_frames(clip.frame_count, MEASURED_FRAMES))


if __name__ == "__main__":
    main()
