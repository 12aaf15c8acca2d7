"""The ``animlod`` command line: argparse subcommands, one module each in this package.

Every subcommand module has ``register(subparsers)`` which adds its parser and sets
``run=function(args) -> int``. A user mistake (bad file, bad value) exits with code 2 and
one line on stderr, never a traceback (set ANIMLOD_DEBUG=1 to see it).
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

# Subcommand modules in the order --help lists them.
COMMAND_MODULES = ("info", "demo", "simplify", "character", "motion", "tdag")


class UserError(Exception):
    """A mistake in what the user asked for; printed as one line, exit code 2."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="animlod",
        description="Level of detail for animated content: meshes, skinned characters, motion and faces.",
    )
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f"{__name__}.{name}").register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.run(args) or 0)
    except (UserError, ValueError, OSError) as error:
        # Readers, validators and the core report bad input as ValueError; ANIMLOD_DEBUG=1 shows
        # the traceback behind the one line, for telling a bug from a user mistake.
        if os.environ.get("ANIMLOD_DEBUG"):
            raise
        print(f"animlod {args.command}: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"animlod {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
