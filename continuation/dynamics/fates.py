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
unstable eigenvector, ``v_u`` oriented as in :mod:`continuation.dynamics.saddles`: its first
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
import math
from dataclasses import dataclass, field

import numpy as np

from ..status import Status
from ..typing import ComplexArray, FloatArray
from .trajectory import Trajectory


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
        """The first visit, or ``None``.

        Of the saddle ``name``, if given; at a nonzero shift if ``shifted``.
        """
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


__all__ = ["Fate", "FateKind", "KnownEquilibrium", "SaddleVisit", "passage_side"]
