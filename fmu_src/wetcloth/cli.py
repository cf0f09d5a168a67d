"""The ``wetcloth`` command line.  Each subcommand lives in its own module with ``add_parser``."""

from __future__ import annotations

import argparse
import importlib
import os
import sys

import wetcloth
from wetcloth import core_build
from wetcloth.commands.common import FAILED, INTERRUPTED
from wetcloth.errors import BlowUpError

#: Modules that each add one subcommand: ``add_parser(subparsers)`` sets ``func(args) -> int``.
COMMAND_MODULES = (
    "wetcloth.commands.run",
    "wetcloth.commands.params",
    "wetcloth.commands.build_fmu",
    "wetcloth.commands.demo",
    "wetcloth.commands.batch",
    "wetcloth.commands.fit",
    "wetcloth.commands.blender_extension",
)


class Parser(argparse.ArgumentParser):
    """An argument parser that takes options only as spelled in full (``--durat`` is not ``--duration``);
    the subcommands' parsers are of this class too (``add_subparsers`` makes its own kind)."""

    def __init__(self, *args, allow_abbrev: bool = False, **kwargs):
        super().__init__(*args, allow_abbrev=allow_abbrev, **kwargs)


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="wetcloth",
        description="Cloth that meets water: simulate, co-simulate (FMI 2.0 and 3.0), export to Blender, run studies.",
    )
    parser.add_argument("--version", action="version", version=f"wetcloth {wetcloth.__version__} (compiled core: {core_build.running()} build)")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(name).add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    argv = sys.argv[1:] if argv is None else list(argv)
    if "--version" in argv and len(argv) > 1:  # argparse would print the version and ignore the rest
        parser.error(f"--version takes no other arguments, got {' '.join(a for a in argv if a != '--version')}")
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except BrokenPipeError:  # the output's reader left (`wetcloth params | head`): stop quietly, as Unix tools do
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # so that the exit's flush cannot fail
        return FAILED
    except (BlowUpError, OSError, ValueError) as exc:  # a clear line, not a traceback
        print(f"wetcloth {args.command}: error: {exc}", file=sys.stderr)
        return FAILED
    except KeyboardInterrupt:  # Ctrl-C where a command has nothing of its own to save
        print(f"wetcloth {args.command}: interrupted", file=sys.stderr)
        return INTERRUPTED


if __name__ == "__main__":
    sys.exit(main())
