r"""Results of a continuation: :class:`Branch`, its rows and its special points.

A :class:`Branch` is a column store (one array per quantity, one row per computed
point, BifurcationKit ``ContResult`` style) plus a tuple of :class:`SpecialPoint`
records and a :class:`~continuation.status.Status`.

Arclength and brackets
----------------------
``Branch.ds[k]`` is the pseudo-arclength step from row ``k - 1`` to row ``k``
(``ds[0] = 0``), measured in the ``theta``-weighted norm of the settings:
it is the projection ``<tau_{k-1}, u_k - u_{k-1}>_theta`` of the step on the tangent
at the row it started from (``u = (z, p)``). :attr:`Branch.arclength` is its cumulative
sum (for branches computed in both directions the steps are re-measured so that the
arclength increases from the backward end to the forward end).

A :class:`SpecialPoint` detected between rows ``index`` and ``index + 1`` carries

* ``bracket = (p[index], p[index + 1])``: the parameter values of the two rows;
* ``s``: its pseudo-arclength position, measured like :attr:`Branch.arclength`.

The located point always satisfies ``arclength[index] <= s <= arclength[index + 1]``
(the locator searches only inside that interval). For Hopf points, branch points and
user events ``p`` also lies in ``[min(bracket), max(bracket)]`` unless a fold lies in
the same step; for a fold ``p`` is an extremum of the parameter and is generally
*outside* the parameter bracket, which is why the invariant is stated in arclength.

Files
-----
:meth:`Branch.save` writes ``name.npz`` (all arrays) and ``name.json`` (free parameter,
names, status, settings, special points) side by side; :meth:`Branch.load` reads them
back without the problem object (``problem=None``) unless one is passed in.
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .settings import ContinuationSettings, DetectionSettings, NewtonSettings
from .status import Status
from .typing import BoolArray, ComplexArray, FloatArray, IntArray

FORMAT_VERSION = 2
"""Version of the Branch file written by :meth:`Branch.save`.

Version 1 stored the period doublings and Neimark-Sacker points of cycle branches
as ``user`` points labelled ``"PD"``/``"NS"``; :meth:`Branch.load` reads them as the
``pd``/``ns`` kinds of version 2.
"""
_LEGACY_CYCLE_KINDS = {"PD": "pd", "NS": "ns"}


class SpecialKind(enum.StrEnum):
    """Kinds of special points along a branch.

    Equilibria: ``fold``, ``hopf``, ``bp`` (and the codimension-two points of the
    curves of :mod:`continuation.codim2`). Periodic orbits: a fold of cycles is a
    ``fold`` (labelled ``"LPC1"``...), a branch point ``bp`` (``"BPC1"``...), a
    period doubling ``pd`` (a Floquet multiplier through ``-1``, labelled ``"PD"``)
    and a Neimark-Sacker point ``ns`` (a complex pair through the unit circle,
    labelled ``"NS"``). ``user`` points are the zeros of monitored events.
    """

    FOLD = "fold"
    HOPF = "hopf"
    BRANCH_POINT = "bp"
    BOGDANOV_TAKENS = "bt"
    CUSP = "cusp"
    ZERO_HOPF = "zh"
    GENERALIZED_HOPF = "gh"
    DOUBLE_HOPF = "hh"
    PERIOD_DOUBLING = "pd"
    NEIMARK_SACKER = "ns"
    USER = "user"


def _kind(kind: SpecialKind | str) -> SpecialKind:
    try:
        return SpecialKind(kind)
    except ValueError:
        raise ValueError(
            f"`kind` must be one of {[k.value for k in SpecialKind]}, got {kind!r}"
        ) from None


@dataclass(frozen=True, eq=False)
class SpecialPoint:
    """A special point (bifurcation or user event) found along a branch.

    Attributes
    ----------
    kind : SpecialKind
        ``fold``, ``hopf``, ``bp``, ``user``, ...
    index : int
        Branch row just before the point (the point lies between rows ``index``
        and ``index + 1``).
    p : float
        Free-parameter value at the point (located value when ``located``).
    x : ndarray, shape (N,)
        Unknowns ``z`` at the point (the state, for equilibrium branches).
    located : bool
        True when the locator converged on a zero of the test function (a sign change
        proved within ``DetectionSettings.tol``, not a jump), to within ``error``;
        False: only bracketed (then ``p``, ``x`` are those of the best trial point or
        of row ``index``).
    bracket : tuple of float
        ``(p[index], p[index + 1])``, the parameter values of the two rows around it.
    delta_unstable : tuple of int
        Change ``(d n_unstable_real, d n_unstable_complex_pairs)`` from row ``index``
        to row ``index + 1``.
    label : str
        ``"F1"``, ``"H2"``, ``"BP1"``, or the user event's name.
    data : mapping
        Extra scalars, e.g. ``{"omega": 1.0}`` for a Hopf point (imaginary part of the
        critical pair), ``{"g": ...}`` (test-function value at the located point).
    s : float
        Pseudo-arclength position; ``arclength[index] <= s <= arclength[index + 1]``.
    tangent : ndarray, shape (N + 1,) or None
        Unit tangent ``(dz/ds, dp/ds)`` of the branch at the point, if known.
    error : float
        The locator's estimate of the error of ``s`` (the distance along the branch to
        the zero of the test function): at most ``DetectionSettings.tol`` when
        ``located``; otherwise the bracket's width, a larger estimate (e.g. a test
        function whose noise leaves its zero uncertain), or NaN (unknown). The unit
        tangent has ``|dp/ds| <= 1 / sqrt(theta)`` (``theta`` of the settings), so the
        error of ``p`` is at most ``error / sqrt(theta)`` to first order.
    """

    kind: SpecialKind
    index: int
    p: float
    x: FloatArray
    located: bool
    bracket: tuple[float, float]
    delta_unstable: tuple[int, int] = (0, 0)
    label: str = ""
    data: Mapping[str, float] = field(default_factory=dict)
    s: float = math.nan
    tangent: FloatArray | None = None
    error: float = math.nan

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", _kind(self.kind))

    def to_json(self) -> dict[str, Any]:
        """Plain-JSON representation (used by :meth:`Branch.save`)."""
        return {
            "kind": self.kind.value,
            "index": int(self.index),
            "p": float(self.p),
            "x": [float(v) for v in np.asarray(self.x).ravel()],
            "located": bool(self.located),
            "bracket": [float(self.bracket[0]), float(self.bracket[1])],
            "delta_unstable": [int(self.delta_unstable[0]), int(self.delta_unstable[1])],
            "label": self.label,
            "data": {k: float(v) for k, v in self.data.items()},
            "s": float(self.s),
            "tangent": None if self.tangent is None else [float(v) for v in self.tangent],
            "error": float(self.error),
        }

    @classmethod
    def from_json(cls, d: Mapping[str, Any]) -> SpecialPoint:
        """Inverse of :meth:`to_json`."""
        return cls(
            kind=SpecialKind(d["kind"]),
            index=int(d["index"]),
            p=float(d["p"]),
            x=np.asarray(d["x"], dtype=float),
            located=bool(d["located"]),
            bracket=(float(d["bracket"][0]), float(d["bracket"][1])),
            delta_unstable=(int(d["delta_unstable"][0]), int(d["delta_unstable"][1])),
            label=str(d.get("label", "")),
            data={k: float(v) for k, v in d.get("data", {}).items()},
            s=float(d.get("s", math.nan)),
            tangent=None if d.get("tangent") is None else np.asarray(d["tangent"], float),
            error=float(d.get("error", math.nan)),
        )

    def reversed(self, index: int, s: float) -> SpecialPoint:
        """The same point on its branch traversed the other way.

        Parameters
        ----------
        index : int
            The row before the point in the reversed order (the caller renumbers).
        s : float
            Its arclength position in the reversed order.

        Returns
        -------
        SpecialPoint
            With ``index`` and ``s``, the bracket swapped and ``delta_unstable`` and
            ``tangent`` negated.
        """
        return dataclasses.replace(
            self,
            index=index,
            bracket=(self.bracket[1], self.bracket[0]),
            delta_unstable=(-self.delta_unstable[0], -self.delta_unstable[1]),
            s=s,
            tangent=None if self.tangent is None else -np.asarray(self.tangent),
        )

    def __repr__(self) -> str:
        extra = "".join(f", {k}={v:.6g}" for k, v in self.data.items())
        return (
            f"SpecialPoint({self.label or self.kind.value}: {self.kind.value} at p={self.p:.10g}, "
            f"index={self.index}, located={self.located}{extra})"
        )


@dataclass(frozen=True, eq=False)
class BranchPoint:
    """One row of a :class:`Branch` (a view; arrays are not copied).

    Attributes
    ----------
    index : int
        Row number.
    p : float
        Free parameter.
    x : ndarray, shape (N,)
        Unknowns (state).
    eigenvalues : ndarray, shape (N,) complex
        Sorted by decreasing real part; NaN where not computed.
    n_unstable : int
        Number of eigenvalues with real part ``> eig_tol`` (-1 if not computed).
    stable : bool
        ``n_unstable == 0``.
    ds : float
        Pseudo-arclength step from the previous row.
    newton_iters : int
        Corrector iterations spent on this row.
    records : mapping
        The problem's named scalars at this row.
    """

    index: int
    p: float
    x: FloatArray
    eigenvalues: ComplexArray
    n_unstable: int
    stable: bool
    ds: float
    newton_iters: int
    records: Mapping[str, float]


def _settings_to_json(s: ContinuationSettings) -> dict[str, Any]:
    return dataclasses.asdict(s)


def _special_points(meta: Mapping[str, Any], cycles: bool) -> tuple[SpecialPoint, ...]:
    """The special points of a Branch file, version-1 cycle points read as ``pd``/``ns``.

    ``cycles``: the branch is one of periodic orbits (it records the period ``T``);
    only there a version-1 ``user`` point labelled ``"PD"``/``"NS"`` was a Floquet
    point (on other branches it is a user event of that name and stays one).
    """
    out = []
    legacy = cycles and int(meta.get("version", 1)) < 2
    for d in meta["special_points"]:
        if legacy and d["kind"] == SpecialKind.USER and d.get("label") in _LEGACY_CYCLE_KINDS:
            d = {**d, "kind": _LEGACY_CYCLE_KINDS[d["label"]]}
        out.append(SpecialPoint.from_json(d))
    return tuple(out)


def _settings_from_json(d: Mapping[str, Any] | None) -> ContinuationSettings | None:
    if d is None:
        return None
    d = dict(d)
    newton = NewtonSettings(**d.pop("newton", {}))
    detect = DetectionSettings(**d.pop("detect", {}))
    return ContinuationSettings(newton=newton, detect=detect, **d)


def _as_names(n: int, names: Sequence[str]) -> tuple[str, ...]:
    names = tuple(names)
    if len(names) == n:
        return names
    return tuple(f"z{k}" for k in range(n))


@dataclass(frozen=True, eq=False)
class Branch:
    """A computed branch of solutions of ``G(z, p) = 0``.

    Attributes
    ----------
    problem : ContinuationProblem or None
        The problem continued (None for a branch loaded from disk).
    free : str
        Name of the free parameter.
    p : ndarray, shape (N,)
        Free-parameter values.
    x : ndarray, shape (N, n)
        Unknowns at each row (the state for equilibrium branches).
    eigenvalues : ndarray, shape (N, n_eig) complex
        Stability eigenvalues, each row sorted by decreasing real part; NaN where not
        computed (e.g. large sparse problems where only ``settings.detect.n_eigs`` are
        computed). ``n_eig = n`` for equilibria; it is the length of
        ``problem.stability`` for other problems, and 0 when that returns None.
    n_unstable : ndarray of int, shape (N,)
        Saddle index: number of eigenvalues with real part ``> eig_tol``; -1 where no
        eigenvalues were computed.
    ds : ndarray, shape (N,)
        Pseudo-arclength step from the previous row (``ds[0] = 0``); see module notes.
    newton_iters : ndarray of int, shape (N,)
        Corrector iterations per row.
    records : mapping of str to ndarray (N,)
        Column store of ``problem.record(z, p)``.
    special_points : tuple of SpecialPoint
        In branch order.
    status : Status
        Why the computation stopped.
    message : str
        Human-readable detail of ``status``.
    settings : ContinuationSettings or None
        Settings used.
    state_names : tuple of str
        Names of the columns of ``x``.
    param_values : mapping of str to float
        All parameter values of the problem (the free one at the start value); lets
        :meth:`param` answer for any parameter, also after :meth:`load`.
    event_names : tuple of str
        Names of the user events that were monitored (so :meth:`find` accepts them).
    """

    problem: Any
    free: str
    p: FloatArray
    x: FloatArray
    eigenvalues: ComplexArray
    n_unstable: IntArray
    ds: FloatArray
    newton_iters: IntArray
    records: Mapping[str, FloatArray]
    special_points: tuple[SpecialPoint, ...]
    status: Status
    message: str = ""
    settings: ContinuationSettings | None = None
    state_names: tuple[str, ...] = ()
    param_values: Mapping[str, float] = field(default_factory=dict)
    event_names: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        p = np.asarray(self.p, dtype=float).reshape(-1)
        N = p.size
        x = np.asarray(self.x, dtype=float).reshape(N, -1) if N else np.asarray(self.x, float)
        if x.ndim != 2:
            x = x.reshape(0, 0)
        n = x.shape[1]
        ev = np.asarray(self.eigenvalues, dtype=complex)
        if ev.size == 0:
            ev = np.zeros((N, 0), dtype=complex)
        for name, arr, shape in (
            ("x", x, (N, n)),
            ("n_unstable", np.asarray(self.n_unstable), (N,)),
            ("ds", np.asarray(self.ds), (N,)),
            ("newton_iters", np.asarray(self.newton_iters), (N,)),
        ):
            if arr.shape != shape:
                raise ValueError(f"`{name}` must have shape {shape}, got {arr.shape}")
        if ev.shape[0] != N:
            raise ValueError(f"`eigenvalues` must have {N} rows, got {ev.shape}")
        recs = {str(k): np.asarray(v, dtype=float).reshape(-1) for k, v in self.records.items()}
        for k, v in recs.items():
            if v.shape != (N,):
                raise ValueError(f"`records[{k!r}]` must have shape ({N},), got {v.shape}")
        arrays = {
            "p": p,
            "x": x,
            "eigenvalues": ev,
            "n_unstable": np.asarray(self.n_unstable, dtype=int),
            "ds": np.asarray(self.ds, dtype=float),
            "newton_iters": np.asarray(self.newton_iters, dtype=int),
        }
        for k, v in arrays.items():
            v = np.array(v)
            v.setflags(write=False)
            object.__setattr__(self, k, v)
        for v in recs.values():
            v.setflags(write=False)
        object.__setattr__(self, "records", recs)
        object.__setattr__(self, "special_points", tuple(self.special_points))
        object.__setattr__(self, "state_names", _as_names(n, self.state_names))
        object.__setattr__(
            self, "param_values", {str(k): float(v) for k, v in self.param_values.items()}
        )
        object.__setattr__(self, "event_names", tuple(str(e) for e in self.event_names))

    # ------------------------------------------------------------------ views
    @property
    def stable(self) -> BoolArray:
        """``n_unstable == 0`` per row, shape ``(N,)``."""
        return self.n_unstable == 0

    @property
    def arclength(self) -> FloatArray:
        """Cumulative pseudo-arclength ``cumsum(ds)``, shape ``(N,)``."""
        return np.cumsum(self.ds)

    def reversed(self, **changes: Any) -> Branch:
        """The branch in the opposite order, with further fields ``changes``.

        Rows, steps (``ds[k]`` of the reversed branch is the step between its rows
        ``k - 1`` and ``k``), records and special points (:meth:`SpecialPoint.reversed`:
        row ``N - 2 - index``, position ``arclength[-1] - s``) are reversed.
        """
        N = len(self)
        ds = np.zeros(N)
        ds[1:] = self.ds[1:][::-1]
        total = float(self.arclength[-1]) if N else 0.0
        sps = [sp.reversed(max(N - 2 - sp.index, 0), total - sp.s) for sp in self.special_points]
        return dataclasses.replace(
            self,
            p=self.p[::-1],
            x=self.x[::-1],
            eigenvalues=self.eigenvalues[::-1],
            n_unstable=self.n_unstable[::-1],
            ds=ds,
            newton_iters=self.newton_iters[::-1],
            records={k: v[::-1] for k, v in self.records.items()},
            special_points=tuple(sps[::-1]),
            **changes,
        )

    @property
    def n_unknowns(self) -> int:
        """Number of unknowns ``n`` (columns of ``x``)."""
        return int(self.x.shape[1])

    def __len__(self) -> int:
        return int(self.p.size)

    def __getitem__(self, i: int) -> BranchPoint:
        N = len(self)
        if not isinstance(i, (int, np.integer)):
            raise TypeError(f"branch rows are indexed by int, got {type(i).__name__}")
        k = int(i) + N if i < 0 else int(i)
        if not 0 <= k < N:
            raise IndexError(f"row {i} out of range for a branch of {N} points")
        return BranchPoint(
            index=k,
            p=float(self.p[k]),
            x=self.x[k],
            eigenvalues=self.eigenvalues[k],
            n_unstable=int(self.n_unstable[k]),
            stable=bool(self.n_unstable[k] == 0),
            ds=float(self.ds[k]),
            newton_iters=int(self.newton_iters[k]),
            records={n: float(v[k]) for n, v in self.records.items()},
        )

    def __iter__(self):  # type: ignore[no-untyped-def]
        return (self[k] for k in range(len(self)))

    def state(self, name: str) -> FloatArray:
        """Column of ``x`` for the state (unknown) ``name``, shape ``(N,)``."""
        try:
            return self.x[:, self.state_names.index(name)]
        except ValueError:
            raise ValueError(
                f"unknown state name {name!r}; valid names are {self.state_names}"
            ) from None

    def param(self, name: str) -> FloatArray:
        """Values of parameter ``name`` along the branch, shape ``(N,)``.

        The free parameter gives :attr:`p`; a recorded quantity gives its column (e.g.
        the first parameter along a fold curve); any other parameter of the problem is
        constant along the branch.
        """
        if name == self.free:
            return np.array(self.p)
        if name in self.records:
            return np.array(self.records[name])
        if name in self.param_values:
            return np.full(len(self), self.param_values[name])
        known = sorted({self.free, *self.records, *self.param_values})
        raise ValueError(f"unknown parameter name {name!r}; valid names are {known}")

    def find(self, kind: SpecialKind | str) -> tuple[SpecialPoint, ...]:
        """Special points of ``kind`` (``"fold"``, ``"hopf"``, ``"bp"``, ``"pd"``...).

        The name of a monitored user event, or a point's label (``"PD"``, ``"LPC1"``),
        is also accepted and selects the points of that label.

        Raises
        ------
        ValueError
            If ``kind`` is neither a :class:`SpecialKind` nor a monitored event name.
        """
        if isinstance(kind, str) and kind not in {k.value for k in SpecialKind}:
            labels = {s.label for s in self.special_points}
            if kind in self.event_names or kind in labels:
                return tuple(s for s in self.special_points if s.label == kind)
            raise ValueError(
                f"`kind` must be one of {[k.value for k in SpecialKind]} or an event name "
                f"{list(self.event_names)}, got {kind!r}"
            )
        k = _kind(kind)
        return tuple(s for s in self.special_points if s.kind == k)

    def __repr__(self) -> str:
        sps = ", ".join(s.label or s.kind.value for s in self.special_points)
        prange = f"[{self.p.min():.6g}, {self.p.max():.6g}]" if len(self) else "[]"
        return (
            f"Branch(free={self.free!r}, N={len(self)}, p in {prange}, "
            f"special=[{sps}], status={self.status.name})"
        )

    # ------------------------------------------------------------------ I/O
    @staticmethod
    def _paths(path: str | Path) -> tuple[Path, Path]:
        path = Path(path)
        npz = path if path.suffix == ".npz" else path.with_name(path.name + ".npz")
        return npz, npz.with_suffix(".json")

    def save(self, path: str | Path) -> Path:
        """Save to ``path`` (``.npz`` appended if missing) plus a ``.json`` beside it.

        The NPZ holds ``p, x, eigenvalues, n_unstable, ds, newton_iters`` and the
        records as ``record:<name>``; the JSON holds the free parameter, state names,
        parameter values, status, message, settings and special points.

        Returns
        -------
        Path
            The NPZ path written.
        """
        npz, js = self._paths(path)
        arrays: dict[str, Any] = {
            "p": self.p,
            "x": self.x,
            "eigenvalues": self.eigenvalues,
            "n_unstable": self.n_unstable,
            "ds": self.ds,
            "newton_iters": self.newton_iters,
        }
        for k, v in self.records.items():
            arrays[f"record:{k}"] = v
        np.savez(npz, **arrays)
        meta = {
            "format": "broachkit.Branch",
            "version": FORMAT_VERSION,
            "free": self.free,
            "state_names": list(self.state_names),
            "param_values": dict(self.param_values),
            "status": self.status.name,
            "message": self.message,
            "settings": None if self.settings is None else _settings_to_json(self.settings),
            "special_points": [s.to_json() for s in self.special_points],
            "records": list(self.records),
            "event_names": list(self.event_names),
        }
        js.write_text(json.dumps(meta, indent=1))
        return npz

    @classmethod
    def load(cls, path: str | Path, problem: Any = None) -> Branch:
        """Load a branch written by :meth:`save`; ``problem`` may be re-attached."""
        npz, js = cls._paths(path)
        if not npz.exists():
            raise ValueError(f"`path`: no such file {npz}")
        if not js.exists():
            raise ValueError(f"`path`: metadata file {js} is missing")
        meta = json.loads(js.read_text())
        if meta.get("format") != "broachkit.Branch":
            raise ValueError(f"`path`: {js} is not a broachkit Branch file")
        with np.load(npz) as data:
            arr = {k: np.array(data[k]) for k in data.files}
        records = {k[len("record:") :]: v for k, v in arr.items() if k.startswith("record:")}
        return cls(
            problem=problem,
            free=meta["free"],
            p=arr["p"],
            x=arr["x"],
            eigenvalues=arr["eigenvalues"],
            n_unstable=arr["n_unstable"],
            ds=arr["ds"],
            newton_iters=arr["newton_iters"],
            records=records,
            special_points=_special_points(meta, "T" in records),
            status=Status[meta["status"]],
            message=meta.get("message", ""),
            settings=_settings_from_json(meta.get("settings")),
            state_names=tuple(meta.get("state_names", ())),
            param_values=meta.get("param_values", {}),
            event_names=tuple(meta.get("event_names", ())),
        )

    def to_csv(self, path: str | Path) -> Path:
        """Write the rows as CSV with a header row of named columns.

        Columns: the free parameter, the state names, ``n_unstable``, ``stable``,
        ``ds``, ``newton_iters``, the records, then ``eig<k>_re``, ``eig<k>_im`` for
        every eigenvalue column. Read back e.g. with
        ``np.genfromtxt(path, delimiter=",", names=True)``.
        """
        path = Path(path)
        cols: list[tuple[str, FloatArray]] = [(self.free, self.p)]
        cols += [(n, self.x[:, k]) for k, n in enumerate(self.state_names)]
        cols += [
            ("n_unstable", self.n_unstable.astype(float)),
            ("stable", self.stable.astype(float)),
            ("ds", self.ds),
            ("newton_iters", self.newton_iters.astype(float)),
        ]
        cols += [(k, v) for k, v in self.records.items()]
        for k in range(self.eigenvalues.shape[1]):
            cols.append((f"eig{k}_re", self.eigenvalues[:, k].real))
            cols.append((f"eig{k}_im", self.eigenvalues[:, k].imag))
        names = [c[0] for c in cols]
        for n in names:
            if "," in n:
                raise ValueError(f"column name {n!r} contains a comma")
        data = np.column_stack([c[1] for c in cols]) if len(self) else np.zeros((0, len(cols)))
        np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
        return path


__all__ = ["Branch", "BranchPoint", "SpecialKind", "SpecialPoint"]
