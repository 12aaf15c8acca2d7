"""`animlod crowd` around its renderer: what is checked before any work, what a run that fails
or is interrupted leaves behind. The binary is a fake (a shell script, as ANIMLOD_CROWD_BIN) that
writes what the real one does, crashes or hangs; only the test of a refused window needs the
real binary.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from animlod.cli import main as cli_main

# Writes the report (and a grid for --heat-map) and each screenshot where it is told, failing as the
# real binary does where it cannot; touches $CROWD_RAN so that a test can tell it never ran.
SUCCEEDS = r"""
touch "$CROWD_RAN"
while [ $# -gt 0 ]; do
  case $1 in
    --json) report=$2; shift ;;
    --screenshot) shot=$3; shift 2 ;;
  esac
  shift
done
if [ -n "$shot" ] && ! printf 'PNG from the fake' > "$shot"; then
  echo "animlod_crowd: error: $shot: cannot write the screenshot" >&2
  exit 1
fi
cell='{"mesh_level": 0, "motion_level": 0, "fps": 1}'
echo "{\"renderer\": \"fake\", \"count\": 2, \"modes\": {}, \"grid\": [$cell]}" > "$report"
echo "| mode | FPS |"
"""
CRASHES = SUCCEEDS + 'echo "animlod_crowd: round 1/1 Original: 12.00 fps" >&2\nkill -SEGV $$\n'
TRUNCATES = SUCCEEDS + """printf '{"renderer": "fake", "modes": {' > "$report"\n"""
# Hangs with a child of its own, having said where it runs: its pid, its child's, the display's
# number and the X authority file that xvfb-run made.
HANGS = r"""
sleep 300 &
echo "$$ $! ${DISPLAY#:} ${XAUTHORITY:-}" > "$CROWD_INFO.part" && mv "$CROWD_INFO.part" "$CROWD_INFO"
wait
"""
no_xvfb_run = pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="no xvfb-run")


@pytest.fixture
def chain(tmp_path) -> Path:
    """A glTF of no node: the CLI's checks take it; only the fake binary is given it."""
    path = tmp_path / "chain.gltf"
    path.write_text('{"asset": {"version": "2.0"}}')
    return path


@pytest.fixture
def fake(tmp_path, monkeypatch):
    """Makes the shell script ``body`` the crowd binary (run without Xvfb: DISPLAY is set)."""

    def install(body: str) -> Path:
        binary = tmp_path / "fake_crowd.sh"
        binary.write_text("#!/bin/bash\n" + body)
        binary.chmod(0o755)
        monkeypatch.setenv("ANIMLOD_CROWD_BIN", str(binary))
        monkeypatch.setenv("DISPLAY", ":0")
        monkeypatch.setenv("CROWD_RAN", str(tmp_path / "ran"))
        return binary

    return install


def _crowd(capsys, *arguments) -> tuple[int, str]:
    code = cli_main(["crowd", *map(str, arguments), "--count", "2", "--frames", "2"])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("option", [["--json"], ["--screenshot", "0"], ["--heat-map"]], ids=lambda o: o[0])
def test_an_output_naming_a_chain_is_refused_before_running(fake, chain, capsys, option) -> None:
    # `--json CHAIN` replaced the LoD GLB with the report, as `-o IN` is refused for doing elsewhere.
    fake(SUCCEEDS)
    before = chain.read_bytes()
    code, err = _crowd(capsys, chain, "--grid", *option, chain)
    assert code == 2 and f"{option[0]} {chain}: is the input file" in err and err.count("\n") == 1
    assert chain.read_bytes() == before


# The CLI as a process that takes SIGINT as a terminal's Ctrl-C (a background job inherits it ignored).
_MAIN_WITH_CTRL_C = (
    "import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
    "from animlod.cli import main; sys.exit(main(sys.argv[1:]))"
)


def _running(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie waiting for its parent to reap it does not)."""
    try:
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.parametrize(
    ("stop", "code", "display"),
    [pytest.param(signal.SIGTERM, 143, None, marks=no_xvfb_run), (signal.SIGINT, 130, ":0")],
    ids=["sigterm-under-xvfb-run", "sigint-on-a-display"],
)
def test_an_interrupted_run_ends_every_process_it_started(fake, chain, tmp_path, stop, code, display) -> None:
    # Only the process started (xvfb-run, or the binary on a display) was killed: Xvfb and the
    # binary (or the binary's children) ran on, and xvfb-run's folder stayed in /tmp.
    fake(HANGS)
    environment = {**os.environ, "CROWD_INFO": str(tmp_path / "info")}
    environment.pop("DISPLAY")
    if display:
        environment["DISPLAY"] = display
    animlod = subprocess.Popen(
        [sys.executable, "-c", _MAIN_WITH_CTRL_C, "crowd", str(chain), "--count", "2", "--frames", "2"],
        env=environment, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    pids, xvfb_folder = [], None
    try:
        deadline = time.monotonic() + 60
        while not (tmp_path / "info").exists() and time.monotonic() < deadline and animlod.poll() is None:
            time.sleep(0.1)
        assert (tmp_path / "info").exists(), "the fake binary did not start"
        binary, child, server, *authority = (tmp_path / "info").read_text().split()
        pids = [int(binary), int(child)]
        if display is None:
            lock, xvfb_folder = Path(f"/tmp/.X{server}-lock"), Path(authority[0]).parent
            assert xvfb_folder.name.startswith("xvfb-run.")
            pids.append(int(lock.read_text()))  # Xvfb's
        animlod.send_signal(stop)
        assert animlod.wait(timeout=30) == code
        assert animlod.stderr.read().count("\n") == 1
        assert not [pid for pid in pids if _running(pid)]
        if display is None:
            assert not lock.exists() and not xvfb_folder.exists()
    finally:  # what a failure left behind
        for pid in pids:
            if _running(pid):
                os.kill(pid, signal.SIGTERM)
        if xvfb_folder is not None:
            shutil.rmtree(xvfb_folder, ignore_errors=True)
        if animlod.poll() is None:
            animlod.kill()


@pytest.mark.parametrize("display", [":0", pytest.param(None, marks=no_xvfb_run)], ids=["display", "xvfb-run"])
def test_a_binary_killed_by_a_signal_is_a_machine_error_and_leaves_no_output(
    fake, chain, tmp_path, capsys, monkeypatch, display
) -> None:
    # Its last progress line was the error, and the screenshot of the failed run was left behind.
    fake(CRASHES)
    if display is None:
        monkeypatch.delenv("DISPLAY")
    shot, report = tmp_path / "shot.png", tmp_path / "crowd.json"
    code, err = _crowd(capsys, chain, "--screenshot", "0", shot, "--json", report)
    assert code == 3 and err == "animlod crowd: error: animlod_crowd: killed by SIGSEGV\n"
    assert not shot.exists() and not report.exists()


@pytest.mark.parametrize(
    ("body", "message"),
    [("exit 0", "exited 0 without writing its report"), (TRUNCATES, "its report is not readable JSON")],
    ids=["no-report", "truncated-report"],
)
def test_a_run_without_a_readable_report_is_the_binarys_failure(fake, chain, capsys, body, message) -> None:
    # The missing report was blamed on the input (exit 2, naming a temporary file).
    fake(body)
    code, err = _crowd(capsys, chain)
    assert code == 3 and f"animlod_crowd: {message}" in err and err.count("\n") == 1


@pytest.mark.parametrize(
    ("ids", "message"),
    [([0], "lists the node itself"), ([1, 1], "lists node 1 twice"), ([1.5], "refers to node 1.5")],
    ids=["itself", "twice", "fractional"],
)
def test_a_damaged_lod_chain_is_refused_before_running(fake, tmp_path, capsys, ids, message) -> None:
    # The renderer's loader benchmarked them without a word (node 1.5 drawn as node 1).
    fake(SUCCEEDS)
    damaged = tmp_path / "damaged.gltf"
    nodes = [{"name": "base", "extensions": {"MSFT_lod": {"ids": ids}}}, {"name": "level 1"}]
    damaged.write_text(json.dumps({"asset": {"version": "2.0"}, "nodes": nodes}))
    code, err = _crowd(capsys, damaged)
    assert code == 2 and f"{damaged}: node 0 'base' MSFT_lod: {message}" in err and err.count("\n") == 1
    assert not (tmp_path / "ran").exists()


@pytest.mark.parametrize(
    ("coverages", "message"),
    [(["0.5", 0.0], "level 0: '0.5' is not a finite number >= 0"), ([0.5, -0.1], "level 1: -0.1 is not a finite"),
     ([0.2, 0.5], "level 1: 0.5 is above level 0's 0.2"), ([0.5], "needs 2 values")],
    ids=["string", "negative", "rising", "short"],
)  # fmt: skip
def test_screen_coverages_the_renderer_cannot_use_are_refused_before_running(
    fake, tmp_path, capsys, coverages, message
) -> None:
    # A string was read as 0 and rising or negative values taken as they were.
    fake(SUCCEEDS)
    damaged = tmp_path / "damaged.gltf"
    base = {"name": "base", "extensions": {"MSFT_lod": {"ids": [1]}}, "extras": {"MSFT_screencoverage": coverages}}
    damaged.write_text(json.dumps({"asset": {"version": "2.0"}, "nodes": [base, {"name": "level 1"}]}))
    code, err = _crowd(capsys, damaged)
    assert code == 2 and f"{damaged}: node 0 'base' extras MSFT_screencoverage: {message}" in err
    assert not (tmp_path / "ran").exists()


def test_a_screenshot_is_refused_before_running_where_it_cannot_be_written(fake, chain, tmp_path, capsys) -> None:
    # Only --json and --heat-map were checked: the screenshot failed after every mode's warm-up.
    fake(SUCCEEDS)
    (tmp_path / "notes.txt").write_text("a file, not a folder")
    shot = tmp_path / "notes.txt" / "shot.png"
    code, err = _crowd(capsys, chain, "--screenshot", "0", shot)
    assert code == 2 and f"--screenshot: {shot}: {tmp_path / 'notes.txt'} is not a folder" in err
    assert not (tmp_path / "ran").exists()


def test_a_screenshot_folder_that_is_missing_is_made(fake, chain, tmp_path, capsys) -> None:
    fake(SUCCEEDS)
    shot = tmp_path / "new" / "folder" / "shot.png"
    assert _crowd(capsys, chain, "--screenshot", "1", shot)[0] == 0
    assert shot.read_text() == "PNG from the fake"


@pytest.mark.parametrize("option", [["--json"], ["--grid", "--heat-map"]], ids=["json", "heat-map"])
def test_a_folder_in_place_of_an_output_is_refused_before_running(fake, chain, tmp_path, capsys, option) -> None:
    # The run was made, then the error named a temporary `.part` file.
    fake(SUCCEEDS)
    (tmp_path / "out").mkdir()
    code, err = _crowd(capsys, chain, *option, tmp_path / "out")
    assert code == 2 and f"{option[-1]}: {tmp_path / 'out'}: is a folder" in err
    assert not (tmp_path / "ran").exists()


@pytest.fixture
def chain_build_fails(monkeypatch) -> None:
    """Building the procedural chain (minutes) fails the test: it must come after the checks."""

    def build_character(*arguments, **keywords):
        raise AssertionError("the procedural chain was built before the options and the machine were checked")

    monkeypatch.setattr("animlod.pipelines.character.build_character", build_character)


@pytest.mark.parametrize(
    ("arguments", "body", "code", "message"),
    [
        (["--count", "0"], SUCCEEDS, 2, "--count: must be >= 1, got 0"),
        (["--frames", "0"], SUCCEEDS, 2, "--frames: must be >= 1, got 0"),
        (["--frames", "2", "--screenshot", "2"], SUCCEEDS, 2, "--screenshot: frame 2 is not among the 2 measured"),
        ([], 'echo "animlod_crowd: error: cannot initialise GLFW (no display?)" >&2; exit 3', 3, "no display"),
        ([], None, 3, "ANIMLOD_CROWD_BIN="),
    ],
    ids=["count", "frames", "screenshot", "no-display", "no-binary"],
)
def test_without_a_chain_the_options_and_the_machine_are_checked_before_it_is_built(
    fake, chain_build_fails, tmp_path, monkeypatch, capsys, arguments, body, code, message
) -> None:
    fake(body or "")
    if body is None:
        monkeypatch.setenv("ANIMLOD_CROWD_BIN", str(tmp_path / "missing"))
    if "--screenshot" in arguments:
        arguments = [*arguments, str(tmp_path / "shot.png")]
    assert cli_main(["crowd", *arguments]) == code
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_without_a_chain_a_window_the_binary_refuses_is_found_before_it_is_built(
    binary, chain_build_fails, capsys
) -> None:
    assert cli_main(["crowd", "--width", "5"]) == 2
    err = capsys.readouterr().err
    assert "--width" in err and err.count("\n") == 1


def test_a_missing_binary_and_a_folder_for_a_chain_are_named(fake, tmp_path, chain, monkeypatch, capsys) -> None:
    monkeypatch.setenv("ANIMLOD_CROWD_BIN", str(tmp_path / "missing"))
    code, err = _crowd(capsys, chain)
    assert code == 3 and f"ANIMLOD_CROWD_BIN={tmp_path / 'missing'}: no such file" in err
    code, err = _crowd(capsys, tmp_path)
    assert code == 2 and f"{tmp_path}: is a folder" in err


def test_what_the_renderer_read_in_place_of_the_file_is_said(fake, chain, capsys) -> None:
    # The binary's warnings (a skin with more influences than the GPU holds) went to its stderr,
    # which a run that succeeds does not show.
    chains = r"\"chains\": [{\"file\": \"chain.gltf\", \"warnings\": [\"mesh 0: 8 largest kept\"]}]"
    warns = SUCCEEDS.replace("[$cell]}", f"[$cell], {chains}}}")
    assert warns != SUCCEEDS
    fake(warns)
    code, err = _crowd(capsys, chain)
    assert code == 0 and "warning: chain.gltf: mesh 0: 8 largest kept" in err
