"""`animlod batch` over the folders of earlier runs: an asset rebuilt where earlier assets lie
nested in its folder keeps them, a library that is its own output folder is not read back, and
option values are refused before anything runs (LocalCluster with 1 worker, tiny NPZ inputs)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from animlod import synth
from animlod.batch import SpecError, read_spec, run_batch
from animlod.cli import main
from animlod.io import write_glb
from animlod.io.detect import ASSET_RECORD
from animlod.io.meshseq import write_sequence
from animlod.io.npz import write_npz


def _bar(path: Path, rings: int = 10) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    write_npz(path, synth.twisting_bar(frames=4, rings=rings, segments=8))
    return path


def _files(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (relative POSIX path -> bytes), records included."""
    return {path.relative_to(folder).as_posix(): path.read_bytes() for path in folder.rglob("*") if path.is_file()}


def _names(folder: Path) -> list[str]:
    return sorted(path.name for path in folder.iterdir())


def test_a_rebuilt_asset_keeps_the_earlier_assets_nested_in_its_folder(client, tmp_path):
    # Run 1 builds hero/run from lib/hero/run.npz; run 2 builds hero from lib/hero.npz. Publishing
    # hero renamed OUT/hero aside and removed it, hero/run's folder with it.
    lib, out = tmp_path / "lib", tmp_path / "out"
    _bar(lib / "hero" / "run.npz")
    assert run_batch(read_spec(lib), out, client=client).failed == 0
    nested = _files(out / "hero" / "run")
    assert ASSET_RECORD in nested

    _bar(lib / "hero.npz", rings=12)
    second = run_batch(read_spec(f"{lib}/*.npz", options={"ratios": [0.5, 0.25]}), out, client=client)
    assert (second.ran, second.failed) == (1, 0)
    assert _files(out / "hero" / "run") == nested
    assert _names(out / "hero") == [ASSET_RECORD, "hero_lod1.npz", "hero_lod2.npz", "run"]
    assert any("earlier runs not in this batch (hero/run)" in note for note in second.notes), second.notes

    # Rebuilt with fewer levels: its own older level goes, the nested asset stays.
    third = run_batch(read_spec(f"{lib}/*.npz", options={"ratios": [0.3]}), out, client=client)
    assert (third.ran, third.failed) == (1, 0)
    assert _names(out / "hero") == [ASSET_RECORD, "hero_lod1.npz", "run"]
    assert _files(out / "hero" / "run") == nested


def test_an_asset_whose_file_would_replace_another_assets_folder_fails_and_removes_nothing(client, tmp_path):
    source = _bar(tmp_path / "lib" / "bar.npz")
    out, manifest = tmp_path / "out", tmp_path / "assets.json"

    def run(name: str) -> dict:
        manifest.write_text(json.dumps({"assets": [{"input": str(source), "name": name, "ratios": [0.5]}]}))
        (record,) = run_batch(read_spec(manifest), out, client=client).records
        return record

    nested = out / "bar" / "bar_lod1.npz"
    assert run("bar/bar_lod1.npz")["status"] == "ok"
    earlier = _files(out / "bar")
    # Asset "bar" would write its level bar_lod1.npz where that asset's folder is.
    failed = run("bar")
    assert failed["status"] == "failed" and failed["error"]["file"] == str(nested)
    assert "is another asset's folder, where asset 'bar' writes its output bar_lod1.npz" in failed["error"]["reason"]
    # The earlier asset's level file is where this asset needs a folder.
    failed = run("bar/bar_lod1.npz/bar_lod1.npz/x")
    assert failed["status"] == "failed" and failed["error"]["file"] == str(nested / "bar_lod1.npz")
    assert "is a file where the outputs of asset" in failed["error"]["reason"]
    assert _files(out / "bar") == earlier


def test_a_library_that_is_its_own_output_folder_is_not_read_back(client, tmp_path):
    # `animlod batch LIB -o LIB`: the rerun took LIB/bar/bar_lod1.npz as a new asset (and renamed
    # the real one bar_npz), and the frames folder's levels as frames of their own; the frames
    # folder is the seq asset's output folder too, which publishing replaced, frames and all.
    lib = tmp_path / "lib"
    _bar(lib / "bar.npz")
    _bar(lib / "hero" / "run.npz", rings=12)
    write_sequence(lib / "seq", synth.bending_cylinder(frames=3, rings=6, segments=6))
    inputs = _files(lib)
    names = sorted(asset.name for asset in read_spec(lib))
    assert names == ["bar", "hero/run", "seq"]

    first = run_batch(read_spec(lib), lib, client=client)
    assert (first.ran, first.failed) == (3, 0)
    assert (lib / "seq" / "seq_lod1").is_dir()  # a frames folder's levels sit beside its frames
    assert sorted(asset.name for asset in read_spec(lib)) == names
    second = run_batch(read_spec(lib), lib, client=client)
    assert (second.ran, second.skipped, second.failed) == (0, 3, 0)
    assert {name: data for name, data in _files(lib).items() if name in inputs} == inputs

    # A record that cannot be read: the whole folder may be outputs, and none is read.
    (lib / "bar" / ASSET_RECORD).write_text("{")
    assert sorted(asset.name for asset in read_spec(lib)) == names


@pytest.fixture(scope="module")
def gltf_library(tmp_path_factory) -> Path:
    lib = tmp_path_factory.mktemp("gltf_library")
    skin, motion = synth.bending_cylinder_skinned(frames=4, rings=6, segments=6)
    write_glb(lib / "cyl.glb", skin, [motion])
    return lib


@pytest.mark.parametrize(
    "option, message",
    [
        ("placement=bogus", "AqemOptions.placement: expected one of 'optimal', 'on_edge', got 'bogus'"),
        ("ratios=[1.5]", "target_ratios: 1.500000 outside (0, 1]"),
        ("ratios=[]", "target_ratios: no level requested"),
        ("max_error=-1", "max_error: must be >= 0"),
        ("viewport_px=0", "viewport_px: must be a positive number, got 0"),
        ("pixel_error=-1", "pixel_error: must be a positive number, got -1"),
        ("fps=0", "fps: must be a positive number, got 0"),
        ("frame_budget=0", "frame_budget: must be a whole number of at least 1, got 0"),
        ("joint_map=map.json", "--set.joint_map: no asset's job takes this option"),
    ],
)
def test_a_bad_option_value_is_one_line_exit_2_before_anything_runs(gltf_library, tmp_path, capsys, option, message):
    out = tmp_path / "out"
    assert main(["batch", str(gltf_library), "-o", str(out), "--set", option]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and message in err, err
    assert not out.exists()  # refused before the output folder, or a cluster, was made


@pytest.mark.parametrize(
    "job, option, message",
    [
        ("motion", "max_frames=1", "max_frames: must be at least 2, got 1"),
        ("motion", "ranking=bogus", "ranking: no ranking named 'bogus'"),
        ("motion", "weights=[0,1,1]", "weights: distance must be positive"),
        ("motion", "levels=0", "levels: must be at least 1, got 0"),
        ("face", "repeats=0", "repeats: must be at least 1, got 0"),
        ("face", "ratios=[1.5]", "target_ratios: 1.500000 outside (0, 1]"),
    ],
)
def test_motion_and_face_values_are_checked_before_anything_runs(gltf_library, tmp_path, capsys, job, option, message):
    # They used to fail each asset as it ran (exit 1, an output folder made); face's repeats=0 ran.
    out = tmp_path / "out"
    assert main(["batch", str(gltf_library), "-o", str(out), "--job", job, "--set", option]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and message in err, err
    assert not out.exists()


def test_option_values_are_checked_for_every_job_that_takes_them(gltf_library, tmp_path):
    bar = _bar(tmp_path / "bar.npz")
    with pytest.raises(SpecError, match=r"target_ratios: 1\.500000 outside \(0, 1\]"):
        read_spec(bar, options={"ratios": [1.5]})
    with pytest.raises(SpecError, match="fps: must be a positive number"):
        read_spec(gltf_library / "cyl.glb", job="character", options={"fps": 0})
    assert read_spec(bar, options={"ratios": [0.5, 0.7], "max_error": 0.0, "placement": "on_edge"})
    good = {"ratios": [0.5], "fps": 24, "frame_budget": 1, "viewport_px": 720, "pixel_error": 0.5}
    assert read_spec(gltf_library, options=good)[0].options == good
