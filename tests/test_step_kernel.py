"""The compiled pseudo-arclength step (continuation._kernel, continuation._tape).

References: the Python step (PALC(kernel=False)) of the same problem, row by row (the
kernel runs the same iteration with the same LAPACK routines, so rows agree to
round-off), and CasADi's own evaluation of every operation the tape interpreter runs.
"""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from helpers import bratu, brusselator, hopf_normal_form, lorenz84, periodic_sine

import continuation._kernel as K
import continuation._tape as T
from continuation.algorithms.corrector import NOISE_SLACK, ROUNDOFF_FLOOR
from continuation.algorithms.palc import PALC
from continuation.api import continue_equilibria
from continuation.problem import EquilibriumProblem
from continuation.settings import ContinuationSettings
from continuation.system import System


# ----------------------------------------------------------------------------- tape
def _all_ops_function() -> ca.Function:
    u = ca.SX.sym("u", 3)
    p = ca.SX.sym("p", 2)
    x, y, z = u[0], u[1], u[2]
    a = 0.3 * x + 0.1  # in (-1, 1) for the inverse trigonometric functions
    exprs = [
        x + y, x - y, x * y, x / y, -x, x**2, 2 * x, 1 / y, ca.sqrt(y), ca.exp(x),
        ca.log(y), y**x, x**2.5 if False else y**2.5, ca.sin(x), ca.cos(x), ca.tan(x),
        ca.asin(a), ca.acos(a), ca.atan(x), ca.sinh(x), ca.cosh(x), ca.tanh(x),
        ca.asinh(x), ca.acosh(1 + y), ca.atanh(a), ca.fabs(z), ca.sign(z), ca.sign(0 * z),
        ca.fmin(x, y), ca.fmax(x, y), ca.atan2(x, y), ca.hypot(x, y), ca.copysign(x, z),
        x < y, x <= y, x == y, x != y, ca.logic_not(x < y), ca.logic_and(x < y, y > 0),
        ca.logic_or(x > y, z > 0), ca.if_else(x < y, x, y), ca.floor(3 * x), ca.ceil(3 * x),
        ca.fmod(7 * y, 0.3 + p[0]), ca.erf(x), ca.log1p(y), ca.expm1(x), p[0] * x + p[1],
        ca.sqrt(-y), ca.log(-y), 1 / (0 * x), ca.fmax(ca.sqrt(-y), x),
    ]  # fmt: skip
    f = ca.vertcat(*exprs)
    nz = ca.vertcat(x * p[1], ca.sin(y) * z)
    return ca.Function("ops", [u, p], [f, nz])


@pytest.mark.parametrize("point", [(0.7, 1.3, -0.4), (-1.2, 0.4, 2.5), (0.2, 0.2, 0.0)])
def test_tape_interpreter_matches_casadi_on_every_operation(point):
    fn = _all_ops_function()
    tape = T.tape_of(fn)
    assert tape is not None
    u, p = np.array(point), np.array([0.25, -0.5])
    want_f = np.asarray(fn(u, p)[0]).ravel()
    want_nz = np.asarray(fn(u, p)[1]).ravel()
    f, nz = np.zeros(want_f.size), np.zeros(want_nz.size)
    K._run_tape(tape.op, tape.ia, tape.ib, tape.io, tape.consts, np.zeros(tape.n_work), u, p,
                f, nz)  # fmt: skip
    np.testing.assert_array_equal(np.isnan(f), np.isnan(want_f))
    np.testing.assert_allclose(f, want_f, rtol=1e-14, atol=1e-300, equal_nan=True)
    np.testing.assert_allclose(nz, want_nz, rtol=1e-14)


def test_unsupported_operation_gives_no_tape():
    u = ca.SX.sym("u", 1)
    fn = ca.Function("f", [u, ca.SX.sym("p", 1)], [ca.erfinv(0.5 * u), u])
    assert T.tape_of(fn) is None


def test_linearisation_tape_values_and_pattern():
    """f and the non-zeros of [G_z G_p] from the tape equal System.f, .jacobian and
    .dfdp (Brusselator at a generic point)."""
    s = brusselator()
    k = 1  # free parameter B
    tape, rows, cols = T.linearisation_tape(s, k)
    x, pv = np.array([1.1, 2.7]), np.array([1.5, 3.1])
    u = np.r_[x, pv[k]]
    f, nz = np.zeros(2), np.zeros(rows.size)
    K._run_tape(
        tape.op,
        tape.ia,
        tape.ib,
        tape.io,
        tape.consts,
        np.zeros(tape.n_work),
        u,
        np.array([1.5, -99.0]),
        f,
        nz,
    )  # fmt: skip  (p[k] is read from u)
    top = np.zeros((2, 3))
    top[rows, cols] = nz
    np.testing.assert_allclose(f, s.f(x, pv), rtol=1e-15)
    np.testing.assert_allclose(top[:, :2], s.jacobian(x, pv), rtol=1e-15)
    np.testing.assert_allclose(top[:, 2], np.asarray(s.dfdp(x, pv))[:, k], rtol=1e-15)


# ----------------------------------------------------------------------------- steps
def _cubic8() -> tuple[System, np.ndarray, dict[str, float]]:
    def rhs(x, p, ops):
        out = [p[0] - x[0] ** 3 + 3.0 * x[0]]
        out += [-float(k) * x[k] + p[1] * ops.tanh(x[k - 1]) for k in range(1, 8)]
        return ops.stack(out)

    s = System(rhs, tuple(f"x{k}" for k in range(8)), ("p", "c"))
    x = np.zeros(8)
    x[0] = -2.195823345445647  # the real root of x^3 - 3x + 4 = 0 (p = -4)
    for k in range(1, 8):
        x[k] = 0.2 * np.tanh(x[k - 1]) / k
    return s, x, {"p": -4.0, "c": 0.2}


def _cases():
    s8, x8, p8 = _cubic8()
    return {
        "cubic8 (2 folds)": (s8, x8, p8, "p", dict(p_min=-4.5, p_max=4.0, ds_max=0.1)),
        "brusselator (Hopf)": (brusselator(), [1.5, 1.0 / 1.5], {"A": 1.5, "B": 1.0}, "B",
                               dict(p_min=1.0, p_max=4.0)),
        "bratu N=20 (fold, BP)": (bratu(20), np.zeros(20), {"lam": 0.0}, "lam",
                                  dict(p_min=0.0, p_max=4.0, ds_max=0.5, max_steps=60)),
        "hopf normal form": (hopf_normal_form(), [0.0, 0.0], {"mu": -1.0}, "mu",
                             dict(p_min=-1.0, p_max=1.0)),
        "lorenz84 (folds, Hopf)": (lorenz84(), [0.0, 1.0, 0.0],
                                   {"a": 0.25, "b": 4.0, "G": 1.0, "F": 0.0}, "F",
                                   dict(p_min=-1.0, p_max=8.0, max_steps=3000)),
        "periodic state (closed loop)": (periodic_sine(), [0.0], {"mu": 0.0}, "mu",
                                         dict(direction="forward", max_steps=2000)),
        "large steps (rejections)": (s8, x8, p8, "p", dict(p_min=-4.5, p_max=4.0, ds=0.5,
                                                           ds_max=2.0)),
    }  # fmt: skip


@pytest.mark.parametrize("name", list(_cases()))
def test_kernel_rows_equal_python_rows(name, monkeypatch):
    """Every row, eigenvalue, count and special point of PALC(kernel=True) equals the
    Python step's, and the kernel accepted most steps itself."""
    s, x0, params, free, kw = _cases()[name]
    used = []
    orig = PALC._kernel_step

    def counting(self, *a, **k):
        out = orig(self, *a, **k)
        used.append(out is not None)
        return out

    monkeypatch.setattr(PALC, "_kernel_step", counting)
    fast = continue_equilibria(s, x0, params, free, algorithm=PALC(kernel=True), **kw)
    assert used and sum(used) >= 0.5 * len(used)
    n_kernel = len(used)
    slow = continue_equilibria(s, x0, params, free, algorithm=PALC(kernel=False), **kw)
    assert len(used) == n_kernel  # the Python step never calls the kernel
    assert fast.status is slow.status
    assert fast.x.shape == slow.x.shape
    scale = 1.0 + np.abs(slow.x).max()
    np.testing.assert_allclose(fast.x, slow.x, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(fast.p, slow.p, rtol=0, atol=1e-12 * (1 + np.abs(slow.p).max()))
    np.testing.assert_allclose(fast.eigenvalues, slow.eigenvalues, rtol=1e-10, atol=1e-10)
    np.testing.assert_array_equal(fast.n_unstable, slow.n_unstable)
    np.testing.assert_array_equal(fast.newton_iters, slow.newton_iters)
    assert [q.kind for q in fast.special_points] == [q.kind for q in slow.special_points]
    assert [q.located for q in fast.special_points] == [q.located for q in slow.special_points]
    np.testing.assert_allclose([q.p for q in fast.special_points],
                               [q.p for q in slow.special_points], atol=1e-10)  # fmt: skip
    if "rejections" in name:
        assert not all(used)  # some steps were redone by the Python step


def test_cubic8_folds_exact_with_kernel():
    """The folds of cubic8 are at p = +-2 exactly (x0 = -+1)."""
    s, x0, params = _cubic8()
    br = continue_equilibria(s, x0, params, "p", p_min=-4.5, p_max=4.0, ds_max=0.1)
    folds = sorted(q.p for q in br.find("fold") if q.located)
    np.testing.assert_allclose(folds, [-2.0, 2.0], atol=1e-12)
    assert br.problem.step_kernel() is not None


def test_when_there_is_no_kernel(monkeypatch):
    """No kernel for sparse problems, NumPy-only systems, large systems or long tapes;
    those runs (and ``PALC(kernel=False)``) take the Python step."""
    assert EquilibriumProblem(bratu(120), {"lam": 0.0}, "lam").step_kernel() is None  # sparse
    numpy_only = System(lambda x, p: np.array([p[0] - x[0] ** 2]), ("x",), ("mu",))
    assert EquilibriumProblem(numpy_only, {"mu": 1.0}, "mu").step_kernel() is None
    big = bratu(40)  # dense (n < 100) but n + 1 > MAX_KERNEL_SIZE
    assert EquilibriumProblem(big, {"lam": 0.0}, "lam", sparse=False).step_kernel() is None
    monkeypatch.setattr(T, "MAX_TAPE_INSTRUCTIONS", 10)
    assert EquilibriumProblem(brusselator(), {"A": 1.5, "B": 1.0}, "B").step_kernel() is None
    monkeypatch.setattr(T, "MAX_TAPE_INSTRUCTIONS", 2000)
    br = continue_equilibria(hopf_normal_form(), [0.0, 0.0], {"mu": -1.0}, "mu", p_min=-1,
                             p_max=1, algorithm=PALC(kernel=False))  # fmt: skip
    (h,) = br.find("hopf")
    assert h.located and abs(h.p) < 1e-10


def test_kernel_argument_validated():
    with pytest.raises(ValueError, match="`kernel`"):
        PALC(kernel="yes")


def test_kernel_safeguards_reject_and_leave_the_step_to_python():
    """The compiled step applies PALC's safeguards: with max_distance or the tangent
    angle made impossible to meet (or Newton allowed no iteration) it accepts nothing
    (returns None, so the Python step decides); unguarded (ds at ds_min) the distance
    and angle tests are waived, as in the Python step."""
    s, x0, params = _cubic8()
    prob = EquilibriumProblem(s, params, "p")
    kern = prob.step_kernel()
    n = s.n_states
    w = np.full(n + 1, 0.5 / n)
    w[-1] = 0.5
    ua = np.r_[x0, params["p"]]
    lin = prob.linearize(x0, params["p"])
    t = np.linalg.solve(np.vstack([np.c_[lin[1], lin[2]], np.eye(n + 1)[-1]]), np.eye(n + 1)[-1])
    tau = t / np.sqrt((w * t) @ t)

    def sc(max_distance=1.0, cos_max=0.5, max_iter=10):
        return np.array([0.05, 1.0, 0.86, 0.8, max_distance, cos_max, 1e-10, 1e-10, max_iter,
                         1e-10, 1e-8, NOISE_SLACK, ROUNDOFF_FLOOR])  # fmt: skip

    ok = kern.step(ua, tau, w, None, None, sc(), False, True, True)
    assert ok is not None
    pt = ok[0]
    np.testing.assert_allclose(prob.residual(pt.z, pt.p), 0.0, atol=1e-10)
    assert kern.step(ua, tau, w, None, None, sc(max_distance=1e-12), False, True, True) is None
    assert kern.step(ua, tau, w, None, None, sc(cos_max=1.0), False, True, True) is None
    assert kern.step(ua, tau, w, None, None, sc(max_iter=0), False, True, True) is None
    assert kern.step(ua, tau, w, None, None, sc(max_distance=1e-12), False, False, True)


def test_kernel_point_fields_equal_the_python_step():
    """One step from the same state by the compiled and the Python step: the point and
    the lazily made fields (G, Gz, Gp of the last corrector iterate, the factors, the
    raw tangent, the branch-point sign, eigenvalues) agree to round-off."""
    s, x0, params = _cubic8()
    prob = EquilibriumProblem(s, params, "p")
    st = ContinuationSettings(ds=0.05, ds_max=0.1, p_min=-4.5, p_max=4.0)
    fast, slow = PALC(kernel=True), PALC(kernel=False)
    state = slow.init(prob, x0, params["p"], st)
    a, _ = fast.step(prob, state, st)
    b, _ = slow.step(prob, state, st)
    pa, pb = a.point, b.point
    assert type(pa).__name__ == "KernelPoint" and type(pb).__name__ == "PointInfo"
    for name in ("u", "tau", "border", "G", "Gz", "Gp", "t_raw"):
        np.testing.assert_allclose(getattr(pa, name), getattr(pb, name), rtol=1e-12,
                                   atol=1e-14, err_msg=name)  # fmt: skip
    assert pa.p == pytest.approx(pb.p, abs=1e-14) and pa.ctau == pytest.approx(pb.ctau)
    assert pa.bp_sign == pb.bp_sign and pa.lu.sign == pb.lu.sign
    assert pa.bp_logdet == pytest.approx(pb.bp_logdet, rel=1e-12)
    e = np.eye(s.n_states + 1)[-1]
    np.testing.assert_allclose(pa.lu.solve(e), pb.lu.solve(e), rtol=1e-12)
    np.testing.assert_allclose(pa.cache["eig"], np.sort_complex(np.linalg.eigvals(pb.Gz))[::-1],
                               rtol=1e-10, atol=1e-12)  # fmt: skip
    np.testing.assert_allclose(a.prev_d, b.prev_d, atol=1e-14)
