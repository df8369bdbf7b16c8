"""Entry point of the ``broachkit`` command.

Each sub-command lives in its own module under :mod:`broachkit_cli.commands` and
provides ``NAME``, ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``.
``broachkit`` with no sub-command runs :data:`DEFAULT_COMMAND`.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from types import ModuleType

#: Sub-command modules, in the order shown by ``broachkit --help``.
COMMAND_MODULES: tuple[str, ...] = (
    "broachkit_cli.commands.reproduce",
    "broachkit_cli.commands.vessels",
    "broachkit_cli.commands.fixed_points",
    "broachkit_cli.commands.manifold",
    "broachkit_cli.commands.critical",
    "broachkit_cli.commands.critical_curve",
    "broachkit_cli.commands.demo",
    "broachkit_cli.commands.sweep",
)

#: What ``broachkit`` runs without a sub-command.
DEFAULT_COMMAND = "reproduce"


def _load_commands() -> dict[str, ModuleType]:
    cmds: dict[str, ModuleType] = {}
    for modname in COMMAND_MODULES:
        try:
            mod = importlib.import_module(modname)
        except ModuleNotFoundError as exc:  # a command whose module is not there yet
            if exc.name == modname:
                continue
            raise
        cmds[mod.NAME] = mod
    return cmds


def build_parser(cmds: dict[str, ModuleType]) -> argparse.ArgumentParser:
    """The top-level parser with one sub-parser per command."""
    parser = argparse.ArgumentParser(
        prog="broachkit",
        description=(
            "Continuation and bifurcation analysis of ship capsizing due to broaching "
            "(Umeda 1999). Without a sub-command: `broachkit " + DEFAULT_COMMAND + "`."
        ),
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, mod in cmds.items():
        p = sub.add_parser(name, help=mod.HELP, description=mod.HELP)
        mod.add_arguments(p)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the ``broachkit`` command line; returns the exit code."""
    cmds = _load_commands()
    parser = build_parser(cmds)
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO,
        format="%(message)s",
        stream=sys.stderr,
    )
    name = args.command or DEFAULT_COMMAND
    if args.command is None:
        args = parser.parse_args([*(argv or sys.argv[1:]), name])
    try:
        return int(cmds[name].run(args))
    except KeyboardInterrupt:
        sys.stderr.write("interrupted; finished results are kept on disk\n")
        return 130
    except ValueError as exc:
        sys.stderr.write(f"broachkit {name}: error: {exc}\n")
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
