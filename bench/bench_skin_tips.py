"""Motion levels of skinned glTF characters with and without skin tips (motion_lod/skin_tips.py).

Run: ``.venv/bin/python bench/bench_skin_tips.py`` (part of ``make bench``). For every skinned,
animated glTF of ../shared/data/gltf and of Castle Game Engine's examples (Debian's
castle-game-engine-doc, Blender exports whose leaf joints carry skin; each distinct file once),
the largest mesh's motion levels as ``animlod character`` builds them (every clip as one motion,
4 levels, the default ranking and solver), once on the bare skeleton and once with the leaf
joints' skin tips. Per level: joints, and the skin's distance to the input over every frame of
every clip (the level's reduced skin played with its re-fitted clips, geometry untouched), max
and mean over vertices and frames, relative to the rest pose's diagonal; and the CPU seconds of the
analysis and the chain on one thread (on the file's first row).
"""

from __future__ import annotations

import hashlib
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from devdata import DATA_DIR
from table import print_table

from animlod.io.gltf_drawable import read_document_drawables
from animlod.motion_lod import analyze_motion, build_motion_chain
from animlod.motion_lod.clips import join_clips
from animlod.motion_lod.skin_tips import measured_by_tips, with_skin_tips, without_skin_tips
from animlod.motion_lod.skin_transfer import transfer_skin

CASTLE = Path("/usr/share/doc/castle-game-engine-doc/examples")
LEVELS = 4


def characters() -> list[Path]:
    """Skinned glTF files of the dev data and the Castle examples, each distinct file once."""
    found = sorted(DATA_DIR.glob("gltf/*.gl*")) + sorted(CASTLE.glob("**/*.gltf"))
    seen, result = set(), []
    for path in found:
        data = path.read_bytes()
        digest = hashlib.sha256(data).hexdigest()
        if digest not in seen and b'"skins"' in data:
            seen.add(digest)
            result.append(path)
    return result


def skin_errors(path: Path) -> list[list[object]]:
    _, drawables = read_document_drawables(path)
    drawables = [d for d in drawables if d.skinned is not None and any(c.motion is not None for c in d.clips)]
    if not drawables:
        return []
    drawable = max(drawables, key=lambda d: d.skinned.vertex_count)
    clips = [clip for clip in drawable.clips if clip.motion is not None]
    joined, spans = join_clips([clip.motion for clip in clips])
    if joined.deforming_joint() is not None:
        return []
    skin = drawable.skinned
    diagonal = float(np.linalg.norm(np.ptp(skin.rest_pose(), axis=0)))
    originals = [skin.bake(clip.motion).frames for clip in clips]
    measured = {}  # tips -> [(joints, max %, mean %) per level]
    seconds = {}  # tips -> CPU seconds of the analysis and the chain, on one thread
    for tips in (False, True):
        started = time.process_time()
        motion = with_skin_tips(joined, [skin]) if tips else joined
        analysis = analyze_motion(motion, clips=spans, workers=1)
        try:
            if tips:
                chain = without_skin_tips(
                    build_motion_chain(motion, LEVELS, analysis=measured_by_tips(analysis, joined), workers=1), joined
                )
            else:
                chain = build_motion_chain(motion, LEVELS, analysis=analysis, workers=1)
        except ValueError:  # fewer joints can freeze than LEVELS levels need
            return []
        seconds[tips] = time.process_time() - started
        measured[tips] = []
        for level in chain.levels[1:]:
            reduced = transfer_skin(skin, level.frozen)
            distances = np.concatenate([
                np.linalg.norm(reduced.bake(level.motion.take_frames(span)).frames - original, axis=-1).ravel()
                for original, span in zip(originals, spans)
            ]) * (100 / diagonal)  # fmt: skip
            measured[tips].append((level.report.joint_count, float(distances.max()), float(distances.mean())))
    label = path.name if path.is_relative_to(DATA_DIR) else str(path.relative_to(CASTLE))
    rows = [
        [label, index, tipped[0], bare[1], tipped[1], bare[2], tipped[2], "", ""]
        for index, (bare, tipped) in enumerate(zip(measured[False], measured[True]), start=1)
    ]
    rows[0][-2:] = [seconds[False], seconds[True]]
    return rows


def main() -> None:
    rows = []
    for path in characters():
        rows += skin_errors(path)
    columns = ["file", "level", "joints", "max %, bare", "max %, tips", "mean %, bare", "mean %, tips",
               "CPU s, bare", "CPU s, tips"]  # fmt: skip
    print_table("Motion levels: skin distance with and without skin tips", columns, rows)


if __name__ == "__main__":
    main()
