r"""Locate the parameter value where a fate switches, by bisection.

A global bifurcation (a heteroclinic or homoclinic connection) shows up as a parameter
value :math:`p^*` on either side of which a branch of an unstable manifold has
different fates: for the ship of Umeda (1999), the upslope branch of the saddle near the
wave crest tends to a periodic attractor (surging) below the critical nominal Froude
number and to capsizing above it, and the switch is the heteroclinic bifurcation.
:func:`bisect_fate` brackets :math:`p^*` to a stated tolerance by evaluating a
user-supplied ``fate_at(p)``. :func:`manifold_fate_function` builds that function for a
branch of an unstable manifold, re-solving the saddle (and the other known equilibria)
at every new parameter value with :class:`EquilibriumTracker`.

Bisection needs only a sign (here: a label) at each point, so it is robust to the
non-smooth dependence of the fate on ``p``; it halves the bracket per evaluation, so
``log2((b - a) / tol)`` evaluations reach ``tol``.

First passage. The *final* fate of a manifold branch may switch not only at the
connection sought (branch of ``W^u(A)`` on ``W^s(B)``) but also at secondary ones
(the branch passes ``B``, then lands on ``W^s`` of a further saddle), which can
accumulate on the primary connection; bisection on the final fate may then lock onto
one of them. The side on which the branch leaves ``B`` on its first passage
(:func:`continuation.dynamics.fates.passage_side`) switches only at the primary connection:
``manifold_fate_function(..., passage="B")`` bisects that instead.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Hashable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..arguments import integer_at_least, positive
from ..errors import ContinuationError, ConvergenceError
from ..newton import newton
from ..settings import NewtonSettings
from ..status import Status
from ..system import as_params
from ..typing import FloatArray
from .classifier import FateClassifier
from .fates import Fate, FateKind, passage_side
from .manifolds import unstable_manifold
from .saddles import REFINE_NEWTON, n_unstable_of, refine_equilibrium

log = logging.getLogger(__name__)


def _at(fn: Callable[[Any, Any], Any], pv: Any) -> Callable[[Any], Any]:
    """``z -> fn(z, pv)`` (the parameter vector bound now)."""
    return lambda z: fn(z, pv)


def fate_label(fate: Any) -> Hashable:
    """The label used to compare fates: ``Fate.label``, or the value itself."""
    if isinstance(fate, Fate):
        return fate.label
    if isinstance(fate, Hashable):
        return fate
    raise ValueError(f"a fate must be a Fate or a hashable label, got {type(fate).__name__}")


def _undecided(fate: Any) -> bool:
    return isinstance(fate, Fate) and fate.kind is FateKind.UNDECIDED


@dataclass(frozen=True)
class BisectionResult:
    """Outcome of :func:`bisect_fate`.

    Attributes
    ----------
    p_critical : float
        Midpoint of the final bracket (NaN without a valid bracket).
    bracket : (float, float)
        ``(lo, hi)`` with ``lo < hi``: the fate at ``lo`` is ``fate_lo``, at ``hi`` it is
        ``fate_hi``, and they differ. ``hi - lo <= tol`` on success.
    fate_lo, fate_hi : Fate or label
        Fates at the bracket ends.
    n_evaluations : int
        Number of calls of ``fate_at``.
    status : Status
        ``SUCCESS``; ``NO_BRACKET`` (ends with the same fate); ``UNDECIDED`` (an
        evaluation ended undecided); ``MAX_ITER``; ``INTERRUPTED``; ``NEWTON_FAILED``
        (``fate_at`` raised a ContinuationError, e.g. the saddle was lost).
    message : str
        Explanation.
    history : tuple of (float, label)
        Every evaluation, in order.
    """

    p_critical: float
    bracket: tuple[float, float]
    fate_lo: Any
    fate_hi: Any
    n_evaluations: int
    status: Status
    message: str = ""
    history: tuple[tuple[float, Hashable], ...] = ()

    @property
    def width(self) -> float:
        """``hi - lo``."""
        return self.bracket[1] - self.bracket[0]


def bisect_fate(
    fate_at: Callable[[float], Any],
    a: float,
    b: float,
    *,
    tol: float = 1e-6,
    max_evaluations: int = 200,
    progress: Callable[[float, float, int], None] | None = None,
    throw: bool = False,
) -> BisectionResult:
    r"""Find where ``fate_at(p)`` switches between ``a`` and ``b``, to ``tol``.

    The fates at the ends must differ (compared by :func:`fate_label`). Each step
    evaluates the midpoint and keeps the half whose ends have different fates: a
    midpoint with the fate of ``lo`` replaces ``lo``, any other fate replaces ``hi``.
    So with several switches in ``[a, b]`` one of them is found, and the bracket
    ``(lo, hi)`` always has ``fate(lo) != fate(hi)``.

    Parameters
    ----------
    fate_at : callable
        ``fate_at(p) -> Fate or hashable label``.
    a, b : float
        Ends of the parameter interval (either order).
    tol : float
        Stop when the bracket is at most ``tol`` wide.
    max_evaluations : int
        Limit on calls of ``fate_at`` (including the two ends).
    progress : callable, optional
        ``progress(lo, hi, n_evaluations)`` after each evaluation.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` unless successful.

    Returns
    -------
    BisectionResult

    Raises
    ------
    ValueError
        For non-finite or equal ``a``, ``b``, a non-positive ``tol``, or a fate that is
        neither a ``Fate`` nor hashable.
    """
    try:
        a, b = float(a), float(b)
    except (TypeError, ValueError):
        raise ValueError(f"`a` and `b` must be numbers, got {a!r}, {b!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)) or a == b:
        raise ValueError(f"`a` and `b` must be distinct finite numbers, got {a}, {b}")
    positive("tol", tol)
    integer_at_least("max_evaluations", max_evaluations, 2)
    if not callable(fate_at):
        raise ValueError("`fate_at` must be callable")
    lo, hi = min(a, b), max(a, b)
    history: list[tuple[float, Hashable]] = []
    fates: dict[str, Any] = {}

    def result(status: Status, message: str) -> BisectionResult:
        valid = "lo" in fates and "hi" in fates and status is not Status.NO_BRACKET
        res = BisectionResult(
            0.5 * (lo + hi) if valid else math.nan,
            (lo, hi),
            fates.get("lo"),
            fates.get("hi"),
            len(history),
            status,
            message,
            tuple(history),
        )
        if throw and status is not Status.SUCCESS:
            raise ContinuationError(f"fate bisection failed: {message}")
        return res

    def evaluate(p: float) -> tuple[Any, Hashable]:
        f = fate_at(p)
        lab = fate_label(f)
        history.append((p, lab))
        if progress is not None:
            progress(lo, hi, len(history))
        return f, lab

    try:
        try:
            fates["lo"], lab_lo = evaluate(lo)
            fates["hi"], lab_hi = evaluate(hi)
        except ContinuationError as exc:
            return result(Status.NEWTON_FAILED, f"evaluation failed: {exc}")
        for key in ("lo", "hi"):
            if _undecided(fates[key]):
                return result(Status.UNDECIDED, f"the fate at the {key} end is undecided")
        if lab_lo == lab_hi:
            return result(
                Status.NO_BRACKET,
                f"both ends of [{lo}, {hi}] have the same fate {lab_lo!r}; no switch to locate",
            )
        while hi - lo > tol:
            if len(history) >= max_evaluations:
                return result(
                    Status.MAX_ITER,
                    f"{max_evaluations} evaluations reached with bracket width {hi - lo:.3g}",
                )
            mid = 0.5 * (lo + hi)
            if not lo < mid < hi:  # bracket at floating-point resolution
                break
            try:
                f_mid, lab_mid = evaluate(mid)
            except ContinuationError as exc:
                return result(Status.NEWTON_FAILED, f"evaluation at {mid!r} failed: {exc}")
            if _undecided(f_mid):
                return result(
                    Status.UNDECIDED,
                    f"the fate at p={mid!r} is undecided (increase t_max); bracket kept",
                )
            if lab_mid == lab_lo:
                lo, fates["lo"] = mid, f_mid
            else:
                hi, fates["hi"], lab_hi = mid, f_mid, lab_mid
            log.debug("fate bisection: [%r, %r] (%s | %s)", lo, hi, lab_lo, lab_hi)
    except KeyboardInterrupt:
        return result(Status.INTERRUPTED, "interrupted; the current bracket is kept")
    return result(
        Status.SUCCESS,
        f"fate switches from {lab_lo!r} to {lab_hi!r} in [{lo!r}, {hi!r}] (width {hi - lo:.3g})",
    )


class EquilibriumTracker:
    r"""Follow equilibria as one parameter changes, by Newton from the nearest solution.

    At a new value ``v`` of the ``free`` parameter, each equilibrium is solved by Newton
    from a secant prediction through the two nearest values already solved (or from the
    nearest one). If Newton fails, the step is halved (up to ``max_halvings`` times)
    and the intermediate values are solved first (natural-parameter continuation).
    The saddle index of each equilibrium is checked to stay the same: a change means a
    local bifurcation in between, and raises :class:`~continuation.errors.ConvergenceError`.

    Parameters
    ----------
    system : System
    params : Params, mapping or array_like
        Parameters at which ``points`` are equilibria.
    free : str
        Name of the varying parameter.
    points : sequence of array_like (n,) or mapping of str to array_like
        Equilibria at ``params``.
    newton : NewtonSettings, optional
    max_halvings : int
        How often a failing step may be halved.
    check_index : bool
        Check that saddle indices do not change.
    """

    def __init__(
        self,
        system: Any,
        params: Any,
        free: str,
        points: Sequence[Any] | Mapping[str, Any],
        *,
        newton: NewtonSettings | None = None,
        max_halvings: int = 10,
        check_index: bool = True,
    ) -> None:
        if free not in system.param_names:
            raise ValueError(f"`free` must be one of {tuple(system.param_names)}, got {free!r}")
        self.system = system
        self.params = as_params(system, params)
        vec = np.array(self.params.values)
        self.free = free
        self.k = list(system.param_names).index(free)
        if isinstance(points, Mapping):
            self.names = tuple(str(n) for n in points)
            pts = list(points.values())
        else:
            pts = list(points)
            self.names = tuple(f"E{i}" for i in range(len(pts)))
        if not pts:
            raise ValueError("`points` must contain at least one equilibrium")
        self.newton = newton or REFINE_NEWTON
        self.max_halvings = int(max_halvings)
        self.check_index = check_index
        v0 = float(vec[self.k])
        sol, idx = [], []
        for name, x in zip(self.names, pts, strict=True):
            xr, _, _, nu = refine_equilibrium(system, x, vec, name=f"points[{name!r}]")
            sol.append(xr)
            idx.append(nu)
        self.index = tuple(idx)
        self._solved: dict[float, FloatArray] = {v0: np.array(sol)}

    def param_vector(self, value: float) -> FloatArray:
        """Full parameter vector with ``free = value``, shape ``(m,)``."""
        v = np.array(self.params.values, dtype=float)
        v[self.k] = value
        return v

    def _predict(self, value: float) -> FloatArray:
        keys = sorted(self._solved, key=lambda v: abs(v - value))
        v1 = keys[0]
        x1 = self._solved[v1]
        if len(keys) > 1:
            v0 = keys[1]
            if (v0 - v1) != 0 and abs(value - v1) <= 2 * abs(v1 - v0):
                return x1 + (x1 - self._solved[v0]) * (value - v1) / (v1 - v0)
        return x1

    def _solve_at(self, value: float) -> FloatArray | None:
        pv = self.param_vector(value)
        guess = self._predict(value)
        out = []
        for j, x0 in enumerate(guess):
            res = newton(
                _at(self.system.f, pv),
                _at(self.system.jacobian, pv),
                x0,
                self.newton,
            )
            if not res.converged:
                return None
            if self.check_index:
                nu = n_unstable_of(np.linalg.eigvals(self.system.jacobian(res.z, pv)))
                if nu != self.index[j]:
                    raise ConvergenceError(
                        f"equilibrium {self.names[j]!r} changed its saddle index from "
                        f"{self.index[j]} to {nu} at {self.free}={value!r} (local bifurcation)"
                    )
            out.append(np.asarray(res.z, dtype=float))
        return np.array(out)

    def at(self, value: float) -> dict[str, FloatArray]:
        """The equilibria at ``free = value``: ``{name: x (n,)}``.

        Raises
        ------
        ConvergenceError
            If Newton fails even after ``max_halvings`` step halvings, or a saddle index
            changes.
        """
        value = float(value)
        if not math.isfinite(value):
            raise ValueError(f"`value` must be finite, got {value!r}")
        if value not in self._solved:
            self._reach(value, self.max_halvings)
        return dict(zip(self.names, (np.array(x) for x in self._solved[value]), strict=True))

    def _reach(self, value: float, budget: int) -> None:
        xs = self._solve_at(value)
        if xs is not None:
            self._solved[value] = xs
            return
        if budget <= 0:
            raise ConvergenceError(
                f"could not follow the equilibria to {self.free}={value!r} "
                f"(Newton failed after {self.max_halvings} step halvings)"
            )
        near = min(self._solved, key=lambda v: abs(v - value))
        self._reach(0.5 * (near + value), budget - 1)
        self._reach(value, budget - 1)


def manifold_fate_function(
    system: Any,
    params: Any,
    free: str,
    x_saddle: Any,
    *,
    branch: int = 1,
    equilibria: Sequence[Any] | Mapping[str, Any] = (),
    eps: float = 1e-6,
    orient: str | int | None = None,
    tracker_options: Mapping[str, Any] | None = None,
    passage: str | None = None,
    passage_labels: Mapping[int, Hashable] | None = None,
    **classifier_options: Any,
) -> Callable[[float], Any]:
    """``fate_at(p)`` for one branch of the unstable manifold of a tracked saddle.

    At each ``p`` the saddle and the other ``equilibria`` are re-solved by an
    :class:`EquilibriumTracker` (Newton from the nearest value already solved), a
    :class:`~continuation.dynamics.fates.FateClassifier` is built with them (the saddle named
    ``"saddle"``, the others as given), and the fate of the ``branch`` of
    :func:`~continuation.dynamics.manifolds.unstable_manifold` is returned.

    Parameters
    ----------
    system, params
        System and parameters at which ``x_saddle`` and ``equilibria`` are solutions.
    free : str
        The parameter to vary.
    x_saddle : array_like, shape (n,)
        Index-1 saddle at ``params``.
    branch : {+1, -1}
        Which branch (see the sign convention of :mod:`continuation.dynamics.manifolds`).
    equilibria : sequence or mapping
        Other equilibria to recognise (e.g. the stable ones, or the neighbouring
        saddle if it is a different point modulo the periods).
    eps, orient
        As for :func:`~continuation.dynamics.manifolds.unstable_manifold`.
    tracker_options : mapping, optional
        Options of :class:`EquilibriumTracker`.
    passage : str, optional
        Name of a saddle in ``equilibria`` (or ``"saddle"`` for copies of the start
        shifted by whole periods): ``fate_at`` then returns the side on which the branch
        leaves its first visit of that saddle (:func:`continuation.dynamics.fates.passage_side`),
        as ``passage_labels[side]``; the plain fate when there is no such visit or
        its side is unknown (far from the connection, or converging onto it). See the
        module notes.
    passage_labels : mapping of {+1, -1} to label, optional
        Labels of the two sides; default ``"passage:<name>:+1"`` / ``":-1"``. Name them
        after the final fates on each side (e.g. ``{+1: "event:y_up", -1:
        "event:y_down"}``) so that evaluations without a visit compare consistently.
    **classifier_options
        Options of :class:`~continuation.dynamics.fates.FateClassifier` (``events``,
        ``poincare``, ``tol``, ``t_max``, ...).

    Returns
    -------
    callable
        ``fate_at(p) -> Fate`` (or a side label, with ``passage``), to pass to
        :func:`bisect_fate`. It raises
        :class:`~continuation.errors.ConvergenceError` if the equilibria are lost.
    """
    if branch not in (1, -1):
        raise ValueError(f"`branch` must be +1 or -1, got {branch!r}")
    if isinstance(equilibria, Mapping):
        others = {str(k): v for k, v in equilibria.items()}
    else:
        others = {f"E{i}": v for i, v in enumerate(equilibria)}
    if "saddle" in others:
        raise ValueError("`equilibria` may not use the name 'saddle' (reserved)")
    points = {"saddle": x_saddle, **others}
    if passage is not None and passage not in points:
        raise ValueError(f"`passage` must be one of {tuple(points)}, got {passage!r}")
    labels: dict[int, Hashable] = {s: f"passage:{passage}:{s:+d}" for s in (1, -1)}
    if passage_labels is not None:
        if not isinstance(passage_labels, Mapping) or set(passage_labels) != {1, -1}:
            raise ValueError(f"`passage_labels` must map +1 and -1, got {passage_labels!r}")
        labels = {int(k): v for k, v in passage_labels.items()}
    tracker = EquilibriumTracker(system, params, free, points, **dict(tracker_options or {}))
    if tracker.index[0] != 1:
        raise ValueError(f"`x_saddle` must be a saddle of index 1, got index {tracker.index[0]}")

    def fate_at(value: float) -> Any:
        eqs = tracker.at(value)
        pv = tracker.param_vector(value)
        clf = FateClassifier(system, pv, equilibria=eqs, **classifier_options)
        res = unstable_manifold(
            system,
            pv,
            eqs["saddle"],
            eps=eps,
            classify=clf,
            branches=(branch,),
            orient=orient,
            refine=False,
        )
        if res.status is Status.INTERRUPTED:
            raise KeyboardInterrupt
        fate = res.branch(branch).fate
        if fate is None:  # pragma: no cover - a classifier always returns a Fate
            raise ContinuationError("no fate computed")
        if passage is not None:
            side = passage_side(fate, passage, shifted=passage == "saddle")
            if side:
                return labels[side]
        return fate

    return fate_at


__all__ = [
    "BisectionResult",
    "EquilibriumTracker",
    "bisect_fate",
    "fate_label",
    "manifold_fate_function",
]
