"""Every command on every model of assimp's test set (Debian's assimp-testmodels, which
scripts/install_system_packages.sh installs; skipped cleanly when absent): real exports and
deliberately broken files from other tools, glTF 1.0 and 2.0, BVH, OBJ and PLY. Each run ends in
data (exit 0) or one error line naming the file (exit 2), never a traceback; the gltfpack
variants (quantized, meshopt-compressed) of its skinned and morphed glTFs read as the originals;
and assimp's own glTF exports of its characters in other formats go through."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from gltf_conformance import added_problems

from animlod.cli import main
from animlod.io.detect import assets_in
from animlod.io.gltf_document import GltfDocument
from animlod.io.gltf_drawable import read_drawables
from animlod.io.obj import read_obj

MODELS = Path("/usr/share/assimp/models")
SUFFIXES = (".glb", ".gltf", ".bvh", ".obj", ".ply")
FILES = sorted(p for p in MODELS.rglob("*") if p.suffix.lower() in SUFFIXES) if MODELS.is_dir() else []
ERROR_LINE = re.compile(r"^animlod (\w+): error: (\S[^:]*): (.+)$")

# Skinned and morphed: gltfpack rewrites their inverse bind matrices and morph deltas too.
PACKED = [
    "glTF2/simple_skin/simple_skin.gltf",
    "glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf",
]
needs_models = pytest.mark.skipif(not FILES, reason=f"assimp's test models not found at {MODELS}")


def _run(argv: list[str], capfd) -> tuple[int, str, str]:
    capfd.readouterr()
    code = main(argv)
    captured = capfd.readouterr()
    return code, captured.out, captured.err


def _command(path: Path, out: Path) -> list[str]:
    if path.suffix.lower() == ".bvh":
        return ["motion", str(path), "-o", str(out / "motion"), "--levels", "3"]
    return [
        "simplify",
        str(path),
        "-o",
        str(out / ("levels.glb" if path.suffix.lower() in (".glb", ".gltf") else "levels")),
    ]


@needs_models
@pytest.mark.parametrize("path", FILES, ids=[str(p.relative_to(MODELS)) for p in FILES] if FILES else None)
def test_every_command_ends_in_data_or_one_error_line(path: Path, tmp_path: Path, capfd) -> None:
    for argv in (["info", str(path)], _command(path, tmp_path)):
        code, _, err = _run(argv, capfd)
        assert "Traceback" not in err
        assert code in (0, 2), err
        if code == 2:
            lines = err.splitlines()
            assert len(lines) == 1, err
            match = ERROR_LINE.match(lines[0])
            assert match and match.group(1) == argv[0] and match.group(2) == str(path), lines[0]
    levels = tmp_path / "levels.glb"
    if levels.exists():  # what it wrote breaks no rule of glTF's that the input kept
        assert added_problems(path, levels) == []


def _model(relative: str) -> Path:
    path = MODELS / relative
    if not path.exists():
        pytest.skip(f"{path} not found")
    return path


def test_a_motion_table_one_row_longer_than_its_frame_count_is_read_whole(tmp_path: Path, capfd) -> None:
    path = _model("BVH/Boxing_Toes.bvh")  # Frames: 3069 above 3070 rows
    code, out, err = _run(["motion", str(path), "-o", str(tmp_path), "--levels", "3"], capfd)
    assert code == 0, err
    assert "Frames: says 3069 but the MOTION table has 3070 rows; read all 3070" in err


def test_blender_24_ply_with_an_unmarked_comment_is_read(tmp_path: Path, capfd) -> None:
    path = _model("PLY/Wuson.ply")
    code, out, err = _run(["simplify", str(path), "-o", str(tmp_path / "levels")], capfd)
    assert code == 0, err
    assert "header line 3: skipped 'Created by Blender3D 247" in err


@pytest.mark.parametrize(
    ("relative", "reason"),
    [
        ("glTF/TwoBoxes/TwoBoxes.gltf", "asset: glTF version '1.0' is not 2.x; convert it to glTF 2.0 first"),
        ("glTF/BoxTextured-glTF-Binary/BoxTextured.glb", "GLB header: container version 1 is not 2: a glTF 1.0"),
    ],
)
def test_gltf_1_files_are_named_as_such(relative: str, reason: str, capfd) -> None:
    path = _model(relative)
    code, _, err = _run(["info", str(path)], capfd)
    assert code == 2 and f"{path}: {reason}" in err


@pytest.mark.skipif(shutil.which("gltfpack") is None, reason="gltfpack not installed")
@pytest.mark.parametrize("relative", PACKED)
@pytest.mark.parametrize("flags", [["-noq"], [], ["-c"], ["-cc"], ["-vpn"]], ids=["noq", "quantized", "c", "cc", "vpn"])
def test_gltfpack_output_reads_as_its_input(relative: str, flags: list[str], tmp_path: Path, capfd) -> None:
    path = _model(relative)
    packed = tmp_path / "packed.glb"
    subprocess.run(["gltfpack", "-i", str(path), "-o", str(packed), *flags], check=True, capture_output=True)
    original, repacked = _corners(path), _corners(packed)
    assert len(original) == len(repacked)
    for before, after in zip(original, repacked):
        # gltfpack reorders and deduplicates vertices and quantizes positions to 14 bits of the
        # mesh's extent (folding the scale into the node or the inverse bind matrices): the
        # triangles' corners, in world space and sorted, agree to that grid.
        grid = 2.0**-13 * np.ptp(before, axis=0).max()
        assert before.shape == after.shape
        assert np.abs(before - after).max() <= grid
    code, _, err = _run(["simplify", str(packed), "-o", str(tmp_path / "levels.glb")], capfd)
    assert code == 0, err
    assert added_problems(packed, tmp_path / "levels.glb") == []


def _corners(path: Path) -> list[np.ndarray]:
    """Each drawable's triangle corners in world space (a skinned one's bind pose), sorted."""
    corners = []
    for drawable in read_drawables(GltfDocument(path)):
        if drawable.skinned is not None:
            positions, faces = drawable.skinned.rest_positions.astype(np.float64), drawable.skinned.faces
        else:
            geometry = drawable.geometry
            world = drawable.world
            positions = geometry.positions @ world[:3, :3].T + world[:3, 3] + drawable.placement
            faces = geometry.faces
        corners.append(np.sort(positions[faces].reshape(-1, 3), axis=0))
    return corners


def test_utf16_obj_reads_as_its_utf8_twin() -> None:
    wide, plain = read_obj(_model("OBJ/box_UTF16BE.obj")), read_obj(_model("OBJ/box.obj"))
    np.testing.assert_array_equal(wide[0], plain[0])
    np.testing.assert_array_equal(wide[1], plain[1])


def test_a_folder_of_assimp_meshes_is_a_library_of_them(tmp_path: Path) -> None:
    folder = _model("OBJ")
    assets = list(assets_in(folder))
    assert folder not in assets and _model("OBJ/spider.obj") in assets


# assimp's own glTF exporter (Debian's assimp-utils) on models of its test set: real exports of
# characters from other formats, with the quirks of that exporter (each fixed here once).
EXPORTS = [
    ("X/BCN_Epileptic.X", "character", None),
    ("FBX/huesitos.fbx", "character", None),
    ("ASE/MotionCaptureROM.ase", "motion", None),  # 3ds Max's Biped scale noise: shears of 2e-4
    ("OBJ/box_mat_with_spaces.obj", "simplify", "not UTF-8 text"),  # a material name in Latin-1
    ("Collada/cube_with_2UVs.DAE", "simplify", "TEXCOORD_0: VEC3"),
    ("OBJ/spider.obj", "simplify", "the output refers to where the input's '.\\\\drkwood2.jpg' does"),
]


@pytest.mark.skipif(shutil.which("assimp") is None, reason="assimp's command line tool not installed")
@pytest.mark.parametrize(("relative", "command", "warning"), EXPORTS, ids=[e[0] for e in EXPORTS])
def test_assimp_gltf_exports_go_through(
    relative: str, command: str, warning: str | None, tmp_path: Path, capfd
) -> None:
    exported = tmp_path / "exported.glb"
    subprocess.run(
        ["assimp", "export", str(_model(relative)), str(exported), "-fglb2"], check=True, capture_output=True
    )
    out = tmp_path / ("out.glb" if command != "motion" else "out")
    code, _, err = _run([command, str(exported), "-o", str(out)], capfd)
    assert code == 0, err
    assert warning is None or warning in err, err
    if out.suffix == ".glb":
        assert added_problems(exported, out) == []
