r"""Where does a trajectory go? Fate classification by simulation in segments.

A trajectory of :math:`\dot x = f(x, p)` is integrated in segments (so that a long run
shows progress and can be interrupted) and, after each segment, tested for:

``event``
    a terminal user event fired (e.g. ``capsize`` when the roll angle exceeds the
    angle of vanishing stability: the caller supplies it, the engine knows no ships);
``equilibrium``
    convergence to a known *stable* equilibrium: scaled distance below ``tol``,
    modulo the periods of periodic states (the shift in periods is reported); or to an
    unknown one (the speed ``|f|`` falls below ``tol`` and Newton confirms a stable
    equilibrium);
``saddle``
    convergence to a known unstable equilibrium (distance below ``tol``): a connecting
    orbit at this precision;
``periodic``
    a periodic attractor: consecutive returns to a Poincare section converge,
    ``d(x_k, x_{k-m}) < tol`` for some ``m <= max_multiplicity``, with the orbit
    longer than ``min_amplitude`` (this excludes a spiral into an equilibrium that lies
    on the section); the period is ``t_k - t_{k-m}``. For a periodic coordinate (the
    ship's ``xi_G``) the section ``x_i = c (mod P)`` is taken on the unwrapped
    coordinate, so surging (``xi_G`` drifting through many wavelengths) is detected;
``escape``
    the integrator failed (blow-up in finite time, non-finite state);
``undecided``
    ``t_max`` was reached first.

Along the way every passage within ``saddle_radius`` of a known saddle is recorded as a
:class:`SaddleVisit` (which saddle, shift in periods, time, closest distance; a visit
ends when the distance exceeds ``2 saddle_radius``, and leaving the saddle the start
lies near is not a visit): the
sequence matters, e.g. the ship's upslope branch "approaches the next saddle, then tends
to a periodic attractor or capsizes" (Umeda 1999, Figs. 10-15).

Passage side. For a saddle of index 1 with a real unstable eigenvalue, a visit also
records on which side of the saddle's stable manifold :math:`W^s` the trajectory
left (:attr:`SaddleVisit.side`): the sign of the unstable coordinate

.. math::

    c_u = \frac{w_u^T\, d}{w_u^T v_u}, \qquad d = x_{exit} - (x_s + k P),

at the first sample beyond ``2 saddle_radius`` (``w_u`` the left and ``v_u`` the right
unstable eigenvector, ``v_u`` oriented as in :mod:`continuation.manifolds`: its first
periodic component positive if not negligible, else its largest component). Near a
hyperbolic saddle, :math:`W^s_{loc}` is the graph :math:`c_u = h(c_s)` with
:math:`h = O(|c_s|^2)` (stable manifold theorem; Guckenheimer & Holmes 1983,
*Nonlinear Oscillations, Dynamical Systems, and Bifurcations of Vector Fields*,
Thm. 3.2.1), and a trajectory never crosses it; on leaving, :math:`|c_s|` has decayed
and :math:`|c_u| \approx 2` ``saddle_radius``, so the sign of :math:`c_u` is the side.
It is the quantity that switches exactly at a heteroclinic connection to that saddle,
whatever happens later (:func:`passage_side`).

Distances use the scaled max-norm :math:`\max_i |d_i| / s_i` with ``d`` the periodic
difference (:meth:`System.difference`) and ``s`` = ``scale`` (default ones).
"""

from __future__ import annotations

import enum
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from dataclasses import replace as dc_replace
from typing import Any

import numpy as np

from .errors import ContinuationError
from .newton import newton
from .settings import NewtonSettings
from .simulate import (
    DEFAULT_ATOL,
    DEFAULT_RTOL,
    EventHits,
    PoincareSection,
    SimEvent,
    Simulator,
    Trajectory,
    _param_vector,
    _period,
)
from .status import Status
from .typing import ComplexArray, FloatArray

log = logging.getLogger(__name__)

#: A saddle visit ends when the distance exceeds this multiple of ``saddle_radius``.
_EXIT = 2.0


class FateKind(enum.StrEnum):
    """Kinds of fate; see the module docstring."""

    EVENT = "event"
    EQUILIBRIUM = "equilibrium"
    SADDLE = "saddle"
    PERIODIC = "periodic"
    ESCAPE = "escape"
    UNDECIDED = "undecided"


@dataclass(frozen=True)
class KnownEquilibrium:
    """An equilibrium the classifier knows, refined and with its stability.

    Attributes
    ----------
    name : str
        Label (``"E0"``, ... unless named by the caller).
    x : ndarray, shape (n,)
        The equilibrium (refined by Newton).
    eigenvalues : ndarray, shape (n,) complex
        Eigenvalues of ``df/dx``, by decreasing real part.
    n_unstable : int
        Number of eigenvalues with positive real part (saddle index).
    """

    name: str
    x: FloatArray
    eigenvalues: ComplexArray
    n_unstable: int
    w_unstable: FloatArray | None = None

    @property
    def stable(self) -> bool:
        """No eigenvalue with positive real part."""
        return self.n_unstable == 0

    def unstable_coordinate(self, d: FloatArray) -> float:
        """Coordinate ``c_u = w_u . d`` of an offset ``d (n,)`` along the oriented ``v_u``.

        ``w_unstable`` is the left unstable eigenvector scaled so that ``w_u . v_u = 1``;
        only saddles of index 1 with a real unstable eigenvalue have one (NaN otherwise).
        """
        if self.w_unstable is None:
            return math.nan
        return float(np.dot(self.w_unstable, np.asarray(d, dtype=float)))


@dataclass(frozen=True)
class SaddleVisit:
    """A passage of a trajectory within ``saddle_radius`` of a known saddle.

    Attributes
    ----------
    index : int
        Index of the saddle in the classifier's equilibria.
    name : str
        Its name.
    shift : tuple of int
        Shift in periods of each periodic state: the trajectory passed near
        ``x_saddle + shift * period``.
    t : float
        Time of closest approach (at the samples).
    distance : float
        Closest scaled distance.
    side : int
        Side of the saddle's stable manifold on which the trajectory left: the sign
        (``+1``/``-1``) of its unstable coordinate on leaving (module notes); ``0`` if
        unknown (the visit has not ended, or the saddle is not of index 1 with a real
        unstable eigenvalue).
    """

    index: int
    name: str
    shift: tuple[int, ...]
    t: float
    distance: float
    side: int = 0

    @property
    def label(self) -> str:
        """``"name"`` or ``"name@shift"`` (e.g. ``"S0@-1"``)."""
        return _with_shift(self.name, self.shift)


def _with_shift(name: str, shift: tuple[int, ...]) -> str:
    if not shift or all(k == 0 for k in shift):
        return name
    if len(shift) == 1:
        return f"{name}@{shift[0]:+d}"
    return f"{name}@(" + ",".join(f"{k:+d}" for k in shift) + ")"


@dataclass(frozen=True, eq=False)
class Fate:
    """The outcome of :func:`classify_fate`.

    Attributes
    ----------
    kind : FateKind
        See the module docstring.
    name : str
        The event name, the equilibrium name, ``"periodic"``, ``"escape"`` or
        ``"undecided"``.
    index : int or None
        Index of the equilibrium in the classifier's list (``None`` otherwise, and for
        an equilibrium that was not in the list).
    shift : tuple of int
        For ``equilibrium``/``saddle``: the trajectory ends at ``x_eq + shift * period``
        (one entry per periodic state). For ``periodic``: the drift in periods per
        period of the orbit (the winding; ``(-1,)`` for the ship's surging).
    t : float
        Time at which the fate was decided.
    x : ndarray, shape (n,)
        State at that time (unwrapped).
    period : float or None
        Period of a periodic attractor.
    multiplicity : int or None
        Section returns per period of a periodic attractor.
    visits : tuple of SaddleVisit
        Passages near known saddles, in time order.
    trajectory : Trajectory or None
        The integrated trajectory (up to ``t``).
    status : Status
        ``SUCCESS``; ``INTEGRATION_FAILED`` for ``escape``; ``INTERRUPTED``.
    message : str
        Human-readable explanation.
    x_equilibrium : ndarray, shape (n,), or None
        For ``equilibrium``/``saddle``, the equilibrium reached (unwrapped, shifted).
    """

    kind: FateKind
    name: str
    index: int | None = None
    shift: tuple[int, ...] = ()
    t: float = math.nan
    x: FloatArray = field(default_factory=lambda: np.zeros(0))
    period: float | None = None
    multiplicity: int | None = None
    visits: tuple[SaddleVisit, ...] = ()
    trajectory: Trajectory | None = None
    status: Status = Status.SUCCESS
    message: str = ""
    x_equilibrium: FloatArray | None = None

    @property
    def label(self) -> str:
        """A comparable label: ``"equilibrium:E0@+1"``, ``"event:capsize"``, ``"periodic"``..."""
        if self.kind in (FateKind.EQUILIBRIUM, FateKind.SADDLE):
            return f"{self.kind.value}:{_with_shift(self.name, self.shift)}"
        if self.kind is FateKind.EVENT:
            return f"event:{self.name}"
        return self.kind.value

    @property
    def path(self) -> tuple[str, ...]:
        """Labels of the visited saddles, then the fate label."""
        return (*(v.label for v in self.visits), self.label)

    @property
    def decided(self) -> bool:
        """False for ``undecided`` (and interrupted) classifications."""
        return self.kind is not FateKind.UNDECIDED

    def first_visit(self, name: str | None = None, *, shifted: bool = False) -> SaddleVisit | None:
        """The first visit (of the saddle ``name``, if given; at a nonzero shift if
        ``shifted``), or ``None``."""
        for v in self.visits:
            if name is not None and v.name != name:
                continue
            if shifted and not any(k != 0 for k in v.shift):
                continue
            return v
        return None

    def __repr__(self) -> str:
        via = " -> ".join(v.label for v in self.visits)
        via = f", via {via}" if via else ""
        return f"Fate({self.label}, t={self.t:.6g}{via})"


# ------------------------------------------------------------------------------- helpers
def _scale(n: int, scale: Any) -> FloatArray:
    if scale is None:
        return np.ones(n)
    s = np.asarray(scale, dtype=float).reshape(-1)
    if s.shape != (n,) or not np.all(np.isfinite(s)) or np.any(s <= 0):
        raise ValueError(f"`scale` must be {n} positive finite numbers, got {scale!r}")
    return s


def _difference(period: FloatArray, x1: FloatArray, x2: FloatArray) -> FloatArray:
    """``x1 - x2`` with periodic components reduced to ``[-P/2, P/2)`` (any leading shape)."""
    d = np.asarray(x1, dtype=float) - np.asarray(x2, dtype=float)
    mask = period > 0
    if np.any(mask):
        per = period[mask]
        d[..., mask] = np.mod(d[..., mask] + per / 2, per) - per / 2
    return d


def _shift(period: FloatArray, x: FloatArray, x_ref: FloatArray) -> tuple[int, ...]:
    """Integer number of periods between ``x`` and ``x_ref`` for each periodic state."""
    mask = period > 0
    if not np.any(mask):
        return ()
    k = np.rint((np.asarray(x)[mask] - np.asarray(x_ref)[mask]) / period[mask])
    return tuple(int(v) for v in k)


def _positive(name: str, v: Any) -> float:
    if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
        raise ValueError(f"`{name}` must be a positive finite number, got {v!r}")
    return float(v)


def _eig_sorted(J: FloatArray) -> tuple[ComplexArray, Any]:
    vals, vecs = np.linalg.eig(np.asarray(J, dtype=float))
    order = np.lexsort((-vals.imag, -vals.real))
    return np.asarray(vals, complex)[order], np.asarray(vecs, complex)[:, order]


def refine_equilibrium(
    system: Any,
    x: Any,
    p: FloatArray,
    *,
    settings: NewtonSettings | None = None,
    eig_tol: float = 1e-9,
    name: str = "x",
    max_move: float = 5e-2,
) -> tuple[FloatArray, ComplexArray, Any, int]:
    """Newton-refine an equilibrium and return ``(x, eigenvalues, eigenvectors, n_unstable)``.

    Parameters
    ----------
    system : System
    x : array_like, shape (n,)
        A point near an equilibrium.
    p : ndarray, shape (m,)
        Parameter vector.
    settings : NewtonSettings, optional
    eig_tol : float
        Real parts above ``eig_tol * max(1, max|lambda|)`` count as unstable.
    name : str
        Argument name for error messages.
    max_move : float
        Largest allowed correction of each component ``i``, relative to
        ``max(1, |x_i|)``: Newton may not wander to another equilibrium.

    Raises
    ------
    ValueError
        If Newton does not converge from ``x``, or converges further than ``max_move``
        away (the point is not near an equilibrium).
    """
    x0 = system.check_state(x, name) if hasattr(system, "check_state") else np.asarray(x, float)
    res = newton(
        lambda z: system.f(z, p),
        lambda z: system.jacobian(z, p),
        x0,
        settings or NewtonSettings(tol=1e-11, step_tol=1e-10, max_iter=30),
    )
    if not res.converged:
        raise ValueError(f"`{name}` is not close to an equilibrium: {res.message}")
    moves = np.abs(res.z - x0)
    move = float(np.max(moves))
    if np.any(moves > max_move * np.maximum(1.0, np.abs(x0))):
        raise ValueError(
            f"`{name}` is not close to an equilibrium: Newton moved it by {move:.3g} to {res.z}"
        )
    vals, vecs = _eig_sorted(system.jacobian(res.z, p))
    scale_eig = max(1.0, float(np.max(np.abs(vals)))) if vals.size else 1.0
    n_unst = int(np.sum(vals.real > eig_tol * scale_eig))
    return np.asarray(res.z, dtype=float), vals, vecs, n_unst


# ------------------------------------------------------------------------------ classifier
class FateClassifier:
    """Classify the fate of trajectories of one system at one parameter vector.

    Build it once and call :meth:`classify` for many initial states (both branches of
    an unstable manifold, a grid of initial conditions, ...).

    Parameters
    ----------
    system : System
        The dynamical system.
    params : Params, mapping or array_like, shape (m,)
        Parameter values.
    equilibria : sequence of array_like (n,) or mapping of str to array_like
        Known equilibria (named ``E0, E1, ...`` unless given as a mapping). Each is
        refined by Newton and its stability computed; each is matched modulo the
        periods, so pass every equilibrium once (not also shifted by a period).
    events : sequence of SimEvent
        User events; a terminal one ends the classification with fate ``event``.
    poincare : PoincareSection, "auto" or None
        Section for detecting periodic attractors. ``"auto"`` (default): the first
        periodic state at ``0`` (mod its period), both directions, if the system has
        a periodic state; otherwise no periodic detection unless a section is given.
    tol : float
        Convergence tolerance (scaled distance) to equilibria and of the return map.
        It must exceed the integration noise of the return map (roughly
        ``100 * rtol * max|x|``), or a period-1 orbit may be reported with a higher
        multiplicity.
    saddle_radius : float
        Scaled distance within which a passage near a saddle is recorded as a visit
        (which ends beyond ``2 saddle_radius``).
    scale : array_like, shape (n,), optional
        Scale of each state in distances (default ones).
    t_max : float
        Time limit of one classification.
    segment : float, optional
        Length of one integration segment (default ``t_max / 20``).
    dt : float, optional
        Sample spacing (default ``segment / 200``); also the resolution of event
        detection and of the distance tests.
    max_multiplicity : int
        Largest number of section returns per period searched for.
    min_amplitude : float, optional
        A periodic orbit must extend further than this (scaled) from its section point
        (default ``1000 * tol``).
    method, rtol, atol : optional
        Integrator and tolerances (see :func:`~continuation.simulate.simulate`).
    """

    def __init__(
        self,
        system: Any,
        params: Any,
        *,
        equilibria: Sequence[Any] | Mapping[str, Any] = (),
        events: Sequence[Any] = (),
        poincare: PoincareSection | str | None = "auto",
        tol: float = 1e-6,
        saddle_radius: float = 1e-2,
        scale: Any = None,
        t_max: float = 1000.0,
        segment: float | None = None,
        dt: float | None = None,
        max_multiplicity: int = 4,
        min_amplitude: float | None = None,
        method: str | None = None,
        rtol: float = DEFAULT_RTOL,
        atol: float = DEFAULT_ATOL,
    ) -> None:
        self.system = system
        self.p = _param_vector(system, params)
        self.n = len(system.state_names)
        self.period = _period(system, self.n)
        self.tol = _positive("tol", tol)
        self.saddle_radius = _positive("saddle_radius", saddle_radius)
        if self.saddle_radius <= self.tol:
            raise ValueError(f"`saddle_radius` ({saddle_radius}) must be larger than `tol` ({tol})")
        self.scale = _scale(self.n, scale)
        self.t_max = _positive("t_max", t_max)
        self.segment = _positive("segment", segment) if segment is not None else t_max / 20
        self.segment = min(self.segment, self.t_max)
        self.dt = _positive("dt", dt) if dt is not None else self.segment / 200
        if not (isinstance(max_multiplicity, int) and max_multiplicity >= 1):
            raise ValueError(
                f"`max_multiplicity` must be an integer >= 1, got {max_multiplicity!r}"
            )
        self.max_multiplicity = max_multiplicity
        self.min_amplitude = (
            _positive("min_amplitude", min_amplitude) if min_amplitude is not None else 1e3 * tol
        )
        self.sim = Simulator(system, self.p, method=method, rtol=rtol, atol=atol)
        self.events = tuple(events) if not isinstance(events, SimEvent) else (events,)
        for ev in self.events:
            if isinstance(ev, PoincareSection):
                raise ValueError("`events` takes SimEvents; pass a section as `poincare`")
        self.section = self._section(poincare)
        self.equilibria = self._known(equilibria)

    # ------------------------------------------------------------------ setup
    def _section(self, poincare: Any) -> PoincareSection | None:
        if poincare is None:
            return None
        if isinstance(poincare, str):
            if poincare != "auto":
                raise ValueError(
                    f"`poincare` must be a PoincareSection, 'auto' or None, got {poincare!r}"
                )
            idx = np.flatnonzero(self.period > 0)
            if idx.size == 0:
                return None
            return PoincareSection(int(idx[0]), 0.0, direction=0, name="_fate_section")
        if not isinstance(poincare, PoincareSection):
            raise ValueError(
                f"`poincare` must be a PoincareSection, 'auto' or None, got {poincare!r}"
            )
        poincare.index(self.system.state_names)  # validates the state
        names = {getattr(e, "name", None) for e in self.events}
        if poincare.name in names:
            raise ValueError(f"`poincare` name {poincare.name!r} clashes with an event name")
        return poincare

    def _known(self, equilibria: Any) -> tuple[KnownEquilibrium, ...]:
        if isinstance(equilibria, Mapping):
            items = [(str(k), v) for k, v in equilibria.items()]
        else:
            if isinstance(equilibria, np.ndarray) and equilibria.ndim == 1:
                raise ValueError("`equilibria` must be a sequence of states (n,), not one state")
            items = [(f"E{i}", v) for i, v in enumerate(equilibria)]
        out: list[KnownEquilibrium] = []
        for name, x in items:
            xr, vals, _, nu = refine_equilibrium(
                self.system, x, self.p, name=f"equilibria[{name!r}]"
            )
            for other in out:
                d = _difference(self.period, xr, other.x)
                if np.max(np.abs(d) / self.scale) <= self.tol:
                    raise ValueError(
                        f"`equilibria` {other.name!r} and {name!r} are the same point (modulo "
                        "the periods); pass each equilibrium once"
                    )
            out.append(KnownEquilibrium(name, xr, vals, nu, self._left_unstable(xr, vals, nu)))
        return tuple(out)

    def _left_unstable(self, x: FloatArray, vals: ComplexArray, nu: int) -> FloatArray | None:
        """Left unstable eigenvector ``w_u`` with ``w_u . v_u = 1`` (see module notes)."""
        if nu != 1:
            return None
        J = np.asarray(self.system.jacobian(x, self.p), dtype=float)
        lam, V = _eig_sorted(J)
        if abs(lam[0].imag) > 1e-12 * max(1.0, abs(lam[0])):
            return None
        v = np.real(V[:, 0])
        big = float(np.max(np.abs(v)))
        cand = [k for k in np.flatnonzero(self.period > 0) if abs(v[k]) >= 1e-3 * big]
        i = int(cand[0]) if cand else int(np.argmax(np.abs(v)))
        if v[i] < 0:
            v = -v
        lamL, W = _eig_sorted(J.T)  # left eigenvectors: same eigenvalues
        k = int(np.argmin(np.abs(lamL - lam[0])))
        w = np.real(W[:, k])
        wv = float(np.dot(w, v))
        if not math.isfinite(wv) or abs(wv) <= 1e-12 * np.linalg.norm(w) * np.linalg.norm(v):
            return None
        return w / wv

    # ------------------------------------------------------------------ distances
    def _distances(self, x: FloatArray) -> FloatArray:
        """Scaled distances of samples ``x (M, n)`` to every known equilibrium, ``(M, k)``."""
        if not self.equilibria:
            return np.zeros((x.shape[0], 0))
        E = np.array([e.x for e in self.equilibria])
        d = _difference(self.period, x[:, None, :], E[None, :, :])
        return np.max(np.abs(d) / self.scale, axis=2)

    def distance(self, x1: FloatArray, x2: FloatArray) -> float:
        """Scaled max-norm distance between two states, modulo the periods."""
        return float(np.max(np.abs(_difference(self.period, x1, x2)) / self.scale))

    # ------------------------------------------------------------------ main
    def classify(
        self,
        start: Any,
        *,
        t0: float = 0.0,
        progress: Callable[[float, FloatArray], None] | None = None,
        exclude_visit: int | None = None,
    ) -> Fate:
        """Integrate from ``start`` (a state, or a Trajectory to continue) and classify.

        Parameters
        ----------
        start : array_like (n,) or Trajectory
            Initial state; or a trajectory, whose samples are analysed first and which
            is then continued from its end (up to ``t_max`` after its start). Its
            section crossings are used if recorded under the name of the classifier's
            section (``self.section.name``; ``"_fate_section"`` for ``"auto"``).
        t0 : float
            Initial time (ignored for a Trajectory).
        progress : callable, optional
            ``progress(t, x)`` after every segment.
        exclude_visit : int, optional
            Index of an equilibrium whose neighbourhood the start lies in (e.g. the saddle
            of an unstable manifold): leaving it is not a visit. By default every known
            saddle within ``saddle_radius`` of the start is excluded this way.

        Returns
        -------
        Fate
        """
        if isinstance(start, Trajectory):
            if start.n_states != self.n:
                raise ValueError(
                    f"`start` trajectory has {start.n_states} states, expected {self.n}"
                )
            traj: Trajectory | None = start
            x = np.array(start.x[0])
            t_start = float(start.t[0])
        else:
            x = self.sim._check_x0(start)
            traj = None
            t_start = float(t0)
        st = _ScanState(self, x, t_start, exclude_visit)
        t_end = t_start + self.t_max
        events = [*self.events, *([self.section] if self.section is not None else [])]
        try:
            if traj is not None:
                fate = st.scan(traj, traj, first=True)
                if fate is not None:
                    return st.truncated(fate, traj)
                if traj.status is not Status.SUCCESS and traj.status is not Status.EVENT:
                    return st.finish(traj, traj.status)
            while True:
                t_now = t_start if traj is None else traj.t_final
                if t_now >= t_end - 1e-12 * max(1.0, abs(t_end)):
                    break
                x_now = x if traj is None else np.array(traj.x_final)
                t1 = min(t_now + self.segment, t_end)
                n_s = max(1, round((t1 - t_now) / self.dt))
                seg = self.sim.run(x_now, (t_now, t1), events=events, dt=(t1 - t_now) / n_s)
                first = traj is None
                traj = seg if traj is None else traj.append(seg)
                fate = st.scan(seg, traj, first=first)
                if fate is not None:
                    return st.truncated(fate, traj)
                if seg.status is Status.INTERRUPTED:
                    return st.finish(traj, Status.INTERRUPTED)
                if seg.status is Status.INTEGRATION_FAILED:
                    return st.finish(traj, Status.INTEGRATION_FAILED, seg.message)
                if progress is not None:
                    progress(traj.t_final, np.array(traj.x_final))
        except KeyboardInterrupt:
            if traj is None:
                traj = Trajectory(
                    np.array([t_start]), x[None, :], state_names=self.system.state_names
                )
            return st.finish(traj, Status.INTERRUPTED)
        if traj is None:  # pragma: no cover - t_max > 0 means at least one segment
            raise ContinuationError("no segment was integrated")
        return st.finish(traj, Status.SUCCESS)


class _ScanState:
    """Incremental state of one classification: visits, section returns."""

    def __init__(self, clf: FateClassifier, x0: FloatArray, t0: float, exclude: int | None) -> None:
        self.c = clf
        self.visits: list[SaddleVisit] = []
        d0 = clf._distances(x0[None, :])[0] if clf.equilibria else np.zeros(0)
        saddles = [i for i, e in enumerate(clf.equilibria) if not e.stable]
        self.saddles = saddles
        # saddles the start lies near: leaving them is not a visit
        if exclude is not None:
            inside = {exclude} if exclude in saddles else set()
        else:
            inside = {i for i in saddles if d0[i] <= clf.saddle_radius}
        self.inside: dict[int, tuple[float, float, FloatArray]] = {
            i: (math.inf, t0, x0) for i in inside
        }
        self.excluded = set(inside)
        self.hits_t: list[float] = []
        self.hits_x: list[FloatArray] = []

    # ------------------------------------------------------------------ helpers
    def _close_visit(self, i: int, x_exit: FloatArray) -> None:
        dmin, tmin, xmin = self.inside.pop(i)
        if i in self.excluded:
            self.excluded.discard(i)
            return
        e = self.c.equilibria[i]
        c_u = e.unstable_coordinate(_difference(self.c.period, x_exit, e.x))
        side = int(np.sign(c_u)) if math.isfinite(c_u) else 0
        self.visits.append(
            SaddleVisit(i, e.name, _shift(self.c.period, xmin, e.x), tmin, dmin, side)
        )

    def _open_visits(self) -> tuple[SaddleVisit, ...]:
        out = list(self.visits)
        for i, (dmin, tmin, xmin) in self.inside.items():
            if i in self.excluded:
                continue
            e = self.c.equilibria[i]
            out.append(SaddleVisit(i, e.name, _shift(self.c.period, xmin, e.x), tmin, dmin))
        out.sort(key=lambda v: v.t)
        return tuple(out)

    # ------------------------------------------------------------------ scanning
    def scan(self, seg: Trajectory, full: Trajectory, *, first: bool) -> Fate | None:
        """Scan a new segment; return a Fate if one is decided in it."""
        c = self.c
        k0 = 0 if first else 1  # the first sample repeats the previous segment's last
        t = seg.t[k0:]
        x = seg.x[k0:]
        fate_eq = None
        if x.shape[0] and c.equilibria:
            D = c._distances(x)
            # convergence to any known equilibrium (stable: attractor; unstable: saddle),
            # except to the saddle the start lies near, until the trajectory has left it
            conv = D <= c.tol
            for i in self.excluded:
                out = np.flatnonzero(D[:, i] > _EXIT * c.saddle_radius)
                conv[: (out[0] if out.size else conv.shape[0]), i] = False
            hit = np.argwhere(conv)
            if hit.size:
                k, i = (int(v) for v in hit[np.argmin(hit[:, 0])])
                fate_eq = (k, i)
            kmax = fate_eq[0] + 1 if fate_eq is not None else x.shape[0]
            self._track_visits(t[:kmax], x[:kmax], D[:kmax])
        fates: list[tuple[float, Fate]] = []
        if fate_eq is not None:
            k, i = fate_eq
            e = c.equilibria[i]
            kind = FateKind.EQUILIBRIUM if e.stable else FateKind.SADDLE
            sh = _shift(c.period, x[k], e.x)
            x_eq = e.x + (np.zeros(c.n) if not sh else self._shift_vector(sh))
            fates.append(
                (
                    float(t[k]),
                    Fate(
                        kind,
                        e.name,
                        i,
                        sh,
                        float(t[k]),
                        np.array(x[k]),
                        visits=tuple(v for v in self.visits if v.t <= t[k]),
                        message=f"converged to {e.name} (distance <= tol={c.tol:g})",
                        x_equilibrium=x_eq,
                    ),
                )
            )
        per = self._periodic(seg, full)
        if per is not None:
            fates.append((per.t, per))
        if seg.status is Status.EVENT and seg.terminal_event is not None:
            name = seg.terminal_event
            if name != (c.section.name if c.section is not None else None):
                fates.append(
                    (
                        seg.t_final,
                        Fate(
                            FateKind.EVENT,
                            name,
                            None,
                            (),
                            seg.t_final,
                            np.array(seg.x_final),
                            visits=self._open_visits(),
                            message=f"terminal event {name!r}",
                        ),
                    )
                )
        if not fates and seg.status is Status.SUCCESS and x.shape[0]:
            unk = self._unknown_equilibrium(float(t[-1]), x[-1])
            if unk is not None:
                fates.append((unk.t, unk))
        if not fates:
            return None
        return min(fates, key=lambda tf: tf[0] * (1 if seg.t[-1] >= seg.t[0] else -1))[1]

    def _shift_vector(self, sh: tuple[int, ...]) -> FloatArray:
        v = np.zeros(self.c.n)
        mask = self.c.period > 0
        v[mask] = np.asarray(sh, dtype=float) * self.c.period[mask]
        return v

    def _track_visits(self, t: FloatArray, x: FloatArray, D: FloatArray) -> None:
        # hysteresis: a visit starts within r and ends beyond 2 r, so a trajectory that
        # lingers around the sphere of radius r makes one visit, not many
        r = self.c.saddle_radius
        for i in self.saddles:
            col = D[:, i]
            for k in range(col.size):
                cur = self.inside.get(i)
                if cur is not None:
                    if col[k] > _EXIT * r:
                        self._close_visit(i, x[k])
                    elif col[k] < cur[0]:
                        self.inside[i] = (float(col[k]), float(t[k]), np.array(x[k]))
                elif col[k] <= r:
                    self.inside[i] = (float(col[k]), float(t[k]), np.array(x[k]))
        self.visits.sort(key=lambda v: v.t)

    def _periodic(self, seg: Trajectory, full: Trajectory) -> Fate | None:
        c = self.c
        if c.section is None:
            return None
        hits = seg.events.get(c.section.name)
        if hits is None or len(hits) == 0:
            return None
        for th, xh in zip(hits.t, hits.x, strict=True):
            self.hits_t.append(float(th))
            self.hits_x.append(np.array(xh))
            K = len(self.hits_t) - 1
            for m in range(1, min(c.max_multiplicity, K) + 1):
                d = c.distance(self.hits_x[K], self.hits_x[K - m])
                if d >= c.tol:
                    continue
                t_a, t_b = self.hits_t[K - m], self.hits_t[K]
                if not self._long_orbit(full, t_a, t_b, self.hits_x[K]):
                    continue
                wind = _shift(c.period, self.hits_x[K], self.hits_x[K - m])
                visits = tuple(v for v in self._open_visits() if v.t <= t_b)
                return Fate(
                    FateKind.PERIODIC,
                    "periodic",
                    None,
                    wind,
                    t_b,
                    np.array(self.hits_x[K]),
                    period=t_b - t_a,
                    multiplicity=m,
                    visits=visits,
                    message=(
                        f"periodic attractor: return map converged (|x_k - x_k-{m}| = {d:.2e} "
                        f"< tol), period {t_b - t_a:.10g}"
                    ),
                )
        return None

    def _long_orbit(self, full: Trajectory, t_a: float, t_b: float, x_ref: FloatArray) -> bool:
        """Does the arc between two returns extend beyond ``min_amplitude``?"""
        lo, hi = min(t_a, t_b), max(t_a, t_b)
        mask = (full.t >= lo) & (full.t <= hi)
        if not np.any(mask):  # pragma: no cover - returns are at least one sample apart
            return True
        # unwrapped difference: a winding orbit moves a whole period
        d = np.max(np.abs(full.x[mask] - x_ref) / self.c.scale)
        return bool(d > self.c.min_amplitude)

    def _unknown_equilibrium(self, t: float, x: FloatArray) -> Fate | None:
        c = self.c
        speed = float(np.max(np.abs(c.system.f(x, c.p)) / c.scale))
        if not speed < c.tol:
            return None
        try:
            xr, vals, _, nu = refine_equilibrium(c.system, x, c.p)
        except ValueError:
            return None
        if nu != 0 or c.distance(xr, x) > 10 * c.tol:
            return None
        for i, e in enumerate(c.equilibria):  # a known one, approached slowly
            if c.distance(xr, e.x) <= c.tol:
                sh = _shift(c.period, x, e.x)
                return Fate(
                    FateKind.EQUILIBRIUM,
                    e.name,
                    i,
                    sh,
                    t,
                    np.array(x),
                    visits=self._open_visits(),
                    message=f"converging to {e.name} (speed below tol; slowly attracting)",
                    x_equilibrium=e.x + self._shift_vector(sh) if sh else np.array(e.x),
                )
        return Fate(
            FateKind.EQUILIBRIUM,
            "unknown",
            None,
            _shift(c.period, x, xr),
            t,
            np.array(x),
            visits=self._open_visits(),
            message="converged to a stable equilibrium that is not in `equilibria`",
            x_equilibrium=xr,
        )

    # ------------------------------------------------------------------ endings
    def truncated(self, fate: Fate, traj: Trajectory) -> Fate:
        """Attach the trajectory, cut at the fate's time."""
        sgn = 1.0 if traj.t[-1] >= traj.t[0] else -1.0
        t_cut = sgn * fate.t + 1e-12 * max(1.0, abs(fate.t))
        keep = sgn * traj.t <= t_cut
        events = {}
        for name, hits in traj.events.items():
            k = sgn * hits.t <= t_cut
            events[name] = EventHits(hits.t[k], hits.x[k] if len(hits) else hits.x)
        is_event = fate.kind is FateKind.EVENT
        tr = dc_replace(
            traj,
            t=traj.t[keep],
            x=traj.x[keep],
            events=events,
            status=traj.status if is_event else Status.SUCCESS,
            message=traj.message if is_event else f"stopped: {fate.message}",
            terminal_event=traj.terminal_event if is_event else None,
            xdot=None,
        )
        return dc_replace(fate, trajectory=tr)

    def finish(self, traj: Trajectory, status: Status, message: str = "") -> Fate:
        """Fate when no criterion was met: escape, interrupted or undecided."""
        if status is Status.INTEGRATION_FAILED:
            kind, name = FateKind.ESCAPE, "escape"
            msg = f"integration failed (escape / blow-up?): {message}"
        elif status is Status.INTERRUPTED:
            kind, name, msg = FateKind.UNDECIDED, "undecided", "interrupted by the user"
        else:
            kind, name = FateKind.UNDECIDED, "undecided"
            msg = f"no fate decided within t_max={self.c.t_max:g}"
        return Fate(
            kind,
            name,
            None,
            (),
            traj.t_final,
            np.array(traj.x_final),
            visits=self._open_visits(),
            trajectory=traj,
            status=status if status is not Status.SUCCESS else Status.SUCCESS,
            message=msg,
        )


def passage_side(fate: Fate, name: str | None = None, *, shifted: bool = False) -> int:
    """Side of the stable manifold on which ``fate``'s trajectory left its first saddle visit.

    A heteroclinic connection from a saddle ``A`` to a saddle ``B`` is where a branch
    of :math:`W^u(A)` lies on :math:`W^s(B)`; on either side of it the branch passes
    ``B`` on opposite sides of :math:`W^s(B)`. So the side of the *first* passage near
    ``B`` switches exactly at the connection, whereas the final fate (the attractor)
    may also switch at later, secondary connections (e.g. from the first passage to
    a saddle shifted by a further period), which accumulate on the primary one and
    make "final fate" a non-monotone function of the parameter there.

    Parameters
    ----------
    fate : Fate
    name : str, optional
        Only visits of this saddle count (default: any saddle).
    shifted : bool
        Only visits at a nonzero shift in periods count (e.g. the neighbouring copy
        of the saddle a manifold starts from).

    Returns
    -------
    int
        ``+1`` or ``-1`` (the sign of the unstable coordinate on leaving; see the
        module notes), or ``0`` if there is no such visit or its side is unknown.
    """
    if not isinstance(fate, Fate):
        raise ValueError(f"`fate` must be a Fate, got {type(fate).__name__}")
    v = fate.first_visit(name, shifted=shifted)
    return 0 if v is None else int(v.side)


def classify_fate(
    system: Any,
    params: Any,
    traj_or_x0: Any,
    *,
    equilibria: Sequence[Any] | Mapping[str, Any] = (),
    events: Sequence[Any] = (),
    poincare: PoincareSection | str | None = "auto",
    tol: float = 1e-6,
    saddle_radius: float = 1e-2,
    scale: Any = None,
    t_max: float = 1000.0,
    segment: float | None = None,
    dt: float | None = None,
    progress: Callable[[float, FloatArray], None] | None = None,
    **options: Any,
) -> Fate:
    """Classify where the trajectory from ``traj_or_x0`` goes; see :class:`FateClassifier`.

    Parameters
    ----------
    system, params
        The system and its parameter values.
    traj_or_x0 : array_like (n,) or Trajectory
        Initial state, or a trajectory to analyse and continue.
    equilibria, events, poincare, tol, saddle_radius, scale, t_max, segment, dt
        See :class:`FateClassifier`.
    progress : callable, optional
        ``progress(t, x)`` after each integration segment.
    **options
        ``max_multiplicity``, ``min_amplitude``, ``method``, ``rtol``, ``atol``.

    Returns
    -------
    Fate
        ``kind`` in ``event/equilibrium/saddle/periodic/escape/undecided``, the
        visited saddles, the trajectory, and a status.

    Examples
    --------
    >>> fate = classify_fate(pendulum, {"gamma": 0.3}, [3.0, 0.0],
    ...                      equilibria={"down": [0, 0], "up": [np.pi, 0]})  # doctest: +SKIP
    >>> fate.label
    'equilibrium:down@+1'
    """
    clf = FateClassifier(
        system,
        params,
        equilibria=equilibria,
        events=events,
        poincare=poincare,
        tol=tol,
        saddle_radius=saddle_radius,
        scale=scale,
        t_max=t_max,
        segment=segment,
        dt=dt,
        **options,
    )
    return clf.classify(traj_or_x0, progress=progress)


__all__ = [
    "Fate",
    "FateClassifier",
    "FateKind",
    "KnownEquilibrium",
    "SaddleVisit",
    "classify_fate",
    "passage_side",
    "refine_equilibrium",
]
