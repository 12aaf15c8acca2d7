"""Every command on the glTF models of Castle Game Engine's examples (Debian's
castle-game-engine-doc, which scripts/install_system_packages.sh installs; skipped cleanly when
absent): Blender exports of skinned, animated characters whose leaf joints carry skin and whose
unweighted vertices have all-zero weights, levels and props. Each distinct file once."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest
from gltf_conformance import added_problems

from animlod.cli import main
from animlod.pipelines.motion import build_motion_levels

EXAMPLES = Path("/usr/share/doc/castle-game-engine-doc/examples")


def _distinct(paths: list[Path]) -> list[Path]:
    seen: dict[str, Path] = {}
    for path in paths:
        seen.setdefault(hashlib.sha256(path.read_bytes()).hexdigest(), path)
    return list(seen.values())


FILES = _distinct(sorted(EXAMPLES.rglob("*.gl[tb]*"))) if EXAMPLES.is_dir() else []
SKINNED = [path for path in FILES if b'"skins"' in path.read_bytes()]
needs_examples = pytest.mark.skipif(not FILES, reason=f"Castle Game Engine's examples not found at {EXAMPLES}")


def _ids(paths: list[Path]) -> list[str] | None:
    return [str(p.relative_to(EXAMPLES)) for p in paths] if paths else None


@needs_examples
@pytest.mark.parametrize("path", FILES, ids=_ids(FILES))
def test_every_model_is_described_and_simplified(path: Path, tmp_path: Path, capfd) -> None:
    assert main(["info", str(path)]) == 0
    assert main(["simplify", str(path), "-o", str(tmp_path / "levels.glb")]) == 0
    assert "Traceback" not in capfd.readouterr().err
    assert added_problems(path, tmp_path / "levels.glb") == []


@needs_examples
@pytest.mark.parametrize("path", SKINNED, ids=_ids(SKINNED))
def test_every_skinned_model_builds_its_character_chain(path: Path, tmp_path: Path, capfd) -> None:
    assert main(["character", str(path), "-o", str(tmp_path / "character.glb")]) == 0
    assert "Traceback" not in capfd.readouterr().err
    assert added_problems(path, tmp_path / "character.glb") == []


@needs_examples
def test_unweighted_vertices_of_a_blender_export_follow_their_first_joint(tmp_path: Path, capfd) -> None:
    soldier = EXAMPLES / "third_person_navigation/data/enemy/soldier1.gltf"
    assert main(["simplify", str(soldier), "-o", str(tmp_path / "levels.glb")]) == 0
    err = capfd.readouterr().err
    assert "mesh 0 WEIGHTS: 174 of 9432 vertices (first: 1518) have no positive skin weight" in err


@needs_examples
def test_the_knight_keeps_its_head_and_drops_its_ik_controls_first(tmp_path: Path) -> None:
    # 'skull' is a leaf joint carrying the whole head: measured by its skin's points, it stays;
    # on the bare skeleton it froze first. Its 18 IK targets and controls move no skin: they
    # freeze first, the 6 translating ones too, so the coarsest level keeps 7 joints, not 13.
    knight = EXAMPLES / "fps_game/data/knight_creature/knight.gltf"
    report = build_motion_levels(knight, tmp_path / "levels", levels=4)
    first = report.chain.levels[1].report
    assert first.joint_count == 34 and not {"skull", "sword_casing", "toes_l", "toes_r"} & set(first.frozen)
    assert {"knee_pole_l", "foot_ctrl_l", "hand_ik_l", "arm_pole_r"} <= set(first.frozen)
    assert first.max_error < 1e-3 * report.chain.figure_size
    assert report.floor.fewest == 7 and report.chain.levels[-1].report.joint_count == 7
    assert any("18 joints move no skin (knee_pole_l, knee_pole_r, " in note for note in report.notes)
