r"""The numbers of the surf-riding/broaching criterion and the user's scatter table.

The IMO second-generation intact stability criteria for surf-riding/broaching
(Interim Guidelines on the Second Generation Intact Stability Criteria,
MSC.1/Circ.1627, 10 December 2020, chapter 2 "Guidelines on vulnerability criteria";
Explanatory Notes, MSC.1/Circ.1652, 26 April 2023) use

* Level 1: not vulnerable if ``L >= 200 m`` or ``Fn <= 0.3``;
* Level 2: the wave-case grid of ``lambda/L`` and ``H/lambda``, the limit ``R_SR`` on
  ``C``, and the sea states of a wave scatter table (IACS Recommendation No. 34,
  North Atlantic).

**What was checked against a citable text, and what was not** (searched again on
2026-12-04). Reached: the title and date of MSC.1/Circ.1627 and the opening of its
chapters 1 and 2 (the rendering at imorules.com): 1.1.1.1 names the five failure
modes, 2.1 (Preface) lists the criteria of chapter 2 for dead ship condition,
excessive acceleration, pure loss of stability, parametric rolling and
surf-riding/broaching, and 2.2 is the dead ship condition; and the title page of
MSC.1/Circ.1652 (26 April 2023; approved by MSC 105, prepared by SDC 8). Two papers
confirm that the Level 2 criterion takes its surf-riding threshold from Melnikov's
method (Maki, Sakai & Ueta 2024, arXiv:2406.12853; Sakai & Umeda 2024,
arXiv:2407.11601). **Not reached**: the text of the surf-riding/broaching section
itself. Its section number (listed last in 2.1, but the number was not seen), every
paragraph or equation number inside it, and every number of the criterion (Level 1
``L`` and ``Fn`` limits, ``R_SR``, the wave-case grid, the spectrum's constants) are
therefore **not verified**: this package cites the section by its subject only, and
each number is marked ``assumed`` in the data file below.

The numbers come from ``ship_models/data/imo/surf_riding_level2.toml`` (every number
with its source and status). The scatter table is **not shipped**: no citable public
copy of IACS Rec. 34 could be reached, so it is a user file read by
:func:`read_scatter_table` (format in its docstring and in ``docs/imo_assessment.md``).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from continuation.typing import FloatArray

from ..vessel import DATA_DIR

STANDARD_FILE = "surf_riding_level2.toml"


@dataclass(frozen=True)
class StandardValue:
    """One number of the standard with its unit, source and status."""

    value: float
    unit: str
    source: str
    status: str


@dataclass(frozen=True)
class SurfRidingStandard:
    """The numbers of the MSC.1/Circ.1627 surf-riding/broaching criterion (module doc).

    Attributes
    ----------
    L_min, Fn_max : float
        Level 1: not vulnerable if ``L >= L_min`` or ``Fn <= Fn_max``.
    R_SR : float
        Level 2: not vulnerable if ``C <= R_SR``.
    lambda_over_L : ndarray, shape (n_lambda,)
        Wave-case wavelengths ``lambda_i / L``.
    steepness : ndarray, shape (n_s,)
        Wave-case steepnesses ``s_j = H_j / lambda``.
    d_lambda_over_L, d_steepness : float
        Grid steps (the cells of the weights ``w_ij``).
    Hs_classes, Tz_classes : ndarray
        Sea-state class midpoints for the heat map without a scatter table.
    values : dict of str to StandardValue
        Every number with its source (for the report).
    """

    L_min: float
    Fn_max: float
    R_SR: float
    lambda_over_L: FloatArray
    steepness: FloatArray
    d_lambda_over_L: float
    d_steepness: float
    Hs_classes: FloatArray
    Tz_classes: FloatArray
    values: dict[str, StandardValue] = field(repr=False)

    def table(self) -> list[dict[str, Any]]:
        """Every number as ``{"name", "value", "unit", "source", "status"}`` rows."""
        return [
            {"name": k, "value": v.value, "unit": v.unit, "source": v.source, "status": v.status}
            for k, v in self.values.items()
        ]


def _grid(first: float, step: float, count: float) -> FloatArray:
    n = int(round(count))
    return first + step * np.arange(n, dtype=float)


def load_standard(path: str | Path | None = None) -> SurfRidingStandard:
    """Read the standard's numbers (default: the shipped file, see the module doc).

    Parameters
    ----------
    path : str or Path, optional
        A file of the same layout (e.g. with numbers checked against the circular).

    Raises
    ------
    ValueError
        Missing or malformed entries, named by their dotted path.
    """
    if path is None:
        text = (DATA_DIR / "imo" / STANDARD_FILE).read_text()
        name = STANDARD_FILE
    else:
        p = Path(path)
        if not p.is_file():
            raise ValueError(f"standard file {str(p)!r} does not exist")
        text, name = p.read_text(), str(p)
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"standard file {name!r} is not valid TOML: {exc}") from None
    vals: dict[str, StandardValue] = {}
    for section in ("level1", "level2", "sea_states"):
        if not isinstance(doc.get(section), dict):
            raise ValueError(f"standard file {name!r}: section [{section}] is missing")
        for key, entry in doc[section].items():
            where = f"{section}.{key}"
            if not isinstance(entry, dict) or set(entry) != {"value", "unit", "source", "status"}:
                raise ValueError(f"{where}: needs exactly value, unit, source and status")
            v = entry["value"]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
                raise ValueError(f"{where}: value must be a finite number")
            vals[where] = StandardValue(float(v), entry["unit"], entry["source"], entry["status"])

    def get(key: str, positive: bool = True) -> float:
        if key not in vals:
            raise ValueError(f"standard file {name!r}: {key} is missing")
        v = vals[key].value
        if positive and not v > 0:
            raise ValueError(f"{key} must be positive, got {v:g}")
        return v

    lam = _grid(
        get("level2.lambda_over_L_first"),
        get("level2.lambda_over_L_step"),
        get("level2.lambda_over_L_count"),
    )
    s = _grid(
        get("level2.steepness_first"), get("level2.steepness_step"), get("level2.steepness_count")
    )
    if s[-1] >= 0.2:
        raise ValueError(f"level2 steepness grid reaches {s[-1]:.4f}; it must stay below 0.2")
    return SurfRidingStandard(
        L_min=get("level1.L_min"),
        Fn_max=get("level1.Fn_max"),
        R_SR=get("level2.R_SR"),
        lambda_over_L=lam,
        steepness=s,
        d_lambda_over_L=get("level2.lambda_over_L_step"),
        d_steepness=get("level2.steepness_step"),
        Hs_classes=_grid(
            get("sea_states.Hs_first"), get("sea_states.Hs_step"), get("sea_states.Hs_count")
        ),
        Tz_classes=_grid(
            get("sea_states.Tz_first"), get("sea_states.Tz_step"), get("sea_states.Tz_count")
        ),
        values=vals,
    )


@dataclass(frozen=True)
class ScatterTable:
    """A wave scatter table: the weights ``W2(Hs, Tz)`` of the sea states.

    Attributes
    ----------
    Hs : ndarray, shape (n_H,)
        Significant wave heights (m), class midpoints.
    Tz : ndarray, shape (n_T,)
        Zero-crossing periods (s), class midpoints.
    counts : ndarray, shape (n_H, n_T)
        Occurrences as given in the file.
    source : str
        Where the table came from (the file's ``# source:`` line, or its path).
    """

    Hs: FloatArray
    Tz: FloatArray
    counts: FloatArray
    source: str

    @property
    def W2(self) -> FloatArray:
        """``W2(Hs, Tz)``: the counts over their sum, shape (n_H, n_T) (sums to 1)."""
        return self.counts / self.counts.sum()


def read_scatter_table(path: str | Path) -> ScatterTable:
    """Read a scatter table from a CSV file.

    Layout (``docs/imo_assessment.md``): optional comment lines starting with ``#``
    (a line ``# source: ...`` names the source), then a header row ``Hs\\Tz`` followed
    by the ``Tz`` class midpoints (s), then one row per ``Hs`` class midpoint (m) with
    the number of occurrences in each ``Tz`` class. Commas separate the fields.
    IACS Rec. 34 (North Atlantic), which the criterion asks for (issue 26; not checked
    against the circular's text), is the intended content; it is
    not shipped with broachkit.

    Raises
    ------
    ValueError
        A missing file, a non-numeric or negative entry, ragged rows, an empty table,
        non-increasing class midpoints (the line is named).
    """
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"scatter table {str(p)!r} does not exist")
    source = str(p)
    rows: list[tuple[int, list[str]]] = []
    for lineno, line in enumerate(p.read_text().splitlines(), start=1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            body = s.lstrip("#").strip()
            if body.lower().startswith("source:"):
                source = body.split(":", 1)[1].strip()
            continue
        rows.append((lineno, [c.strip() for c in s.split(",")]))
    if len(rows) < 2:
        raise ValueError(f"scatter table {str(p)!r}: needs a header row and at least one Hs row")

    def num(txt: str, lineno: int) -> float:
        try:
            v = float(txt)
        except ValueError:
            raise ValueError(f"scatter table line {lineno}: {txt!r} is not a number") from None
        if not np.isfinite(v) or v < 0:
            raise ValueError(f"scatter table line {lineno}: {txt!r} must be finite and >= 0")
        return v

    head_line, head = rows[0]
    Tz = np.array([num(t, head_line) for t in head[1:]])
    if Tz.size == 0:
        raise ValueError(f"scatter table line {head_line}: no Tz columns")
    Hs, counts = [], []
    for lineno, r in rows[1:]:
        if len(r) != Tz.size + 1:
            raise ValueError(
                f"scatter table line {lineno}: {len(r) - 1} counts for {Tz.size} Tz columns"
            )
        Hs.append(num(r[0], lineno))
        counts.append([num(c, lineno) for c in r[1:]])
    H = np.array(Hs)
    for name, arr in (("Tz", Tz), ("Hs", H)):
        if np.any(arr <= 0) or np.any(np.diff(arr) <= 0):
            raise ValueError(f"scatter table: {name} midpoints must be positive and increasing")
    C = np.array(counts, dtype=float)
    if not C.sum() > 0:
        raise ValueError(f"scatter table {str(p)!r}: all counts are zero")
    return ScatterTable(H, Tz, C, source)


__all__ = [
    "STANDARD_FILE",
    "ScatterTable",
    "StandardValue",
    "SurfRidingStandard",
    "load_standard",
    "read_scatter_table",
]
