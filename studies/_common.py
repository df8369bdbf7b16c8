"""Shared output helpers for the study scripts: output folder, figure style, PNG and CSV.

Study modules import this one as ``from studies._common import ...`` (``studies`` is
a package installed with broachkit, so ``python -m studies.<script>`` and
``python studies/<script>.py`` both find it). Everything here is generic: nothing
knows about ships.
Every file is written atomically (a temporary file renamed onto the final name,
:mod:`continuation.atomic`), so an interrupted study never leaves a truncated file.

- :func:`output_dir` -- ``<root>/<name>``, created; root from ``--out``, else the
  environment variable ``BROACHKIT_OUT``, else ``./out``.
- :data:`STYLE` / :func:`figure_style` -- one consistent matplotlib look.
- :func:`new_figure` -- a styled figure that needs no GUI backend.
- :func:`save_figure` -- PNG at a fixed resolution, figure closed afterwards.
- :func:`save_csv` / :func:`read_csv` -- numeric columns with ``#`` metadata lines.
- :func:`save_table` -- rows of text and numbers (e.g. a coefficient table).
- :func:`write_summary` -- a step's ``summary.json`` (its results, the same bytes on
  every run of the same inputs) and ``timings.json`` (this run's clock and reuse).
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import json
import logging
import math
import os
import sys
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from continuation.atomic import atomic_path, write_atomic, write_atomic_group, write_json
from ship_models.columns import ANGLE_STATES, RATE_STATES, state_columns

log = logging.getLogger(__name__)

#: Environment variable naming the default output root.
OUT_ENV = "BROACHKIT_OUT"

#: Keys of a summary that describe the run rather than its results (wall-clock and
#: CPU times, how many checkpointed tasks were reused, worker counts):
#: :func:`write_summary` moves them to ``timings.json``. Keys ending in one of
#: :data:`RUN_SUFFIXES` (e.g. ``threshold_elapsed_s``) are run keys too.
RUN_KEYS = frozenset({"seconds", "elapsed_s", "wall_s", "reused", "workers"})
RUN_SUFFIXES = ("_elapsed_s", "_seconds", "_wall_s")


def is_run_key(key: object) -> bool:
    """Whether a summary key describes the run (its clock or reuse), not a result."""
    return isinstance(key, str) and (key in RUN_KEYS or key.endswith(RUN_SUFFIXES))


def split_run_record(doc: Any) -> tuple[Any, Any]:
    """Split a summary into its results and its run record.

    Parameters
    ----------
    doc : Any
        A JSON-like value (dicts, lists, scalars).

    Returns
    -------
    results : Any
        ``doc`` without its run keys (:func:`is_run_key`), at any depth.
    record : Any
        The removed entries in the same nesting (dicts only; ``None`` when there are
        none). Entries inside lists are keyed by their index as a string.
    """
    if isinstance(doc, Mapping):
        kept: dict[str, Any] = {}
        record: dict[str, Any] = {}
        for k, v in doc.items():
            if is_run_key(k):
                record[k] = v
                continue
            kept[k], sub = split_run_record(v)
            if sub is not None:
                record[k] = sub
        return kept, record or None
    if isinstance(doc, list | tuple):
        items = [split_run_record(v) for v in doc]
        sub_rec = {str(i): r for i, (_, r) in enumerate(items) if r is not None}
        return [v for v, _ in items], sub_rec or None
    return doc, None


def write_summary(out: str | os.PathLike[str], summary: Mapping[str, Any], **kw: Any) -> Path:
    """Write a step's ``summary.json`` and ``timings.json`` into folder ``out``.

    ``summary.json`` holds the results only, so a step rerun on the same inputs, or
    resumed after Ctrl-C, writes the same bytes; the run's clock and reuse counts
    (:data:`RUN_KEYS`) go to ``timings.json`` beside it. Both atomically.

    Parameters
    ----------
    out : path-like
        The step's folder.
    summary : Mapping
        The summary as the study computed it (the caller keeps its own copy whole).
    **kw
        Passed to :func:`continuation.atomic.write_json` (e.g. ``default=float``).

    Returns
    -------
    Path
        The path of ``summary.json``.
    """
    folder = Path(out)
    write_results(folder / "summary.json", summary, record=folder / "timings.json", **kw)
    return folder / "summary.json"


def write_results(
    path: str | os.PathLike[str],
    doc: Mapping[str, Any],
    *,
    record: str | os.PathLike[str] | None = None,
    **kw: Any,
) -> Path:
    """Write a JSON result file without its run keys, and the run keys beside it.

    Parameters
    ----------
    path : path-like
        The result file (e.g. ``critical.json``).
    doc : Mapping
        The document as computed.
    record : path-like, optional
        Where the run keys go (default: ``<stem>.timings.json`` beside ``path``).
    **kw
        Passed to :func:`continuation.atomic.write_json`.

    Returns
    -------
    Path
        ``path``.
    """
    path = Path(path)
    results, run = split_run_record(dict(doc))
    rec = Path(record) if record is not None else path.with_name(f"{path.stem}.timings.json")
    write_json(rec, run or {}, **kw)
    write_json(path, results, **kw)  # last: a step's summary marks the step finished
    return path


#: matplotlib rcParams of all study figures.
STYLE: dict[str, Any] = {
    "figure.dpi": 100,
    "savefig.dpi": 150,
    "font.size": 9,
    "axes.titlesize": 10,
    "axes.labelsize": 9,
    "legend.fontsize": 8,
    "xtick.labelsize": 8,
    "ytick.labelsize": 8,
    "axes.grid": True,
    "grid.alpha": 0.3,
    "lines.linewidth": 1.4,
    "axes.spines.top": False,
    "axes.spines.right": False,
}


def study_main(
    doc: str,
    default_out: str,
    compute: Callable[..., dict[str, Any]],
    argv: Sequence[str] | None = None,
    *,
    flags: Sequence[tuple[str, str]] = (),
    shown: Sequence[str] | None = None,
) -> int:
    """The command-line entry of a figure step: ``python studies/<step>.py --out DIR``.

    Parameters
    ----------
    doc : str
        The module docstring (its first line is the description).
    default_out : str
        Default ``--out`` folder.
    compute : callable
        ``compute(out, progress=..., **flags) -> summary``.
    argv : sequence of str, optional
        Arguments (default ``sys.argv[1:]``).
    flags : sequence of (name, help)
        Boolean options ``--name`` passed to ``compute`` as ``name=True/False``.
    shown : sequence of str, optional
        The summary keys printed (default: all of it).

    Returns
    -------
    int
        0 (a failure raises).
    """
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(default_out))
    for name, help_ in flags:
        ap.add_argument(f"--{name}", action="store_true", help=help_)
    args = ap.parse_args(argv)
    options = {name: getattr(args, name) for name, _ in flags}
    s = compute(args.out, progress=lambda m: sys.stdout.write(m + "\n"), **options)
    sys.stdout.write(json.dumps(s if shown is None else {k: s[k] for k in shown}, indent=2) + "\n")
    return 0


def begin_step(
    out: Path, progress: Callable[[str], None] | None = None
) -> tuple[Callable[[str], None], float]:
    """Start a figure step: create its folder, return its progress callback and start time.

    Parameters
    ----------
    out : Path
        The step's output folder (created with its parents).
    progress : callable, optional
        ``progress(message)``; None: messages are dropped.

    Returns
    -------
    say : callable
        ``progress``, or a callable that ignores its message.
    started : float
        A :func:`time.perf_counter` reading, for :func:`finish_summary`.
    """
    out.mkdir(parents=True, exist_ok=True)
    return progress or _quiet, time.perf_counter()


def _quiet(msg: str) -> None:
    """A progress callback that drops ``msg``."""


def finish_summary(
    out: str | os.PathLike[str], summary: dict[str, Any], started: float, **kw: Any
) -> dict[str, Any]:
    """Stamp the step's wall time, write its summary, return it.

    Sets ``summary["seconds"]`` to the seconds since ``started`` (a
    :func:`time.perf_counter` reading, rounded to 0.01 s) and writes the summary with
    :func:`write_summary` (``**kw`` as there).
    """
    summary["seconds"] = round(time.perf_counter() - started, 2)
    write_summary(out, summary, **kw)
    return summary


def rows_main(
    doc: str,
    name: str,
    run: Callable[..., list[dict[str, Any]]],
    argv: Sequence[str] | None = None,
    *,
    quick_help: str,
    line: Callable[[dict[str, Any]], str] | None = None,
) -> int:
    """The command line of a study that returns table rows: ``--out DIR``, ``--quick``.

    Runs ``run(output_dir(name, DIR), quick=...)`` and prints one line per row,
    ``key=value`` pairs (values as ``.6g`` unless ``line`` formats the row).

    Returns
    -------
    int
        0 (a failure raises).
    """
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--out", default=None, help="output root (default ./out)")
    ap.add_argument("--quick", action="store_true", help=quick_help)
    a = ap.parse_args(argv)
    rows = run(output_dir(name, a.out), quick=a.quick)
    for r in rows:
        text = line(r) if line is not None else " ".join(f"{k}={v:.6g}" for k, v in r.items())
        sys.stdout.write(text + "\n")
    return 0


def output_dir(name: str = "", root: str | os.PathLike[str] | None = None) -> Path:
    """The folder ``root/name``, created if needed.

    Parameters
    ----------
    name : str
        Sub-folder (e.g. the study name); "" for ``root`` itself.
    root : path, optional
        Default: ``$BROACHKIT_OUT`` if set, else ``./out``.
    """
    base = Path(root) if root is not None else Path(os.environ.get(OUT_ENV, "out"))
    out = base / name if name else base
    out.mkdir(parents=True, exist_ok=True)
    return out


def use_agg() -> None:
    """Select the non-interactive Agg backend (call before importing pyplot in scripts)."""
    import matplotlib

    matplotlib.use("Agg")


@contextlib.contextmanager
def figure_style() -> Iterator[None]:
    """Context in which matplotlib uses :data:`STYLE`."""
    import matplotlib

    with matplotlib.rc_context(STYLE):
        yield


def new_figure(figsize: tuple[float, float]) -> Any:
    """A :class:`matplotlib.figure.Figure` in :data:`STYLE`, independent of pyplot.

    It needs no GUI backend (it renders with Agg when saved), so scripts and tests
    can make figures anywhere.
    """
    import matplotlib
    from matplotlib.figure import Figure

    with matplotlib.rc_context(STYLE):
        return Figure(figsize=figsize, layout="constrained")


def save_figure(fig: Any, path: str | os.PathLike[str], *, dpi: int | None = None) -> Path:
    """Save ``fig`` as PNG at ``path`` (suffix ``.png`` added if missing) and close it."""
    p = Path(path)
    if p.suffix.lower() != ".png":
        p = p.with_name(p.name + ".png")
    from continuation.plotting import MIN_FONT_PX, displayed_font_px, legibility_metadata

    meta = legibility_metadata(fig)
    d = dpi or STYLE["savefig.dpi"]
    with atomic_path(p) as tmp:
        fig.savefig(tmp, dpi=d, metadata=meta)
    w_px = fig.get_size_inches()[0] * d
    shown = displayed_font_px(float(meta["broachkit:min_font_pt"]), w_px, d)
    if shown < MIN_FONT_PX:
        log.warning("%s: smallest text %.1f px high in the report (< %g)", p.name, shown,
                    MIN_FONT_PX)  # fmt: skip
    if getattr(fig.canvas, "manager", None) is not None:  # a pyplot figure
        import matplotlib.pyplot as plt

        plt.close(fig)
    return p


# ------------------------------------------------------------ the paper's planes
# The states that are angles (written in degrees, ``<name>_deg``, in every CSV) and
# angular rates (``<name>_deg_s``): ANGLE_STATES, RATE_STATES and state_columns come
# from ship_models.columns and are re-exported here.

#: Axis labels of the paper's quantities (symbol list of Umeda 1999).
PLANE_LABELS: dict[str, str] = {
    "xi": r"nondimensional longitudinal position $\xi_G/\lambda$",
    "xi_unwrapped": r"$\xi_G/\lambda$ (unwrapped)",
    "u_c": "nondimensional surge velocity $u/c$",
    "chi": r"heading angle $\chi$ (deg)",
    "r_nd": r"nondimensional yaw rate $r' = rL/\sqrt{u^2+v^2}$",
    "phi": r"roll angle $\phi$ (deg)",
    "p_nd": r"nondimensional roll rate $p' = pL/\sqrt{u^2+v^2}$",
    "delta": r"rudder angle $\delta$ (deg)",
}


def paper_quantities(
    x: np.ndarray, names: Sequence[str], c: float, L: float
) -> dict[str, np.ndarray]:
    """The paper's plotted quantities of states ``x`` (shape (N, 8)).

    ``u_c = u/c``; ``r_nd = r L / sqrt(u^2 + v^2)`` and ``p_nd = p L / sqrt(u^2 + v^2)``
    (the symbol list's r' and p'); angles in degrees; ``xi_unwrapped`` is xi_G/lambda.
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    i = {n: k for k, n in enumerate(names)}
    speed = np.hypot(x[:, i["u"]], x[:, i["v"]])
    return {
        "xi_unwrapped": x[:, i["xi_G"]],
        "u_c": x[:, i["u"]] / c,
        "chi": np.degrees(x[:, i["chi"]]),
        "r_nd": x[:, i["r"]] * L / speed,
        "phi": np.degrees(x[:, i["phi"]]),
        "p_nd": x[:, i["p_roll"]] * L / speed,
        "delta": np.degrees(x[:, i["delta"]]),
    }


def wrap_position(xi: np.ndarray, low: float) -> np.ndarray:
    """``xi`` wrapped into ``[low, low + 1)``, with NaN where it jumps (breaks the line).

    The paper draws positions in one window of one wavelength plus (Figs. 10, 12, 14:
    -0.6 .. 1), so a periodic motion that drifts back one wave per period shows as a
    closed loop.
    """
    w = low + np.mod(np.asarray(xi, dtype=float) - low, 1.0)
    if w.size < 2:
        return w
    jumps = np.nonzero(np.abs(np.diff(w)) > 0.5)[0]
    return np.insert(w, jumps + 1, np.nan)


def insert_breaks(y: np.ndarray, xi: np.ndarray, low: float) -> np.ndarray:
    """``y`` with NaN inserted where :func:`wrap_position` breaks ``xi``."""
    w = low + np.mod(np.asarray(xi, dtype=float) - low, 1.0)
    jumps = np.nonzero(np.abs(np.diff(w)) > 0.5)[0] if w.size > 1 else np.array([], int)
    return np.insert(np.asarray(y, dtype=float), jumps + 1, np.nan)


def _meta_lines(meta: Mapping[str, Any] | None) -> list[str]:
    lines = []
    for k, v in (meta or {}).items():
        text = str(v).replace("\n", " ")
        lines.append(f"# {k}: {text}")
    return lines


def save_csv(
    path: str | os.PathLike[str],
    columns: Mapping[str, Any],
    *,
    meta: Mapping[str, Any] | None = None,
) -> Path:
    """Write numeric columns to CSV, with ``# key: value`` metadata lines on top.

    Parameters
    ----------
    path : path
        Output file (parents created).
    columns : mapping of str to array_like, each shape (N,)
        Column name -> values; all of the same length.
    meta : mapping, optional
        Written first as comment lines (units, parameters, sources).

    Raises
    ------
    ValueError
        If ``columns`` is empty or the columns differ in length (names the column).
    """
    if not columns:
        raise ValueError("`columns` must not be empty")
    arrays = {k: np.asarray(v, dtype=float).reshape(-1) for k, v in columns.items()}
    n = len(next(iter(arrays.values())))
    for k, a in arrays.items():
        if a.size != n:
            raise ValueError(f"`columns[{k!r}]` has {a.size} values, expected {n}")
    data = np.column_stack(list(arrays.values()))
    rows = [[float(x) if math.isfinite(x) else math.nan for x in row] for row in data]
    return save_table(path, list(arrays), rows, meta=meta)


def read_csv(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """Read a file written by :func:`save_csv`: ``{column: ndarray (N,)}``."""
    with Path(path).open(newline="") as fh:
        rows = [r for r in csv.reader(line for line in fh if not line.startswith("#"))]
    if not rows:
        raise ValueError(f"`path`: {path} has no header row")
    header, body = rows[0], rows[1:]
    data = np.array([[float(x) for x in r] for r in body], dtype=float).reshape(-1, len(header))
    return {name: data[:, i].copy() for i, name in enumerate(header)}


def save_table(
    path: str | os.PathLike[str],
    header: Sequence[str],
    rows: Sequence[Sequence[Any]],
    *,
    meta: Mapping[str, Any] | None = None,
) -> Path:
    """Write rows of mixed text and numbers to CSV (floats at full precision).

    Raises
    ------
    ValueError
        If a row's length differs from ``header`` (names the row index).
    """
    p = Path(path)
    with atomic_path(p) as tmp, tmp.open("w", newline="") as fh:
        for line in _meta_lines(meta):
            fh.write(line + "\n")
        w = csv.writer(fh)
        w.writerow(list(header))
        for i, r in enumerate(rows):
            if len(r) != len(header):
                raise ValueError(f"`rows[{i}]` has {len(r)} fields, expected {len(header)}")
            w.writerow([repr(float(x)) if isinstance(x, float) else x for x in r])
    return p


__all__ = [
    "ANGLE_STATES",
    "OUT_ENV",
    "PLANE_LABELS",
    "RATE_STATES",
    "RUN_KEYS",
    "is_run_key",
    "split_run_record",
    "write_results",
    "write_summary",
    "STYLE",
    "figure_style",
    "insert_breaks",
    "paper_quantities",
    "state_columns",
    "wrap_position",
    "new_figure",
    "finish_summary",
    "output_dir",
    "rows_main",
    "begin_step",
    "read_csv",
    "save_csv",
    "save_figure",
    "save_table",
    "use_agg",
    "write_atomic",
    "write_atomic_group",
    "write_json",
]
