"""Fingerprints of AQEM's levels, to show that a change of the core's speed left them alone.

    .venv/bin/python bench/level_hashes.py [--random N] > before.txt   # with one extension
    .venv/bin/python bench/level_hashes.py [--random N] > after.txt    # with the other
    diff before.txt after.txt

One line per case: the SHA-256 (first 10 hex digits) of every level's faces and positions.
The cases go through both collapse orders (collapse passes above 100k edges, the greedy order
below): three weightings at 50/25/10% on a 4-frame 217k sphere, a 319k sphere, the bending tube
and, when ../shared/data is present, crane and face-poses; on-edge placement, frame subsets,
locked and guarded points; and N random greedy cases (holes, locks, guards, attribute seams,
every weighting, fold limit 0; seeded, so the same N cases each time).
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_aqem import bending_tube, bumpy_sphere
from devdata import DATA_DIR

from animlod.aqem import simplify_animated
from animlod.io.meshseq import read_sequence
from animlod.model import AnimatedMesh

WEIGHTINGS = ({}, {"use_motion_features": False}, {"feature_weighting": "paper"})


def fingerprint(result) -> str:
    digest = hashlib.sha256()
    for level in result.levels:
        digest.update(np.ascontiguousarray(level.mesh.faces).tobytes())
        digest.update(np.ascontiguousarray(level.mesh.frames).tobytes())
    return digest.hexdigest()[:10]


def fixed_cases() -> None:
    inputs = {"sphere 4 x 217k": bumpy_sphere(330, 330, 4), "sphere 319k": bumpy_sphere(400, 400, 1)}
    inputs["bending tube"] = bending_tube()
    sequences = DATA_DIR / "meshseq"
    for name in ("crane", "face-poses"):
        if (sequences / name).is_dir():
            inputs[name] = read_sequence(sequences / name)
    for name, mesh in inputs.items():
        counts = [mesh.face_count // 2, mesh.face_count // 4, mesh.face_count // 10]
        for options in WEIGHTINGS:
            print(name, options, fingerprint(simplify_animated(mesh, target_face_counts=counts, **options)))
    small = bumpy_sphere(330, 330, 3)
    for options in ({"placement": "on_edge"}, {"max_frames": 2}, {"frame_subset": [0, 2]}):
        counts = [small.face_count // 2, small.face_count // 10]
        print("sphere 3 x 217k", options, fingerprint(simplify_animated(small, target_face_counts=counts, **options)))
    locks = {"guarded_vertices": np.arange(0, 89000, 3), "locked_vertices": np.arange(1, 89000, 11)}
    sphere = bumpy_sphere(300, 300, 1)
    print("sphere 180k, guarded and locked", fingerprint(simplify_animated(sphere, (0.1, 0.03, 0.005), **locks)))


def random_cases(count: int) -> None:
    rng = np.random.default_rng(1)
    for case in range(count):
        rings = int(rng.integers(12, 60))
        base = bumpy_sphere(rings, rings, int(rng.choice([1, 2, 5])))
        faces = base.faces[rng.random(base.face_count) > rng.choice([0.0, 0.02, 0.1])]
        mesh = AnimatedMesh(faces, base.frames + rng.normal(scale=1e-3, size=base.frames.shape).astype(np.float32))
        vertices = mesh.vertex_count
        data = {}
        if rng.random() < 0.4:
            data["locked_vertices"] = rng.choice(vertices, size=vertices // 20, replace=False)
        if rng.random() < 0.4:
            guarded = rng.choice(vertices, size=vertices // 15, replace=False)
            data["guarded_vertices"] = np.setdiff1d(guarded, data.get("locked_vertices", []))
        if rng.random() < 0.3:
            data["attributes"] = np.round(rng.random((vertices, 2)) * 3).astype(np.float32)
        options = dict(rng.choice([*WEIGHTINGS, {"placement": "on_edge"}, {"fold_limit": 0.0}]))
        counts = [max(1, mesh.face_count // 3), max(1, mesh.face_count // 12)]
        result = simplify_animated(mesh, target_face_counts=counts, **data, **options)
        print("random", case, rings, mesh.frame_count, sorted(data), options, fingerprint(result))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--random", type=int, default=0, help="also N random greedy-order cases")
    args = parser.parse_args()
    fixed_cases()
    random_cases(args.random)


if __name__ == "__main__":
    main()
