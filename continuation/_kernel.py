r"""The compiled pseudo-arclength step for small dense systems (Numba).

A pseudo-arclength step of a system of a few states is mostly interpreter overhead:
at ``n = 8`` the arithmetic of a Newton iteration (an evaluation of the residual and
Jacobian, an LU factorisation and solve of order ``n + 1``) takes a microsecond or two,
its Python driving some ten times that. :func:`_step` does one whole step of
:class:`~continuation.algorithms.palc.PALC` in one compiled call:

* the predictor (tangent, or cubic Hermite from the last two points);
* Newton's method on the bordered system with the iteration and acceptance rules of
  the Python corrector (``continuation.algorithms.corrector._correct_fused`` with
  ``exact=False``), the residual and ``[G_z G_p]`` from the system's instruction tape
  (:mod:`continuation._tape`) run by a compiled interpreter, so that the compiled code
  is generic, cached on disk once and never recompiled per system;
* LAPACK ``dgetrf``/``dgetrs`` (SciPy's, through named symbols so that the compiled
  code can be cached) for the Newton correction and the unnormalised tangent in one
  factorisation, as ``dgesv`` in the Python corrector;
* the step safeguards (distance to the predictor, tangent angle, contraction), the
  normalised and oriented tangent, the sign of ``det M``, and the eigenvalues of
  ``G_z`` (LAPACK ``dgeev``) sorted by decreasing real, then imaginary part, with the
  unstable counts of :func:`~continuation.stability.count_unstable`.

A step the kernel does not accept as a whole (any rejection or rare case) is redone by
the Python step, which is authoritative; accepted steps are the same as the Python
step's to round-off (the same LAPACK routines on the same matrices; tested against
the Python path row by row).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import llvmlite.binding as _llvm
import numba
import numpy as np
from numba.core import types as _nbt
from numba.extending import get_cython_function_address as _cython_address

from ._tape import (
    _K_ACOS,
    _K_ACOSH,
    _K_ADD,
    _K_AND,
    _K_ASIN,
    _K_ASINH,
    _K_ASSIGN,
    _K_ATAN,
    _K_ATAN2,
    _K_ATANH,
    _K_CEIL,
    _K_CONST,
    _K_CONSTPOW,
    _K_COPYSIGN,
    _K_COS,
    _K_COSH,
    _K_DIV,
    _K_EQ,
    _K_ERF,
    _K_EXP,
    _K_FABS,
    _K_FLOOR,
    _K_FMAX,
    _K_FMIN,
    _K_FMOD,
    _K_HYPOT,
    _K_IF_ELSE_ZERO,
    _K_INPUT,
    _K_INV,
    _K_LE,
    _K_LOG,
    _K_LOG1P,
    _K_LT,
    _K_MUL,
    _K_NE,
    _K_NEG,
    _K_NOT,
    _K_OR,
    _K_OUTPUT,
    _K_POW,
    _K_SIGN,
    _K_SIN,
    _K_SINH,
    _K_SQ,
    _K_SQRT,
    _K_SUB,
    _K_TAN,
    _K_TANH,
    _K_TWICE,
    Tape,
)  # fmt: skip
from .algorithms.point import PointInfo
from .linalg import BorderedLU

log = logging.getLogger(__name__)

# SciPy's LAPACK, called from compiled code through named symbols (not baked-in
# addresses), so that the compiled functions can be cached on disk
for _name in ("dgetrf", "dgetrs", "dgeev"):
    _llvm.add_symbol("broachkit_" + _name, _cython_address("scipy.linalg.cython_lapack", _name))
_vp = _nbt.voidptr
_dgetrf = _nbt.ExternalFunction("broachkit_dgetrf", _nbt.void(*([_vp] * 6)))
_dgetrs = _nbt.ExternalFunction("broachkit_dgetrs", _nbt.void(*([_vp] * 9)))
_dgeev = _nbt.ExternalFunction("broachkit_dgeev", _nbt.void(*([_vp] * 14)))


# ----------------------------------------------------------------------------- compiled
def _offsets(n: int) -> tuple[int, int, int, int, int, int, int, int, int, int]:
    """Offsets in a step's output buffer (:func:`out_layout`) for ``n`` unknowns."""
    n1 = n + 1
    o_eig = 0  # first: the complex view needs 16-byte alignment
    o_u = o_eig + 2 * n
    o_d = o_u + n1
    o_g = o_d + n1
    o_gz = o_g + n
    o_gp = o_gz + n * n
    o_lu = o_gp + n
    o_t = o_lu + n1 * n1
    o_tau = o_t + n1
    o_c = o_tau + n1
    return o_eig, o_u, o_d, o_g, o_gz, o_gp, o_lu, o_t, o_tau, o_c


def out_layout(n: int) -> int:
    """Length of a step's output buffer.

    ``eig`` (``2n``, complex as pairs), ``u``, ``d`` (``n + 1`` each), ``G`` (``n``),
    ``G_z`` (``n^2``, Fortran order), ``G_p`` (``n``), the LU factors (``(n + 1)^2``,
    Fortran order), ``t_raw``, ``tau``, ``c`` (``n + 1`` each), in that order.
    """
    return _offsets(n)[-1] + n + 1


# error_model="numpy": float division by zero and math domain errors give inf/NaN
# as in C (CasADi's own virtual machine), not Python exceptions
_jit = numba.njit(cache=True, nogil=True, boundscheck=False, error_model="numpy")
out_offsets = _jit(_offsets)  # (the same offsets inside the compiled step)


@_jit
def _run_tape(op, ia, ib, io, consts, w, u, p, f, nz):  # pragma: no cover - compiled
    """Evaluate a linearisation tape (:func:`linearisation_tape`).

    Inputs ``(u, p)``, outputs ``(f, nz)``. One flat branch chain, the most frequent
    operations first (a call per operation costs more than the operation).
    """
    for k in range(op.size):
        o = op[k]
        if o == _K_MUL:
            w[io[k]] = w[ia[k]] * w[ib[k]]
        elif o == _K_ADD:
            w[io[k]] = w[ia[k]] + w[ib[k]]
        elif o == _K_OUTPUT:
            if io[k] == 0:
                f[ib[k]] = w[ia[k]]
            else:
                nz[ib[k]] = w[ia[k]]
        elif o == _K_SUB:
            w[io[k]] = w[ia[k]] - w[ib[k]]
        elif o == _K_INPUT:
            if ia[k] == 0:
                w[io[k]] = u[ib[k]]
            else:
                w[io[k]] = p[ib[k]]
        elif o == _K_CONST:
            w[io[k]] = consts[k]
        elif o == _K_SQ:
            x = w[ia[k]]
            w[io[k]] = x * x
        elif o == _K_DIV:
            w[io[k]] = w[ia[k]] / w[ib[k]]
        elif o == _K_NEG:
            w[io[k]] = -w[ia[k]]
        elif o == _K_TWICE:
            w[io[k]] = 2.0 * w[ia[k]]
        elif o == _K_FABS:
            w[io[k]] = abs(w[ia[k]])
        elif o == _K_FMAX or o == _K_FMIN:  # C fmax/fmin: a NaN operand is ignored
            x = w[ia[k]]
            y = w[ib[k]]
            if x != x:
                w[io[k]] = y
            elif y != y:
                w[io[k]] = x
            elif o == _K_FMAX:
                w[io[k]] = x if x >= y else y
            else:
                w[io[k]] = x if x <= y else y
        elif o == _K_INV:
            w[io[k]] = 1.0 / w[ia[k]]
        elif o == _K_SQRT:
            w[io[k]] = math.sqrt(w[ia[k]])
        elif o == _K_EXP:
            w[io[k]] = math.exp(w[ia[k]])
        elif o == _K_LOG:
            w[io[k]] = math.log(w[ia[k]])
        elif o == _K_POW or o == _K_CONSTPOW:
            w[io[k]] = w[ia[k]] ** w[ib[k]]
        elif o == _K_SIN:
            w[io[k]] = math.sin(w[ia[k]])
        elif o == _K_COS:
            w[io[k]] = math.cos(w[ia[k]])
        elif o == _K_TAN:
            w[io[k]] = math.tan(w[ia[k]])
        elif o == _K_TANH:
            w[io[k]] = math.tanh(w[ia[k]])
        elif o == _K_ASSIGN:
            w[io[k]] = w[ia[k]]
        elif o == _K_ASIN:
            w[io[k]] = math.asin(w[ia[k]])
        elif o == _K_ACOS:
            w[io[k]] = math.acos(w[ia[k]])
        elif o == _K_ATAN:
            w[io[k]] = math.atan(w[ia[k]])
        elif o == _K_SINH:
            w[io[k]] = math.sinh(w[ia[k]])
        elif o == _K_COSH:
            w[io[k]] = math.cosh(w[ia[k]])
        elif o == _K_ASINH:
            w[io[k]] = math.asinh(w[ia[k]])
        elif o == _K_ACOSH:
            w[io[k]] = math.acosh(w[ia[k]])
        elif o == _K_ATANH:
            w[io[k]] = math.atanh(w[ia[k]])
        elif o == _K_SIGN:
            x = w[ia[k]]
            w[io[k]] = 1.0 if x > 0.0 else (-1.0 if x < 0.0 else x)
        elif o == _K_ATAN2:
            w[io[k]] = math.atan2(w[ia[k]], w[ib[k]])
        elif o == _K_HYPOT:
            w[io[k]] = math.hypot(w[ia[k]], w[ib[k]])
        elif o == _K_COPYSIGN:
            w[io[k]] = math.copysign(w[ia[k]], w[ib[k]])
        elif o == _K_LT:
            w[io[k]] = 1.0 if w[ia[k]] < w[ib[k]] else 0.0
        elif o == _K_LE:
            w[io[k]] = 1.0 if w[ia[k]] <= w[ib[k]] else 0.0
        elif o == _K_EQ:
            w[io[k]] = 1.0 if w[ia[k]] == w[ib[k]] else 0.0
        elif o == _K_NE:
            w[io[k]] = 1.0 if w[ia[k]] != w[ib[k]] else 0.0
        elif o == _K_NOT:
            w[io[k]] = 1.0 if w[ia[k]] == 0.0 else 0.0
        elif o == _K_AND:
            w[io[k]] = 1.0 if (w[ia[k]] != 0.0 and w[ib[k]] != 0.0) else 0.0
        elif o == _K_OR:
            w[io[k]] = 1.0 if (w[ia[k]] != 0.0 or w[ib[k]] != 0.0) else 0.0
        elif o == _K_IF_ELSE_ZERO:
            w[io[k]] = w[ib[k]] if w[ia[k]] != 0.0 else 0.0
        elif o == _K_FLOOR:
            w[io[k]] = math.floor(w[ia[k]])
        elif o == _K_CEIL:
            w[io[k]] = math.ceil(w[ia[k]])
        elif o == _K_FMOD:
            w[io[k]] = np.fmod(w[ia[k]], w[ib[k]])
        elif o == _K_ERF:
            w[io[k]] = math.erf(w[ia[k]])
        elif o == _K_LOG1P:
            w[io[k]] = math.log1p(w[ia[k]])
        else:  # _K_EXPM1 (tape_of admits no other operation)
            w[io[k]] = math.expm1(w[ia[k]])


@_jit
def _linearise(tp_op, tp_ia, tp_ib, tp_io, tp_c, w, u, p, f, nz, rows, cols, c, h, M, r):
    """``f``, ``[G_z G_p]`` and the bordered residual at ``u`` (pragma: compiled).

    Writes the non-zeros into the top block of ``M`` (its structural zeros stay 0,
    its last row is the border ``c``) and ``r = (f, c . u - h)``. Returns
    ``(max|r|, r . r, max|u|, max|f|, sum M_ij^2)`` (maxima ignore NaN, the sums
    do not), as the norms output of the CasADi evaluator.
    """
    _run_tape(tp_op, tp_ia, tp_ib, tp_io, tp_c, w, u, p, f, nz)
    n1 = u.size
    n = n1 - 1
    for k in range(nz.size):
        M[rows[k], cols[k]] = nz[k]
    s = 0.0
    un = 0.0
    for j in range(n1):
        M[n, j] = c[j]
        s += c[j] * u[j]
        v = abs(u[j])
        if v > un:
            un = v
    rr = 0.0
    rn = 0.0
    gn = 0.0
    for i in range(n):
        v = f[i]
        r[i] = v
        rr += v * v
        v = abs(v)
        if v > gn:
            gn = v
    rn = gn
    v = s - h
    r[n] = v
    rr += v * v
    if abs(v) > rn:
        rn = abs(v)
    mm = 0.0
    for j in range(n1):
        for i in range(n1):
            v = M[i, j]
            mm += v * v
    return rn, rr, un, gn, mm


@_jit
def _backward_error(M, r, u):  # pragma: no cover - compiled
    """``corrector._backward_error`` of the bordered residual ``r`` at ``u``.

    ``max(max_i |G_i| / max_i (|M| |u|)_i, |r_n| / (|M| |u|)_n)``, ``i < n``.
    """
    n1 = u.size
    n = n1 - 1
    sf = 0.0
    sb = 0.0
    for i in range(n1):
        s = 0.0
        for j in range(n1):
            s += abs(M[i, j]) * abs(u[j])
        if i < n:
            sf = max(sf, s)
        else:
            sb = s
    gf = 0.0
    for i in range(n):
        gf = max(gf, abs(r[i]))
    wf = gf / (sf + 1e-300) if n else 0.0
    return max(wf, abs(r[n]) / (sb + 1e-300))


@_jit
def _factor_solve(M, r, lu, x, piv, iw, ch):  # pragma: no cover - compiled
    """LAPACK ``dgetrf`` and ``dgetrs``: what ``dgesv`` does. Returns info.

    ``dgetrf`` of a copy of ``M`` into ``lu`` (1-based ``piv``) and ``dgetrs`` for ``x =
    M^{-1} [r, e_{N+1}]``.
    """
    n1 = r.size
    for j in range(n1):
        for i in range(n1):
            lu[i, j] = M[i, j]
        x[j, 0] = r[j]
        x[j, 1] = 0.0
    x[n1 - 1, 1] = 1.0
    iw[0] = n1
    iw[1] = 2
    iw[2] = 0
    _dgetrf(iw.ctypes, iw.ctypes, lu.ctypes, iw.ctypes, piv.ctypes, iw[2:].ctypes)
    info = iw[2]
    if info != 0:
        return info
    _dgetrs(ch.ctypes, iw.ctypes, iw[1:].ctypes, lu.ctypes, iw.ctypes, piv.ctypes,
            x.ctypes, iw.ctypes, iw[2:].ctypes)  # fmt: skip
    return iw[2]


@_jit
def _eigs(M, n, A, wr, wi, work, iw, ch):  # pragma: no cover - compiled
    """LAPACK ``dgeev`` (no vectors) of ``M[:n, :n]``. Returns info."""
    for j in range(n):
        for i in range(n):
            A[i, j] = M[i, j]
    iw[3] = n
    iw[4] = work.size
    iw[5] = 1
    iw[6] = 0
    _dgeev(ch.ctypes, ch.ctypes, iw[3:].ctypes, A.ctypes, iw[3:].ctypes, wr.ctypes,
           wi.ctypes, work.ctypes, iw[5:].ctypes, work.ctypes, iw[5:].ctypes,
           work.ctypes, iw[4:].ctypes, iw[6:].ctypes)  # fmt: skip
    return iw[6]


@_jit
def _views(fb, ib):  # pragma: no cover - compiled
    """The kernel's buffers as views of its two packed arrays.

    One argument each: a compiled call pays for every argument it unboxes. Layout:
    :class:`StepKernel`.
    """
    n, m, nnz, k, nw, lwork = ib[0], ib[1], ib[2], ib[3], ib[4], ib[5]
    n1 = n + 1
    o = 8
    tp_op = ib[o : o + k]
    tp_ia = ib[o + k : o + 2 * k]
    tp_ib = ib[o + 2 * k : o + 3 * k]
    tp_io = ib[o + 3 * k : o + 4 * k]
    o += 4 * k
    rows = ib[o : o + nnz]
    cols = ib[o + nnz : o + 2 * nnz]
    o += 2 * nnz
    piv = ib[o : o + n1]
    iw = ib[o + n1 : o + n1 + 8]
    ch = ib[o + n1 + 8 : o + n1 + 9]  # the character 'N' (first byte of an int32)
    o = 0
    w = fb[o : o + nw]
    o += nw
    p = fb[o : o + m]
    o += m
    f = fb[o : o + n]
    o += n
    nz = fb[o : o + nnz]
    o += nnz
    M = fb[o : o + n1 * n1].reshape((n1, n1)).T
    o += n1 * n1
    r = fb[o : o + n1]
    o += n1
    lu = fb[o : o + n1 * n1].reshape((n1, n1)).T
    o += n1 * n1
    x = fb[o : o + 2 * n1].reshape((2, n1)).T
    o += 2 * n1
    A = fb[o : o + n * n].reshape((n, n)).T
    o += n * n
    wr = fb[o : o + n]
    wi = fb[o + n : o + 2 * n]
    o += 2 * n
    work = fb[o : o + lwork]
    o += lwork
    tp_c = fb[o : o + k]
    return (tp_op, tp_ia, tp_ib, tp_io, tp_c, w, p, f, nz, rows, cols, M, r, lu, x, piv,
            A, wr, wi, work, iw, ch)  # fmt: skip


@_jit
def _step(fb, ib, out, piv_out, ua, tau, wt, prev_d, prev_tau, sc, hermite, guarded,
          want_eig):  # fmt: skip  # pragma: no cover - compiled
    """One pseudo-arclength step, compiled.

    ``PALC.step`` with ``correct(..., exact=False)`` and ``make_point``.

    ``sc = (ds, prev_h, cos_hermite, max_contraction, max_distance, cos_max, tol,
    step_tol, max_iter, eig_tol, imag_tol, NOISE_SLACK, ROUNDOFF_FLOOR)``. On
    acceptance the point is written into ``out`` (layout :func:`out_layout`) and
    ``piv_out`` (0-based pivots).
    Returns ``(code, iters, rn, gn, jac_finite, ctau, det_sign, eig_ok, n_real,
    n_pairs)``; ``code`` 0: the step is accepted with these values; 1: anything
    else (a rejection or a rare case: the caller runs the Python step instead,
    which is authoritative).
    """
    (tp_op, tp_ia, tp_ib, tp_io, tp_c, w, p, f, nz, rows, cols, M, r, lu, x, piv,
     A, wr, wi, work, iw, ch) = _views(fb, ib)  # fmt: skip
    n1 = ua.size
    n = n1 - 1
    ds, prev_h, cos_hermite, max_contraction = sc[0], sc[1], sc[2], sc[3]
    max_distance, cos_max, tol, step_tol = sc[4], sc[5], sc[6], sc[7]
    max_iter, eig_tol, imag_tol = int(sc[8]), sc[9], sc[10]
    noise_slack, roundoff = sc[11], sc[12]
    fail = (1, 0, 0.0, 0.0, False, 0.0, 0.0, False, 0, 0)
    o_eig, o_u, o_d, o_g, o_gz, o_gp, o_lu, o_t, o_tau, o_c = out_offsets(n)
    # predictor
    c = out[o_c : o_c + n1]
    u = out[o_u : o_u + n1]
    d = out[o_d : o_d + n1]  # (first the tangent prediction u_lin, then u - u_lin)
    for i in range(n1):
        c[i] = wt[i] * tau[i]
        d[i] = ua[i] + ds * tau[i]
        u[i] = d[i]
    if hermite:
        ctp = 0.0
        for i in range(n1):
            ctp += c[i] * prev_tau[i]
        if ctp >= cos_hermite:
            h = prev_h
            rr_ = ds / h
            al = rr_ * rr_ * (3.0 + 2.0 * rr_)
            be = rr_ * rr_ * (h + ds)
            for i in range(n1):
                u[i] = d[i] - al * prev_d[i] + (be - al * h) * (prev_tau[i] - tau[i])
    hlev = 0.0
    for i in range(n1):
        hlev += c[i] * ua[i]
    hlev += ds
    # the componentwise step scale max(|u_pred,i|, |u_ref,i|) + a (corrector._step_ok)
    su = np.empty(n1)
    ur = 0.0
    for i in range(n1):
        su[i] = max(abs(u[i]), abs(ua[i]))
        ur = max(ur, abs(ua[i]))
    # corrector (Newton on the bordered system, the rules of _correct_fused)
    rn, rr, un, gn, mm = _linearise(tp_op, tp_ia, tp_ib, tp_io, tp_c, w, u, p, f, nz,
                                     rows, cols, c, hlev, M, r)  # fmt: skip
    finite = rr < math.inf
    rn0 = rn
    rn_prev = math.inf
    step = math.inf
    it = 0
    a = min(1.0, un) + 1e-300
    lo = step_tol * a
    hi = step_tol * (max(un, ur) + a)
    step_ok = False  # the last step passed the step test
    mc = max_contraction if guarded else -1.0
    dn = 0.0
    dn_ok = False
    while True:
        if not finite:
            return fail
        if _factor_solve(M, r, lu, x, piv, iw, ch) != 0:
            return fail
        dd = 0.0
        dn = 0.0
        ratio = 0.0  # max_i |du_i| / (su_i + a)
        for i in range(n1):
            v = x[i, 0]
            dd += v * v
            v = abs(v)
            if v > dn:
                dn = v
            q = v / (su[i] + a)
            if q > ratio:
                ratio = q
        if not dd < math.inf:
            return fail
        dn_ok = dn <= lo or (dn <= hi and ratio <= step_tol)
        if (
            (rn <= tol and (dn_ok or step_ok))
            or (
                it > 0
                and rn <= tol
                and rn > 0.5 * rn_prev
                and dn > 0.5 * step
                and dn <= noise_slack * hi
                and ratio <= noise_slack * step_tol
            )
            or (step_ok and rn > 0.5 * rn_prev and _backward_error(M, r, u) <= roundoff)
            or (it > 0 and dn_ok and 10.0 * rn * dn * dn <= tol * step * step)
        ):
            break
        if it >= max_iter:
            return fail
        if it >= 2 and rn > 1e4 * max(rn0, tol):
            return fail
        for i in range(n1):
            u[i] -= x[i, 0]
        it += 1
        step_prev = step
        step = dn
        step_ok = dn_ok
        if mc >= 0.0 and it >= 2 and step > mc * step_prev and not step_ok and rn > tol:
            return fail
        rn_prev = rn
        rn, rr, un, gn, mm = _linearise(tp_op, tp_ia, tp_ib, tp_io, tp_c, w, u, p, f, nz,
                                         rows, cols, c, hlev, M, r)  # fmt: skip
        finite = rr < math.inf
    # accepted by the corrector: lin is of the last evaluation, the factorisation too
    if dn_ok:
        for i in range(n1):
            u[i] -= x[i, 0]
    dist = 0.0
    for i in range(n1):
        v = u[i] - d[i]
        d[i] = v
        dist += wt[i] * v * v
    if guarded and math.sqrt(dist) > max_distance * ds:
        return fail
    # tangent from the same factorisation (make_point with lu and t_raw)
    t_raw = out[o_t : o_t + n1]
    nrm2 = 0.0
    for i in range(n1):
        v = x[i, 1]
        t_raw[i] = v
        nrm2 += wt[i] * v * v
    if not (0.0 < nrm2 < math.inf):
        return fail
    scale = 1.0 / math.sqrt(nrm2)
    tau_b = out[o_tau : o_tau + n1]
    ctau = 0.0
    for i in range(n1):
        tau_b[i] = t_raw[i] * scale
        ctau += c[i] * tau_b[i]
    if ctau < 0.0:
        for i in range(n1):
            tau_b[i] = -tau_b[i]
        ctau = -ctau
    if ctau == 0.0:
        return fail
    if ctau < cos_max and guarded:
        return fail
    # G, Gz (Fortran order), Gp of the last evaluation; the factors; sign of det M
    for i in range(n):
        out[o_g + i] = f[i]
        out[o_gp + i] = M[i, n]
    for j in range(n):
        for i in range(n):
            out[o_gz + i + j * n] = M[i, j]
    neg = 0
    for j in range(n1):
        for i in range(n1):
            out[o_lu + i + j * n1] = lu[i, j]
        piv_out[j] = piv[j] - 1
        if piv_out[j] != j:
            neg += 1
        if lu[j, j] < 0.0:
            neg += 1
    det_sign = -1.0 if neg % 2 else 1.0
    # eigenvalues of G_z, sorted by decreasing real, then imaginary part, and counts
    jac_finite = mm < math.inf
    eig_ok = False
    n_real = 0
    n_pairs = 0
    if want_eig and jac_finite and _eigs(M, n, A, wr, wi, work, iw, ch) == 0:
        eig_ok = True
        order = np.empty(n, dtype=np.int64)
        for i in range(n):  # insertion sort on (-re, -im); n is small
            j = i
            while j > 0 and (
                wr[order[j - 1]] < wr[i] or (wr[order[j - 1]] == wr[i] and wi[order[j - 1]] < wi[i])
            ):
                order[j] = order[j - 1]
                j -= 1
            order[j] = i
        for i in range(n):
            k = order[i]
            re = wr[k]
            im = wi[k]
            out[o_eig + 2 * i] = re
            out[o_eig + 2 * i + 1] = im
            if re > eig_tol:
                if abs(im) > imag_tol * max(1.0, math.hypot(re, im)):
                    if im > 0.0:
                        n_pairs += 1
                else:
                    n_real += 1
    return (0, it, rn, gn, jac_finite, ctau, det_sign, eig_ok, n_real, n_pairs)


# ----------------------------------------------------------------------------- Python side
class StepKernel:
    """The compiled pseudo-arclength step of one dense problem (its buffers and tape).

    Parameters
    ----------
    tape : Tape
        Of :func:`linearisation_tape`.
    rows, cols : ndarray (nnz,) int64
        Positions of the tape's non-zeros in ``[G_z G_p]``.
    n : int
        Number of unknowns.
    params : ndarray, shape (m,)
        All parameter values (the free one is read from ``u``).
    """

    __slots__ = ("tape", "rows", "cols", "n", "p", "_fb", "_ib", "size", "offsets")

    def __init__(self, tape: Tape, rows: Any, cols: Any, n: int, params: Any) -> None:
        self.tape, self.rows, self.cols, self.n = tape, rows, cols, n
        self.size = out_layout(n)
        self.offsets = _offsets(n)
        self.p = np.array(np.asarray(params, dtype=float).reshape(-1), dtype=float)
        n1 = n + 1
        k, nnz, m = int(tape.op.size), int(rows.size), int(self.p.size)
        nw, lwork = max(tape.n_work, 1), max(34 * n, 1)  # dgeev: lwork >= 3n
        ints = [np.array([n, m, nnz, k, nw, lwork, 0, 0], dtype=np.int32),
                tape.op, tape.ia, tape.ib, tape.io, rows.astype(np.int32),
                cols.astype(np.int32), np.zeros(n1 + 8, dtype=np.int32),
                np.array([ord("N")], dtype=np.int32)]  # fmt: skip
        self._ib = np.concatenate(ints).astype(np.int32)
        # floats: w, p, f, nz, M, r, lu, x, A, wr, wi, work, consts (see _views)
        sizes = (nw, m, n, nnz, n1 * n1, n1, n1 * n1, 2 * n1, n * n, n, n, lwork, k)
        self._fb = np.zeros(sum(sizes))
        self._fb[nw : nw + m] = self.p
        self._fb[sum(sizes[:-1]) :] = tape.consts

    def step(self, ua: Any, tau: Any, w: Any, prev_d: Any, prev_tau: Any, sc: Any,
             hermite: bool, guarded: bool, want_eig: bool) -> tuple[Any, ...] | None:  # fmt: skip
        """One step from the point ``ua`` with tangent ``tau``.

        Parameters
        ----------
        ua, tau, w : ndarray, shape (n + 1,)
            Last point, its tangent, the ``theta`` weights.
        prev_d, prev_tau : ndarray, shape (n + 1,), or None
            For the Hermite predictor (ignored unless ``hermite``).
        sc : ndarray, shape (13,)
            ``(ds, prev_h, cos_hermite, max_contraction, max_distance, cos_max, tol,
            step_tol, max_iter, eig_tol, imag_tol, NOISE_SLACK, ROUNDOFF_FLOOR)``
            (the last two: :mod:`continuation.algorithms.corrector`).
        hermite, guarded, want_eig : bool
            Try the Hermite predictor; apply the step safeguards; compute eigenvalues.

        Returns
        -------
        tuple or None
            None when the kernel did not accept the step; else ``(point, iters, rn,
            d)``: the new :class:`KernelPoint`, the corrector iterations, the final
            bordered residual ``max |r|`` and ``d = u - (u_a + ds tau)`` (the corrector's
            move from the tangent prediction, for the next Hermite predictor).
        """
        n1 = self.n + 1
        if not hermite:
            prev_d = prev_tau = ua
        out = np.empty(self.size)
        piv = np.empty(n1, dtype=np.int32)
        code, it, rn, gn, jac_finite, ctau, det_sign, eig_ok, n_real, n_pairs = _step(
            self._fb, self._ib, out, piv, ua, tau, w, prev_d, prev_tau, sc, hermite, guarded,
            want_eig,
        )  # fmt: skip
        if code != 0:
            return None
        o = self.offsets
        cache: dict[str, Any] = {"jac_finite": True} if jac_finite else {}
        if eig_ok:
            cache["eig"] = out[o[0] : o[1]].view(np.complex128)
            cache["counts"] = (n_real, n_pairs)
        return KernelPoint(self, out, piv, it, gn, ctau, det_sign, cache), it, rn, out[o[2] : o[3]]


def _lazy(name: str, make: Any) -> property:
    """A property over ``PointInfo``'s slot ``name``, filled with ``make(self)`` on first read.

    It is written as the slot.
    """
    slot = getattr(PointInfo, name)

    def get(self: Any) -> Any:
        try:
            return slot.__get__(self, type(self))
        except AttributeError:
            value = make(self)
            slot.__set__(self, value)
            return value

    def put(self: Any, value: Any) -> None:
        slot.__set__(self, value)

    return property(get, put, doc=f"``{name}`` (made from the step's buffer on first use)")


def _lu_of(pt: KernelPoint) -> BorderedLU:
    n1 = pt._k.n + 1
    o = pt._k.offsets
    lu = BorderedLU.from_dense_factors(pt._out[o[6] : o[7]].reshape((n1, n1), order="F"), pt._piv)
    # (ctau > 0: det [Gz Gp; (w o tau)^T] has the sign of det M; 2.0: not computed yet)
    lu._sign = 2.0 if pt._bp_sign is None else pt._bp_sign
    return lu


class KernelPoint(PointInfo):
    """A :class:`~continuation.algorithms.point.PointInfo` of the compiled step.

    The fields the continuation needs at every row (``z``, ``p``, ``u``, ``tau``,
    ``border``, ``ctau``, the sign of the branch-point test, eigenvalues and counts in
    ``cache``) are set at once; ``G``, ``Gz``, ``Gp``, ``lu`` and ``t_raw``, needed only
    where a special point is located, are views of the step's output buffer made on
    first use (layout :func:`out_layout`).
    """

    __slots__ = ("_k", "_out", "_piv")

    def __init__(self, k: StepKernel, out: Any, piv: Any, iters: int, gn: float, ctau: float,
                 det_sign: float, cache: dict[str, Any]) -> None:  # fmt: skip
        o = k.offsets
        u = out[o[1] : o[2]]
        self._k, self._out, self._piv = k, out, piv
        self.z = u[:-1]
        self.p = float(u[-1])
        self._u = u
        self.tau = out[o[8] : o[9]]
        self.border = out[o[9] :]
        self.ctau = ctau
        self.iters = iters
        self.residual_norm = gn
        self.cache = cache
        self._bp_sign = det_sign
        self._bp_logdet = None

    G = _lazy("G", lambda pt: pt._out[pt._k.offsets[3] : pt._k.offsets[4]])
    Gz = _lazy(
        "Gz",
        lambda pt: pt._out[pt._k.offsets[4] : pt._k.offsets[5]].reshape(
            (pt._k.n, pt._k.n), order="F"
        ),
    )
    Gp = _lazy("Gp", lambda pt: pt._out[pt._k.offsets[5] : pt._k.offsets[6]])
    lu = _lazy("lu", _lu_of)
    t_raw = _lazy("t_raw", lambda pt: pt._out[pt._k.offsets[7] : pt._k.offsets[8]])


__all__ = ["StepKernel", "out_layout"]
