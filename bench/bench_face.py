"""Facial LoD (seeds/004): Table 1 for the procedural face, deformation LoD, runtime selection
with frame skipping, and blendshape faces.

Run: ``.venv/bin/python bench/bench_face.py [--quick]``. Tables:

1. Table 1 of the paper for the procedural head (2,304 triangles; the paper's 2,313 / 1,533 /
   357 levels as ratios): per level, triangles, vertices, regions animated, lattices, MPAs
   processed, the largest time per frame to animate over the four-expression sequence ("MAT":
   MPA intensities to control displacements, then the core's rational FFD over the level's
   vertices; each frame the fastest of ``--repeats`` runs) and its ratio to level 0 (the paper:
   13.16 ms -> 3.84 and 0.85 ms at level 1, 0 at level 2), and the largest symmetric Hausdorff
   distance over the sequence against the full face, as % of its bounding-box diagonal. Extra
   rows put geometry level 1 at other animation levels, and the level-1 mesh of plain AQEM (no
   region importance) at the same animation level, as peers in the same run.
2. Deformation LoD: level 1 with every active region on 3x3x3 lattices against the fitted 2x2x2
   lattices of the reduction rule (time and error), and the 2x2x2 fit error per region.
3. Runtime selection: the face at distances from 0.3 m to 40 m (60 degree field of view, 720
   pixel viewport, 1 pixel tolerance): coverage, geometry level, animation level (lowered by
   the geometry, Figure 6), frame step of frame skipping, and the animation time per displayed
   frame over the sequence (the computed frames' times, each the fastest of ``--repeats``
   runs, summed and divided by the frames shown).
4. Blendshape faces: the face-pose scans (neutral + 3 expressions, 57,836 triangles) and every
   morph-target glTF of ../shared/data: per level, triangles, targets kept, the largest and the
   median time to blend a frame (numpy), the median's ratio to level 0, and the Hausdorff error
   over the animation. glTF faces twice: levels from the whole-document pipeline (every
   primitive, attribute and normal kept; what ``animlod face`` writes) and from face_lod's own
   AQEM run over the neutral face and targets with UVs only, as a peer.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table, stopwatch

from animlod.face_lod import FaceLodOptions, build_blendshape_lod, build_face_lod, expression_sequence, procedural_face
from animlod.face_lod.blendshape import measure_blendshape_lod
from animlod.face_lod.lod_glb import gltf_face_levels, read_gltf_face
from animlod.face_lod.measure import (
    animate,
    animation_errors,
    every_nth,
    measure_level,
    time_animators,
    time_frames,
)
from animlod.face_lod.selection import (
    Camera,
    coverage_thresholds,
    projected_coverage,
    select_face_levels,
    skipped_frames,
)
from animlod.face_lod.sources import read_pose_face
from animlod.metrics import surface_error

MORPH_FILES = ["morph/Parrot.glb", "morph/Stork.glb", "morph/MorphStressTest.gltf",
               "meshseq/Flamingo-morph-glTF/Flamingo.glb"]  # fmt: skip


def table_one(face, animation, repeats: int, error_frames: int):
    rig = face.rig
    with stopwatch() as built:
        chain = build_face_lod(rig, face.tree, animation)
    plain = build_face_lod(rig, face.tree, animation, FaceLodOptions(region_importance=False))
    reference = animate(chain.animator(0, 0), rig.faces, every_nth(animation, error_frames))
    pairs = [(chain, g, chain.geometry[g].animation_floor, f"level {g}") for g in range(len(chain.geometry))]
    # Coarser animation on the level-1 mesh (a finer one is not allowed there: Figure 6).
    pairs += [(chain, 1, a, f"level 1, animation {a}") for a in range(chain.geometry[1].animation_floor + 1,
                                                                          chain.tree.level_count)]  # fmt: skip
    pairs += [(plain, 1, 1, "level 1, plain AQEM mesh"), (plain, 2, 3, "level 2, plain AQEM mesh")]
    mask = rig.regions.mask(next(group.regions for group in rig.regions.groups if group.name == "face_mask"))
    times = time_animators([source.animator(g, a) for source, g, a, _ in pairs], animation.intensities, repeats)
    rows, base = [], None
    for (source, g, a, label), timed in zip(pairs, times):
        row = measure_level(source, g, a, animation, reference, error_frames=error_frames, focus=mask, times=timed)
        base = base or (row.max_frame_seconds, row.median_frame_seconds)
        rows.append([label, row.triangles, row.vertices, row.animated_regions, row.lattices, row.active_mpas,
                     1e6 * row.max_frame_seconds, 1e6 * row.median_frame_seconds, row.max_frame_seconds / base[0],
                     row.median_frame_seconds / base[1], 100 * row.hausdorff, 100 * row.focus_error])  # fmt: skip
    print_table(
        f"Table 1, procedural face ({len(animation.intensities)} frames of smile, anger, surprise, sadness; "
        f"levels built in {built[0]:.2f} s)",
        ["level", "triangles", "vertices", "regions animated", "lattices", "MPAs", "MAT (us)", "median (us)",
         "MAT / level 0", "median / level 0", "Hausdorff (% diag)", "face mask to level (% diag)"],
        rows,
    )  # fmt: skip
    return chain


def deformation_lod(chain, animation, repeats: int, error_frames: int):
    sampled = every_nth(animation, error_frames)
    reference = animate(chain.animator(0, 0), chain.rig.faces, sampled)
    level = chain.geometry[1]
    rows = []
    variants = (("3x3x3 everywhere", frozenset()), ("reduction rule", level.reduced))
    animators = [chain.rig.animator(level.rest, level.regions.vertex_regions, chain.tree.active(1), reduced)
                 for _, reduced in variants]  # fmt: skip
    for (label, _), animator, times in zip(variants, animators, time_animators(animators, animation.intensities,
                                                                                repeats)):  # fmt: skip
        error = surface_error(reference, animate(animator, level.faces, sampled))
        controls = int(np.prod(animator.sizes, axis=1).sum())
        rows.append([label, len(animator.regions), controls, 1e6 * times.max(), 1e6 * np.median(times),
                     100 * float(error.relative_hausdorff.max())])  # fmt: skip
    print_table(
        f"Deformation LoD at geometry level 1 ({level.triangle_count} triangles, animation level 1; "
        f"geometric error {1000 * level.geometric_error:.3g} mm)",
        ["lattices", "regions", "control points", "MAT (us)", "median (us)", "Hausdorff (% diag)"],
        rows,
    )
    fits = sorted(chain.reduction_error.items(), key=lambda item: item[1])
    print_table(
        "2x2x2 fit error per region (largest over its MPAs at intensity 1; reduced at level 1 when <= the "
        "level's geometric error)",
        ["region", "fit error (mm)", "reduced at level 1"],
        [[name, 1000 * error, name in level.reduced] for name, error in fits],
    )


def selection(chain, animation, repeats: int, error_frames: int):
    camera = Camera()
    sampled = every_nth(animation, error_frames)
    reference = animate(chain.animator(0, 0), chain.rig.faces, sampled)
    points = chain.rig.positions.astype(np.float64)
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    radius = float(np.linalg.norm(points - centre, axis=1).max())
    geometry_errors = []
    for g, level in enumerate(chain.geometry):
        error = surface_error(reference, animate(chain.animator(g, 0), level.faces, sampled), samples=5000)
        geometry_errors.append(float(error.hausdorff.max()))
    geometry_thresholds = coverage_thresholds(geometry_errors, radius, camera, 1.0)
    animation_thresholds = coverage_thresholds(animation_errors(chain, sampled), radius, camera, 1.0)
    floors = [level.animation_floor for level in chain.geometry]
    rows = []
    for distance in (0.3, 0.6, 1.0, 2.0, 4.0, 8.0, 16.0, 40.0):
        coverage = projected_coverage(radius, distance, camera)
        chosen = select_face_levels(coverage, geometry_thresholds, animation_thresholds, floors)
        animator = chain.animator(chosen.geometry_level, chosen.animation_level)
        shown = skipped_frames(animation.frame_count, chosen.frame_step)
        computed = np.unique(shown)
        # Each computed frame's fastest of `repeats` runs (as the MAT), summed, per shown frame.
        per_frame = time_frames(animator, animation.intensities[computed], repeats).sum() / animation.frame_count
        rows.append([distance, coverage, 720 * coverage, chosen.geometry_level,
                     chain.geometry[chosen.geometry_level].triangle_count, chosen.animation_level, chosen.frame_step,
                     f"{computed.size}/{animation.frame_count}", 1e6 * per_frame])  # fmt: skip
    print_table(
        "Runtime selection from the view distance (head radius "
        f"{radius:.3f} m; level errors {', '.join(f'{1000 * e:.2f}' for e in geometry_errors)} mm)",
        [
            "distance (m)",
            "coverage",
            "pixels",
            "geometry level",
            "triangles",
            "animation level",
            "frame step",
            "frames computed",
            "animation (us / shown frame)",
        ],
        rows,
    )


def blendshape_faces(repeats: int, error_frames: int, quick: bool):
    """Pose scans through face_lod's own AQEM run; glTF faces through the whole-document pipeline
    (what the CLI writes) and, as a peer, through face_lod's own run (neutral + targets + UVs)."""
    cases = []
    poses = DATA_DIR / "meshseq" / "face-poses"
    if poses.is_dir():
        label = "face-poses (neutral face-poses.obj)"
        cases.append((label, "own AQEM", lambda: read_pose_face(poses, "face-poses.obj")))
    for name in MORPH_FILES[: 1 if quick else None]:
        if (DATA_DIR / name).exists():
            cases.append((Path(name).name, "document", lambda name=name: read_gltf_face(DATA_DIR / name)))
            cases.append((Path(name).name, "own AQEM", lambda name=name: read_gltf_face(DATA_DIR / name).face))
    if not cases:
        print(f"\n(blendshape faces skipped: no development data at {DATA_DIR})")
        return
    rows = []
    for label, path, read in cases:
        source = read()
        with stopwatch() as built:
            if path == "document":
                face, levels = source.face, gltf_face_levels(source).levels
            else:
                face, levels = source, build_blendshape_lod(source)
        measured = measure_blendshape_lod(face, levels, repeats=repeats, max_frames=error_frames)
        base = measured[0].median_frame_seconds
        for row in measured:
            first = row.level == 0
            rows.append([label if first else "", path if first else "", row.level, row.triangles, row.vertices,
                         f"{row.targets}/{face.target_count}", 1e6 * row.max_frame_seconds,
                         1e6 * row.median_frame_seconds, row.median_frame_seconds / base, 100 * row.hausdorff,
                         f"{built[0]:.2f}" if first else ""])  # fmt: skip
    print_table(
        "Blendshape faces: levels with targets pruned by geometric error (none at the coarsest), blended with numpy",
        ["face", "levels by", "level", "triangles", "vertices", "targets", "blend max (us)", "blend median (us)",
         "median / level 0", "Hausdorff (% diag)", "build (s)"],
        rows,
    )  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats and files")
    parser.add_argument("--repeats", type=int, default=None, help="timing runs per frame (default 20, quick 3)")
    args = parser.parse_args()
    repeats = args.repeats or (3 if args.quick else 20)
    error_frames = 12 if args.quick else 40
    face = procedural_face()
    animation = expression_sequence(face.expressions, face.rig.mpa_names)
    chain = table_one(face, animation, repeats, error_frames)
    deformation_lod(chain, animation, repeats, error_frames)
    selection(chain, animation, repeats, error_frames)
    blendshape_faces(repeats, error_frames, args.quick)


if __name__ == "__main__":
    main()
