"""Motion levels of skinned glTF characters measured on the bare skeleton and as the skin sees it
(motion_lod/skin_measure.py: skinned leaf joints by points of their skin, joints that move no skin
not at all).

Run: ``.venv/bin/python bench/bench_skin_measure.py`` (part of ``make bench``). For every skinned,
animated glTF of ../shared/data/gltf and of Castle Game Engine's examples (Debian's
castle-game-engine-doc, Blender exports whose leaf joints carry skin; each distinct file once),
the largest mesh's motion levels as ``animlod character`` builds them (every clip as one motion,
4 levels, the default ranking and solver; on that mesh's skin alone, where ``character`` also
counts the parts that play the same levels, Soldier's visor), on the bare skeleton, as the skin sees it with the
ranking's trial re-fits scored by the joints' mean error, and as the skin sees it with the trials
scored by the skin's mean distance (the default; VARIANTS). Per level: joints, and the skin's
distance to the input over every frame of every clip (the level's reduced skin played with its
re-fitted clips, geometry untouched), max and mean over vertices and frames, relative to the rest
pose's diagonal; and the CPU seconds of the analysis and the chain on one thread (on the file's
first row).
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
# The bare skeleton (the paper's measures); measured as the skin sees it but with the refit
# ranking's trials scored by the joints' mean error; and the default, trials scored by the skin's.
VARIANTS = ("bare", "joint-scored", "skin")


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
    measured = {}  # variant -> [(joints, max %, mean %) per level]
    seconds = {}  # variant -> CPU seconds of the analysis and the chain, on one thread
    for variant in VARIANTS:
        started = time.process_time()
        if variant == "bare":
            motion, analysis, measure = joined, analyze_motion(joined, clips=spans, workers=1), None
        else:
            attached = [attachment.joint for attachment in find_attachments(doc, drawable.rig)]
            motion, analysis, measure = analyze_skinned_motion(joined, [skin], attached, clips=spans, workers=1)
            if variant == "joint-scored":
                measure = None
        try:
            chain = build_motion_chain(motion, LEVELS, analysis=analysis, workers=1, trial_measure=measure)
            if variant != "bare":
                chain = without_skin_tips(chain, joined)
        except ValueError:  # fewer joints can freeze than LEVELS levels need
            return []
        seconds[variant] = time.process_time() - started
        measured[variant] = []
        for level in chain.levels[1:]:
            reduced = transfer_skin(skin, level.frozen)
            distances = np.concatenate([
                np.linalg.norm(reduced.bake(level.motion.take_frames(span)).frames - original, axis=-1).ravel()
                for original, span in zip(originals, spans)
            ]) * (100 / diagonal)  # fmt: skip
            measured[variant].append((level.report.joint_count, float(distances.max()), float(distances.mean())))
    label = path.name if path.is_relative_to(DATA_DIR) else str(path.relative_to(CASTLE))
    rows = []
    for index, per_variant in enumerate(zip(*(measured[v] for v in VARIANTS)), start=1):
        joints, maxima, means = zip(*per_variant)
        rows.append([label, index, joints[0], joints[-1], *maxima, *means] + [""] * len(VARIANTS))
    rows[0][-len(VARIANTS) :] = [seconds[v] for v in VARIANTS]
    return rows


def main() -> None:
    rows = []
    for path in characters():
        rows += skin_errors(path)
    columns = ["file", "level", "joints, bare", "joints, skin"]
    for quantity in ("max %", "mean %", "CPU s"):
        columns += [f"{quantity}, {variant}" for variant in VARIANTS]
    print_table("Motion levels: skin distance, bare skeleton against skin-measured", columns, rows)


if __name__ == "__main__":
    main()
