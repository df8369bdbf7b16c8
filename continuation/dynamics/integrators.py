r"""The two integrator back-ends of :class:`~continuation.dynamics.simulate.Simulator`.

``method="cvodes"`` (default when the system has a CasADi trace)
    SUNDIALS CVODES (Hindmarsh et al. 2005, "SUNDIALS: Suite of nonlinear and
    differential/algebraic equation solvers", ACM TOMS 31(3)) through
    ``casadi.integrator``: variable-order BDF (orders 1-5) with a Newton corrector
    on the exact Jacobian ``T df/dx`` that CasADi derives from the trace. Robust on
    stiff models (the ship's rudder servo is much faster than its surge motion).
``method="cvodes_adams"``
    CVODES with variable-order Adams-Moulton (orders 1-12), for non-stiff models.
``method in {"RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA"}``
    SciPy's ``OdeSolver`` classes stepped one by one, calling the compiled CasADi
    ``f`` (and ``jacobian`` for the implicit ones). Available for any system,
    including NumPy-only ones; default for those.

One CasADi ``f`` call from Python costs tens of microseconds of overhead, so the SciPy
methods are dominated by call overhead on small models, while CVODES calls the compiled
function in C. BDF is the default rather than Adams for its robustness on stiff models,
at a small extra cost on non-stiff ones (measurements: ``benchmarks/README.md``,
"Time integrators").

Compiled right-hand side. For a large model (at least
:data:`continuation.casadi_compile.MIN_INSTRUCTIONS` instructions, e.g. the ship's)
CVODES runs the time-scaled right-hand side and its Jacobian compiled to machine code
once their library is in the cache (:func:`continuation.casadi_compile.compiled_soon`
starts the compilation in the background on first use; until it is ready, and when no
compiler exists, CasADi's virtual machine evaluates the same expressions). The
integration is the same, step for step (same expressions in the same order); the
ship's sudden-change runs take about 2.7x less time.

State transition matrix. :func:`state_transition` integrates the system with its
variational equations :math:`\dot\Phi = (\partial f/\partial x)\,\Phi` by CVODES
(the ``n + n^2`` states under the same error control, the exact ``df/dx`` of the
trace; compiled like the plain right-hand side once its library is ready): the
Jacobian of a flow map to integration accuracy, e.g. for the return map of
:mod:`continuation.dynamics.shooting`. (CasADi's own forward sensitivities of the
plain integrator, ``jac:xf:x0``, gave the same matrix to 5e-10 on the ship's orbit at
Fn 0.1 but took 9 times longer than this uncompiled, 0.9 s against 0.1 s.)

Interrupts. A CVODES call is native code, but CasADi polls Python's signal handlers
between right-hand-side evaluations, so a Ctrl-C (SIGINT) stops it within one
integrator step; the call then fails with a ``RuntimeError`` (``CV_RHSFUNC_FAIL``)
whose message, with CasADi's warnings off, does not say why.
:func:`~continuation.sigint.sigint_recorded` counts the SIGINTs that arrive while a
simulation runs, so that :class:`_CvodesBackend` raises ``KeyboardInterrupt`` for such
a failure instead of reporting an integration failure (which would be misread as a
blow-up, and retried).

A SIGINT can also be *lost* in a CasADi call from Python: CasADi converts a NumPy
argument with a Python helper (``DM_from_array``) called from its SWIG type check,
and a ``KeyboardInterrupt`` raised in that helper (Python runs the handler at the
next bytecode, often there, since a call follows each progress report) is cleared
as a failed check; the call then runs to its end and nothing is raised (seen in
``tests/test_interrupts.py``: 20 s instead of 0.2 s to stop, about one run in eight).
So :class:`_CvodesBackend` converts the arguments to ``DM`` itself and checks the
count before and after the native call, and
:meth:`~continuation.dynamics.simulate.Simulator.run` and the fate classifier check
:func:`~continuation.sigint.sigints_counted` after every block: a counted SIGINT always
stops the simulation, at worst one call late.
"""

from __future__ import annotations

import math
import weakref
from typing import Any

import casadi as ca
import numpy as np
import scipy.integrate as si

from ..casadi_compile import compiled_soon
from ..sigint import _Sigints, sigint_recorded
from ..typing import FloatArray

SCIPY_METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
CVODES_METHODS = ("cvodes", "cvodes_adams")
METHODS = CVODES_METHODS + SCIPY_METHODS

#: Default relative and absolute tolerances of the integrators.
DEFAULT_RTOL = 1e-10
DEFAULT_ATOL = 1e-12
#: CVODES internal steps allowed per output interval before it reports failure.
_MAX_STEPS_PER_SAMPLE = 20000


class _IntegrationFailure(Exception):
    """Raised by a backend when the integrator fails on an interval."""


def _scaled_ode(system: Any, n: int, n_params: int) -> ca.Function:
    """The time-scaled right-hand side ``T f(x, p)`` as a CasADi DAE function.

    Inputs ``(t, x, z, p, u)`` with ``p = (params, T)``, outputs ``(ode, alg, quad,
    zero)`` (CasADi's integrator signature; ``z``, ``u``, ``alg``, ``quad``, ``zero``
    empty), so that its compiled copy can be handed to ``casadi.integrator`` directly.
    """
    f = system.casadi_functions()["f"]
    t, X, P = ca.SX.sym("t"), ca.SX.sym("x", n), ca.SX.sym("p", n_params + 1)
    empty = ca.SX(0, 1)
    return ca.Function(
        "scaled_ode", [t, X, ca.SX.sym("z", 0), P, ca.SX.sym("u", 0)],
        [P[-1] * f(X, P[:-1]), empty, empty, empty], ca.dyn_in(), ca.dyn_out(),
    )  # fmt: skip


def _variational_ode(system: Any, n: int, n_params: int) -> ca.Function:
    r"""The time-scaled system with its variational equations, as a CasADi DAE function.

    States :math:`z = (x, \operatorname{vec} \Phi)` (``n + n^2``, :math:`\Phi`
    column-major), parameters ``(params, T)``, on :math:`s \in [0, 1]`:

    .. math::

        \frac{dx}{ds} = T f(x, p), \qquad
        \frac{d\Phi}{ds} = T \, \frac{\partial f}{\partial x}(x, p) \, \Phi,

    so that :math:`\Phi(1) = \partial x(T) / \partial x(0)` with :math:`\Phi(0) = I`
    (the state transition matrix, the solution of the variational equation; e.g.
    Parker & Chua 1989, *Practical Numerical Algorithms for Chaotic Systems*).
    ``df/dx`` is the exact Jacobian of the system's CasADi trace. Signature as
    :func:`_scaled_ode`'s.
    """
    funcs = system.casadi_functions()
    f, jac = funcs["f"], funcs["jac"]
    X, Phi = ca.SX.sym("x", n), ca.SX.sym("Phi", n, n)
    P = ca.SX.sym("p", n_params + 1)
    T, p = P[-1], P[:-1]
    rhs = ca.vertcat(T * f(X, p), ca.vec(T * ca.mtimes(ca.densify(jac(X, p)), Phi)))
    empty = ca.SX(0, 1)
    return ca.Function(
        "variational_ode", [ca.SX.sym("t"), ca.vertcat(X, ca.vec(Phi)), ca.SX.sym("z", 0), P,
        ca.SX.sym("u", 0)], [rhs, empty, empty, empty], ca.dyn_in(), ca.dyn_out(),
    )  # fmt: skip


class _CvodesBackend:
    """CVODES through ``casadi.integrator`` with time scaled to ``[0, 1]``.

    The integrated system is ``dx/ds = T f(x, p)`` on ``s in [0, 1]``, ``T`` an extra
    parameter, so one compiled integrator serves every segment length (and both time
    directions). Integrators are cached per system and options.
    """

    _cache: weakref.WeakKeyDictionary[Any, dict[tuple[Any, ...], Any]] = weakref.WeakKeyDictionary()

    def __init__(
        self, system: Any, p: FloatArray, method: str, rtol: float, atol: float, max_step: float
    ) -> None:
        self.system = system
        self.p = np.asarray(p, dtype=float)
        self.lmm = "adams" if method == "cvodes_adams" else "bdf"
        self.rtol = rtol
        self.atol = atol
        self.max_step = max_step
        self.n = len(system.state_names)
        self.n_calls = 0
        self._local: dict[tuple[Any, ...], Any] = {}

    def _integrator(self, n_out: int, span: float) -> Any:
        ms = self.max_step / abs(span) if math.isfinite(self.max_step) else 0.0
        store = self._store()
        ode = self.ode_function(store)
        fast = compiled_soon(ode, jacobian=True)
        key = (n_out, self.lmm, self.rtol, self.atol, ms, fast is not None)
        integ = store.get(key)
        if integ is None:
            # the compiled right-hand side with its Jacobian when ready (the same
            # expressions, evaluated in machine code; module notes), else the VM
            dae = fast if fast is not None else ode
            opts = self._options(_MAX_STEPS_PER_SAMPLE)
            if ms > 0:
                opts["max_step_size"] = ms
            grid = [k / n_out for k in range(1, n_out + 1)]
            integ = ca.integrator(f"sim_{n_out}", "cvodes", dae, 0.0, grid, opts)
            store[key] = integ
        return integ

    def _options(self, max_steps: int) -> dict[str, Any]:
        """CVODES options: this backend's tolerances and method, quiet, failing loudly."""
        return {
            "reltol": self.rtol,
            "abstol": self.atol,
            "max_num_steps": max_steps,
            "linear_multistep_method": self.lmm,
            "disable_internal_warnings": True,
            "show_eval_warnings": False,
            "error_on_fail": True,
        }

    def _store(self) -> dict[Any, Any]:
        try:
            return self._cache.setdefault(self.system, {})
        except TypeError:  # system not weak-referenceable: cache on this backend only
            return self._local

    def ode_function(self, store: dict[Any, Any] | None = None) -> ca.Function:
        """The system's time-scaled right-hand side (:func:`_scaled_ode`), built once."""
        store = self._store() if store is None else store
        ode = store.get("ode")
        if ode is None:
            ode = store["ode"] = _scaled_ode(self.system, self.n, self.p.size)
        return ode

    def uses_compiled(self) -> bool:
        """True when CVODES runs the compiled right-hand side (ready in the cache)."""
        return compiled_soon(self.ode_function(), jacobian=True) is not None

    def run(self, x0: FloatArray, T: float, n_out: int, span_hint: float) -> FloatArray:
        """States at ``t0 + T k / n_out``, k = 1..n_out, shape ``(n_out, n)``."""
        out = self._call(self._integrator(n_out, span_hint), x0, T)
        xs = out.reshape(self.n, n_out).T
        if not np.all(np.isfinite(xs)):
            raise _IntegrationFailure("non-finite state")
        return xs

    def _call(self, integ: Any, z0: FloatArray, T: float) -> FloatArray:
        """``xf`` of one CVODES call from ``z0`` over time ``T`` (states x outputs).

        Raises ``KeyboardInterrupt`` for a SIGINT counted before, during or after the
        native call (also one whose exception CasADi discarded), and
        ``_IntegrationFailure`` when CVODES fails otherwise.
        """
        self.n_calls += 1
        n_sigint = _Sigints.count
        # DM arguments, converted first: a NumPy argument is converted inside the call by
        # Python code whose KeyboardInterrupt CasADi discards (module notes)
        args = {"x0": ca.DM(np.asarray(z0, dtype=float)), "p": ca.DM(np.append(self.p, T))}
        if _Sigints.count != n_sigint:  # handled in the conversion, and discarded there
            raise KeyboardInterrupt
        try:
            out = integ.call(args)
        except RuntimeError as exc:
            if _Sigints.count != n_sigint or "KeyboardInterrupt" in str(exc):
                raise KeyboardInterrupt from None  # Ctrl-C inside CVODES (module notes)
            msg = str(exc).strip().splitlines()[-1] if str(exc).strip() else "CVODES failed"
            raise _IntegrationFailure(msg) from None
        if _Sigints.count != n_sigint:  # handled during the call, but lost (module notes)
            raise KeyboardInterrupt
        return np.asarray(out["xf"], dtype=float)

    def transition(self, x0: FloatArray, T: float) -> tuple[FloatArray, FloatArray]:
        r"""The state and the state transition matrix after time ``T`` from ``x0``.

        CVODES on the variational equations (:func:`_variational_ode`), with the
        backend's tolerances applied to every component of :math:`\Phi` as well as of
        :math:`x` (so :math:`\Phi` is accurate to the integration accuracy, not to a
        difference quotient's).

        Parameters
        ----------
        x0 : ndarray, shape (n,)
        T : float
            Integration time (negative integrates backwards).

        Returns
        -------
        x_T : ndarray, shape (n,)
        Phi : ndarray, shape (n, n)
            :math:`\partial x(T) / \partial x_0`.

        Raises
        ------
        KeyboardInterrupt
            On a SIGINT during the call.
        _IntegrationFailure
            If CVODES fails.
        """
        n = self.n
        store = self._store()
        ode = store.get("variational_ode")
        if ode is None:
            ode = store["variational_ode"] = _variational_ode(self.system, n, self.p.size)
        # compiled with its Jacobian when ready, as the plain runs (module notes)
        fast = compiled_soon(ode, jacobian=True)
        key = ("transition", self.lmm, self.rtol, self.atol, fast is not None)
        integ = store.get(key)
        if integ is None:
            dae = fast if fast is not None else ode
            opts = self._options(10 * _MAX_STEPS_PER_SAMPLE)
            integ = store[key] = ca.integrator("transition", "cvodes", dae, 0.0, [1.0], opts)
        z0 = np.concatenate([np.asarray(x0, dtype=float), np.eye(n).reshape(-1)])
        z = self._call(integ, z0, T).reshape(-1)
        if not np.all(np.isfinite(z)):
            raise _IntegrationFailure("non-finite state or state transition matrix")
        return z[:n].copy(), z[n:].reshape(n, n, order="F")

    def advance(self, x0: FloatArray, tau: float, span_hint: float) -> FloatArray:
        """State at ``t0 + tau``, shape ``(n,)``."""
        if tau == 0.0:
            return np.array(x0, dtype=float)
        return self.run(x0, tau, 1, span_hint)[0]


class _ScipyBackend:
    """A SciPy ``OdeSolver`` driven step by step with the compiled right-hand side."""

    def __init__(
        self, system: Any, p: FloatArray, method: str, rtol: float, atol: float, max_step: float
    ) -> None:
        self.system = system
        self.p = np.asarray(p, dtype=float)
        self.method = method
        self.rtol = rtol
        self.atol = atol
        self.max_step = max_step
        self.n_calls = 0
        f = getattr(system, "casadi_functions", None)
        funcs = None
        if getattr(system, "has_casadi", False) and f is not None:
            funcs = f()
        if funcs is not None:
            cf, cj = funcs["f"], funcs["jac"]
            pp = self.p
            self.fun = lambda t, x: np.asarray(cf(x, pp)).reshape(-1)
            self.jac = lambda t, x: np.asarray(cj(x, pp))
        else:
            self.fun = lambda t, x: np.asarray(system.f(x, self.p), dtype=float).reshape(-1)
            self.jac = lambda t, x: np.asarray(system.jacobian(x, self.p), dtype=float)

    def solver(self, t0: float, x0: FloatArray, t1: float) -> Any:
        cls = getattr(si, self.method)
        kw: dict[str, Any] = {"rtol": self.rtol, "atol": self.atol, "max_step": self.max_step}
        if self.method in ("Radau", "BDF", "LSODA"):
            kw["jac"] = self.jac
        return cls(self.fun, t0, np.array(x0, dtype=float), t1, **kw)


def state_transition(
    system: Any,
    p: FloatArray,
    x0: FloatArray,
    T: float,
    *,
    rtol: float = DEFAULT_RTOL,
    atol: float = DEFAULT_ATOL,
    method: str = "cvodes",
) -> tuple[FloatArray, FloatArray]:
    r"""The state :math:`x(T)` and the state transition matrix :math:`\partial x(T)/\partial x_0`.

    CVODES on :math:`\dot x = f(x, p)` augmented with its variational equations
    :math:`\dot\Phi = (\partial f/\partial x)\,\Phi`, :math:`\Phi(0) = I`
    (:meth:`_CvodesBackend.transition`), the tolerances applied to :math:`\Phi` too.

    Parameters
    ----------
    system : System
        With a CasADi trace (``has_casadi``).
    p : ndarray, shape (m,)
        Parameter vector.
    x0 : ndarray, shape (n,)
    T : float
        Integration time.
    rtol, atol : float
        CVODES tolerances.
    method : {"cvodes", "cvodes_adams"}

    Returns
    -------
    x_T : ndarray, shape (n,)
    Phi : ndarray, shape (n, n)

    Raises
    ------
    ValueError
        For a system without a CasADi trace or a method other than CVODES'.
    _IntegrationFailure
        If CVODES fails.
    """
    if not getattr(system, "has_casadi", False):
        raise ValueError("`system` has no CasADi trace: no variational equations")
    if method not in CVODES_METHODS:
        raise ValueError(f"`method` must be one of {CVODES_METHODS}, got {method!r}")
    backend = _CvodesBackend(system, p, method, rtol, atol, math.inf)
    with sigint_recorded():
        return backend.transition(x0, T)
