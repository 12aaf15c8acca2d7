"""`animlod character` on a character exported in many pieces: where the time goes.

Run: ``.venv/bin/python bench/bench_character_parts.py`` (part of ``make bench``; skips without
../shared/data). Xbot.glb whole (2 meshes) and split into 10 and 60 meshes: each mesh's
triangles cut into runs, every run a mesh of its own with the vertices it uses, drawn by a node
of its own on the same skin (as exporters write a character in parts). Per case the wall
seconds of ``build_character`` (default settings, one run): motion levels, geometry levels, and
the rest (writing the LoD GLB and measuring every chain, most of it measuring), with the largest
error of the coarsest level over the meshes, in asset units. The
measuring draws one point per face of each mesh, at most 4,000 (``measure_samples``); the rows
"fixed 4,000" patch in the count used before 2026-12-05, 4,000 on every mesh however small.
"""

from __future__ import annotations

import contextlib
import sys
import tempfile
from pathlib import Path
from unittest import mock

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table, stopwatch

from animlod.io.glb_builder import GlbBuilder
from animlod.io.gltf_document import GltfDocument
from animlod.pipelines import character

SOURCE = DATA_DIR / "gltf" / "Xbot.glb"


def split_into_pieces(source: Path, target: Path, pieces: int) -> None:
    """``source`` with each skinned mesh node replaced by ``pieces`` nodes on its skin, each
    drawing a run of the mesh's triangles with the vertices that run uses."""
    doc = GltfDocument(source)
    builder = GlbBuilder.from_document(doc)
    added = []
    for node in list(builder.json["nodes"]):  # not the pieces it adds
        if "mesh" not in node or "skin" not in node:
            continue
        for primitive in builder.json["meshes"][node.pop("mesh")]["primitives"]:
            faces = np.asarray(doc.accessor(primitive["indices"], "indices")).reshape(-1, 3)
            attributes = {
                name: np.asarray(doc.accessor(index, name)) for name, index in primitive["attributes"].items()
            }
            for run in np.array_split(faces, pieces):
                used, corners = np.unique(run, return_inverse=True)
                piece = {key: value for key, value in primitive.items() if key not in ("attributes", "indices")}
                piece["indices"] = builder.add(corners.astype(np.uint32).reshape(-1, 1))
                piece["attributes"] = {
                    name: builder.add(values[used].reshape(len(used), -1), bounds=name == "POSITION")
                    for name, values in attributes.items()
                }
                mesh = builder.append("meshes", {"primitives": [piece]})
                added.append(builder.append("nodes", {"name": f"piece {mesh}", "mesh": mesh, "skin": node["skin"]}))
        del node["skin"]
    builder.json["scenes"][builder.json.get("scene", 0)]["nodes"] += added
    builder.save(target)


def run(source: Path, output: Path) -> tuple[float, character.CharacterReport]:
    with stopwatch() as elapsed:
        report = character.build_character(source, output)
    return elapsed[0], report


def main() -> None:
    if not SOURCE.exists():
        print(f"skipped: {SOURCE} is absent")
        return
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        cases = [("whole", SOURCE, False)]
        for pieces in (10, 60):
            path = folder / f"xbot_{pieces}.glb"
            split_into_pieces(SOURCE, path, pieces)
            cases.append((f"{pieces} runs per mesh", path, False))
        cases.append(("60 runs per mesh, fixed 4,000", folder / "xbot_60.glb", True))
        for name, path, fixed in cases:
            patch = mock.patch.object(character, "measure_samples", lambda drawable: 4000)
            with patch if fixed else contextlib.nullcontext():
                seconds, report = run(path, folder / "out.glb")
            coarsest = max(chain[-1].error for chain in report.chains.values())
            rest = seconds - report.motion_seconds - report.geometry_seconds
            rows.append((name, len(report.chains), seconds, report.motion_seconds, report.geometry_seconds, rest,
                         f"{coarsest:.4g}"))  # fmt: skip
    print_table(
        "animlod character on Xbot.glb in pieces (one run each)",
        (
            "input",
            "meshes",
            "total s",
            "motion s",
            "geometry s",
            "writing and measuring s",
            "coarsest level's largest error (asset units)",
        ),
        rows,
    )


if __name__ == "__main__":
    main()
