"""The fate classifier: integrate in segments and test each segment for a fate.

See :mod:`continuation.dynamics.fates` for the kinds of fate and the notes on saddle
visits and passage sides; the per-segment tests are in
:mod:`continuation.dynamics.fate_scan`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ..arguments import integer_at_least, positive
from ..errors import ContinuationError
from ..sigint import sigint_recorded, sigints_counted
from ..status import Status
from ..typing import FloatArray
from ._common import check_scale, param_vector, periodic_difference, state_period
from .events import PoincareSection, SimEvent
from .fate_scan import _ScanState
from .fates import Fate, KnownEquilibrium
from .integrators import DEFAULT_ATOL, DEFAULT_RTOL
from .saddles import left_unstable_vector, refine_equilibrium
from .simulate import Simulator
from .trajectory import Trajectory


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
        Integrator and tolerances (see :func:`~continuation.dynamics.simulate.simulate`).
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
        self.p = param_vector(system, params)
        self.n = len(system.state_names)
        self.period = state_period(system, self.n)
        self.tol = positive("tol", tol)
        self.saddle_radius = positive("saddle_radius", saddle_radius)
        if self.saddle_radius <= self.tol:
            raise ValueError(f"`saddle_radius` ({saddle_radius}) must be larger than `tol` ({tol})")
        self.scale = check_scale(self.n, scale)
        self.t_max = positive("t_max", t_max)
        self.segment = positive("segment", segment) if segment is not None else t_max / 20
        self.segment = min(self.segment, self.t_max)
        self.dt = positive("dt", dt) if dt is not None else self.segment / 200
        self.max_multiplicity = integer_at_least("max_multiplicity", max_multiplicity, 1)
        self.min_amplitude = (
            positive("min_amplitude", min_amplitude) if min_amplitude is not None else 1e3 * tol
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
                d = periodic_difference(self.period, xr, other.x)
                if np.max(np.abs(d) / self.scale) <= self.tol:
                    raise ValueError(
                        f"`equilibria` {other.name!r} and {name!r} are the same point (modulo "
                        "the periods); pass each equilibrium once"
                    )
            w_u = (
                left_unstable_vector(self.system.jacobian(xr, self.p), self.period)
                if nu == 1
                else None
            )
            out.append(KnownEquilibrium(name, xr, vals, nu, w_u))
        return tuple(out)

    # ------------------------------------------------------------------ distances
    def _distances(self, x: FloatArray) -> FloatArray:
        """Scaled distances of samples ``x (M, n)`` to every known equilibrium, ``(M, k)``."""
        if not self.equilibria:
            return np.zeros((x.shape[0], 0))
        E = np.array([e.x for e in self.equilibria])
        d = periodic_difference(self.period, x[:, None, :], E[None, :, :])
        return np.max(np.abs(d) / self.scale, axis=2)

    def distance(self, x1: FloatArray, x2: FloatArray) -> float:
        """Scaled max-norm distance between two states, modulo the periods."""
        return float(np.max(np.abs(periodic_difference(self.period, x1, x2)) / self.scale))

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
        with sigint_recorded():  # one count for all segments (a SIGINT lost in a
            n_sigint = sigints_counted()  # CasADi call between them still stops)
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
                    if sigints_counted() != n_sigint:
                        raise KeyboardInterrupt
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


def classify_fate(
    system: Any,
    params: Any,
    traj_or_x0: Any,
    *,
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
    progress : callable, optional
        ``progress(t, x)`` after each integration segment.
    **options
        The options of :class:`FateClassifier` (``equilibria``, ``events``,
        ``poincare``, ``tol``, ``saddle_radius``, ``scale``, ``t_max``, ``segment``,
        ``dt``, ``max_multiplicity``, ``min_amplitude``, ``method``, ``rtol``, ``atol``),
        with its defaults.

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
    return FateClassifier(system, params, **options).classify(traj_or_x0, progress=progress)


__all__ = ["FateClassifier", "classify_fate"]
