"""An OBJ sequence's materials (``mtllib``, ``usemtl``) reach every level `simplify` writes: each
level face keeps the material of the input faces it comes from, borders between materials are
kept as seams, as a glTF primitive's are, and the levels name the input's .mtl file where it is.
They were dropped without a word, and a textured scan's levels came out untextured."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from simplify_inputs import twisting_cylinder

from animlod.cli import main
from animlod.io.obj import read_obj_textured


def _two_material_sequence(folder: Path) -> float:
    """The twisting cylinder as OBJ frames in ``folder``, its lower half 'skin' and its upper half
    'cloth' (by the faces' height at rest), with ``mtllib ../lib/body.mtl``; the height between
    them."""
    rest, twisted = twisting_cylinder()
    heights = rest.frames[0][:, 1]
    rings = np.unique(heights)
    middle = float(rings[len(rings) // 2])  # a ring of vertices: the border between the materials
    upper = rest.frames[0][rest.faces, 1].mean(axis=1) > middle
    order = np.argsort(upper, kind="stable")  # the faces in runs of one material, as exporters write them
    folder.mkdir(parents=True)
    (folder.parent / "lib").mkdir()
    (folder.parent / "lib" / "body.mtl").write_text("newmtl skin\nKd 1 0.8 0.7\nnewmtl cloth\nKd 0.2 0.2 0.8\n")
    for index, frame in enumerate(twisted):
        lines = ["mtllib ../lib/body.mtl\n", *(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in frame)]
        for material, faces in (("skin", rest.faces[order][~upper[order]]), ("cloth", rest.faces[order][upper[order]])):
            lines += [f"usemtl {material}\n", *(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)]
        (folder / f"shot_{index}.obj").write_text("".join(lines))
    return middle


def test_an_obj_sequences_materials_reach_every_level(tmp_path, capsys):
    middle = _two_material_sequence(tmp_path / "in" / "shot")
    assert main(["info", str(tmp_path / "in" / "shot")]) == 0
    assert "materials: skin, cloth from ../lib/body.mtl" in capsys.readouterr().out
    for source in ("shot", "shot/shot_0.obj"):  # a sequence, and one mesh file
        assert main(["simplify", str(tmp_path / "in" / source), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    assert "not read" not in capsys.readouterr().err
    rest = read_obj_textured(tmp_path / "in" / "shot" / "shot_0.obj")
    for level in (1, 2, 3):
        for path in (tmp_path / "out" / f"shot_lod{level}" / "shot_0.obj", tmp_path / "out" / f"shot_0_lod{level}.obj"):
            mesh = read_obj_textured(path)
            (library,) = mesh.materials.libraries
            assert os.path.samefile(path.parent / library, tmp_path / "in" / "lib" / "body.mtl")
            assert set(mesh.materials.names) == {"skin", "cloth"}
            assert len(mesh.faces) < len(rest.faces)
            # The border between the materials is a seam: every face stays on its side of it, and
            # its points are written once (one v line each, used by the faces of both).
            named = np.array(mesh.materials.names)[mesh.materials.faces]
            lowest, highest = mesh.vertices[mesh.faces, 1].min(axis=1), mesh.vertices[mesh.faces, 1].max(axis=1)
            assert lowest[named == "cloth"].min() >= middle - 1e-6 and highest[named == "skin"].max() <= middle + 1e-6
            assert len(np.unique(mesh.vertices, axis=0)) == len(mesh.vertices)
