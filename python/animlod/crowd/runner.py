"""Run the native crowd benchmark ``animlod_crowd`` (bench/crowd/) and read its report.

The binary is built by the top-level CMake build (``make bench-crowd`` or ``make test``); it is
found through ``ANIMLOD_CROWD_BIN``, the checkout's ``build/cpp/bench/crowd/``, or ``PATH``.
Without a display it is started under ``xvfb-run`` (Mesa's llvmpipe renders off-screen). It runs
in a session of its own, ended whole (xvfb-run, Xvfb and the binary) when the caller is
interrupted; it writes its outputs into a temporary folder, from which they are copied into place
only once the run has succeeded.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ..io.atomic import atomic_write

MODES = ("Original", "GLoD", "MLoD", "G+MLoD")
PATHS = ("nav1", "nav2", "pullback")
# Exit codes of animlod_crowd (bench/crowd/main.cpp).
_BAD_INPUT, _NO_CONTEXT = 2, 3
# Seconds an interrupted run's processes get to exit on SIGTERM (Xvfb removing its lock) before
# they are killed.
_STOP_SECONDS = 3.0


class CrowdError(RuntimeError):
    """animlod_crowd refused its input or could not run; ``str()`` is its one-line message."""

    def __init__(self, message: str, bad_input: bool) -> None:
        super().__init__(message)
        self.bad_input = bad_input


@dataclass
class CrowdReport:
    """One run of ``animlod_crowd``.

    Attributes
    ----------
    data : the JSON report: ``renderer``, ``chains``, and ``modes`` (mode name -> fps,
        frame_ms_p50, frame_ms_p95, triangles, joints, drawn, ...) or ``grid`` (list of cells).
    markdown : the table the binary printed.
    command : the command line that produced it.
    """

    data: dict
    markdown: str
    command: list[str] = field(default_factory=list)

    @property
    def modes(self) -> dict[str, dict]:
        return self.data.get("modes", {})

    @property
    def renderer(self) -> str:
        return str(self.data.get("renderer", ""))


def find_crowd_binary() -> Path | None:
    """The ``animlod_crowd`` executable, or None when it has not been built."""
    explicit = os.environ.get("ANIMLOD_CROWD_BIN")
    if explicit:
        return Path(explicit) if Path(explicit).is_file() else None
    checkout = Path(__file__).resolve().parents[3] / "build" / "cpp" / "bench" / "crowd" / "animlod_crowd"
    if checkout.is_file():
        return checkout
    found = shutil.which("animlod_crowd")
    return Path(found) if found else None


def mode_list(modes: str | Sequence[str], frame_skipping: bool | None = None) -> list[str]:
    """Mode names for ``--modes``: "all" or names from MODES (optionally with "+skip").

    ``frame_skipping`` None keeps the names as given, True / False adds or drops "+skip".
    Raises ValueError naming an unknown mode.
    """
    if modes == "all":
        names = list(MODES) + [f"{m}+skip" for m in MODES]
    else:
        names = [n.strip() for item in ([modes] if isinstance(modes, str) else modes) for n in str(item).split(",")]
    out = []
    for name in names:
        base = name[: -len("+skip")] if name.endswith("+skip") else name
        if base not in MODES:
            raise ValueError(f"mode {name!r}: expected one of {', '.join(MODES)}, optionally with +skip, or all")
        if frame_skipping is None:
            out.append(name)
        else:
            out.append(f"{base}+skip" if frame_skipping else base)
    return list(dict.fromkeys(out))


def run_crowd(
    chains: Sequence[str | os.PathLike],
    *,
    count: int = 1000,
    frames: int = 300,
    warmup: int = 10,
    rounds: int = 1,
    modes: str | Sequence[str] = "all",
    path: str = "nav1",
    width: int = 1280,
    height: int = 720,
    pixel_error: float = 2.0,
    level_colors: bool = False,
    grid: bool = False,
    screenshots: Sequence[tuple[int, str | os.PathLike]] = (),
    json_path: str | os.PathLike | None = None,
    extra_args: Sequence[str] = (),
    binary: str | os.PathLike | None = None,
    timeout: float | None = None,
) -> CrowdReport:
    """Run ``animlod_crowd`` on LoD GLB ``chains`` and return its report.

    Parameters
    ----------
    chains : LoD GLB files (MSFT_lod chains; a GLB without MSFT_lod is one level).
    count, frames, warmup : characters, measured frames per mode and unmeasured frames before.
    rounds : the path split into this many segments, the modes taking turns on each (so that a
        change in machine load hits every mode alike); each round repeats the warm-up.
    modes : "all" or names from MODES, each optionally with "+skip" (frame skipping).
    path : camera path, one of PATHS.
    width, height : window in pixels (under xvfb-run the screen is made this large).
    pixel_error : the selector's screen-space error budget in pixels.
    level_colors : tint every character by its level.
    grid : Fig. 1 instead of modes: every (mesh level, motion level) forced on all characters.
    screenshots : (measured frame of the first mode, PNG path) pairs.
    json_path : where to write the JSON report (not written when None).
    extra_args : further animlod_crowd options (see ``animlod_crowd --help``).
    binary : the executable; find_crowd_binary() when None.
    timeout : seconds before the run is stopped (subprocess.TimeoutExpired).

    The screenshots and the JSON are written (atomically, their folders made) only once the run
    has succeeded. On any exception while the binary runs (Ctrl-C, a SIGTERM the caller turned
    into an exception as the CLI does, the timeout) its processes are ended, Xvfb's included.

    Raises
    ------
    CrowdError with a one-line message: the binary's own (bad input, ``bad_input``; no GL
    context), the signal that killed it, a report missing or unreadable, or the binary missing.
    """
    if not chains:
        raise CrowdError("chains: none given", bad_input=True)
    if path not in PATHS:
        raise CrowdError(f"path {path!r}: expected one of {', '.join(PATHS)}", bad_input=True)
    try:
        names = mode_list(modes)
    except ValueError as error:
        raise CrowdError(str(error), bad_input=True) from None
    executable = _executable(binary)
    with tempfile.TemporaryDirectory(prefix="animlod_crowd_") as scratch:
        # Every output is written into scratch first: a failed run leaves none behind.
        report_path = Path(scratch) / "crowd.json"
        outputs = [(report_path, json_path)] if json_path else []
        command = [str(executable), *(str(Path(c)) for c in chains)]
        command += ["--count", str(count), "--frames", str(frames), "--warmup", str(warmup), "--rounds", str(rounds)]
        command += ["--modes", ",".join(names), "--path", path, "--width", str(width), "--height", str(height)]
        command += ["--pixel-error", repr(float(pixel_error)), "--json", str(report_path)]
        if level_colors:
            command.append("--level-colors")
        if grid:
            command.append("--grid")
        for index, (frame, png) in enumerate(screenshots):
            outputs.append((Path(scratch) / f"screenshot_{index}.png", png))
            command += ["--screenshot", str(int(frame)), str(outputs[-1][0])]
        command += [str(arg) for arg in extra_args]
        launch, environment = list(command), dict(os.environ)
        wrapped = not os.environ.get("DISPLAY") and shutil.which("xvfb-run") is not None
        if wrapped:
            launch = ["xvfb-run", "-a", "-s", f"-screen 0 {max(width, 640)}x{max(height, 480)}x24", *command]
            # Its folder (the X authority file) in scratch: xvfb-run, a dash script, dies on SIGTERM
            # without removing it.
            environment["TMPDIR"] = scratch
        returncode, stdout, stderr = _run_session(launch, environment, timeout)
        if returncode != 0:
            raise _failure(returncode, stderr, wrapped)
        data = _read_report(report_path)
        if missing := [target for written, target in outputs if not written.is_file()]:
            raise CrowdError(f"animlod_crowd: exited 0 without writing {missing[0]}", bad_input=False)
        for written, target in outputs:
            with open(written, "rb") as source, atomic_write(target) as handle:
                shutil.copyfileobj(source, handle)
    return CrowdReport(data=data, markdown=stdout, command=command)


def _executable(binary: str | os.PathLike | None) -> Path:
    """``binary``, else find_crowd_binary(); CrowdError (not bad input) when there is none."""
    named = binary or os.environ.get("ANIMLOD_CROWD_BIN")
    if named and not Path(named).is_file():
        where = "" if binary else "ANIMLOD_CROWD_BIN="
        reason = "not a file" if Path(named).exists() else "no such file"
        raise CrowdError(f"{where}{os.fspath(named)}: {reason} (the animlod_crowd binary)", bad_input=False)
    executable = Path(named) if named else find_crowd_binary()
    if executable is None:
        raise CrowdError(
            "animlod_crowd is not built: run `make bench-crowd` (or cmake --build build/cpp), "
            "or point ANIMLOD_CROWD_BIN at it",
            bad_input=False,
        )
    return executable


def _run_session(launch: list[str], environment: dict[str, str], timeout: float | None) -> tuple[int, str, str]:
    """Run ``launch`` in a session of its own; its return code, stdout and stderr.

    On any exception here (Ctrl-C, the CLI's SIGTERM, the timeout) the whole session is ended:
    killing only the process started, as subprocess.run does, left xvfb-run's Xvfb and the
    binary running.
    """
    with subprocess.Popen(
        launch, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=environment, start_new_session=True
    ) as process:
        try:
            stdout, stderr = process.communicate(timeout=timeout)
        except BaseException:
            _end_session(process)
            raise
    return process.returncode, stdout, stderr


def _end_session(process: subprocess.Popen) -> None:
    """End the process group that ``process`` leads (xvfb-run, its Xvfb and the binary): SIGTERM,
    up to _STOP_SECONDS for every member to exit (Xvfb removes its lock and socket), then SIGKILL
    to what is left."""
    deadline = time.monotonic() + _STOP_SECONDS
    with contextlib.suppress(ProcessLookupError):  # raised once no process of the group is left
        os.killpg(process.pid, signal.SIGTERM)
        while time.monotonic() < deadline:
            process.poll()  # reaps the leader, whose zombie would keep the group alive
            os.killpg(process.pid, 0)
            time.sleep(0.05)
        os.killpg(process.pid, signal.SIGKILL)
    process.wait()


def _failure(returncode: int, stderr: str, wrapped: bool) -> CrowdError:
    """The error of a run that exited with ``returncode``: the signal that killed the binary, or
    its last error line (bad input when it exited with _BAD_INPUT)."""
    # Under xvfb-run, a binary killed by signal N is the shell's exit status 128 + N.
    killed_by = -returncode if returncode < 0 else returncode - 128 if wrapped and returncode > 128 else 0
    if killed_by:
        try:
            name = signal.Signals(killed_by).name
        except ValueError:
            name = f"signal {killed_by}"
        return CrowdError(f"animlod_crowd: killed by {name}", bad_input=False)
    lines = [line for line in stderr.splitlines() if "error" in line]  # not its progress lines
    message = lines[-1].removeprefix("animlod_crowd: error: ") if lines else f"animlod_crowd: exit code {returncode}"
    return CrowdError(message, bad_input=returncode == _BAD_INPUT)


def _read_report(path: Path) -> dict:
    """The binary's JSON report; CrowdError (the binary's failure, not bad input) when it wrote
    none or an unreadable one."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise CrowdError("animlod_crowd: exited 0 without writing its report", bad_input=False) from None
    except (OSError, ValueError) as error:  # JSONDecodeError and UnicodeDecodeError are ValueErrors
        raise CrowdError(f"animlod_crowd: its report is not readable JSON ({error})", bad_input=False) from None
