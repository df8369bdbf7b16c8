"""Entry point of the ``broachkit`` command.

Each sub-command lives in its own module under :mod:`broachkit_cli.commands` and
provides ``NAME``, ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``, and is
listed in :data:`COMMANDS` (a command line loads the module of its command only); the
options they share are in :mod:`broachkit_cli.options`. ``broachkit`` with no
sub-command runs :data:`DEFAULT_COMMAND` (so ``broachkit --out X`` is
``broachkit reproduce --out X``).

Errors never end in a traceback unless ``--verbose``: bad input (a
:class:`ValueError`, which names the option or the vessel-file field) prints one line
and exits with 2; any other failure prints one line and exits with 1; Ctrl-C exits
with 130 and keeps what finished.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys
import traceback
import warnings
from collections.abc import Iterable
from types import ModuleType
from typing import Any

from .interrupt import (
    INTERRUPTED_LINE,
    acknowledge,
    end_process,
    show_teardown,
    sticky_interrupt,
    was_interrupted,
)
from .options import OneLineParser, add_verbose

#: Sub-command name -> its module, in the order shown by ``broachkit --help``. A command
#: line naming one loads that module alone (issue 27: a single query does not import
#: the other commands); ``broachkit --help`` loads them all.
COMMANDS: dict[str, str] = {
    "reproduce": "broachkit_cli.commands.reproduce",
    "vessels": "broachkit_cli.commands.vessels",
    "fixed-points": "broachkit_cli.commands.fixed_points",
    "manifold": "broachkit_cli.commands.manifold",
    "critical": "broachkit_cli.commands.critical",
    "critical-curve": "broachkit_cli.commands.critical_curve",
    "sensitivity": "broachkit_cli.commands.sensitivity",
    "calibrate": "broachkit_cli.commands.calibrate",
    "demo": "broachkit_cli.commands.demo",
    "sweep": "broachkit_cli.commands.sweep",
    "cycles": "broachkit_cli.commands.cycles",
    "periodic": "broachkit_cli.commands.periodic",
    "periodic-branch": "broachkit_cli.commands.periodic_branch",
    "assess": "broachkit_cli.commands.assess",
}

#: Sub-command modules, in the order shown by ``broachkit --help``.
COMMAND_MODULES: tuple[str, ...] = tuple(COMMANDS.values())

#: What ``broachkit`` runs without a sub-command.
DEFAULT_COMMAND = "reproduce"

#: Top-level flags that may precede the command name.
_TOP_FLAGS = ("-v", "--verbose")
_HELP_FLAGS = ("-h", "--help")


def _load_commands(names: Iterable[str] | None = None) -> dict[str, ModuleType]:
    """The command modules keyed by their ``NAME``: all, or those of ``names``."""
    modules = COMMAND_MODULES if names is None else tuple(COMMANDS[n] for n in names)
    cmds: dict[str, ModuleType] = {}
    for modname in modules:
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
    parser = OneLineParser(
        prog="broachkit",
        description=(
            "Continuation and bifurcation analysis of ship capsizing due to broaching "
            "(Umeda 1999). Without a sub-command: `broachkit " + DEFAULT_COMMAND + "`."
        ),
    )
    parser.add_argument(
        "-v", "--verbose", action="store_true", help="show library messages and tracebacks"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, mod in cmds.items():
        p = sub.add_parser(name, help=mod.HELP, description=mod.HELP)
        mod.add_arguments(p)
        add_verbose(p)
    return parser


def requested_command(argv: list[str]) -> str | None:
    """The one command ``argv`` runs (:func:`with_default_command`), or None for help.

    ``["fixed-points", ...]`` -> ``"fixed-points"``; ``["--out", "X"]`` and ``[]`` ->
    :data:`DEFAULT_COMMAND`; ``["-h"]`` -> None (the top-level help lists every command).
    """
    i = 0
    while i < len(argv) and argv[i] in _TOP_FLAGS:
        i += 1
    rest = argv[i:]
    if rest and rest[0] in _HELP_FLAGS:
        return None
    return rest[0] if rest and rest[0] in COMMANDS else DEFAULT_COMMAND


def with_default_command(argv: list[str], commands: dict[str, ModuleType]) -> list[str]:
    """``argv`` with :data:`DEFAULT_COMMAND` inserted when it names no command.

    ``[]`` -> ``["reproduce"]``; ``["--out", "X"]`` -> ``["reproduce", "--out", "X"]``;
    ``["-v", "--out", "X"]`` -> ``["-v", "reproduce", "--out", "X"]``; a help request
    alone (``-h``) is left as it is.
    """
    i = 0
    while i < len(argv) and argv[i] in _TOP_FLAGS:
        i += 1
    rest = argv[i:]
    if rest and (rest[0] in commands or rest[0] in _HELP_FLAGS):
        return list(argv)
    return [*argv[:i], DEFAULT_COMMAND, *rest]


class _StderrHandler(logging.StreamHandler):
    """Writes to the ``sys.stderr`` of the moment (never to a stream closed since)."""

    @property  # type: ignore[override]
    def stream(self) -> Any:
        return sys.stderr

    @stream.setter
    def stream(self, value: Any) -> None:
        pass


def configure_logging(verbose: bool) -> None:
    """Library messages: warnings only by default, everything with ``--verbose``."""
    root = logging.getLogger()
    for h in list(root.handlers):
        if getattr(h, "_broachkit", False):
            root.removeHandler(h)
    handler = _StderrHandler()
    handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
    handler._broachkit = True  # type: ignore[attr-defined]
    root.addHandler(handler)
    root.setLevel(logging.DEBUG if verbose else logging.WARNING)
    for noisy in ("matplotlib", "PIL", "numba", "asyncio"):
        logging.getLogger(noisy).setLevel(logging.WARNING)
    from continuation.sweep.backends import WORKER_LOG_ENV

    if not verbose:
        handler.addFilter(_quiet_libraries)
        # worker processes read their log level from the environment they inherit: Dask's
        # own messages not at all, the library's (a spawned worker has no filter) from
        # ERROR up; the parent says in one line what happened
        os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "critical")
        os.environ[WORKER_LOG_ENV] = "ERROR"
        # multiprocessing's resource tracker (a helper process that outlives a stopped
        # command) warns about the semaphores of the workers it cleans up after Ctrl-C
        warn = os.environ.get("PYTHONWARNINGS", "")
        if _QUIET_TRACKER not in warn:
            os.environ["PYTHONWARNINGS"] = ",".join(filter(None, (warn, _QUIET_TRACKER)))
    else:
        os.environ.pop(WORKER_LOG_ENV, None)


#: Warning filter (``PYTHONWARNINGS``) for multiprocessing's resource tracker.
_QUIET_TRACKER = "ignore::UserWarning:multiprocessing.resource_tracker"


#: Loggers of the library and of Dask: shown only with ``--verbose`` (errors always).
LIBRARY_LOGGERS = ("continuation", "ship_models", "studies", "capytaine")


#: Dask's loggers: its own shutdown reports (workers "died" when a sweep is stopped)
#: are not the user's concern; shown only with ``--verbose``. ``asyncio`` too: in this
#: command line only Dask runs an event loop, and a stopped cluster's tasks report
#: their cancellation there ("Task exception was never retrieved").
DASK_LOGGERS = ("distributed", "dask", "tornado", "asyncio")


def _quiet_libraries(record: logging.LogRecord) -> bool:
    """Without ``--verbose``: library records only from ERROR up, Dask's not at all."""
    top = record.name.split(".")[0]
    if top in DASK_LOGGERS:
        return record.levelno >= logging.CRITICAL
    return top not in LIBRARY_LOGGERS or record.levelno >= logging.ERROR


def main(argv: list[str] | None = None) -> int:
    """Run the ``broachkit`` command line; returns the exit code.

    Called without ``argv`` (the installed script, ``python -m broachkit_cli.main``),
    an interrupted command ends the process itself once it has written what it keeps
    (:func:`~broachkit_cli.interrupt.end_process`: its worker processes are killed and
    the interpreter's exit handlers, which may wait for a Dask cluster, are skipped),
    so Ctrl-C ends it within about a second at any moment.
    """
    code = _main(argv, terminal=argv is None)
    if argv is None and code == INTERRUPTED_EXIT:
        end_process(code)
    return code


#: Exit status after Ctrl-C (128 + SIGINT, as a shell reports it).
INTERRUPTED_EXIT = 130

#: Seconds after Ctrl-C by which the command-line process ends even if it is inside a
#: long native call (:func:`~broachkit_cli.interrupt.sticky_interrupt`'s watchdog);
#: with the 0.3-s wait for its processes, within the 2-s bound of issue 28.
DEADLINE_S = 1.4


def _interrupted() -> int:
    acknowledge()
    sys.stderr.write(INTERRUPTED_LINE + "\n")
    return INTERRUPTED_EXIT


def _main(argv: list[str] | None, terminal: bool = False) -> int:
    name = "reproduce"
    verbose = False
    deadline = DEADLINE_S if terminal else None
    try:
        # from the start: a Ctrl-C while the modules load ends quietly too
        with sticky_interrupt(deadline=deadline, code=INTERRUPTED_EXIT):
            argv = list(sys.argv[1:] if argv is None else argv)
            one = requested_command(argv)
            cmds = _load_commands(None if one is None else (one,))
            if not cmds:  # its module is not there: as before, with all the others
                cmds = _load_commands()
            parser = build_parser(cmds)
            argv = with_default_command(argv, cmds)
            args = parser.parse_args(argv)
            verbose = bool(getattr(args, "verbose", False))
            configure_logging(verbose)
            show_teardown(verbose)
            name = args.command
            with warnings.catch_warnings():
                if not verbose:
                    warnings.filterwarnings("ignore", module="matplotlib")
                    warnings.filterwarnings("ignore", category=UserWarning, message=".*[Ll]ayout.*")
                code = int(cmds[name].run(args))
        if was_interrupted() and code != INTERRUPTED_EXIT:
            return _interrupted()  # the command finished what it had, but was stopped
        return code
    except KeyboardInterrupt:
        return _interrupted()
    except ValueError as exc:
        if was_interrupted():  # a library call stopped by Ctrl-C left an unusable result
            return _interrupted()
        if verbose:
            traceback.print_exc()
        sys.stderr.write(f"broachkit {name}: error: {_one_line(exc)}\n")
        return 2
    except Exception as exc:  # noqa: BLE001 - the front door never shows a traceback
        if was_interrupted():
            return _interrupted()
        if verbose:
            traceback.print_exc()
        sys.stderr.write(
            f"broachkit {name}: failed: {_failure_text(exc)} (--verbose shows the traceback)\n"
        )
        return 1


def _failure_text(exc: BaseException) -> str:
    """A failure in words, without the exception's class name."""
    if isinstance(exc, OSError) and exc.strerror:
        where = f" ({exc.filename})" if exc.filename else ""
        return f"{exc.strerror}{where}"
    if isinstance(exc, MemoryError):
        return "out of memory"
    text = _one_line(exc)
    return text or "an internal error"


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= 400 else text[:397] + "..."


if __name__ == "__main__":
    raise SystemExit(main())
