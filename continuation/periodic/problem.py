r"""The periodic-orbit continuation problem :class:`PeriodicOrbitProblem`.

``G(z, p) = 0`` is the collocation system of :mod:`continuation.periodic.collocation`
(unknowns ``z = [vec X, T]``, ``n M + 1`` of them) with the free parameter ``p``; it
is a :class:`~continuation.problem.ContinuationProblem`, so the pseudo-arclength
driver :func:`~continuation.driver.continue_branch` continues it.

The phase condition's reference orbit is the previous accepted point: it is held in
a small mutable slot of the (otherwise frozen) problem and replaced by
:meth:`PeriodicOrbitProblem.accept` after every accepted row
(the driver's ``accept`` hook, :class:`~continuation.problem.ProblemHooks`, which
runs after the step's special points were located, so every point of one step uses
the same reference); the driver's ``relabel`` hook names the special points as those
of cycles (:meth:`PeriodicOrbitProblem.relabel`).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from .._jit import compiled
from ..branch import SpecialKind, SpecialPoint
from ..bvp.collocation import CollocationMesh, LocalError
from ..bvp.layout import phase_reference
from ..linalg import csc_with_data
from ..params import Params
from ..typing import ComplexArray, FloatArray
from .collocation import CollocationLayout, StageEvaluator, monodromy_factors
from .floquet import FloquetResult, exponents, floquet, is_neimark_sacker, ns_test, pd_test
from .orbit import PeriodicOrbit

#: Number of points whose Floquet multipliers :meth:`PeriodicOrbitProblem.floquet` keeps.
FLOQUET_MEMO = 4

log = logging.getLogger(__name__)


def error_estimate(mesh: CollocationMesh, X: FloatArray) -> float:
    r"""Estimate of the uniform error of the collocation polynomial, max over states.

    On interval ``j`` the error of degree-``m`` Gauss collocation is
    :math:`\approx C_m h_j^{m+1} |x^{(m+1)}|` (de Boor & Swartz 1973) with
    :math:`C_m = \max_{s\in[0,1]} |\prod_k (s - c_k)| / (m+1)!`; :math:`x^{(m+1)}`
    is estimated by differences of the piecewise-constant ``m``-th derivatives of
    neighbouring intervals, wrapped around the ends (the cycle closes on itself).
    The estimate is :class:`~continuation.bvp.collocation.LocalError`, the monitor of
    the adaptive mesh of connections, landings and cycles
    (:meth:`~continuation.bvp.collocation.CollocationMesh.equidistributed`). An
    estimate (good to a factor of a few on resolved meshes), not a bound; nan on fewer
    than 3 intervals.
    """
    return LocalError(mesh, periodic=True)(X)


#: The compiled collocation system (:func:`continuation._jit.compiled`): the rows of every
#: collocated orbit and the cycle's own (``cycle_residual``, ``cycle_linearize``).
KERNELS = "continuation.bvp._collocation_jit"


#: A located period doubling has a multiplier within this distance of -1 (as
#: :func:`~continuation.periodic.floquet.is_neimark_sacker` asks of a pair on the unit
#: circle); the test :math:`\prod (\mu_i + 1)` can change sign across a jump where other
#: multipliers are huge (cycles near a homoclinic orbit), with none at -1.
PD_TOL = 1e-3


@dataclass(frozen=True, eq=False)
class PeriodicOrbitProblem:
    r"""Cycles of a :class:`~continuation.system.System` as a continuation problem.

    Parameters
    ----------
    system : System
    params : Params or mapping
        All parameters; the ``free`` entry is overwritten by ``p``.
    free : str
        The continuation parameter.
    mesh : CollocationMesh
        Nodes and degree of the discretisation (``mesh.T`` unused).
    winding : tuple of int
        ``k_i`` per state: ``x(1) = x(0) + k o period`` (nonzero only for periodic
        states; :func:`~continuation.periodic.orbit.winding_vector`).
    reference : ndarray, shape (n M + 1,)
        The unknowns of the first phase reference (updated by :meth:`accept`).

    Notes
    -----
    ``stability`` returns the Floquet exponents ``ln|mu| + i arg mu`` of the
    nontrivial multipliers (:func:`~continuation.periodic.floquet.exponents`), so the
    driver's count of ``Re > 0`` is the number of multipliers outside the unit circle;
    the multipliers themselves are :meth:`floquet`. Records per row: ``T`` (period),
    ``max_<state>``, ``min_<state>``, ``L2`` (the :math:`L_2` norm
    :math:`(\int_0^1 |x|^2 d\tau)^{1/2}`), ``mu_max`` (largest nontrivial ``|mu|``),
    ``trivial_error`` (``|mu_trivial - 1|``) and ``error`` (:func:`error_estimate`).
    """

    #: Marks the problem of a cycle branch (``switch_branch`` hands it to the cycles').
    is_cycle_problem: ClassVar[bool] = True

    system: Any
    params: Params
    free: str
    mesh: CollocationMesh
    winding: tuple[int, ...]
    reference: FloatArray
    _slot: dict[str, Any] = field(default_factory=dict, init=False, repr=False)
    _shift: FloatArray = field(init=False, repr=False)

    #: The Jacobian is a SciPy sparse (CSC) matrix: the driver's sparse solvers (a
    #: dense Jacobian was measured 10x slower in the driver even for 400 unknowns).
    sparse: ClassVar[bool] = True

    def __post_init__(self) -> None:
        if not isinstance(self.params, Params):
            vec = self.system.check_params(self.params, "params")
            object.__setattr__(self, "params", Params(self.system.param_names, vec))
        if self.free not in self.system.param_names:
            raise ValueError(f"`free` must be one of {self.system.param_names}, got {self.free!r}")
        n = self.system.n_states
        if len(self.winding) != n:
            raise ValueError(f"`winding` must have {n} entries, got {self.winding!r}")
        lay = CollocationLayout(n, self.mesh)
        ref = np.asarray(self.reference, dtype=float)
        if ref.shape != (lay.n_unknowns,):
            raise ValueError(f"`reference` must have shape ({lay.n_unknowns},), got {ref.shape}")
        per = np.asarray(getattr(self.system, "period", np.zeros(n)), dtype=float)
        object.__setattr__(self, "_layout", lay)
        index = self.system.param_names.index(self.free)
        object.__setattr__(self, "_eval", StageEvaluator(self.system, lay.N * lay.m, index))
        object.__setattr__(self, "_nodes_eval", StageEvaluator(self.system, lay.N + 1))
        object.__setattr__(self, "_errw", LocalError(self.mesh, periodic=True))
        object.__setattr__(self, "_index", index)
        object.__setattr__(self, "_shift", np.asarray(self.winding, dtype=float) * per)
        self.accept(ref)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_orbit(cls, orbit: PeriodicOrbit, free: str) -> PeriodicOrbitProblem:
        """The problem on ``orbit``'s mesh with ``orbit`` as the phase reference."""
        lay = CollocationLayout(orbit.system.n_states, orbit.mesh)
        return cls(orbit.system, orbit.params, free, orbit.mesh, orbit.winding,
                   lay.join(orbit.X, orbit.T))  # fmt: skip

    @property
    def layout(self) -> CollocationLayout:
        """Index bookkeeping (:class:`~continuation.periodic.collocation.CollocationLayout`)."""
        return self._layout  # type: ignore[attr-defined,no-any-return]

    @property
    def n_unknowns(self) -> int:
        """``n M + 1``."""
        return int(self.layout.n_unknowns)

    @property
    def exact_jacobian(self) -> bool:
        """The derivatives are exact where the system has a CasADi trace.

        Else they are the system's finite differences:
        :func:`~continuation.problem.exact_jacobian`.
        """
        return bool(getattr(self.system, "has_casadi", False))

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the unknowns: ``<state>@<point>`` and ``T``."""
        names = self.system.state_names
        return tuple(f"{s}@{q}" for q in range(self.layout.M) for s in names) + ("T",)

    def param_vector(self, p: float) -> FloatArray:
        """Full parameter vector with the free entry ``p``."""
        v = np.array(self.params.values, dtype=float)
        v[self._index] = p  # type: ignore[attr-defined]
        return v

    # ------------------------------------------------------------------ phase reference
    def accept(self, z: FloatArray, p: float | None = None) -> None:
        """Make the cycle ``z`` the reference of the integral phase condition.

        With ``p`` (an accepted row of the branch): its Floquet multipliers, if already
        computed, are kept for the life of the problem, so that
        :func:`~continuation.periodic.rows.multipliers` of the branch does not
        compute them again.
        """
        lay = self.layout
        if p is not None:
            key = (np.asarray(z, dtype=float).tobytes(), float(p))
            res = self._slot.get("floquet", {}).get(key)
            if res is not None:
                self._slot.setdefault("rows", {})[key] = res
        X, _ = lay.split(np.asarray(z, dtype=float))
        # the connections' integral phase condition (continuation.bvp.layout)
        self._slot["ref"], self._slot["dref"] = phase_reference(self.mesh, X)
        self._slot["cache"] = None

    def relabel(self, specials: Sequence[SpecialPoint]) -> tuple[SpecialPoint, ...]:
        """The special points as points of cycles (the driver calls this once per branch).

        Folds become ``LPC1, LPC2, ...``, branch points ``BPC1, ...``; the zeros of the
        events ``"PD"``/``"NS"`` become the kinds ``pd`` (with the multiplier ``mu``
        next to ``-1``) and ``ns`` (with the angle ``theta`` of the pair on the unit
        circle); an NS zero without such a pair (a neutral saddle) is dropped, a PD zero
        without a multiplier within :data:`PD_TOL` of ``-1`` is reported as bracketed
        (not located).
        """
        out = []
        count = {"LPC": 0, "BPC": 0}
        for sp in specials:
            if sp.kind == SpecialKind.FOLD:
                count["LPC"] += 1
                sp = dataclasses.replace(sp, label=f"LPC{count['LPC']}")
            elif sp.kind == SpecialKind.BRANCH_POINT:
                count["BPC"] += 1
                sp = dataclasses.replace(sp, label=f"BPC{count['BPC']}")
            elif sp.kind == SpecialKind.USER and sp.label == "NS":
                ok, theta = is_neimark_sacker(self.floquet(sp.x, sp.p).multipliers)
                if not ok:
                    log.info("NS test zero at p=%.8g is a neutral saddle: not reported", sp.p)
                    continue
                sp = dataclasses.replace(
                    sp, kind=SpecialKind.NEIMARK_SACKER, data={**sp.data, "theta": theta}
                )
            elif sp.kind == SpecialKind.USER and sp.label == "PD":
                mu = self.floquet(sp.x, sp.p).multipliers
                k = int(np.argmin(np.abs(mu + 1.0)))
                located = sp.located
                if located and not abs(mu[k] + 1.0) <= PD_TOL:
                    # the test's sign changed, but no multiplier is at -1 where the locator
                    # stopped (multipliers of 1e10 and more: a jump of the product, not a
                    # zero): bracketed only
                    log.warning("PD at p=%.8g: no multiplier at -1 there (nearest %.6g); "
                                "reported as bracketed, not located", sp.p, mu[k].real)  # fmt: skip
                    located = False
                sp = dataclasses.replace(
                    sp, kind=SpecialKind.PERIOD_DOUBLING, located=located,
                    data={**sp.data, "mu": float(mu[k].real)},
                )  # fmt: skip
            out.append(sp)
        return tuple(out)

    # ------------------------------------------------------------------ evaluation
    def _stages(self, z: FloatArray, p: float, full: bool) -> Any:
        lay = self.layout
        X, T = lay.split(z)
        P = self.param_vector(p)
        Xs = X[lay.stage_points]
        if not full:
            return X, T, P, self._eval.f(Xs, P), None, None  # type: ignore[attr-defined]
        F, J, Jp = self._eval.all(Xs, P)  # type: ignore[attr-defined]
        return X, T, P, F, J, Jp

    def residual(self, z: FloatArray, p: float) -> FloatArray:
        """``G(z, p)``, shape ``(n M + 1,)``."""
        X, T, _, F, _, _ = self._stages(np.asarray(z, float), p, False)
        s = self._slot
        D, e, h, w, sp_ = self.layout.kernel_args()[:5]
        G = np.empty(self.layout.n_unknowns)
        kern = compiled(KERNELS)
        kern.cycle_residual(X, T, F, D, e, h, self._shift, s["ref"], s["dref"], w, sp_, G)
        return G

    def linearize(self, z: FloatArray, p: float) -> tuple[FloatArray, Any, FloatArray]:
        """``(G, dG/dz (CSC), dG/dp)`` in one evaluation of ``f, f_x, f_p``."""
        z = np.asarray(z, dtype=float)
        lay = self.layout
        X, T, _, F, J, Jp = self._stages(z, p, True)
        s = self._slot
        # residual, Jacobian values and dG/dp in one compiled call
        args = lay.kernel_args()
        G = np.empty(lay.n_unknowns)
        Gp = np.empty(lay.n_unknowns)
        vals = np.empty(lay._n_vals)
        data = np.empty(lay._template.nnz)
        compiled(KERNELS).cycle_linearize(
            X,
            T,
            F,
            J,
            Jp,
            *args[:3],
            self._shift,
            s["ref"],
            s["dref"],
            *args[3:],
            G,
            vals,
            data,
            Gp,
        )
        B = vals[: lay._col_rows.size].reshape(lay.N, lay.m, lay.m + 1, lay.n, lay.n)
        self._slot["cache"] = (z.copy(), float(p), B, F)
        return G, csc_with_data(lay._template, data), Gp

    def jacobian(self, z: FloatArray, p: float) -> Any:
        """``dG/dz``, SciPy CSC of shape ``(n M + 1, n M + 1)``."""
        return self.linearize(z, p)[1]

    def dp(self, z: FloatArray, p: float) -> FloatArray:
        """``dG/dp``, shape ``(n M + 1,)``."""
        return self.linearize(z, p)[2]

    # ------------------------------------------------------------------ Floquet
    def _blocks(self, z: FloatArray, p: float) -> tuple[FloatArray, FloatArray]:
        z = np.asarray(z, dtype=float)
        c = self._slot.get("cache")
        if c is not None and c[1] == p and np.array_equal(c[0], z):
            return c[2], c[3]
        X, T, _, F, J, _ = self._stages(z, p, True)
        B = self.layout.blocks(X, T, J)
        self._slot["cache"] = (z.copy(), float(p), B, F)
        return B, F

    def floquet(self, z: FloatArray, p: float) -> FloquetResult:
        """Floquet multipliers of the cycle ``z`` by condensation of the collocation blocks.

        See :func:`~continuation.periodic.collocation.monodromy_factors`.
        """
        key = (np.asarray(z, dtype=float).tobytes(), float(p))
        # a few points: the driver asks for the multipliers at a row, at the row moved
        # along its tangent (the events' slopes) and at the row again (records), in turn
        memo = self._slot.setdefault("floquet", {})
        if key in memo:
            return memo[key]  # type: ignore[no-any-return]
        rows = self._slot.get("rows")
        if rows is not None and key in rows:
            return rows[key]  # type: ignore[no-any-return]
        B, _ = self._blocks(z, p)
        X, _ = self.layout.split(np.asarray(z, dtype=float))
        P = self.param_vector(p)
        f_nodes = self._nodes_eval.f(X[:: self.layout.m + 1], P)  # type: ignore[attr-defined]
        res = floquet(
            monodromy_factors(self.layout, B), f_nodes, self._slot.setdefault("schur", {})
        )
        if len(memo) >= FLOQUET_MEMO:
            del memo[next(iter(memo))]  # oldest first (dicts keep insertion order)
        memo[key] = res
        return res

    def monodromy(self, z: FloatArray, p: float) -> FloatArray:
        """The monodromy matrix of the discretised variational equation, ``(n, n)``."""
        from .floquet import monodromy

        B, _ = self._blocks(z, p)
        return monodromy(monodromy_factors(self.layout, B))

    def stability(self, z: FloatArray, p: float) -> ComplexArray:
        """Floquet exponents of the nontrivial multipliers (see the class notes)."""
        return exponents(self.floquet(z, p).multipliers)

    def pd_test(self, z: FloatArray, p: float) -> float:
        """Period-doubling test function (:func:`~continuation.periodic.floquet.pd_test`)."""
        return pd_test(self.floquet(z, p).multipliers)

    def ns_test(self, z: FloatArray, p: float) -> float:
        """Neimark-Sacker test function (:func:`~continuation.periodic.floquet.ns_test`)."""
        return ns_test(self.floquet(z, p).multipliers)

    # ------------------------------------------------------------------ records
    def orbit(self, z: FloatArray, p: float) -> PeriodicOrbit:
        """The cycle ``z`` at ``p`` as a :class:`PeriodicOrbit`."""
        X, T = self.layout.split(np.asarray(z, dtype=float))
        params = Params(self.params.names, self.param_vector(p))
        return PeriodicOrbit(self.system, params, self.mesh, X.copy(), T, self.winding)

    def record(self, z: FloatArray, p: float) -> Mapping[str, float]:
        """Period, extrema, L2 norm, largest multiplier, accuracy (class notes)."""
        lay = self.layout
        X, T = lay.split(np.asarray(z, dtype=float))
        Xs = X[lay.stage_points]
        out: dict[str, float] = {"T": T}
        hi, lo = X.max(axis=0).tolist(), X.min(axis=0).tolist()
        for i, name in enumerate(self.system.state_names):
            out[f"max_{name}"] = hi[i]
            out[f"min_{name}"] = lo[i]
        out["L2"] = float(np.sqrt(np.sum(lay.weights[:, None] * Xs**2)))
        fl = self.floquet(z, p)
        out["mu_max"] = float(np.max(np.abs(fl.multipliers))) if fl.multipliers.size else 0.0
        out["trivial_error"] = fl.trivial_error
        out["error"] = self._errw(X)  # type: ignore[attr-defined]
        return out


__all__ = ["PeriodicOrbitProblem", "error_estimate"]
