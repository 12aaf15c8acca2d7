"""`animlod batch` on a real LocalCluster with 2 single-threaded workers: outputs equal to the
direct pipeline, a broken asset reported and the rest written, reruns that do no work, a killed
worker leaving nothing half-written."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

from animlod import Motion, Skeleton, rotations, synth
from animlod.batch import BatchProgress, SpecError, read_catalogue, read_spec, run_batch
from animlod.batch.jobs import check_options, find_job
from animlod.cli import main
from animlod.io import write_bvh, write_glb
from animlod.io.detect import BATCH_STATE
from animlod.io.glb_builder import GlbBuilder
from animlod.io.meshseq import write_sequence
from animlod.io.npz import write_npz
from animlod.io.obj import write_obj
from animlod.pipelines import simplify_asset

# Small enough for a quick suite: few drive and measured frames per clip.
QUICK = {"frame_budget": 6, "measured_frames": 2}
OPTIONS = {**QUICK, "levels": 3}  # levels: the motion job's, for the BVH


def _arm_motion() -> Motion:
    """Four joints in a chain, each turning a little over 8 frames."""
    skeleton = Skeleton(
        ["hips", "a", "b", "c", "c_End"], [-1, 0, 1, 2, 3],
        [[0, 1, 0], [0, 0.4, 0], [0, 0.4, 0], [0, 0.4, 0], [0, 0.2, 0]], end_sites=[False] * 4 + [True],
    )  # fmt: skip
    local = rotations.identity((8, 5))
    for joint, axis in ((1, [1.0, 0, 0]), (2, [0, 0, 1.0]), (3, [1.0, 0, 0])):
        local[:, joint] = rotations.from_axis_angle(np.array(axis), np.linspace(0, 0.3 * joint, 8))
    return Motion(skeleton, np.tile([0.0, 1.0, 0.0], (8, 1)), local, fps=24.0)


@pytest.fixture(scope="module")
def library(tmp_path_factory) -> Path:
    """Five small procedural assets of four kinds and one broken file."""
    root = tmp_path_factory.mktemp("library")
    for index, rings in enumerate((10, 14)):
        skin, motion = synth.bending_cylinder_skinned(frames=6, rings=rings, segments=10)
        (root / "characters").mkdir(exist_ok=True)
        write_glb(root / "characters" / f"cyl{index}.glb", skin, [motion])
    write_npz(root / "bar.npz", synth.twisting_bar(frames=5, rings=10, segments=8))
    write_sequence(root / "seq", synth.bending_cylinder(frames=4, rings=8, segments=8))
    (root / "motions").mkdir()
    write_bvh(root / "motions" / "arm.bvh", _arm_motion())
    (root / "broken.glb").write_bytes(b"glTF\x02\x00\x00\x00 not a glb")
    return root


def _files(folder: Path) -> dict[str, bytes]:
    """Every file below ``folder`` (relative POSIX path -> bytes), the batch's own record aside."""
    return {
        path.relative_to(folder).as_posix(): path.read_bytes()
        for path in sorted(folder.rglob("*"))
        if path.is_file() and path.name != ".animlod-asset.json"
    }


class Recorder(BatchProgress):
    def __init__(self) -> None:
        self.events: list[str] = []
        self.done: list[str] = []

    def asset_event(self, name, fraction, message) -> None:
        self.events.append(name)

    def asset_done(self, record) -> None:
        self.done.append(record["name"])


def test_outputs_equal_the_direct_pipeline_and_broken_asset_is_reported(client, library, tmp_path):
    assets = read_spec(library, options=OPTIONS)
    names = ["bar", "broken", "characters/cyl0", "characters/cyl1", "motions/arm", "seq"]
    assert sorted(asset.name for asset in assets) == names
    recorder = Recorder()
    result = run_batch(assets, tmp_path / "out", client=client, progress=recorder)
    assert (result.ran, result.skipped, result.failed, result.workers) == (6, 0, 1, 2)
    assert sorted(recorder.done) == sorted(asset.name for asset in assets)
    assert recorder.events  # the workers' progress reached the client

    for asset in assets:
        if asset.name == "broken":
            continue
        direct = tmp_path / "direct" / asset.name
        find_job(asset.job).function()(asset.input, direct, **asset.options)
        batch = _files(tmp_path / "out" / asset.name)
        assert batch and batch == _files(direct), asset.name

    broken = next(record for record in result.records if record["name"] == "broken")
    assert broken["status"] == "failed"
    assert broken["error"]["file"].endswith("broken.glb") and broken["error"]["element"] and broken["error"]["reason"]
    assert not (tmp_path / "out" / "broken").exists()
    assert list((tmp_path / "out" / BATCH_STATE / "staging").iterdir()) == []

    rows = read_catalogue(result.catalogue).to_pylist()
    failed = [row for row in rows if row["status"] == "failed"]
    assert [(row["asset"], row["error_element"]) for row in failed] == [("broken", broken["error"]["element"])]
    for asset in ("bar", "seq", "characters/cyl0", "characters/cyl1"):
        levels = [row for row in rows if row["asset"] == asset]
        assert [row["level"] for row in levels] == [0, 1, 2, 3], asset
        triangles = [row["triangles"] for row in levels]
        assert triangles == sorted(triangles, reverse=True) and triangles[-1] > 0
        assert all(row["worker"].startswith("tcp://") and row["ran"] for row in levels)
        assert all((tmp_path / "out" / output).exists() for output in levels[0]["outputs"])
    motion = [row for row in rows if row["asset"] == "motions/arm"]
    assert [(row["level"], row["joints"]) for row in motion][0] == (0, 4)
    assert len(motion) == 3 and motion[-1]["joints"] < 4 and motion[-1]["error"] > 0


class CatalogueWatcher(BatchProgress):
    """Reads the catalogue each time an asset finishes: how many assets it held then."""

    def __init__(self, path: Path) -> None:
        self.path, self.seen = path, []

    def asset_done(self, record) -> None:
        rows = read_catalogue(self.path).to_pylist() if self.path.exists() else []
        self.seen.append(len({row["asset"] for row in rows}))


def test_second_run_does_no_work_and_a_changed_option_redoes_one_asset(client, library, tmp_path, monkeypatch):
    import animlod.batch.runner

    monkeypatch.setattr(animlod.batch.runner, "CATALOGUE_INTERVAL", 0.0)  # rewrite it after every asset
    assets = [asset for asset in read_spec(library, options=OPTIONS) if asset.name != "broken"]
    watcher = CatalogueWatcher(tmp_path / "out" / "catalogue.parquet")
    first = run_batch(assets, tmp_path / "out", client=client, progress=watcher)
    assert (first.ran, first.failed) == (5, 0)
    assert watcher.seen == [0, 1, 2, 3, 4]  # the catalogue grew as the assets finished
    outputs = [path for asset in assets for path in (tmp_path / "out" / asset.name).rglob("*") if path.is_file()]
    before = {path: path.stat().st_mtime_ns for path in outputs}

    second = run_batch(assets, tmp_path / "out", client=None, workers=1)  # no cluster is started: nothing to do
    assert (second.ran, second.skipped, second.failed, second.workers) == (0, 5, 0, 0)
    after = {path: path.stat().st_mtime_ns for path in before}
    assert after == before
    rows = read_catalogue(second.catalogue).to_pylist()
    assert len(rows) == 19 and not any(row["ran"] for row in rows)

    changed = [
        type(asset)(asset.name, asset.input, asset.kind, asset.job, {**asset.options, "ratios": [0.5]})
        if asset.name == "bar"
        else asset
        for asset in assets
    ]
    third = run_batch(changed, tmp_path / "out", scheduler=client.scheduler.address)  # as --scheduler tcp://...
    assert (third.ran, third.skipped) == (1, 4)
    assert sorted(path.name for path in (tmp_path / "out" / "bar").iterdir()) == [".animlod-asset.json", "bar_lod1.npz"]

    # A run that stops before running the changed asset keeps its earlier rows in the catalogue.
    from animlod.batch import SchedulerUnreachable

    listed = read_catalogue(third.catalogue).to_pylist()
    changed[[asset.name for asset in changed].index("bar")].options["ratios"] = [0.4]
    with pytest.raises(SchedulerUnreachable):
        run_batch(changed, tmp_path / "out", scheduler="tcp://127.0.0.1:9", connect_timeout=1)
    assert read_catalogue(third.catalogue).to_pylist() == [{**row, "ran": False} for row in listed]

    # An asset renamed ("seq" -> "seq_frames") or taken out of the spec ("bar") leaves its folder
    # as it is: named in a note, out of the catalogue.
    assert not [note for note in [*first.notes, *third.notes] if "earlier runs" in note]
    renamed = [type(asset)("seq_frames" if asset.name == "seq" else asset.name, asset.input, asset.kind, asset.job,
                           asset.options) for asset in assets if asset.name != "bar"]  # fmt: skip
    fourth = run_batch(renamed, tmp_path / "out", client=client)
    assert (fourth.ran, fourth.skipped) == (1, 3)
    (earlier,) = [note for note in fourth.notes if "earlier runs" in note]
    assert "2 asset folders of earlier runs not in this batch (bar, seq): left as they are" in earlier
    assert (tmp_path / "out" / "seq").is_dir() and (tmp_path / "out" / "bar").is_dir()
    listed = {row["asset"] for row in read_catalogue(fourth.catalogue).to_pylist()}
    assert "seq_frames" in listed and not listed & {"seq", "bar"}


def test_killed_worker_leaves_no_partial_file_and_the_asset_is_redone(client, library, tmp_path):
    source = library / "characters" / "cyl0.glb"
    positions, faces = synth.icosphere(2, 0.1)  # a face job's pose folder: neutral and one expression
    poses = tmp_path / "poses"
    poses.mkdir()
    write_obj(poses / "neutral.obj", positions, faces)
    write_obj(poses / "bulge.obj", positions * (1.0 + 0.2 * np.clip(positions[:, 1:2] / 0.1, 0, 1)), faces)
    manifest = tmp_path / "assets.json"
    entries = [
        {"input": str(source), "name": "crashes_once", "job": "batch_jobs:crash_once",
         "marker": str(tmp_path / "crashed"), **QUICK},
        {"input": str(source), "name": "always_crashes", "job": "batch_jobs:always_crash"},
        {"input": str(library / "bar.npz"), "name": "bar"},
        {"input": str(library / "bar.npz"), "name": "bar_half", "ratios": [0.5]},
        {"input": str(library / "seq"), "name": "seq"},
        {"input": str(poses), "name": "face", "job": "face", "ratios": [0.5], "repeats": 1,
         "error_frames": 4},
    ]  # fmt: skip
    manifest.write_text(json.dumps({"assets": entries}))
    result = run_batch(read_spec(manifest), tmp_path / "out", client=client)
    records = {record["name"]: record for record in result.records}

    assert (tmp_path / "crashed").exists()  # the first attempt did die
    assert records["crashes_once"]["status"] == "ok"
    direct = tmp_path / "direct"
    simplify_asset(source, direct, **QUICK)
    assert _files(tmp_path / "out" / "crashes_once") == _files(direct)  # no half-written file

    assert records["always_crashes"]["status"] == "failed"
    assert records["always_crashes"]["error"]["element"] == "worker"
    assert not (tmp_path / "out" / "always_crashes").exists()
    # The others all finished: none was counted against the deaths of the workers beside it.
    assert all(records[name]["status"] == "ok" for name in ("bar", "bar_half", "seq", "face"))
    face = records["face"]["result"]["levels"]  # the face job on a pose folder, beside the crashes
    assert [(row["level"], row["triangles"]) for row in face] == [(0, 320), (1, 160)] and face[1]["error"] > 0
    assert not list((tmp_path / "out").rglob("half_written*"))
    client.wait_for_workers(2, timeout=30)  # the nannies restarted the killed workers


def test_each_asset_shares_the_cores_of_its_host(client, library, tmp_path):
    # Two single-threaded workers on one host: an asset's core loops take half of the cores
    # (animlod.set_thread_limit), not every core each.
    manifest = tmp_path / "assets.json"
    entries = [{"input": str(library / "bar.npz"), "name": f"bar{index}", "job": "batch_jobs:report_threads"}
               for index in range(2)]  # fmt: skip
    manifest.write_text(json.dumps({"assets": entries}))
    result = run_batch(read_spec(manifest), tmp_path / "out", client=client)
    share = max(1, (os.cpu_count() or 1) // 2)
    assert all(f"core threads: {share}" in record["result"]["notes"] for record in result.records), result.records


def test_cli_bad_inputs_are_one_line_exit_2(library, tmp_path, capsys):
    manifest = tmp_path / "m.toml"
    manifest.write_text(f'[[assets]]\ninput = "{library / "bar.npz"}"\nbogus = 1\n')
    assert main(["batch", str(manifest), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "assets[0]" in err and "'bogus'" in err

    manifest.write_text('[[assets]]\ninput = "missing.glb"\n')
    assert main(["batch", str(manifest), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "missing.glb" in err and "does not exist" in err

    (tmp_path / "file").write_text("x")
    assert main(["batch", str(library), "-o", str(tmp_path / "file")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "is a file" in err

    out = str(tmp_path / "o2")
    assert main(["batch", str(library), "-o", out, "--scheduler", "tcp://127.0.0.1:9", "--connect-timeout", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--scheduler: tcp://127.0.0.1:9: no Dask scheduler answered within 1 s" in err
    assert main(["batch", str(library), "-o", out, "--scheduler", "farm:notaport"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--scheduler: farm:notaport: not a scheduler address like tcp://HOST:PORT" in err

    with pytest.raises(SpecError, match="no asset's job takes this option"):
        read_spec(library, options={"nonsense": 1})


def test_manifest_defaults_and_per_asset_options(library, tmp_path):
    manifest = tmp_path / "lib.toml"
    manifest.write_text(
        "[defaults]\nratios = [0.5, 0.25]\nframe_budget = 6\n\n"
        f'[[assets]]\ninput = "{library / "characters" / "cyl0.glb"}"\nname = "hero"\nmeasured_frames = 2\n\n'
        f'[[assets]]\nglob = "{library}/*.npz"\nratios = [0.3]\n'
    )
    assets = {asset.name: asset for asset in read_spec(manifest)}
    assert assets["hero"].options == {"measured_frames": 2, "ratios": [0.5, 0.25], "frame_budget": 6}
    assert assets["bar"].options == {"ratios": [0.3]}  # frame_budget is not a sequence option
    assert np.isclose(assets["bar"].options["ratios"][0], 0.3)


def test_manifest_takes_the_aqem_options_by_their_field_names(library, tmp_path):
    manifest = tmp_path / "lib.toml"
    source = library / "characters" / "cyl0.glb"
    manifest.write_text(f'[[assets]]\ninput = "{source}"\nname = "hero"\nnoise_mads = 3.0\nplacement = "on_edge"\n')
    assert read_spec(manifest)[0].options == {"noise_mads": 3.0, "placement": "on_edge"}
    manifest.write_text(f'[[assets]]\ninput = "{source}"\nname = "hero"\nnoise_mad = 3.0\n')
    with pytest.raises(SpecError, match=r"option 'noise_mad': unknown for job simplify on gltf input"):
        read_spec(manifest)


def test_scheduler_without_workers_is_a_clear_error_after_the_timeout(library, tmp_path):
    import logging

    from distributed import LocalCluster

    from animlod.batch import SchedulerUnreachable

    assets = read_spec(library / "bar.npz")
    with LocalCluster(n_workers=0, dashboard_address=":0", silence_logs=logging.ERROR) as empty:
        address = empty.scheduler_address
        with pytest.raises(SchedulerUnreachable, match="the scheduler has no worker after 1 s"):
            run_batch(assets, tmp_path / "out", scheduler=address, connect_timeout=1)


def test_spec_forms_and_their_errors(library, tmp_path):
    by_glob = read_spec(f"{library}/characters/*.glb", options=QUICK)
    assert [(asset.name, asset.job, asset.kind) for asset in by_glob] == [
        ("cyl0", "simplify", "gltf"),
        ("cyl1", "simplify", "gltf"),
    ]
    assert [asset.name for asset in read_spec(library / "characters", job="character")] == ["cyl0", "cyl1"]
    with pytest.raises(SpecError, match="pattern: matches no file"):
        read_spec(f"{library}/*.nothing")
    (tmp_path / "fbx").mkdir()
    (tmp_path / "fbx" / "hero.fbx").write_bytes(b"")
    with pytest.raises(SpecError, match=r"holds no asset \(.*\), but 1 model file in a format animlod does not read"):
        read_spec(tmp_path / "fbx")
    with pytest.raises(SpecError, match="does not take bvh input"):
        read_spec(library / "motions", job="simplify")
    with pytest.raises(SpecError, match="job 'nosuchjob': unknown"):
        read_spec(library / "bar.npz", job="nosuchjob")

    def manifest(text: str) -> Path:
        path = tmp_path / "m.toml"
        path.write_text(text)
        return path

    bar, arm = library / "bar.npz", library / "motions" / "arm.bvh"
    cases = [
        (f'[[assets]]\ninput = "{bar}"\nname = "a"\n[[assets]]\ninput = "{bar}"\nname = "a"\n', "given to both"),
        (f'[[assets]]\ninput = "{bar}"\nname = "../a"\n', "relative path without '.' parts"),
        (f'[[assets]]\ninput = "{bar}"\nname = "a"\n[[assets]]\ninput = "{bar}"\nname = "a/b"\n', "inside the folder"),
        (f'[[asset]]\ninput = "{bar}"\n', "asset: unknown key"),
        (f'[[assets]]\ninput = "{bar}"\nglob = "*.npz"\n', "needs exactly one of 'input'"),
        (f'[defaults]\ninput = "{bar}"\n[[assets]]\ninput = "{bar}"\n', "defaults.input: belongs to an asset"),
        (f'[[assets]]\ninput = "{bar}"\nratios = [0.5, "x"]\n', "in the list: expected a number"),
        ("[[assets]\n", "not valid TOML"),
        # Options whose default is None are checked against their annotation; callbacks are no options.
        (f'[[assets]]\ninput = "{arm}"\nlevels = "eight"\n', "option 'levels': expected a whole number, got 'eight'"),
        (f'[[assets]]\ninput = "{arm}"\nclip = 1.5\n', "option 'clip': expected a whole number or a string"),
        (f'[[assets]]\ninput = "{arm}"\non_choice = "print"\n', "option 'on_choice': unknown for job motion"),
    ]
    for text, message in cases:
        with pytest.raises(SpecError, match=re.escape(message)):
            read_spec(manifest(text))


def test_a_gltf_of_clips_alone_defaults_to_the_motion_job(tmp_path):
    """An animation library's GLBs draw no mesh: the default job, simplify, failed on each."""
    skin, motion = synth.bending_cylinder_skinned(frames=6, rings=10, segments=10)
    write_glb(tmp_path / "cyl.glb", skin, [motion])
    write_glb(tmp_path / "clips.glb", None, [motion])
    (tmp_path / "broken.glb").write_bytes(b"glTF\x02\x00\x00\x00 not a glb")
    jobs = {asset.name: asset.job for asset in read_spec(tmp_path)}
    assert jobs == {"cyl": "simplify", "clips": "motion", "broken": "simplify"}


def test_folder_scan_names_what_a_studio_library_holds(tmp_path):
    # read_spec looks at names only, so placeholder bytes stand for the models.
    lib = tmp_path / "lib"
    for name in ("a.glb", "take[1].glb", "hero.glb", "hero/walk.bvh", "mixed/Stork.glb", "mixed/prop.obj"):
        (lib / name).parent.mkdir(parents=True, exist_ok=True)
        (lib / name).write_bytes(b"x")
    (lib / "._a.glb").write_bytes(b"\x00\x05\x16\x07")  # a macOS resource fork
    (lib / ".cache").mkdir()
    (lib / ".cache" / "b.glb").write_bytes(b"x")
    (lib / "props").mkdir()
    (lib / "props" / "link.glb").symlink_to(lib / "a.glb")
    (lib / "dangling.glb").symlink_to(lib / "nowhere.glb")
    (lib / "loop1.glb").symlink_to(lib / "loop2.glb")
    (lib / "loop2.glb").symlink_to(lib / "loop1.glb")
    (lib / "_lod" / BATCH_STATE).mkdir(parents=True)  # an earlier batch's output inside the library
    (lib / "_lod" / "a" / "a_lod.glb").parent.mkdir()
    (lib / "_lod" / "a" / "a_lod.glb").write_bytes(b"x")

    found = {asset.name: (Path(asset.input).relative_to(lib).as_posix(), asset.kind) for asset in read_spec(lib)}
    assert found == {
        "a": ("a.glb", "gltf"),
        "hero_glb": ("hero.glb", "gltf"),  # beside a folder of clips: its own name would hold them
        "take[1]": ("take[1].glb", "gltf"),  # a file name, not a pattern
        "hero/walk": ("hero/walk.bvh", "bvh"),
        "mixed_frames": ("mixed", "sequence"),  # a folder of frames that also holds a model
        "mixed/Stork": ("mixed/Stork.glb", "gltf"),
        "props/link": ("props/link.glb", "gltf"),  # a link is named after itself
    }
    # A folder that holds frames and models is a library, not one sequence.
    assert sorted(asset.name for asset in read_spec(lib / "mixed")) == ["Stork", "mixed"]
    assert [(asset.name, asset.kind) for asset in read_spec(lib / "mixed" / "prop.obj")] == [("prop", "sequence")]


def _interrupt_handler() -> object:
    import signal

    return signal.getsignal(signal.SIGINT)


def test_local_workers_end_quietly_on_ctrl_c(client):
    # Ctrl-C reaches the workers too: the default action ends them without a traceback each.
    import signal

    assert set(client.run(_interrupt_handler).values()) == {signal.SIG_DFL}


@pytest.mark.parametrize(
    "options, problem",
    [
        ({"frames": [1, 2], "rate": "fast"}, None),
        ({"frames": "all", "rate": 24}, None),
        ({"frames": 7}, "option 'frames': expected a list or a string, got 7"),
        ({"rate": float("nan")}, "option 'rate': expected a number or a string, got nan"),
        ({"rate": [1.0]}, "option 'rate': expected a number or a string, got [1.0]"),
        # A list with an item of another kind: cutting the list's message apart gave "expected in
        # the list: expected a whole number or a string, got [1.5]".
        ({"frames": [1.5]}, "option 'frames': in the list: expected a whole number, got 1.5"),
        # An empty default list has no item to check against: its annotation gives the kind.
        ({"tags": ["hero"]}, None),
        ({"tags": [1]}, "option 'tags': in the list: expected a string, got 1"),
    ],
)
def test_an_option_of_several_kinds_names_them_or_the_bad_item(options, problem):
    assert check_options(find_job("batch_jobs:several_kinds"), "npz", options) == problem


def test_an_assets_warnings_go_with_its_notes_and_the_summary(tmp_path, capsys):
    # A BVH whose Frames: line counts one short reads whole with a warning; in a batch that
    # warning went to the worker's stderr, out of the asset's record and the summary.
    from animlod.batch.task import run_asset
    from animlod.cli import main

    library = tmp_path / "library"
    library.mkdir()
    write_bvh(library / "arm.bvh", _arm_motion())
    text = (library / "arm.bvh").read_text()
    (library / "arm.bvh").write_text(text.replace("Frames: 8", "Frames: 7"))
    (asset,) = read_spec(library, options={"levels": 2})
    record = run_asset(asset, str(tmp_path / "out"), fingerprint="f")
    warning = "Frames: says 7 but the MOTION table has 8 rows; read all 8"
    assert record["status"] == "ok" and any(warning in note for note in record["result"]["notes"])
    assert main(["batch", str(library), "-o", str(tmp_path / "cli"), "--set", "levels=2", "--workers", "1"]) == 0
    assert f"warning arm: {library / 'arm.bvh'}: {warning}" in capsys.readouterr().out


def test_the_fingerprint_covers_the_images_the_job_reads(tmp_path):
    # The job finds an image written with backslashes ('.\\tex\\wood.png', as Windows exporters
    # write) and a GLB's external one: a rerun must see them change.
    from animlod.batch.fingerprint import fingerprint, input_files

    (tmp_path / "tex").mkdir()
    (tmp_path / "tex" / "wood.png").write_bytes(b"\x89PNG wood")
    gltf = tmp_path / "a.gltf"
    gltf.write_text('{"asset": {"version": "2.0"}, "images": [{"uri": ".\\\\tex\\\\wood.png"}, {"uri": "gone.png"}]}')
    builder = GlbBuilder(document={"asset": {"version": "2.0"}, "images": [{"uri": "tex/wood.png"}]})
    builder.save(tmp_path / "b.glb")
    for name in ("a.gltf", "b.glb"):
        (asset,) = read_spec(tmp_path / name)
        assert input_files(asset) == [tmp_path / name, tmp_path / "tex" / "wood.png"]
        before = fingerprint(asset)
        (tmp_path / "tex" / "wood.png").write_bytes(b"\x89PNG oak " + name.encode())
        assert fingerprint(asset) != before


def test_a_workers_share_of_its_host_and_its_own_thread_cap(monkeypatch):
    from types import SimpleNamespace

    import distributed

    from animlod import set_thread_limit, thread_limit
    from animlod.batch.task import _share_cores

    worker = SimpleNamespace(address="tcp://10.0.0.5:4000", state=SimpleNamespace(nthreads=1))
    monkeypatch.setattr(distributed, "get_worker", lambda: worker)
    monkeypatch.setattr(os, "cpu_count", lambda: 64)
    monkeypatch.delenv("ANIMLOD_THREADS", raising=False)
    set_thread_limit(0)
    every = thread_limit()
    try:
        _share_cores({"10.0.0.5": 64})  # 64 single-threaded workers on a 64-core host
        assert thread_limit() == 1
        _share_cores({})  # a host the scheduler did not list: this worker's one thread alone
        assert thread_limit() == every
        set_thread_limit(0)
        monkeypatch.setenv("ANIMLOD_THREADS", "3")  # the worker sets its own cap: no share imposed
        _share_cores({"10.0.0.5": 64})
        assert thread_limit() == every
        monkeypatch.setenv("ANIMLOD_THREADS", "x2")  # no cap the core takes: the share stands
        _share_cores({"10.0.0.5": 64})
        assert thread_limit() == 1
    finally:
        set_thread_limit(0)
