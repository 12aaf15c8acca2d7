"""The ``animlod`` command line: argparse subcommands, one module each in this package.

Every subcommand module has ``register(subparsers)`` which adds its parser and sets
``run=function(args) -> int``.

The error contract: a user mistake (bad file, bad value, unwritable output) exits with code 2
and exactly one line on stderr, ``animlod CMD: error: WHERE: WHAT``, where WHERE names the file
(input or output) and the element; nothing is written to stderr before it (progress bars and
numpy warnings of the failed run are withheld, see :class:`_HeldStderr`), and there is no
traceback (set ANIMLOD_DEBUG=1 to see it).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import io
import os
import select
import signal
import sys
import threading
import warnings
from collections.abc import Iterator

from ..io.errors import error_line

# Subcommand modules in the order --help lists them.
COMMAND_MODULES = ("info", "demo", "simplify", "character", "motion", "face", "tdag", "crowd", "batch")


class UserError(Exception):
    """A mistake in what the user asked for; printed as one line, exit code 2.

    The message is ``WHERE: WHAT``, WHERE being an option (``--ratio``) or a file.
    """


class MachineError(Exception):
    """What this machine cannot do for a well-formed request (no display or OpenGL context for
    the crowd, its binary not built); printed as one line like a UserError, exit code 3."""


class _Parser(argparse.ArgumentParser):
    """argparse with the one-line error contract: no usage block before the error line."""

    def error(self, message: str) -> None:  # type: ignore[override]
        if message.startswith("argument "):  # "argument --ratio: invalid float value: 'x'"
            message = message[len("argument ") :]
        self.exit(2, f"{self.prog}: error: {message}\n")


def non_negative_int(text: str) -> int:
    """argparse type: a whole number >= 0 (``--max-frames -3`` is refused by argparse)."""
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {value}")
    return value


def positive_int(text: str) -> int:
    """argparse type: a whole number >= 1."""
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def add_joint_map_argument(parser: argparse.ArgumentParser) -> None:
    """``--joint-map FILE``, the table of nodes that BVH clips' joints drive (with ``--clips``)."""
    parser.add_argument(
        "--joint-map", metavar="MAP.json",
        help='with BVH --clips: {"BVH joint": "node name" or node index, ...}, the node each joint drives, where '
        "the skeletons' shape, body parts and names do not tell (only its entries are matched)",
    )  # fmt: skip


def print_rows(rows: list[tuple], indent: str = "") -> None:
    """Print ``rows`` (the header first) as right-aligned columns two spaces apart."""
    widths = [max(len(str(row[column])) for row in rows) for column in range(len(rows[0]))]
    for row in rows:
        print(indent + "  ".join(str(value).rjust(width) for value, width in zip(row, widths)))


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="animlod",
        description="Level of detail for animated content: meshes, skinned characters, motion and faces.",
    )
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"animlod {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f"{__name__}.{name}").register(subparsers)
    return parser


class _HeldStderr(io.TextIOBase):
    """Stands in for sys.stderr while a command runs, so that a failed run prints its error line
    and nothing before it.

    On a terminal, writes pass through (progress bars stay live) and a line left unfinished by
    a progress bar is cleared before the error line. Elsewhere (a pipe, a log, a test), writes
    are held and replayed only when the command succeeds.
    """

    def __init__(self, stream) -> None:
        super().__init__()
        self.stream = stream
        self.live = bool(getattr(stream, "isatty", lambda: False)())
        self.held: list[str] = []
        self.partial_line = False

    def write(self, text: str) -> int:
        if self.live:
            self.stream.write(text)
            if text:
                self.partial_line = not text.endswith("\n")
        else:
            self.held.append(text)
        return len(text)

    def flush(self) -> None:
        if self.live:
            self.stream.flush()

    def isatty(self) -> bool:
        return self.live

    def release(self, failed: bool) -> None:
        """Replay what was held (success), or drop it and clear a live partial line (failure)."""
        if failed:
            if self.live and self.partial_line:
                self.stream.write("\r\x1b[2K")
        else:
            self.stream.write("".join(self.held))
        self.held = []


@contextlib.contextmanager
def _guarded_stderr(command: str) -> Iterator[_HeldStderr]:
    """Hold stderr and warnings for the run; warnings of a successful run are printed after it,
    one line each (``animlod CMD: warning: ...``), those of a failed run are dropped."""
    original = sys.stderr
    held = _HeldStderr(original)
    sys.stderr = held
    failed = True
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("default")
            yield held
            failed = False
    finally:
        sys.stderr = original
        held.release(failed)
        if not failed:
            for warning in caught:
                print(f"animlod {command}: warning: {' '.join(str(warning.message).split())}", file=original)


class _Terminated(BaseException):
    """SIGTERM, raised in the main thread so that every write in progress removes its temporary."""


def _raise_terminated(signum, frame) -> None:
    raise _Terminated


@contextlib.contextmanager
def _sigterm_unwinds() -> Iterator[None]:
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _stdout_gone() -> bool:
    """Whether stdout is a pipe whose reader has left (poll reports an error on its write end);
    if so, later writes, the interpreter's final flush included, go to the null device."""
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        gone = any(events & select.POLLERR for _, events in poller.poll(0))
    except (AttributeError, OSError, ValueError):  # no poll (Windows), or no real stdout
        return False
    if gone:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return gone


def check_output_is_not_input(
    source: str | os.PathLike | None, output: object, option: str = "-o", what: str = "the levels"
) -> None:
    """UserError when ``option`` (``-o``) names the input file itself: ``what`` it writes would
    replace the file it is made from (a LoD GLB holds the input, but not byte for byte)."""
    if source is None or not isinstance(output, (str, os.PathLike)) or not os.path.isfile(source):
        return
    if os.path.exists(output) and os.path.samefile(source, output):
        raise UserError(f"{option} {os.fspath(output)}: is the input file; write {what} to another file")


def check_output_writable(output: object) -> None:
    """Raise, before any work, the OSError that writing ``-o`` would meet only at the end: the
    folder ``output`` names, or the folder of the file it names, must take new files."""
    if isinstance(output, (str, os.PathLike)):
        from ..io.atomic import check_writable_folder

        check_writable_folder(output if os.path.isdir(output) else os.path.dirname(os.fspath(output)) or ".")


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:  # --help (0), or the one-line usage error of _Parser (2)
        return int(stop.code or 0)
    source = getattr(args, "input", None) or getattr(args, "path", None) or getattr(args, "tdag", None)
    if not isinstance(source, (str, os.PathLike)):
        source = None  # e.g. crowd's --path, a list of navigation paths, names no input file
    output = getattr(args, "output", None)
    if os.environ.get("ANIMLOD_DEBUG"):  # tracebacks and live output, for telling a bug from a mistake
        check_output_is_not_input(source, output)
        check_output_writable(output)
        return int(args.run(args) or 0)
    try:
        check_output_is_not_input(source, output)
        check_output_writable(output)
        with _sigterm_unwinds(), _guarded_stderr(args.command):
            return int(args.run(args) or 0)
    except (UserError, MachineError) as error:
        print(f"animlod {args.command}: error: {' '.join(str(error).split())}", file=sys.stderr)
        return 3 if isinstance(error, MachineError) else 2
    except BrokenPipeError as error:
        if not _stdout_gone():
            print(f"animlod {args.command}: error: {error_line(error, source)}", file=sys.stderr)
            return 2
        return 141  # stdout's reader left (`animlod info DIR | head`): quiet, as 128 + SIGPIPE
    except (ValueError, OSError, MemoryError) as error:
        # Readers, validators and the core report bad input as ValueError (FormatError names the
        # file); the data model and the core name only the element, so the input is added.
        if isinstance(error, MemoryError):
            error = ValueError(f"not enough memory ({error or 'allocation failed'})")
        print(f"animlod {args.command}: error: {error_line(error, source)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"animlod {args.command}: interrupted", file=sys.stderr)
        return 130
    except _Terminated:
        print(f"animlod {args.command}: terminated", file=sys.stderr)
        return 143


if __name__ == "__main__":
    sys.exit(main())
