"""Clip names become parts of `animlod motion`'s BVH file names (``<stem>_lod<i>_<clip>.bvh``):
a glTF whose animations had long names (Blender allows names of 253 bytes) failed with "File
name too long" when the first level was written. The names are now cut
to fit, between characters, with a hash of the whole name to keep them apart (pipelines/motion.py)."""

from __future__ import annotations

import os

from animlod import synth
from animlod.cli import main
from animlod.io import write_glb
from animlod.pipelines.motion import _clip_suffixes

WALK, RUN = "歩" * 84 + "x", "歩" * 84 + "y"  # 253 bytes each, alike up to the last character


def test_motion_writes_clips_of_long_names_to_distinct_files_that_fit(tmp_path, capsys):
    character = synth.humanoid()
    clips = [synth.humanoid_motion(character.skeleton, kind, cycles=1) for kind in ("walk", "run")]
    source = tmp_path / "hero.glb"
    write_glb(source, character, clips, names=[WALK, RUN])
    assert main(["motion", str(source), "-o", str(tmp_path / "levels"), "--levels", "3"]) == 0
    assert "error" not in capsys.readouterr().err
    names = sorted(os.listdir(tmp_path / "levels"))
    clip_files = [name for name in names if name.endswith(".bvh")]
    assert len(clip_files) == 6 and len(set(clip_files)) == 6
    # Fit with the temporary name the atomic write gives each file beside it (".NAME.animlod-PID-XXXXXXXX.part").
    assert all(len(name.encode()) <= 224 for name in names), [len(name.encode()) for name in names]
    for index in range(3):
        mine = [name for name in clip_files if name.startswith(f"hero_lod{index}_歩歩")]
        assert len(mine) == 2, clip_files


def test_short_names_keep_their_suffixes_and_long_ones_are_cut_between_characters():
    assert _clip_suffixes(["Walk"]) == [""]
    assert _clip_suffixes(["Armature|Walk", "Run", "Run"]) == ["_Armature_Walk", "_Run_1", "_Run_2"]
    suffixes = _clip_suffixes([WALK, WALK, "é" * 300, "Run"], room=40)
    assert [len(suffix.encode()) <= 40 for suffix in suffixes] == [True] * 4 and len(set(suffixes)) == 4
    assert suffixes[0].endswith("_0") and suffixes[1].endswith("_1") and suffixes[0][:-2] == suffixes[1][:-2]
    assert suffixes[3] == "_Run" and suffixes[2].startswith("_éé") and len(suffixes[2].encode()) in (39, 40)
    assert _clip_suffixes([WALK, RUN], room=40) == _clip_suffixes([WALK, RUN], room=40)  # the same each run
