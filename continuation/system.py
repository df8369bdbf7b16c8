r"""User-facing dynamical systems :math:`\dot x = f(x, p)` with named states and parameters.

A user writes the right-hand side once as ``rhs(x, p, ops)`` against an
:class:`~continuation.ops.Ops` namespace. :class:`System` evaluates it with NumPy
and traces it once with CasADi ``SX`` symbols, giving compiled functions for
``f``, the state Jacobian ``df/dx`` and the parameter Jacobian ``df/dp``. A plain
NumPy callable ``rhs(x, p)`` also works: then derivatives come from central
differences.

A state may be periodic (an angle, or the ship's wave-relative position
``xi_G/lambda`` with period 1): :meth:`System.wrap`, :meth:`System.difference` and
:meth:`System.same_point` treat ``x`` and ``x + period`` as one point.
"""

from __future__ import annotations

import inspect
import logging
import threading
import warnings
import weakref
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol, runtime_checkable

import casadi as ca
import numpy as np
import scipy.sparse as sp

from .differentiation import fd_jacobian
from .errors import ModelError
from .linalg import csc_with_data
from .ops import CASADI_OPS, NUMPY_OPS, Ops
from .params import Params, name_index
from .typing import FloatArray

log = logging.getLogger(__name__)

RhsFn = Callable[..., Any]


@runtime_checkable
class DynamicalSystem(Protocol):
    """What the engine needs of a system ``x' = f(x, p)``."""

    state_names: tuple[str, ...]
    param_names: tuple[str, ...]

    def f(self, x: FloatArray, p: FloatArray) -> FloatArray:
        """Right-hand side, shape ``(n,)``."""
        ...

    def jacobian(self, x: FloatArray, p: FloatArray) -> FloatArray:
        """State Jacobian ``df/dx``, shape ``(n, n)``."""
        ...

    def dfdp(self, x: FloatArray, p: FloatArray) -> FloatArray:
        """Parameter Jacobian ``df/dp``, shape ``(n, m)``."""
        ...


def _accepts_ops(fn: RhsFn) -> bool:
    try:
        sig = inspect.signature(fn)
    except (TypeError, ValueError):
        return True
    params = list(sig.parameters.values())
    if any(p.kind == p.VAR_POSITIONAL for p in params):
        return True
    if "ops" in sig.parameters:
        return True
    positional = [p for p in params if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    return len(positional) >= 3


def _names(arg: Sequence[str] | str, what: str) -> tuple[str, ...]:
    if isinstance(arg, str):
        arg = (arg,)
    names = tuple(str(n) for n in arg)
    if not names and what == "state_names":
        raise ValueError("`state_names` must name at least one state")
    if len(set(names)) != len(names):
        raise ValueError(f"`{what}` must be unique, got {names}")
    return names


class _BufferedFunction:
    """Evaluate a CasADi ``Function`` of dense vector inputs through its buffer API.

    ``Function.buffer()`` evaluates into pre-bound NumPy memory, avoiding the DM
    conversions of ``Function.__call__`` (tens of microseconds per call, which dominate
    continuation steps of small systems). Each call returns fresh copies of the
    outputs' non-zeros (column-major for dense outputs). Not thread-safe.
    """

    def __init__(self, fn: ca.Function) -> None:
        self._buf, self._eval = fn.buffer()
        self._args = [np.zeros(fn.nnz_in(i)) for i in range(fn.n_in())]
        self._res = [np.zeros(fn.nnz_out(i)) for i in range(fn.n_out())]
        for i, a in enumerate(self._args):
            self._buf.set_arg(i, memoryview(a))
        for i, r in enumerate(self._res):
            self._buf.set_res(i, memoryview(r))

    def __call__(self, *args: Any) -> tuple[FloatArray, ...]:
        for a, v in zip(self._args, args, strict=True):
            a[:] = v
        self._eval()
        return tuple(r.copy() for r in self._res)


def _exact_args(fn: ca.Function, args: tuple[Any, ...]) -> list[FloatArray] | None:
    """The arguments as flat float arrays of the function's input sizes, or None."""
    out = []
    for i, v in enumerate(args):
        a = np.asarray(v, dtype=float).reshape(-1)
        if a.size != fn.nnz_in(i):
            return None
        out.append(a)
    return out


#: Buffered point evaluators of ``f``, ``df/dx``, ``df/dp`` per system and per thread
#: (a buffer is bound memory: one per thread), kept outside the instance so that the
#: system's own state is unchanged.
_POINT_FNS: weakref.WeakKeyDictionary[Any, dict[int, dict[str, _BufferedFunction]]] = (
    weakref.WeakKeyDictionary()
)


class BorderedEvaluator:
    """Buffers and compiled function of :meth:`System.bordered_evaluator`.

    Usage: ``ev.set_border(c, h)``, then write the point into ``ev.u`` (the function's
    input buffer, shape ``(n + 1,)``) and call ``ev()``; ``ev.r`` (shape ``(n + 1,)``)
    and ``ev.M`` (shape ``(n + 1, n + 1)``, Fortran order) then hold the bordered
    residual and matrix, until the next call. ``ev.r`` is the first column of
    ``ev.rt`` (shape ``(n + 1, 2)``, Fortran order), whose second column is the unit
    vector ``e_{n+1}``: ``M x = rt`` gives the Newton correction and the (unnormalised)
    tangent in one solve. ``ev.lin()`` copies ``(f, df/dx,
    df/dp)`` out of them. When the compiled function has a third output (as built by
    :meth:`System.bordered_evaluator`), ``ev.norms`` (shape ``(5,)``) holds
    ``(max |r|, r . r, max |u|, max |f|, sum M_ij^2)`` of the same call (None
    otherwise): the corrector's convergence and finiteness tests, the residual norm of
    ``f`` alone and the finiteness of the matrix without further NumPy calls. ``max``
    ignores NaN entries, the sums of squares do not (they are NaN or inf for any
    non-finite entry). Not
    thread-safe; one evaluator per problem.
    """

    __slots__ = ("_buf", "run", "u", "p", "c", "h", "r", "rt", "M", "n", "norms", "_bound")

    def __init__(self, fn: ca.Function, n: int, params: Any) -> None:
        self._buf, self.run = fn.buffer()
        self.n = n
        self.u = np.zeros(n + 1)
        self.p = np.array(np.asarray(params, dtype=float).reshape(-1), dtype=float)
        self.c = np.zeros(n + 1)
        self.h = np.zeros(1)
        # two right-hand sides in one Fortran array: the residual (written by the call)
        # and the unit vector e_{n+1} of the tangent, solved together by one LAPACK gesv
        self.rt = np.zeros((n + 1, 2), order="F")
        self.rt[n, 1] = 1.0
        self.r = self.rt[:, 0]
        m_flat = np.zeros((n + 1) * (n + 1))
        for i, a in enumerate((self.u, self.p, self.c, self.h)):
            self._buf.set_arg(i, memoryview(a))
        self._buf.set_res(0, memoryview(self.r))
        self._buf.set_res(1, memoryview(m_flat))
        self.M = m_flat.reshape(n + 1, n + 1).T  # column-major buffer: a Fortran view
        self.norms = None
        if fn.n_out() > 2 and fn.nnz_out(2) == 5:
            self.norms = np.zeros(5)
            self._buf.set_res(2, memoryview(self.norms))
        # the buffer holds raw pointers: keep every bound array alive with the evaluator
        self._bound = (self.u, self.p, self.c, self.h, self.rt, m_flat, self.norms)

    def set_border(self, c: FloatArray, h: float) -> None:
        """Set the border row ``c`` and the level ``h`` of the constraint ``c . u = h``."""
        self.c[:] = c
        self.h[0] = h

    def __call__(self) -> None:
        """Evaluate ``r`` and ``M`` at ``u``."""
        self.run()

    def lin(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Copies ``(f (n,), df/dx (n, n) Fortran order, df/dp (n,))`` of the last call."""
        n = self.n
        top = self.M[:n, :].copy(order="F")
        return self.r[:n].copy(), top[:, :n], top[:, n]


def _finite_vector(arr: FloatArray, names: tuple[str, ...], kind: str, name: str) -> FloatArray:
    """``arr`` if it holds one finite value per name in ``names``.

    Else a ValueError naming the argument ``name`` and the ``kind`` of vector
    (``"states"``, ``"parameters"``).
    """
    if arr.shape != (len(names),):
        raise ValueError(
            f"`{name}` must have shape ({len(names)},) for {kind} {names}, got {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"`{name}` contains NaN or inf: {arr}")
    return arr


class System:
    r"""An autonomous ODE :math:`\dot x = f(x, p)` with named states and parameters.

    Parameters
    ----------
    rhs : callable
        ``rhs(x, p, ops) -> sequence of n expressions`` (preferred: traced with CasADi
        for exact derivatives) or ``rhs(x, p) -> ndarray (n,)`` (NumPy only;
        derivatives by central differences). ``x`` has shape ``(n,)``, ``p`` shape
        ``(m,)``; use ``ops.sin`` etc. and return ``ops.stack([...])``.
    state_names : sequence of str
        Names of the ``n`` states.
    param_names : sequence of str
        Names of the ``m`` parameters (may be empty).
    periodic : mapping of str to float, optional
        ``{state_name: period}`` for states that live on a circle.
    defaults : mapping of str to float, optional
        Default parameter values, used by :meth:`params`.
    name : str, optional
        A label for messages and saved files.
    backend : {"auto", "casadi", "numpy"}
        ``"auto"`` traces with CasADi when ``rhs`` accepts ``ops`` and falls back to
        NumPy (with a logged note) if tracing fails; ``"casadi"`` requires tracing;
        ``"numpy"`` never traces.

    Raises
    ------
    ValueError
        For duplicate or empty names, unknown periodic states, non-positive periods,
        an unknown backend, or ``backend="casadi"`` with an ``rhs`` that cannot be traced.

    Examples
    --------
    >>> def rhs(x, p, ops):
    ...     return ops.stack([p[0] - x[0] ** 2])
    >>> s = System(rhs, ("x",), ("mu",))
    >>> s.jacobian(np.array([1.0]), np.array([0.0]))
    array([[-2.]])
    """

    def __init__(
        self,
        rhs: RhsFn,
        state_names: Sequence[str] | str,
        param_names: Sequence[str] | str = (),
        *,
        periodic: Mapping[str, float] | None = None,
        defaults: Mapping[str, float] | None = None,
        name: str = "",
        backend: str = "auto",
    ) -> None:
        if not callable(rhs):
            raise ValueError(f"`rhs` must be callable, got {type(rhs).__name__}")
        if backend not in ("auto", "casadi", "numpy"):
            raise ValueError(f"`backend` must be 'auto', 'casadi' or 'numpy', got {backend!r}")
        self._rhs = rhs
        self.state_names = _names(state_names, "state_names")
        self.param_names = _names(param_names, "param_names")
        self.name = name or getattr(rhs, "__name__", "system")
        self._with_ops = _accepts_ops(rhs)
        n = len(self.state_names)
        period = np.zeros(n)
        for k, v in dict(periodic or {}).items():
            if k not in self.state_names:
                raise ValueError(
                    f"`periodic` names unknown state {k!r}; states are {self.state_names}"
                )
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"`periodic[{k!r}]` must be a positive period, got {v}")
            period[self.state_names.index(k)] = float(v)
        period.setflags(write=False)
        self.period: FloatArray = period
        self._defaults = None
        if defaults is not None:
            self._defaults = Params.from_mapping(self.param_names, defaults)
        self._ca: dict[str, ca.Function] | None = None
        if backend != "numpy" and self._with_ops:
            try:
                self._ca = self._trace()
            except Exception as exc:  # tracing may fail for numpy-only code
                if backend == "casadi":
                    raise ValueError(f"`rhs` could not be traced with CasADi: {exc}") from exc
                warnings.warn(
                    f"rhs of {self.name!r} could not be traced with CasADi ({exc}); "
                    "using NumPy with finite-difference derivatives",
                    stacklevel=2,
                )
        elif backend == "casadi":
            raise ValueError("`rhs` must accept an `ops` argument for backend='casadi'")

    def __getstate__(self) -> dict[str, Any]:
        """The state to pickle, without the evaluators built on first use.

        ``_ca_lin`` and ``_ca_lin_free`` hold buffer evaluators that cannot be pickled
        (a system that ran a continuation could otherwise not be sent to another process
        or saved with an orbit); they are rebuilt on first use after unpickling.
        """
        state = dict(self.__dict__)
        for key in ("_ca_lin", "_ca_lin_free"):
            state.pop(key, None)
        return state

    # ------------------------------------------------------------------ sizes/names
    @property
    def n_states(self) -> int:
        """Number of states ``n``."""
        return len(self.state_names)

    @property
    def n_params(self) -> int:
        """Number of parameters ``m``."""
        return len(self.param_names)

    @property
    def has_casadi(self) -> bool:
        """True when exact derivatives from a CasADi trace are available."""
        return self._ca is not None

    def state_index(self, name: str) -> int:
        """Position of state ``name``; raises ValueError listing valid names."""
        return name_index(self.state_names, name, "state")

    def param_index(self, name: str) -> int:
        """Position of parameter ``name``; raises ValueError listing valid names."""
        return name_index(self.param_names, name, "parameter")

    def params(self, **values: float) -> Params:
        """Named parameters: the defaults, updated by ``values``.

        Without defaults every parameter must be given.
        """
        if self._defaults is None:
            return Params.from_mapping(self.param_names, values)
        return self._defaults.replace(**values)

    # ------------------------------------------------------------------ checking
    def check_state(self, x: Any, name: str = "x") -> FloatArray:
        """Return ``x`` as a float array of shape ``(n,)``; raise ValueError if not."""
        return _finite_vector(np.asarray(x, dtype=float), self.state_names, "states", name)

    def check_params(self, p: Any, name: str = "p") -> FloatArray:
        """Return a parameter vector of shape ``(m,)`` from an array, Params or mapping."""
        if isinstance(p, Params):
            if p.names != self.param_names:
                raise ValueError(f"`{name}` has names {p.names}, expected {self.param_names}")
            return np.array(p.values, dtype=float)
        if isinstance(p, Mapping):
            unknown = sorted(set(p) - set(self.param_names))
            if unknown:
                raise ValueError(
                    f"`{name}` names unknown parameter(s) {unknown}; valid names are "
                    f"{self.param_names}"
                )
            base = self._defaults
            if base is not None:
                return np.array(base.replace(**p).values)
            return np.array(Params.from_mapping(self.param_names, p).values)
        arr = np.asarray(p, dtype=float).reshape(-1) if np.ndim(p) else np.asarray([p], float)
        return _finite_vector(arr, self.param_names, "parameters", name)

    def as_params(self, p: Any = None, name: str = "params") -> Params:
        """Named parameters from a Params, a mapping or an array, checked.

        The one coercion of user parameters in the library: every entry point that
        takes ``params`` calls it.

        Parameters
        ----------
        p : Params, mapping or array_like, shape (m,), optional
            A :class:`Params` with this system's names (returned as it is), a mapping
            (missing names from the defaults when the system has them) or a vector in
            ``param_names`` order. ``None`` means the defaults.
        name : str
            Argument name used in error messages.

        Returns
        -------
        Params
            Shape ``(m,)``, names ``param_names``.

        Raises
        ------
        ValueError
            Wrong names, shape or non-finite values (message names ``name``); ``None``
            for a system without defaults.
        """
        if p is None:
            if self._defaults is None:
                raise ValueError(f"`{name}` is required: {self.param_names} have no defaults")
            return self._defaults
        vec = self.check_params(p, name)
        if isinstance(p, Params):
            return p
        return Params(self.param_names, vec)

    # ------------------------------------------------------------------ evaluation
    def rhs(self, x: Any, p: Any, ops: Ops = NUMPY_OPS) -> Any:
        """Call the user's right-hand side with the given ops namespace."""
        if self._with_ops:
            return self._rhs(x, p, ops)
        if ops is not NUMPY_OPS:
            raise ValueError("this System's `rhs` is NumPy-only and takes no `ops`")
        return self._rhs(x, p)

    def symbolic(self, x: Any, p: Any) -> Any:
        """CasADi expression of ``f`` for symbolic ``x`` (n,) and ``p`` (m,).

        Used by derived problems (fold/Hopf augmentations, collocation) so that they
        share one source of truth with the equilibrium engine.
        """
        if not self._with_ops:
            raise ValueError("this System's `rhs` is NumPy-only; it has no CasADi path")
        out = self._rhs(x, p, CASADI_OPS)
        if isinstance(out, (list, tuple)):
            out = ca.vertcat(*out)
        return out

    def _trace(self) -> dict[str, ca.Function]:
        n, m = self.n_states, self.n_params
        X = ca.SX.sym("x", n)
        P = ca.SX.sym("p", max(m, 0))
        F = self.symbolic(X, P)
        if F.shape != (n, 1):
            raise ModelError(f"rhs returned shape {F.shape}, expected ({n}, 1)")
        J = ca.jacobian(F, X)
        Jp = ca.jacobian(F, P) if m else ca.SX(n, 0)
        return {
            "f": ca.Function("f", [X, P], [F], ["x", "p"], ["f"]),
            "jac": ca.Function("jac_x", [X, P], [J], ["x", "p"], ["J"]),
            "dfdp": ca.Function("dfdp", [X, P], [Jp], ["x", "p"], ["Jp"]),
        }

    def linearize(self, x: FloatArray, p: FloatArray, *, sparse: bool = False) -> tuple[Any, ...]:
        """``(f, df/dx, df/dp)`` at ``(x, p)`` in one evaluation.

        Returns
        -------
        f : ndarray, shape (n,)
        J : ndarray, shape (n, n), or SciPy CSC matrix when ``sparse``
        Jp : ndarray, shape (n, m)

        Notes
        -----
        With a CasADi trace the three come from one compiled function (built on first
        use), which saves call overhead in continuation loops.
        """
        if self._ca is None:
            J = self.jacobian(x, p)
            return self.f(x, p), (sp.csc_matrix(J) if sparse else J), self.dfdp(x, p)
        lin = getattr(self, "_ca_lin", None)
        if lin is None:
            lin = self._ca_lin = self._build_linearize()
        n, m = self.n_states, self.n_params
        if sparse:
            f, nz, Jp = lin["sparse"](x, p)
            Jout: Any = sp.csc_matrix((nz, lin["indices"], lin["indptr"]), shape=(n, n))
        else:
            f, Jd, Jp = lin["dense"](x, p)
            Jout = Jd.reshape(n, n, order="F")
        return f, Jout, Jp.reshape(n, m, order="F")

    def _build_linearize(self) -> dict[str, Any]:
        X = ca.SX.sym("x", self.n_states)
        P = ca.SX.sym("p", self.n_params)
        F = self.symbolic(X, P)
        J = ca.jacobian(F, X)
        Jp = ca.jacobian(F, P) if self.n_params else ca.SX(self.n_states, 0)
        # sparse variant: the Jacobian leaves as its vector of structural non-zeros
        # (CSC order), so a SciPy matrix is built without converting a CasADi DM
        nz = ca.vertcat(*J.nonzeros()) if J.nnz() else ca.SX(0, 1)
        spy = J.sparsity()
        return {
            "dense": _BufferedFunction(
                ca.Function("lin", [X, P], [F, ca.densify(J), ca.densify(Jp)])
            ),
            "sparse": _BufferedFunction(ca.Function("lin_nz", [X, P], [F, nz, ca.densify(Jp)])),
            "indptr": np.asarray(spy.colind(), dtype=np.int32),
            "indices": np.asarray(spy.row(), dtype=np.int32),
        }

    def linearizer(
        self, index: int, params: Any, *, sparse: bool = False
    ) -> Callable[[FloatArray, float], tuple[FloatArray, Any, FloatArray]] | None:
        """A fast evaluator of ``(f, df/dx, df/dp_index)`` with the other parameters fixed.

        Parameters
        ----------
        index : int
            Position of the varying parameter in ``param_names``.
        params : array_like, shape (m,)
            Values of all parameters (the entry ``index`` is overwritten at each call).
        sparse : bool
            Return ``df/dx`` as a SciPy CSC matrix.

        Returns
        -------
        callable or None
            ``lin(x, p_index) -> (f (n,), J, Jp (n,))`` with fresh arrays at every call
            (``J`` dense ``(n, n)``, Fortran-ordered, or CSC), evaluated by one call of a
            compiled CasADi function through its buffer API into memory owned by this
            evaluator (so every evaluator is independent; not thread-safe); None
            without a CasADi trace. This is the hot path of continuation steps: it
            avoids the per-call conversions of :meth:`linearize`.
        """
        if self._ca is None:
            return None
        n, m = self.n_states, self.n_params
        if not 0 <= int(index) < m:
            raise ValueError(f"`index` must be in [0, {m}), got {index!r}")
        key = (int(index), bool(sparse))
        cache = self.__dict__.setdefault("_ca_lin_free", {})
        built = cache.get(key)
        if built is None:
            X = ca.SX.sym("x", n)
            P = ca.SX.sym("p", m)
            F = self.symbolic(X, P)
            J = ca.jacobian(F, X)
            Jq = ca.densify(ca.jacobian(F, P[int(index)]))
            if sparse:
                nz = ca.vertcat(*J.nonzeros()) if J.nnz() else ca.SX(0, 1)
                spy = J.sparsity()
                built = (
                    ca.Function("lin_free_nz", [X, P], [F, nz, Jq]),
                    np.asarray(spy.row(), dtype=np.int32),
                    np.asarray(spy.colind(), dtype=np.int32),
                )
            else:
                built = (ca.Function("lin_free", [X, P], [F, ca.densify(ca.horzcat(J, Jq))]),)
            cache[key] = built
        fn = built[0]
        buf, run = fn.buffer()
        x_in = np.zeros(n)
        p_in = np.array(np.asarray(params, dtype=float).reshape(m), dtype=float)
        f_out = np.zeros(n)
        buf.set_arg(0, memoryview(x_in))
        buf.set_arg(1, memoryview(p_in))
        buf.set_res(0, memoryview(f_out))
        k = int(index)
        if sparse:
            rows, colind = built[1], built[2]
            nz_out = np.zeros(fn.nnz_out(1))
            q_out = np.zeros(n)
            buf.set_res(1, memoryview(nz_out))
            buf.set_res(2, memoryview(q_out))

            template = sp.csc_matrix((nz_out.copy(), rows, colind), shape=(n, n))
            template.has_canonical_format  # noqa: B018  (checked once, inherited below)

            def lin_sparse(x: FloatArray, p: float) -> tuple[FloatArray, Any, FloatArray]:
                x_in[:] = x
                p_in[k] = p
                run()
                # same structure every call: share it, skip SciPy's format checks
                J = csc_with_data(template, nz_out.copy())
                return f_out.copy(), J, q_out.copy()

            lin_sparse.buffers = (buf, x_in, p_in, f_out, nz_out, q_out)  # type: ignore[attr-defined]
            return lin_sparse
        a_out = np.zeros(n * (n + 1))
        buf.set_res(1, memoryview(a_out))

        def lin_dense(x: FloatArray, p: float) -> tuple[FloatArray, Any, FloatArray]:
            x_in[:] = x
            p_in[k] = p
            run()
            A = a_out.reshape(n + 1, n).T.copy(order="F")  # [J, Jp], column-major
            return f_out.copy(), A[:, :n], A[:, n]

        lin_dense.buffers = (buf, x_in, p_in, f_out, a_out)  # type: ignore[attr-defined]
        return lin_dense

    def bordered_evaluator(self, index: int, params: Any) -> BorderedEvaluator | None:
        """A fused evaluator of the bordered Newton system of pseudo-arclength steps.

        For ``u = (x, p_index)`` (shape ``(n + 1,)``), a border ``c`` (shape
        ``(n + 1,)``) and a level ``h``, one call of a compiled CasADi function gives the
        bordered residual ``r = (f(x, p), c . u - h)`` and the bordered matrix
        ``M = [[df/dx, df/dp_index], [c^T]]`` (dense, Fortran order), the other
        parameters fixed at ``params``. See :class:`BorderedEvaluator`. None without a
        CasADi trace.
        """
        if self._ca is None:
            return None
        n, m = self.n_states, self.n_params
        k = int(index)
        if not 0 <= k < m:
            raise ValueError(f"`index` must be in [0, {m}), got {index!r}")
        cache = self.__dict__.setdefault("_ca_bordered", {})
        fn = cache.get(k)
        if fn is None:
            U = ca.SX.sym("u", n + 1)
            P = ca.SX.sym("p", m)
            C = ca.SX.sym("c", n + 1)
            H = ca.SX.sym("h")
            X = U[:n]
            Pk = ca.vertcat(P[:k], U[n], P[k + 1 :]) if m > 1 else U[n]
            F = self.symbolic(X, Pk)
            top = ca.horzcat(ca.jacobian(F, X), ca.jacobian(F, U[n]))
            M = ca.densify(ca.vertcat(top, C.T))
            R = ca.vertcat(F, ca.dot(C, U) - H)
            Mv = ca.vec(M)
            norms = ca.vertcat(
                ca.norm_inf(R), ca.dot(R, R), ca.norm_inf(U), ca.norm_inf(F), ca.dot(Mv, Mv)
            )
            fn = cache[k] = ca.Function("bordered", [U, P, C, H], [R, M, norms])
        return BorderedEvaluator(fn, n, params)

    def casadi_functions(self) -> dict[str, ca.Function]:
        """The compiled CasADi functions ``{"f", "jac", "dfdp"}`` (x, p) -> value."""
        if self._ca is None:
            raise ValueError(f"system {self.name!r} has no CasADi trace")
        return self._ca

    def _point(self, name: str, x: Any, p: Any) -> tuple[FloatArray, ...] | None:
        """``name`` in ``{"f", "jac", "dfdp"}`` at one point, or None.

        Through a buffered evaluator of this thread (dense outputs, column-major); None when
        ``x`` or ``p`` do not have the function's sizes (the caller then lets CasADi report
        the error).
        """
        assert self._ca is not None
        per = _POINT_FNS.get(self)
        if per is None:
            per = _POINT_FNS.setdefault(self, {})
        tid = threading.get_ident()
        fns = per.get(tid)
        if fns is None:
            X = ca.SX.sym("x", self.n_states)
            P = ca.SX.sym("p", max(self.n_params, 0))
            fns = per[tid] = {
                k: _BufferedFunction(ca.Function(f"{k}_dense", [X, P], [ca.densify(fn(X, P))]))
                for k, fn in self._ca.items()
            }
        fn = fns[name]
        args = _exact_args(self._ca[name], (x, p))
        return None if args is None else fn(*args)

    def f(self, x: FloatArray, p: FloatArray) -> FloatArray:
        """Evaluate ``f(x, p)``; returns shape ``(n,)``."""
        if self._ca is not None:
            ev = self._point("f", x, p)
            if ev is not None:
                return ev[0]
            return np.asarray(self._ca["f"](x, p)).reshape(-1)
        out = np.asarray(self.rhs(np.asarray(x, float), np.asarray(p, float)), dtype=float)
        return out.reshape(-1)

    def jacobian(self, x: FloatArray, p: FloatArray) -> FloatArray:
        """State Jacobian ``df/dx`` at ``(x, p)``, dense, shape ``(n, n)``."""
        if self._ca is not None:
            ev = self._point("jac", x, p)
            if ev is not None:
                n = self.n_states
                return ev[0].reshape(n, n, order="F")
            return np.asarray(self._ca["jac"](x, p))
        return fd_jacobian(lambda y: self.f(y, p), np.asarray(x, float))

    def jacobian_sparse(self, x: FloatArray, p: FloatArray) -> sp.csc_matrix:
        """State Jacobian as a SciPy CSC matrix (exact sparsity with CasADi)."""
        if self._ca is not None:
            return sp.csc_matrix(self._ca["jac"](x, p).sparse())
        return sp.csc_matrix(self.jacobian(x, p))

    def dfdp(self, x: FloatArray, p: FloatArray) -> FloatArray:
        """Parameter Jacobian ``df/dp`` at ``(x, p)``, shape ``(n, m)``."""
        if self._ca is not None:
            ev = self._point("dfdp", x, p)
            if ev is not None:
                return ev[0].reshape(self.n_states, self.n_params, order="F")
            return np.asarray(self._ca["dfdp"](x, p)).reshape(self.n_states, self.n_params)
        return fd_jacobian(lambda q: self.f(np.asarray(x, float), q), np.asarray(p, float))

    # ------------------------------------------------------------------ periodicity
    def wrap(self, x: FloatArray) -> FloatArray:
        """Map periodic coordinates into ``[0, period)``; shape of ``x`` kept (..., n)."""
        x = np.array(x, dtype=float)
        mask = self.period > 0
        if np.any(mask):
            x[..., mask] = np.mod(x[..., mask], self.period[mask])
        return x

    def difference(self, x1: FloatArray, x2: FloatArray) -> FloatArray:
        """``x1 - x2`` with periodic components reduced to ``[-period/2, period/2)``."""
        d = np.asarray(x1, dtype=float) - np.asarray(x2, dtype=float)
        mask = self.period > 0
        if mask.any():
            per = self.period[mask]
            d[..., mask] = np.mod(d[..., mask] + per / 2, per) - per / 2
        return d

    def same_point(self, x1: FloatArray, x2: FloatArray, tol: float = 1e-6) -> bool:
        """True if ``x1`` and ``x2`` are the same point modulo the periods (max-norm)."""
        return bool(np.max(np.abs(self.difference(x1, x2))) <= tol)

    def __repr__(self) -> str:
        return (
            f"System({self.name!r}, states={self.state_names}, params={self.param_names}, "
            f"backend={'casadi' if self.has_casadi else 'numpy'})"
        )


def check_jacobian(
    system: DynamicalSystem,
    x: FloatArray,
    p: FloatArray,
    *,
    rtol: float = 1e-6,
    atol: float = 1e-8,
) -> tuple[float, float]:
    """Compare ``system.jacobian`` and ``system.dfdp`` with central differences.

    Returns
    -------
    tuple of float
        Maximum scaled errors ``(err_x, err_p)``, each
        ``max |J - J_fd| / (atol + rtol * max|J_fd|)``; both must be ``<= 1``.

    Raises
    ------
    AssertionError
        Never; the caller decides. Use ``assert max(check_jacobian(...)) <= 1``.
    """
    x = np.asarray(x, dtype=float)
    p = np.asarray(p, dtype=float)
    J = np.asarray(system.jacobian(x, p))
    Jfd = fd_jacobian(lambda y: system.f(y, p), x)
    ex = float(np.max(np.abs(J - Jfd)) / (atol + rtol * max(1.0, np.max(np.abs(Jfd)))))
    ep = 0.0
    if p.size:
        Jp = np.asarray(system.dfdp(x, p))
        Jpfd = fd_jacobian(lambda q: system.f(x, q), p)
        ep = float(np.max(np.abs(Jp - Jpfd)) / (atol + rtol * max(1.0, np.max(np.abs(Jpfd)))))
    return ex, ep


def as_params(system: Any, p: Any, name: str = "params") -> Params:
    """``p`` as :class:`Params` of ``system``: :meth:`System.as_params`.

    For a duck-typed system without ``as_params`` (only ``param_names``) a Params is
    returned as it is and anything else is read as a vector in ``param_names`` order.
    """
    if hasattr(system, "as_params"):
        return system.as_params(p, name)  # type: ignore[no-any-return]
    if isinstance(p, Params):
        return p
    return Params(tuple(system.param_names), np.asarray(p, dtype=float))


__all__ = ["as_params", "DynamicalSystem", "System", "check_jacobian"]
