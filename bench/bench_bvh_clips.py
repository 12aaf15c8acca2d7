"""BVH clips on the dev characters: how their joints were matched, and where the feet land.

Run: ``.venv/bin/python bench/bench_bvh_clips.py`` (part of ``make bench``; skips without
../shared/data). Every BVH file of ../shared/data/bvh added to every skinned glTF character of
../shared/data/gltf (``with_clips``, as ``--clips`` does), one row per pair: how the joints
were matched (the note's words, or the refusal), the joints driven, and the skin's lowest point
per frame of the clip, above the rest pose's lowest point, in percent of the rest pose's height
(the least and the most over the clip's frames: a figure whose feet touch the floor in the
clip keeps it near 0, below 0 it sinks into the floor, above it floats). The frames played
are the document's (at most 240 per clip by default).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table

from animlod.io.errors import FormatError
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_drawable import read_drawables
from animlod.pipelines.clip_import import with_clips

_METHODS = ("by the two skeletons' shape", "by body part", "by name up to case")


def main() -> None:
    clips = sorted((DATA_DIR / "bvh").glob("*.bvh"))
    characters = [path for path in sorted((DATA_DIR / "gltf").glob("*.gl*")) if _skinned(path)]
    if not clips or not characters:
        print(f"no BVH clips or skinned characters under {DATA_DIR}: skipped")
        return
    rows = []
    for character in characters:
        for clip in clips:
            notes: list[str] = []
            try:
                document = with_clips(GltfDocument(character), [clip], notes.append)
            except FormatError as error:
                rows.append((character.name, clip.name, "refused: " + str(error).split(": ", 2)[-1], "", "", ""))
                continue
            note = notes[0]
            method = next((words for words in _METHODS if words in note), "by name")
            joints = note.split("(", 1)[1].split(" joints)", 1)[0]
            lowest, highest = _floor_range(document)
            rows.append((character.name, clip.name, method, joints, f"{lowest:+.1f}", f"{highest:+.1f}"))
    print_table(
        "BVH clips on the dev characters: joints matched, and the skin's lowest point per frame above the rest "
        "pose's, % of the rest height",
        ("character", "clip", "joints matched", "joints driven", "lowest (least)", "lowest (most)"),
        rows,
    )


def _skinned(path: Path) -> bool:
    return bool(GltfDocument(path).gltf.skins)


def _floor_range(document: GltfDocument) -> tuple[float, float]:
    """The least and most, over the added clip's frames, of the skin's lowest point above the
    rest pose's lowest, in percent of the rest pose's height (every skinned mesh together)."""
    drawables = [drawable for drawable in read_drawables(document) if drawable.clips]
    rest = np.concatenate([drawable.rest_positions()[:, 1] for drawable in drawables])
    played = np.concatenate([drawable.clip_frames(drawable.clips[-1])[..., 1] for drawable in drawables], axis=1)
    lowest = 100.0 * (played.min(axis=1) - rest.min()) / np.ptp(rest)
    return float(lowest.min()), float(lowest.max())


if __name__ == "__main__":
    main()
