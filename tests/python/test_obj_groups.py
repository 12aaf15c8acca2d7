"""An OBJ file's objects and groups (``o`` and ``g`` lines: Blender writes one ``o`` per object)
are not kept apart in what animlod reads: three objects become one unnamed mesh. They were
dropped without a word; now a file whose faces fall into several is read with an
:class:`UnreadAttributesWarning` naming how many, once for a sequence (io/obj.py)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from simplify_inputs import twisting_cylinder

from animlod.cli import main
from animlod.io.errors import UnreadAttributesWarning
from animlod.io.obj import read_obj, read_obj_textured

QUAD = "v 0 0 {z}\nv 1 0 {z}\nv 1 1 {z}\nv 0 1 {z}\nf -4 -3 -2\nf -4 -2 -1\n"


def _read(path: Path, reader) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        reader(path)
    return [str(w.message) for w in caught if issubclass(w.category, UnreadAttributesWarning)]


@pytest.mark.parametrize("reader", [read_obj, read_obj_textured])
@pytest.mark.parametrize(
    ("text", "said"),
    [
        (f"o Body\n{QUAD.format(z=0)}o Hat\n{QUAD.format(z=1)}o Boots\n{QUAD.format(z=2)}", "3 objects (o lines)"),
        # Blender's "object groups" and "material groups": an object's faces in groups of their own.
        (f"o Body\ng Body_skin\n{QUAD.format(z=0)}g Body_cloth\n{QUAD.format(z=1)}o Hat\ng Hat_felt\n"
         f"{QUAD.format(z=2)}", "2 objects (o lines) and 3 groups (g lines)"),
        (f"g a\n{QUAD.format(z=0)}g b\n{QUAD.format(z=1)}g a\n{QUAD.format(z=2)}", "2 groups (g lines)"),
    ],
)  # fmt: skip
def test_faces_in_several_objects_or_groups_are_said_to_lose_them(tmp_path, reader, text, said):
    path = tmp_path / "parts.obj"
    path.write_text(text)
    (message,) = _read(path, reader)
    assert message == (f"{path}: its faces fall into {said}, whose names are not read: the levels are written "
                       "as one mesh without them")  # fmt: skip


@pytest.mark.parametrize(
    "text",
    [
        QUAD.format(z=0) + QUAD.format(z=1),  # no o or g line
        "o Cube\n" + QUAD.format(z=0) + QUAD.format(z=1),  # one object: only its name goes, the file names the levels
        "o Cube\ng Cube_Material\n" + QUAD.format(z=0),
        "g default\n" + QUAD.format(z=0).replace("f", "#f") + "g pCube1\n" + QUAD.format(z=0),  # Maya's empty default
    ],
)
def test_a_file_of_one_object_is_read_without_a_word(tmp_path, text):
    path = tmp_path / "cube.obj"
    path.write_text(text)
    assert _read(path, read_obj) == [] and _read(path, read_obj_textured) == []


def test_a_sequence_of_three_objects_says_so_once(tmp_path, capsys):
    rest, twisted = twisting_cylinder()
    heights = rest.frames[0][rest.faces, 1].mean(axis=1)
    parts = np.digitize(heights, np.quantile(heights, [1 / 3, 2 / 3]))
    folder = tmp_path / "shot"
    folder.mkdir()
    for index, frame in enumerate(twisted):
        lines = [f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in frame]
        for part, name in enumerate(("Legs", "Body", "Head")):
            lines += [f"o {name}\n", *(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in rest.faces[parts == part])]
        (folder / f"shot_{index}.obj").write_text("".join(lines))
    assert main(["simplify", str(folder), "-o", str(tmp_path / "out"), "--no-metrics"]) == 0
    err = capsys.readouterr().err
    assert err.count("whose names are not read") == 1 and "shot_0.obj: its faces fall into 3 objects (o lines)" in err
