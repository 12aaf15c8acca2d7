"""Run the native crowd benchmark ``animlod_crowd`` (bench/crowd/) and read its report.

The binary is built by the top-level CMake build (``make bench-crowd`` or ``make test``); it is
found through ``ANIMLOD_CROWD_BIN``, the checkout's ``build/cpp/bench/crowd/``, or ``PATH``.
Without a display it is started under ``xvfb-run`` (Mesa's llvmpipe renders off-screen).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

MODES = ("Original", "GLoD", "MLoD", "G+MLoD")
PATHS = ("nav1", "nav2", "pullback")
# Exit codes of animlod_crowd (bench/crowd/main.cpp).
_BAD_INPUT, _NO_CONTEXT = 2, 3


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
    json_path : where the binary writes its JSON (a temporary file when None).
    extra_args : further animlod_crowd options (see ``animlod_crowd --help``).
    binary : the executable; find_crowd_binary() when None.

    Raises
    ------
    CrowdError with the binary's one-line message: bad input (``bad_input``), no GL context, or
    the binary missing.
    """
    if not chains:
        raise CrowdError("chains: none given", bad_input=True)
    if path not in PATHS:
        raise CrowdError(f"path {path!r}: expected one of {', '.join(PATHS)}", bad_input=True)
    try:
        names = mode_list(modes)
    except ValueError as error:
        raise CrowdError(str(error), bad_input=True) from None
    executable = Path(binary) if binary else find_crowd_binary()
    if executable is None or not executable.is_file():
        raise CrowdError(
            "animlod_crowd is not built: run `make bench-crowd` (or cmake --build build/cpp), "
            "or point ANIMLOD_CROWD_BIN at it",
            bad_input=False,
        )
    with tempfile.TemporaryDirectory(prefix="animlod_crowd_") as scratch:
        report_path = Path(json_path) if json_path else Path(scratch) / "crowd.json"
        command = [str(executable), *(str(Path(c)) for c in chains)]
        command += ["--count", str(count), "--frames", str(frames), "--warmup", str(warmup), "--rounds", str(rounds)]
        command += ["--modes", ",".join(names), "--path", path, "--width", str(width), "--height", str(height)]
        command += ["--pixel-error", repr(float(pixel_error)), "--json", str(report_path)]
        if level_colors:
            command.append("--level-colors")
        if grid:
            command.append("--grid")
        for frame, png in screenshots:
            command += ["--screenshot", str(int(frame)), str(png)]
        command += [str(arg) for arg in extra_args]
        launch = list(command)
        if not os.environ.get("DISPLAY") and shutil.which("xvfb-run"):
            launch = ["xvfb-run", "-a", "-s", f"-screen 0 {max(width, 640)}x{max(height, 480)}x24", *command]
        completed = subprocess.run(launch, capture_output=True, text=True, timeout=timeout, check=False)
        if completed.returncode != 0:
            lines = [line for line in completed.stderr.splitlines() if "error" in line] or completed.stderr.splitlines()
            message = lines[-1].removeprefix("animlod_crowd: error: ") if lines else f"exit code {completed.returncode}"
            raise CrowdError(message, bad_input=completed.returncode == _BAD_INPUT)
        data = json.loads(report_path.read_text())
    return CrowdReport(data=data, markdown=completed.stdout, command=command)
