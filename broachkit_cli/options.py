"""Options shared by the ``broachkit`` commands, and their checks.

One place defines the common options (vessel, wave, autopilot course, Froude number,
output folder, ``--json``, ``--verbose``) so that every command spells and checks
them alike. Names follow the paper's symbols: the flag is the kebab-case of the
library name and argparse's ``dest`` is the library name itself (``--fn`` ->
``Fn``, ``--fn-guess`` -> ``Fn_guess``, ``--chi-c`` -> ``chi_c``, ``--h-over-lambda``
-> ``H_over_lambda``). Degrees on the command line, radians in the library.

Every check raises a one-line :class:`ValueError` naming the option; the entry
point (:func:`broachkit_cli.main.main`) prints it and exits with status 2.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

#: Largest autopilot course accepted (deg); beyond it the ship is no longer in
#: following/quartering seas and the wave model's encounter assumptions fail.
CHI_C_MAX_DEG = 85.0
#: Plausible range of the wavelength-to-length ratio lambda/L (the strip wave
#: forces and the paper's regime: 0.5 .. 3 in Umeda 1999).
LAMBDA_OVER_L_RANGE = (0.2, 5.0)
#: Most values a list option (``--chi-c 0:30:5``) may give; a range with a tiny step
#: is refused before anything is allocated.
MAX_LIST_VALUES = 1000


class OneLineParser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` whose usage errors are one line (exit 2)."""

    def error(self, message: str) -> Any:  # noqa: D102 - argparse's contract
        self.exit(2, f"{self.prog}: error: {message}\n")


# ---------------------------------------------------------------- adding options


def add_verbose(parser: argparse.ArgumentParser) -> None:
    """``-v/--verbose``: debug messages and tracebacks (accepted before or after COMMAND)."""
    parser.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        default=argparse.SUPPRESS,
        help="show library messages and the traceback of an error",
    )


def add_json(parser: argparse.ArgumentParser) -> None:
    """``--json``: print the result as one JSON document on stdout."""
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


def add_out(parser: argparse.ArgumentParser, default: str | None, what: str) -> None:
    """``--out DIR`` (checked by :func:`prepare_out` before any computing)."""
    parser.add_argument(
        "--out",
        type=Path,
        default=None if default is None else Path(default),
        help=f"folder for {what}" + ("" if default is None else f" (default {default})"),
    )


def add_vessel(parser: argparse.ArgumentParser) -> None:
    """``--vessel NAME|FILE``."""
    parser.add_argument(
        "--vessel",
        default="purse_seiner",
        help="registered model name or path of a vessel TOML file (default: purse_seiner)",
    )


def _float_option(
    parser: argparse.ArgumentParser, flag: str, dest: str, help_: str, default: Any = None
) -> None:
    """One float option ``flag`` stored in ``args.<dest>``."""
    parser.add_argument(flag, dest=dest, type=float, default=default, help=help_)


def add_wave(parser: argparse.ArgumentParser) -> None:
    """``--h-over-lambda`` and ``--lambda-over-l`` (default: the vessel file's wave)."""
    _float_option(
        parser,
        "--h-over-lambda",
        "H_over_lambda",
        "wave steepness H/lambda (default: the vessel's; at most 1/7, breaking)",
    )
    _float_option(
        parser,
        "--lambda-over-l",
        "lambda_over_L",
        "wavelength over ship length lambda/L (default: the vessel's)",
    )


def add_chi_c(parser: argparse.ArgumentParser, default: float = 10.0) -> None:
    """``--chi-c DEG``: one autopilot course in degrees."""
    _float_option(
        parser,
        "--chi-c",
        "chi_c",
        f"autopilot course chi_c in degrees (default {default:g})",
        default,
    )


def add_fn(parser: argparse.ArgumentParser) -> None:
    """``--fn``: the nominal Froude number (default: the model's, ``paper.PAPER_FN``)."""
    _float_option(parser, "--fn", "Fn", "nominal Froude number Fn (default: the model's)")


def add_fn_guess(parser: argparse.ArgumentParser) -> None:
    """``--fn-guess``: the Fn of the simulation that seeds a connecting orbit."""
    _float_option(
        parser,
        "--fn-guess",
        "Fn_guess",
        "Fn of the unstable-manifold simulation that seeds the orbit (default: model's)",
    )


def add_ship(parser: argparse.ArgumentParser, *, fn: bool = True, chi_c: bool = True) -> None:
    """Vessel, wave, course and (optionally) Fn options, plus ``--json``."""
    add_vessel(parser)
    if fn:
        add_fn(parser)
    if chi_c:
        add_chi_c(parser)
    add_wave(parser)
    add_json(parser)


# ---------------------------------------------------------------- checking


def finite(name: str, value: float, *, low: float = -math.inf, high: float = math.inf,
           low_open: bool = True, unit: str = "") -> float:  # fmt: skip
    """``value`` as a float if finite and in ``(low, high]`` (``[low, high]``), else ValueError.

    ``name`` is the option as the user typed it (``"--fn-max"``).
    """
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    below = v <= low if low_open else v < low
    if not math.isfinite(v) or below or v > high:
        lo = "(" if low_open else "["
        rng = f"{lo}{low:g}, {high:g}]"
        raise ValueError(
            f"{name} must be finite and in {rng}{' ' + unit if unit else ''}, got {value}"
        )
    return v


def parse_list(
    text: str, flag: str, *, default_step: float | None = None, max_count: int = MAX_LIST_VALUES
) -> Any:
    """Values of a list option: ``"start:stop:step"`` (inclusive), ``"a,b,c"`` or ``"a"``.

    Parameters
    ----------
    text : str
        What the user typed.
    flag : str
        The option as typed (``"--chi-c"``), named in every error.
    default_step : float, optional
        Allows ``"start:stop"`` with this step.
    max_count : int
        Most values allowed (checked before the values are built).

    Returns
    -------
    numpy.ndarray
        Shape ``(k,)``, finite, ``1 <= k <= max_count``.

    Raises
    ------
    ValueError
        One line naming ``flag``: unreadable, an empty or reversed range, a step that is
        not positive, non-finite values, or more than ``max_count`` values.
    """
    import numpy as np

    form = "'start:stop[:step]'" if default_step is not None else "'start:stop:step'"
    grid = None
    try:
        if ":" in text:
            parts = [float(s) for s in text.split(":")]
            if len(parts) == 2 and default_step is not None:
                parts.append(default_step)
            if len(parts) != 3:
                raise ValueError
            a, b, step = parts
            if not all(math.isfinite(v) for v in parts) or step <= 0 or b < a:
                raise ValueError
            grid = (a, step, (b - a) / step)
        else:
            vals = np.array([float(s) for s in text.split(",")])
    except ValueError:
        raise ValueError(f"{flag} must be {form} or a comma list 'a,b,c', got {text!r}") from None
    if grid is not None:
        a, step, q = grid
        if not q + 1 <= max_count:  # before anything is allocated; also an infinite count
            n = math.floor(q + 1e-9) + 1 if math.isfinite(q) else "infinitely many"
            raise ValueError(f"{flag} gives {n} values; at most {max_count}")
        vals = a + step * np.arange(math.floor(q + 1e-9) + 1)
    if vals.size == 0 or not np.all(np.isfinite(vals)):
        raise ValueError(f"{flag} must give finite numbers, got {text!r}")
    if vals.size > max_count:
        raise ValueError(f"{flag} gives {vals.size} values; at most {max_count}")
    return vals


def prepare_out(out: Path | str | None, name: str = "--out") -> Path | None:
    """Create the output folder and prove it writable, before anything is computed.

    Raises
    ------
    ValueError
        Naming ``name`` when the path is a file, cannot be created, or is not writable.
    """
    if out is None:
        return None
    p = Path(out)
    if "\x00" in str(p):
        raise ValueError(f"{name}: the path contains a NUL character")
    if p.exists() and not p.is_dir():
        raise ValueError(f"{name}: {p} exists and is not a folder")
    try:
        p.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".write-test-", dir=p)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        reason = exc.strerror or "not writable"
        raise ValueError(f"{name}: cannot write to {p} ({reason})") from None
    return p


def prepare_out_file(out: Path | str, default_name: str, name: str = "--out") -> Path:
    """The output *file* of a command, checked writable before anything is computed.

    An existing folder (or a path ending in ``/``) means ``folder/default_name``.

    Raises
    ------
    ValueError
        Naming ``name`` when the file's folder cannot be created or written to.
    """
    text = str(out)
    p = Path(out)
    if p.is_dir() or text.endswith(("/", os.sep)):
        p = p / default_name
    if p.exists() and not p.is_file():
        raise ValueError(f"{name}: {p} exists and is not a file")
    prepare_out(p.parent if str(p.parent) else Path("."), name)
    return p


def _check_vessel_name(name: str) -> None:
    text = str(name)
    if not text.strip():
        raise ValueError("--vessel must name a vessel (see `broachkit vessels list`)")
    if "\x00" in text:
        raise ValueError("--vessel contains a NUL character")
    if text.endswith(".toml") or "/" in text or os.sep in text:
        p = Path(text)
        if not p.is_file():
            raise ValueError(f"--vessel: no vessel file {text!r}")
        from ship_models.validation import check_file_size

        try:
            check_file_size(p)
        except ValueError as exc:
            raise ValueError(f"--vessel: {exc}") from None


def load_model(vessel: str) -> Any:
    """The model of ``--vessel`` through :func:`ship_models.registry.get_model`.

    Raises
    ------
    ValueError
        Unknown name, unreadable or invalid vessel file (the message names the field).
    """
    from ship_models.registry import PluginError, get_model

    _check_vessel_name(vessel)
    try:
        return get_model(vessel)
    except PluginError as exc:
        raise ValueError(f"--vessel {vessel!r}: {exc}") from exc
    except ValueError as exc:
        raise ValueError(f"--vessel {vessel!r}: {exc}") from exc
    except OSError as exc:
        raise ValueError(f"--vessel {vessel!r}: cannot read ({exc.strerror})") from exc


def fn_limit(model: Any) -> float:
    """Largest Fn the model is valid for (:func:`ship_models.analysis.fn_window.fn_limit`)."""
    from ship_models.analysis.fn_window import fn_limit as limit

    return limit(model)


def check_fn(model: Any, name: str, value: float) -> float:
    """A Froude number within ``(0, fn_limit(model)]``, else ValueError naming ``name``."""
    hi = fn_limit(model)
    v = finite(name, value)
    if not 0.0 < v <= hi:
        raise ValueError(
            f"{name} = {value} is outside (0, {hi:g}], the Froude-number range of the "
            "vessel's resistance fit (resistance.Fn_max_fit)"
        )
    return v


def check_chi_c_deg(name: str, value: float) -> float:
    """An autopilot course in degrees within +-:data:`CHI_C_MAX_DEG`."""
    v = finite(name, value)
    if not abs(v) < CHI_C_MAX_DEG:
        raise ValueError(
            f"{name} must be a course in degrees within +-{CHI_C_MAX_DEG:g}, got {value}"
        )
    return v


#: Environment variable giving the default number of worker processes (read once, here).
WORKERS_ENV = "BROACHKIT_WORKERS"


def check_workers(value: Any, name: str = "--workers") -> int:
    """A count of worker processes for a command, passed on to the library as an argument.

    ``value`` when given, else ``$BROACHKIT_WORKERS`` when set, else one per core;
    checked by the library's one check (:func:`continuation.sweep.check_workers`: a
    positive integer, at most :data:`continuation.sweep.MAX_WORKERS`).

    Raises
    ------
    ValueError
        Naming the option (or the environment variable).
    """
    from continuation.sweep.backends import check_workers as check
    from continuation.sweep.backends import default_workers

    if value is not None:
        return int(check(value, name))
    raw = os.environ.get(WORKERS_ENV, "").strip()
    if not raw:
        return default_workers()
    try:
        n = int(raw)
    except ValueError:
        raise ValueError(f"{WORKERS_ENV} must be a positive integer, got {raw!r}") from None
    return int(check(n, WORKERS_ENV))


def add_backend(parser: argparse.ArgumentParser, what: str) -> None:
    """Where ``what`` runs (read by :func:`backend_options`), one of four exclusive options.

    ``--processes N`` (local processes; default ``$BROACHKIT_WORKERS``, else one per
    core), ``--workers N`` (a Dask ``LocalCluster`` of ``N``), ``--scheduler ADDRESS``
    (a running Dask scheduler) or ``--serial`` (this process).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's parser.
    what : str
        What runs there, the start of each help text (``"exact threshold"``).
    """
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--processes",
        type=int,
        default=None,
        help=f"{what} on N local processes (default: ${WORKERS_ENV}, else one per core)",
    )
    where.add_argument(
        "--workers", type=int, default=None, help=f"{what} on a Dask LocalCluster of N"
    )
    where.add_argument(
        "--scheduler", default=None, help=f"{what} on a Dask scheduler tcp://HOST:PORT"
    )
    where.add_argument("--serial", action="store_true", help=f"{what} in this process (debugging)")


def backend_options(args: argparse.Namespace) -> dict[str, Any]:
    """Where a sweep's tasks run, from ``--scheduler``, ``--workers``, ``--serial`` and
    ``--processes`` (in that order of precedence): the keyword arguments of
    :func:`continuation.sweep.run_sweep` naming the backend and its worker count."""
    if args.scheduler:
        return {"scheduler": args.scheduler}
    if args.workers is not None:
        return {"backend": "dask", "workers": check_workers(args.workers, "--workers")}
    if args.serial:
        return {"backend": "serial"}
    return {"backend": "processes", "workers": check_workers(args.processes, "--processes")}


def wave_changes(args: argparse.Namespace) -> dict[str, float]:
    """Checked ``H_over_lambda`` / ``lambda_over_L`` from the options that were given."""
    from ship_models.vessel import BREAKING_STEEPNESS

    changes: dict[str, float] = {}
    h = getattr(args, "H_over_lambda", None)
    if h is not None:
        v = finite("--h-over-lambda", h)
        if not 0.0 < v <= BREAKING_STEEPNESS:
            raise ValueError(
                f"--h-over-lambda = {h} is impossible: a wave is in (0, 1/7 = "
                f"{BREAKING_STEEPNESS:.4f}] (steeper waves break; Michell 1893)"
            )
        changes["H_over_lambda"] = v
    lam = getattr(args, "lambda_over_L", None)
    if lam is not None:
        lo, hi = LAMBDA_OVER_L_RANGE
        v = finite("--lambda-over-l", lam)
        if not lo <= v <= hi:
            raise ValueError(f"--lambda-over-l must be in [{lo:g}, {hi:g}], got {lam}")
        changes["lambda_over_L"] = v
    return changes


def ship_from_args(args: argparse.Namespace) -> tuple[Any, Any]:
    """The model (through ``get_model``) and its parameters from the shared options.

    Reads ``vessel``, and if present ``Fn``, ``chi_c`` (degrees), ``H_over_lambda``,
    ``lambda_over_L``; the parameters are the model's defaults with those replaced
    (``chi_c`` in radians).

    Raises
    ------
    ValueError
        For an unknown vessel, a bad vessel file, or an option out of range (naming it).
    """
    changes = wave_changes(args)
    chi = getattr(args, "chi_c", None)
    if chi is not None:
        changes["chi_c"] = math.radians(check_chi_c_deg("--chi-c", chi))
    model = load_model(args.vessel)
    names = tuple(getattr(model, "param_names", ()))
    if "chi_c" not in names or not hasattr(model, "vessel"):
        raise ValueError(
            f"--vessel {args.vessel!r} is not a 4-DOF ship model (parameters {names}); "
            "use a vessel name or file (see `broachkit vessels list`)"
        )
    if getattr(args, "Fn", None) is not None:
        changes["Fn"] = check_fn(model, "--fn", args.Fn)
    return model, model.default_params().replace(**changes)


def numerical_failure_exit(
    name: str, run: Callable[[argparse.Namespace], int], args: argparse.Namespace
) -> int:
    """``run(args)``; a numerical failure (ContinuationError) is one line on stderr naming
    the command ``name`` and exit status 1, never a traceback (logged at debug level,
    shown with ``--verbose``)."""
    from continuation.errors import ContinuationError

    try:
        return run(args)
    except ContinuationError as exc:
        logging.getLogger(__name__).debug("%s failed", name, exc_info=True)
        sys.stderr.write(f"broachkit {name}: {exc}\n")
        return 1


def json_safe(obj: Any) -> Any:
    """``obj`` with every non-finite float replaced by ``None`` (:mod:`continuation.atomic`)."""
    from continuation.atomic import json_safe as safe

    return safe(obj)


def print_json(doc: Any) -> None:
    """Print a command's result ``doc`` as one JSON document (``--json``) on stdout.

    Parameters
    ----------
    doc : object
        JSON-serialisable result; non-finite floats are written as ``null``
        (:func:`json_safe`), indented by 2.
    """
    sys.stdout.write(json.dumps(json_safe(doc), indent=2) + "\n")


def emit(args: argparse.Namespace, doc: dict[str, Any], text: Callable[[dict], str]) -> None:
    """``doc`` as JSON with ``--json``, else its text (``text(doc)``) and the files written."""
    if args.json:
        print_json(doc)
        return
    lines = [text(doc)] + [f"  wrote {f}" for f in doc.get("files", [])]
    sys.stdout.write("\n".join(lines) + "\n")


__all__ = [
    "CHI_C_MAX_DEG",
    "LAMBDA_OVER_L_RANGE",
    "OneLineParser",
    "add_backend",
    "add_chi_c",
    "add_fn",
    "add_fn_guess",
    "add_json",
    "add_out",
    "add_ship",
    "add_vessel",
    "add_verbose",
    "add_wave",
    "check_chi_c_deg",
    "check_fn",
    "WORKERS_ENV",
    "check_workers",
    "emit",
    "finite",
    "fn_limit",
    "json_safe",
    "load_model",
    "prepare_out",
    "prepare_out_file",
    "print_json",
    "ship_from_args",
    "wave_changes",
]
