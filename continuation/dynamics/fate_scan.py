"""One classification's incremental scan: saddle visits, convergence, periodic returns.

:class:`_ScanState` is fed the segments of one trajectory by
:class:`~continuation.dynamics.classifier.FateClassifier` and decides, segment by
segment, whether a fate is reached (module notes of :mod:`continuation.dynamics.fates`):
convergence to a known equilibrium, a terminal event, a periodic attractor (returns to
the Poincare section that repeat after ``m <= max_multiplicity`` crossings, over an orbit
longer than ``min_amplitude``), or an unknown stable equilibrium (slow speed confirmed by
Newton). Along the way it records the visits to known saddles, with hysteresis (a visit
starts within ``saddle_radius`` and ends beyond ``2 saddle_radius``).
"""

from __future__ import annotations

import math
from dataclasses import replace as dc_replace
from typing import TYPE_CHECKING

import numpy as np

from ..status import Status
from ..typing import FloatArray
from ._common import period_shift, periodic_difference
from .fates import Fate, FateKind, SaddleVisit
from .saddles import refine_equilibrium
from .trajectory import EventHits, Trajectory

if TYPE_CHECKING:
    from .classifier import FateClassifier

#: A saddle visit ends when the distance exceeds this multiple of ``saddle_radius``.
_EXIT = 2.0


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
        c_u = e.unstable_coordinate(periodic_difference(self.c.period, x_exit, e.x))
        side = int(np.sign(c_u)) if math.isfinite(c_u) else 0
        self.visits.append(
            SaddleVisit(i, e.name, period_shift(self.c.period, xmin, e.x), tmin, dmin, side)
        )

    def _open_visits(self) -> tuple[SaddleVisit, ...]:
        out = list(self.visits)
        for i, (dmin, tmin, xmin) in self.inside.items():
            if i in self.excluded:
                continue
            e = self.c.equilibria[i]
            out.append(SaddleVisit(i, e.name, period_shift(self.c.period, xmin, e.x), tmin, dmin))
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
            sh = period_shift(c.period, x[k], e.x)
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
        # (sample by sample in effect: each pass jumps to the next entry, or to the
        # next exit taking the closest sample on the way, the first one of equals)
        r = self.c.saddle_radius
        for i in self.saddles:
            col = D[:, i]
            k, n = 0, col.size
            while k < n:
                cur = self.inside.get(i)
                if cur is None:
                    enter = np.flatnonzero(col[k:] <= r)
                    if enter.size == 0:
                        break
                    k += int(enter[0])
                    self.inside[i] = (float(col[k]), float(t[k]), np.array(x[k]))
                    k += 1
                    continue
                leave = np.flatnonzero(col[k:] > _EXIT * r)
                end = k + int(leave[0]) if leave.size else n
                if end > k:
                    j = k + int(np.argmin(col[k:end]))
                    if col[j] < cur[0]:
                        self.inside[i] = (float(col[j]), float(t[j]), np.array(x[j]))
                if end == n:
                    break
                self._close_visit(i, x[end])
                k = end + 1
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
                if m > 1 and self._shorter_orbit(K, m):
                    continue
                t_a, t_b = self.hits_t[K - m], self.hits_t[K]
                if not self._long_orbit(full, t_a, t_b, self.hits_x[K]):
                    continue
                wind = period_shift(c.period, self.hits_x[K], self.hits_x[K - m])
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

    def _shorter_orbit(self, K: int, m: int) -> bool:
        r"""Are returns ``K`` and ``K - m`` close only because the map converges onto a cycle?

        A cycle of ``j | m`` returns, e.g. a 1-cycle with a negative multiplier.

        Near a 1-cycle with multiplier :math:`\mu \in (-1, 0)` the returns alternate,
        :math:`x_k - x^* \propto \mu^k`, so :math:`|x_k - x_{k-2}|` falls below ``tol``
        before :math:`|x_k - x_{k-1}|` does, by the factor :math:`|\mu| / |1 + \mu|`: a
        2-cycle would be reported for a 1-cycle. A true ``m``-cycle keeps its ``j``-step
        separations; converging onto a ``j``-cycle shrinks them by :math:`|\mu|^m` per
        ``m`` returns. So ``m`` is refused while, for a proper divisor ``j`` of ``m``,
        :math:`d(x_K, x_{K-j}) < 0.9\, d(x_{K-m}, x_{K-m-j})` (still contracting).
        """
        if K - m - 1 < 0:
            return True  # too few returns to tell
        dist, x = self.c.distance, self.hits_x
        for j in range(1, m):
            if m % j:
                continue
            if K - m - j < 0:
                return True
            if dist(x[K], x[K - j]) < 0.9 * dist(x[K - m], x[K - m - j]):
                return True
        return False

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
                sh = period_shift(c.period, x, e.x)
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
            period_shift(c.period, x, xr),
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
