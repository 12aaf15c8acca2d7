"""Motion levels of skinned glTF characters measured on the bare skeleton and as the skin sees it
(motion_lod/skin_measure.py: skinned leaf joints by points of their skin, joints that move no skin
not at all).

Run: ``.venv/bin/python bench/bench_skin_measure.py`` (part of ``make bench``). For every skinned,
animated glTF of ../shared/data/gltf and of Castle Game Engine's examples (Debian's
castle-game-engine-doc, Blender exports whose leaf joints carry skin; each distinct file once),
the largest mesh's motion levels as ``animlod character`` builds them (every clip as one motion,
4 levels, the default ranking and solver), once on the bare skeleton and once as the skin sees
it (the default). Per level: joints, and the skin's distance to the input over every frame of
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
from animlod.motion_lod.skin_measure import analyze_skinned_motion, without_skin_tips
from animlod.motion_lod.skin_transfer import transfer_skin
from animlod.pipelines.attachments import find_attachments

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
    doc, drawables = read_document_drawables(path)
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
    measured = {}  # skin-measured -> [(joints, max %, mean %) per level]
    seconds = {}  # skin-measured -> CPU seconds of the analysis and the chain, on one thread
    for by_skin in (False, True):
        started = time.process_time()
        if by_skin:
            attached = [attachment.joint for attachment in find_attachments(doc, drawable.rig)]
            motion, analysis = analyze_skinned_motion(joined, [skin], attached, clips=spans, workers=1)
        else:
            motion, analysis = joined, analyze_motion(joined, clips=spans, workers=1)
        try:
            chain = build_motion_chain(motion, LEVELS, analysis=analysis, workers=1)
            if by_skin:
                chain = without_skin_tips(chain, joined)
        except ValueError:  # fewer joints can freeze than LEVELS levels need
            return []
        seconds[by_skin] = time.process_time() - started
        measured[by_skin] = []
        for level in chain.levels[1:]:
            reduced = transfer_skin(skin, level.frozen)
            distances = np.concatenate([
                np.linalg.norm(reduced.bake(level.motion.take_frames(span)).frames - original, axis=-1).ravel()
                for original, span in zip(originals, spans)
            ]) * (100 / diagonal)  # fmt: skip
            measured[by_skin].append((level.report.joint_count, float(distances.max()), float(distances.mean())))
    label = path.name if path.is_relative_to(DATA_DIR) else str(path.relative_to(CASTLE))
    rows = [
        [label, index, bare[0], skin[0], bare[1], skin[1], bare[2], skin[2], "", ""]
        for index, (bare, skin) in enumerate(zip(measured[False], measured[True]), start=1)
    ]
    rows[0][-2:] = [seconds[False], seconds[True]]
    return rows


def main() -> None:
    rows = []
    for path in characters():
        rows += skin_errors(path)
    columns = ["file", "level", "joints, bare", "joints, skin", "max %, bare", "max %, skin",
               "mean %, bare", "mean %, skin", "CPU s, bare", "CPU s, skin"]  # fmt: skip
    print_table("Motion levels: skin distance, bare skeleton against skin-measured", columns, rows)


if __name__ == "__main__":
    main()
