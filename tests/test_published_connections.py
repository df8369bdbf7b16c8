"""Connecting orbits at the default settings on published problems not used elsewhere.

Run as a researcher would: :func:`~continuation.bvp.find_connection` from the saddle
alone (or :func:`~continuation.bvp.solve_connection` from a rough guess), default
:class:`~continuation.bvp.ConnectionAccuracy`, then
:func:`~continuation.bvp.continue_connection` in a second parameter. A ``SUCCESS`` is a
claim: its value must be within its own error estimate of the reference, and that
estimate small enough to be useful (below the default tolerance ``atol + rtol |p|``).

* Chua's circuit with the smooth nonlinearity ``|x| ~ (2 x / pi) arctan(K x)``, ``K =
  10`` (Khibnik, Roose & Chua 1993, "On periodic orbits and homoclinic bifurcations in
  Chua's circuit with a smooth nonlinearity", IJBC 3:363-384; equations of AUTO-07p's
  ``demos/chu/chu.f90``): the Shilnikov homoclinic orbit of the saddle-focus origin
  (``lambda_u = 2.83 > -Re lambda_s = 1.12``), ``alpha* = 11.07840157874`` at ``beta =
  14.3``, and its curve in ``beta``. Reference: the side on which the 1-D unstable
  manifold is ejected after its return changes sign at the connection (SciPy DOP853,
  ``rtol = 1e-12``, Brent to 1e-13; :func:`_chua_alpha`), independent of collocation.
* The electronic circuit of Freire, Rodriguez-Luis, Gamero & Ponce (1993), "A case
  study for homoclinic chaos in an autonomous electronic circuit", Physica D
  62:230-253 (AUTO-07p ``demos/tor/tor.f90``, ``beta = 0.5``, ``gamma = -0.6``, ``r =
  0.6``, ``a3 = 0.328578``, ``b3 = 0.933578``): the homoclinic orbit of the
  saddle-focus ``E = (x, 0, beta x + b3 x^3)``, ``x^2 = -(beta + nu) / (a3 + b3)``,
  whose unstable manifold is 2-D (eigenvalues 0.25 +- 0.63 i, -1.6): found in
  reversed time, ``nu* = -0.72894100482`` (the 1-D stable manifold's side changes sign,
  :func:`_tor_nu`; the same value is the period limit of the cycles in
  ``tests/test_published_cycles.py``).
* The reversible fourth-order equation of AUTO-07p's HomCont demo ``rev``
  (``demos/rev/rev.f90``; Champneys & Spence 1993, "Hunting for homoclinic orbits in
  reversible systems: a shooting technique", Adv. Comput. Math. 1:81-108):
  ``u'''' + P u'' + u - u^3 = 0``. Its homoclinic orbits of the origin persist in
  ``P`` (a Hamiltonian, reversible family), so a dissipative term ``eps u'`` is added
  and solved for: ``dH/dt = -eps u'^2`` for the energy ``H = u' u''' - u''^2 / 2 + P
  u'^2 / 2 + u^2 / 2 - u^4 / 4``, so a homoclinic orbit has ``eps = 0`` exactly, for
  every ``P``. At ``P = -5/2`` the orbit is in closed form (derived here: insert ``A
  sech^2(k t)``; the ``sech^2, sech^4, sech^6`` terms give ``16 k^4 + 4 P k^2 + 1 = 0``,
  ``P = -20 k^2``, ``A^2 = 120 k^4``): ``u = sqrt(15/8) sech^2(t / (2 sqrt 2))``.
  Continued to the demo's ``P = 1.6``, where the origin is a saddle-focus.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import chua_rhs
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

from continuation import ContinuationSettings, Status, System
from continuation.bvp import (
    HeteroclinicProblem,
    connection_at,
    continue_connection,
    find_connection,
    solve_connection,
)

#: ConnectionAccuracy's default tolerances (rtol, atol): a useful estimate is below them.
RTOL, ATOL = 1e-6, 1e-8


def _useful(res, name):
    """The estimate is finite, positive and within the default tolerance."""
    e = res.error(name)
    return 0.0 < e <= ATOL + RTOL * abs(res.value(name))


def _sphere(center, r, direction):
    e = lambda t, x: float((x - center) @ (x - center)) - r * r  # noqa: E731
    e.terminal, e.direction = True, direction
    return e


def _ejection_side(f, x_start, center, w, steps, t_max=200.0):
    """``w . (x - center)`` where the orbit of ``f`` from ``x_start`` leaves the last
    sphere about ``center`` of ``steps``, a sequence of ``(radius, direction)``: it
    crosses each sphere in turn, inwards (-1) or outwards (+1)."""
    x = x_start
    for r, d in steps:
        sol = solve_ivp(lambda t, y: f(y), (0, t_max), x, rtol=1e-12, atol=1e-16,
                        method="DOP853", events=_sphere(center, r, d))  # fmt: skip
        x = center + (sol.y_events[0][0] - center) * (1 + 1e-12 * d)
    return float(w @ (x - center))


def _eigen_pair(J, pick):
    """The real eigenvector and left eigenvector of the eigenvalue chosen by ``pick``
    (argmax/argmin of the real part), signed so that ``w . v > 0``."""
    lam, V = np.linalg.eig(J)
    laml, W = np.linalg.eig(J.T)
    v = V[:, int(pick(lam.real))].real
    w = W[:, int(pick(laml.real))].real
    return v, w * np.sign(w @ v)


# ------------------------------------------------------------------ Chua (smooth)
CHUA = {"alpha": 11.0, "beta": 14.3, "K": 10.0, "a0": -1.0 / 7.0, "a1": 2.0 / 7.0}


def _chua_np(al, be):
    K, a0, a1 = CHUA["K"], CHUA["a0"], CHUA["a1"]

    def h(u, d=False):
        if d:
            g = lambda s: 2 / math.pi * (np.arctan(K * s) + K * s / (1 + (K * s) ** 2))  # noqa: E731
            return a1 + 0.5 * (a0 - a1) * (g(u + 1) - g(u - 1))
        g = lambda s: 2 * s * np.arctan(K * s) / math.pi  # noqa: E731
        return a1 * u + 0.5 * (a0 - a1) * (g(u + 1) - g(u - 1))

    f = lambda x: np.array([al * (x[1] - h(x[0])), x[0] - x[1] + x[2], -be * x[1]])  # noqa: E731
    J = np.array([[-al * h(0.0, True), al, 0.0], [1.0, -1.0, 1.0], [0.0, -be, 0.0]])
    return f, J


def _chua_alpha(be, lo, hi, size=1.0):
    """``alpha`` of the homoclinic orbit of the origin at ``beta`` by Brent on the side
    of the unstable manifold's ejection after its return (spheres of radii 0.5, 0.15 and
    0.4 times ``size``: 1 at ``beta = 14.3`` as in ``tests/test_published_cycles.py``,
    the orbit's largest ``|x|`` elsewhere)."""

    def side(al):
        f, J = _chua_np(al, be)
        v, w = _eigen_pair(J, np.argmax)
        steps = ((0.5 * size, 1), (0.15 * size, -1), (0.4 * size, 1))
        return _ejection_side(f, 1e-9 * v, np.zeros(3), w, steps)

    return brentq(side, lo, hi, xtol=1e-13)


@pytest.fixture(scope="module")
def chua():
    s = System(chua_rhs, ("x", "y", "z"), tuple(CHUA))
    res = find_connection(s, s.params(**CHUA), "alpha", source=[0.0, 0.0, 0.0], shift=0)
    return s, res


def test_chua_shilnikov_homoclinic_from_the_saddle_alone(chua):
    """From ``alpha = 11`` (and 9, 10.5, 12, 20) the connection is found within its estimate
    of ``alpha* = 11.07840157874``; the orbit leaves and returns to the origin and its
    excursion is that of the unstable manifold at ``alpha*`` (first maximum of ``|x|``
    along the manifold, integrated by SciPy: the orbit's error is of the order of the
    parameter's, 1e-7 allowed)."""
    s, res = chua
    ref = _chua_alpha(14.3, 11.07835, 11.07845, 1.0)
    assert ref == pytest.approx(11.07840157874, abs=1e-10)
    for r in (
        res,
        *(
            find_connection(s, s.params(**{**CHUA, "alpha": a}), "alpha", source=[0, 0, 0], shift=0)
            for a in (9.0, 10.5, 20.0)
        ),
        find_connection(
            s, s.params(**{**CHUA, "alpha": 12.0}), "alpha", source=[0, 0, 0], shift=0, branch=-1
        ),  # fmt: skip
    ):
        assert r.status is Status.SUCCESS, r.message
        assert abs(r.value("alpha") - ref) <= r.error("alpha"), (r.value("alpha"), r.errors)
        assert _useful(r, "alpha")
    x = res.x
    assert np.linalg.norm(x[0]) < 1e-3 and np.linalg.norm(x[-1]) < 1e-3
    f, J = _chua_np(ref, 14.3)
    v, _ = _eigen_pair(J, np.argmax)
    v = v * np.sign(v @ x[int(np.argmax(np.linalg.norm(x, axis=1)))])
    sol = solve_ivp(lambda t, y: f(y), (0, 12), 1e-9 * v, rtol=1e-12, atol=1e-16,
                    method="DOP853", dense_output=True)  # fmt: skip
    tt = np.linspace(0, 12, 24001)
    r_sim = np.linalg.norm(sol.sol(tt), axis=0)
    k = int(np.argmax(r_sim > 1.0))
    k += int(np.argmax(np.diff(r_sim[k:]) < 0))  # first maximum after leaving
    x_fine = res.interpolate(np.linspace(0.0, res.T, 20001))
    assert np.max(np.linalg.norm(x_fine, axis=1)) == pytest.approx(r_sim[k], abs=1e-6)


def test_chua_another_homoclinic_orbit_from_further_away(chua):
    """From ``alpha = 8`` the closest approach of the manifold picks another homoclinic
    orbit of the origin, a longer one (``T = 17.5``; it passes 0.69, 0.43 and 0.31 from
    the origin before spiralling in): shooting (ejection side after the manifold has
    gone beyond 1, come within 0.1 and left 0.3) puts it at ``alpha = 10.2692090943``;
    the SUCCESS is within its estimate (about 5e-6, the mesh's) of that, not of the
    primary orbit's 11.078."""
    s, _ = chua
    res = find_connection(s, s.params(**{**CHUA, "alpha": 8.0}), "alpha", source=[0, 0, 0], shift=0)

    def side(al):
        f, J = _chua_np(al, 14.3)
        v, w = _eigen_pair(J, np.argmax)
        return _ejection_side(f, 1e-9 * v, np.zeros(3), w, ((1.0, 1), (0.1, -1), (0.3, 1)))

    ref = brentq(side, 10.2691, 10.2693, xtol=1e-13)
    assert ref == pytest.approx(10.2692090943, abs=1e-9)
    assert res.status is Status.SUCCESS, res.message
    assert abs(res.value("alpha") - ref) <= res.error("alpha"), res.errors
    assert _useful(res, "alpha")


def test_chua_homoclinic_curve_in_beta(chua):
    """Continued in ``beta`` over [13, 16] at default settings: rows agree with the
    shooting reference within the default tolerance ``atol + rtol |alpha|`` (branch
    rows carry no estimate; they stay on the start's adapted mesh and ``T``), and a
    row re-solved by :func:`solve_connection` is within its own estimate."""
    _, res = chua
    br = continue_connection(res, "beta", ContinuationSettings(p_min=13.0, p_max=16.0),
                             direction="both")  # fmt: skip
    assert br.status is Status.PARAM_BOUND, br.message
    assert br.p.min() == pytest.approx(13.0, abs=1e-10)
    assert br.p.max() == pytest.approx(16.0, abs=1e-10)
    assert np.all(np.diff(br.records["alpha"][np.argsort(br.p)]) > 0)
    for j in (int(np.argmin(br.p)), int(np.argmax(br.p))):
        be, al = float(br.p[j]), float(br.records["alpha"][j])
        size = float(np.max(np.linalg.norm(connection_at(br, j).x, axis=1)))
        ref = _chua_alpha(be, al - 0.05, al + 0.05, size)
        assert abs(al - ref) <= ATOL + RTOL * abs(ref), (be, al, ref)
        re = solve_connection(connection_at(br, j).problem, connection_at(br, j))
        assert re.status is Status.SUCCESS, re.message
        assert abs(re.value("alpha") - ref) <= re.error("alpha"), (be, re.errors)
        assert _useful(re, "alpha")


@pytest.mark.parametrize("scale", [1e-6, 1e-4, 1e-3, 1e3, 1e5])
def test_chua_homoclinic_in_other_units(scale):
    """The same circuit with the states in other units, ``X = scale x`` (volts against
    millivolts): the orbit and ``alpha*`` are those of ``scale = 1``. Regressions: the
    Newton tolerance (1e-10, absolute) was below the residual's rounding floor (about
    1e-16 |X| in the collocation rows, 1e-16 |X|^2 in the integral phase row), so at
    ``scale = 1e3`` the halved-mesh re-solve failed (DISCRETISATION_ERROR) and at
    ``1e5`` the solve itself (NEWTON_FAILED); the rows are now weighted by the states'
    magnitude (``continuation.bvp.solve._row_weights``). At ``scale <= 1e-4`` the
    fixed end distance 1e-4 of ``find_connection`` was a third of the orbit or more
    (NEWTON_FAILED, DISCRETISATION_ERROR), at ``1e-3`` it gave an error of 1e-6 (within
    its estimate); the default now shrinks where the flow is not linear at that
    distance or the manifold's excursion is small (``find._linear_distance``)."""

    def rhs(x, p, ops):
        return scale * chua_rhs([x[i] / scale for i in range(3)], p, ops)

    s = System(rhs, ("x", "y", "z"), tuple(CHUA))
    res = find_connection(s, s.params(**CHUA), "alpha", source=[0.0, 0.0, 0.0], shift=0)
    assert res.status is Status.SUCCESS, res.message
    assert abs(res.value("alpha") - 11.078401578740419) <= res.error("alpha")
    assert _useful(res, "alpha")
    assert np.max(np.linalg.norm(res.x, axis=1)) == pytest.approx(3.27 * scale, rel=0.01)


# ------------------------------------------------------------------ tor (Freire et al.)
TOR = {"nu": -0.72, "beta": 0.5, "gamma": -0.6, "r": 0.6, "a3": 0.328578, "b3": 0.933578}


def _tor_system(sign):
    """The tor vector field times ``sign`` (-1: time reversed)."""

    def rhs(x, p, ops):
        nu, be, ga, r, a3, b3 = (p[i] for i in range(6))
        d3 = (x[1] - x[0]) ** 3
        return ops.stack([
            sign * (-(be + nu) * x[0] + be * x[1] - a3 * x[0] ** 3 + b3 * d3) / r,
            sign * (be * x[0] - (be + ga) * x[1] - x[2] - b3 * d3),
            sign * x[1],
        ])  # fmt: skip

    return System(rhs, ("x", "y", "z"), tuple(TOR))


def _tor_E(nu):
    x = math.sqrt(-(TOR["beta"] + nu) / (TOR["a3"] + TOR["b3"]))
    return np.array([x, 0.0, TOR["beta"] * x + TOR["b3"] * x**3])


def _tor_reversed(nu):
    """The reversed flow ``-f`` and its Jacobian ``-Df`` at ``nu`` (NumPy)."""
    be, ga, r, a3, b3 = (TOR[k] for k in ("beta", "gamma", "r", "a3", "b3"))

    def f(x):
        d3 = (x[1] - x[0]) ** 3
        return -np.array([(-(be + nu) * x[0] + be * x[1] - a3 * x[0] ** 3 + b3 * d3) / r,
                          be * x[0] - (be + ga) * x[1] - x[2] - b3 * d3, x[1]])  # fmt: skip

    def jac(x):
        q = 3 * b3 * (x[1] - x[0]) ** 2
        return -np.array([[(-(be + nu) - 3 * a3 * x[0] ** 2 - q) / r, (be + q) / r, 0.0],
                          [be + q, -(be + ga) - q, -1.0], [0.0, 1.0, 0.0]])  # fmt: skip

    return f, jac


def _tor_nu(lo=-0.729, hi=-0.7289, size=1.0):
    """``nu`` of the homoclinic orbit of ``E``: the 1-D stable manifold, integrated
    backward from ``E`` (on the side away from the origin), spirals back into ``E`` and
    is ejected along one side of that manifold or the other; Brent on the side (spheres
    about ``E`` of radii 0.5, 0.11 and 0.3 times ``size``, the orbit's largest distance
    from ``E`` over 0.70 elsewhere than at the demo's parameters)."""

    def side(nu):
        f, jac = _tor_reversed(nu)
        E = _tor_E(nu)
        v, w = _eigen_pair(jac(E), np.argmax)  # the unstable direction of the reversed flow
        v = -v * np.sign(v @ E)
        steps = ((0.5 * size, 1), (0.11 * size, -1), (0.3 * size, 1))
        return _ejection_side(f, E + 1e-9 * v, E, w, steps)

    return brentq(side, lo, hi, xtol=1e-14)


def _tor_heteroclinic_nu(lo, hi):
    """``nu`` of a connection ``E+ -> E-`` (``E- = -E+``; its mirror image ``E- -> E+``
    closes the heteroclinic cycle): the 1-D stable manifold of ``E-``, integrated
    backward towards ``E+``, comes within 0.15 of ``E+`` and is ejected on one side of
    the stable manifold of ``E+`` or the other (as ``_tor_heteroclinic_nu`` of
    ``tests/test_published_cycles.py``); Brent on the side in ``[lo, hi]``."""

    def side(nu):
        f, jac = _tor_reversed(nu)
        Ep = _tor_E(nu)
        v, _ = _eigen_pair(jac(-Ep), np.argmax)
        v = v * np.sign(v @ Ep)
        _, w = _eigen_pair(jac(Ep), np.argmax)
        return _ejection_side(f, -Ep + 1e-9 * v, Ep, w, ((0.15, -1), (0.3, 1)))

    return brentq(side, lo, hi, xtol=1e-15)


def test_tor_saddle_focus_homoclinic_in_reversed_time():
    """``E`` has a 2-D unstable manifold: ``find_connection`` says so and points to the
    time-reversed flow, where it finds the orbit from several starting ``nu`` within its
    estimate of ``nu* = -0.72894100482``; the other branch of the reversed manifold
    escapes to infinity and fails, saying the manifold does not come near the target."""
    ref = _tor_nu()
    assert ref == pytest.approx(-0.72894100482, abs=1e-11)
    fwd = _tor_system(1)
    with pytest.raises(ValueError, match="2-dimensional unstable manifold.*reverse time"):
        find_connection(fwd, fwd.params(**TOR), "nu", source=_tor_E(-0.72), shift=0)
    rev = _tor_system(-1)
    for nu0 in (-0.70, -0.72, -0.75):
        res = find_connection(rev, rev.params(**{**TOR, "nu": nu0}), "nu", source=_tor_E(nu0),
                              shift=0, branch=-1)  # fmt: skip
        assert res.status is Status.SUCCESS, res.message
        assert abs(res.value("nu") - ref) <= res.error("nu"), (nu0, res.errors)
        assert _useful(res, "nu")
        # the orbit ends at E(nu*) (the saddle is refined with the parameter)
        assert res.x_from == pytest.approx(_tor_E(ref), abs=1e-6)
    bad = find_connection(rev, rev.params(**TOR), "nu", source=_tor_E(-0.72), shift=0, branch=1)
    assert not bad.success
    assert "does not come near the target" in bad.message


def test_tor_homoclinic_curve_in_gamma(monkeypatch):
    """The saddle-focus homoclinic orbit continued in ``gamma`` from -0.6 to -0.7 at
    default settings (reversed time): the end row is within the default tolerance
    ``atol + rtol |nu|`` of shooting (``nu = -0.77005809975`` at ``gamma = -0.7``),
    its re-solve within its own estimate."""
    rev = _tor_system(-1)
    res = find_connection(rev, rev.params(**TOR), "nu", source=_tor_E(-0.72), shift=0, branch=-1)
    size0 = float(np.max(np.linalg.norm(res.x - res.x_from, axis=1)))
    br = continue_connection(res, "gamma", ContinuationSettings(p_min=-0.7, p_max=-0.6),
                             direction="backward")  # fmt: skip
    assert br.status is Status.PARAM_BOUND, br.message
    j = int(np.argmin(br.p))
    assert br.p[j] == pytest.approx(-0.7, abs=1e-10)
    nu, row = float(br.records["nu"][j]), connection_at(br, j)
    size = float(np.max(np.linalg.norm(row.x - row.x_from, axis=1))) / size0
    monkeypatch.setitem(TOR, "gamma", -0.7)
    ref = _tor_nu(nu - 1e-3, nu + 1e-3, size)
    assert ref == pytest.approx(-0.77005809975, abs=1e-10)
    assert abs(nu - ref) <= ATOL + RTOL * abs(ref)
    again = solve_connection(row.problem, row)
    assert again.status is Status.SUCCESS, again.message
    assert abs(again.value("nu") - ref) <= again.error("nu"), again.errors
    assert _useful(again, "nu")


def test_tor_heteroclinic_connection_between_the_saddle_foci():
    """``E+ -> E-`` in reversed time (source ``E-``, the target ``E+`` of the reversed
    flow): from ``nu = -0.8`` the primary connection of the heteroclinic cycle,
    ``nu* = -0.79751983065`` (the limit of the symmetric cycles'
    snake in ``tests/test_published_cycles.py``); from ``nu = -0.7`` another, longer one
    (the closest approach of the manifold picks the orbit; shooting finds that one at
    ``-0.70422393628`` too: near a heteroclinic cycle of saddle-foci there are many).
    Both within their estimates."""
    rev = _tor_system(-1)
    refs = []
    for nu0, lo, hi in ((-0.8, -0.7975, -0.79752), (-0.7, -0.7043, -0.7041)):
        ref = _tor_heteroclinic_nu(lo, hi)
        refs.append(ref)
        E = _tor_E(nu0)
        res = find_connection(rev, rev.params(**{**TOR, "nu": nu0}), "nu", source=-E, target=E)
        assert res.status is Status.SUCCESS, res.message
        assert abs(res.value("nu") - ref) <= res.error("nu"), (nu0, ref, res.errors)
        assert _useful(res, "nu")
        assert res.x_to == pytest.approx(_tor_E(ref), abs=1e-6)
    assert refs == pytest.approx([-0.79751983065, -0.70422393628], abs=1e-10)


# ------------------------------------------------------------------ rev (Champneys)
A_REV, K_REV = math.sqrt(15.0 / 8.0), 1.0 / (2.0 * math.sqrt(2.0))


def _rev_rhs(x, p, ops):
    P, eps = p[0], p[1]
    return ops.stack([x[1], x[2], x[3], -P * x[2] - x[0] + x[0] ** 3 - eps * x[1]])


def _rev_exact(t):
    """``u = A sech^2(k t)`` and its first three derivatives, shape (K, 4)."""
    s, th = 1.0 / np.cosh(K_REV * t), np.tanh(K_REV * t)
    k = K_REV
    return np.column_stack([
        A_REV * s**2,
        -2 * A_REV * k * s**2 * th,
        A_REV * k**2 * (4 * s**2 - 6 * s**4),
        A_REV * k**3 * (-8 * s**2 * th + 24 * s**4 * th),
    ])  # fmt: skip


@pytest.fixture(scope="module")
def rev():
    """Solved from a rough guess: 0.8 times the closed form, ``eps = 0.05``."""
    s = System(_rev_rhs, ("u", "u1", "u2", "u3"), ("P", "eps"))
    T = 60.0
    t = np.linspace(0.0, T, 400)
    prob = HeteroclinicProblem(s, s.params(P=-2.5, eps=0.05), "eps", saddle_from=np.zeros(4),
                               shift=0, T=T)  # fmt: skip
    return solve_connection(prob, (t, 0.8 * _rev_exact(t - T / 2)))


def test_rev_homoclinic_closed_form(rev):
    """At ``P = -5/2``: ``eps = 0`` within the estimate, and the orbit is the closed form
    ``sqrt(15/8) sech^2(t / (2 sqrt 2))`` up to a time shift (collocation error of the
    adapted mesh, under 1e-5; the ends within 1e-7 of the origin)."""
    res = rev
    assert res.status is Status.SUCCESS, res.message
    assert abs(res.value("eps")) <= res.error("eps") < ATOL
    t = res.t
    shift = minimize_scalar(lambda c: np.max(np.abs(res.x - _rev_exact(t - c))),
                            bounds=(25.0, 35.0), method="bounded",
                            options={"xatol": 1e-9}).x  # fmt: skip
    assert np.max(np.abs(res.x - _rev_exact(t - shift))) < 1e-5
    assert np.max(res.x[:, 0]) == pytest.approx(A_REV, abs=1e-6)


def test_rev_homoclinic_persists_in_P(rev):
    """Continued in ``P`` from -5/2 (a real saddle) through ``P = -2`` (double
    eigenvalues) to the demo's 1.6 (a saddle-focus): ``eps`` stays 0 along the branch
    (to 1e-10: truncation at ``T = 60``), and a re-solve at ``P = 1.6`` is within its
    estimate of 0."""
    br = continue_connection(rev, "P", ContinuationSettings(p_min=-2.5, p_max=1.6))
    assert br.status is Status.PARAM_BOUND, br.message
    assert br.p.max() == pytest.approx(1.6, abs=1e-10)
    assert np.max(np.abs(br.records["eps"])) < 1e-10
    j = int(np.argmax(br.p))
    end = solve_connection(connection_at(br, j).problem, connection_at(br, j))
    assert end.status is Status.SUCCESS, end.message
    assert abs(end.value("eps")) <= end.error("eps") < ATOL
    # the origin is a saddle-focus there: the orbit's tail oscillates (u changes sign)
    assert np.min(end.x[:, 0]) < 0.0
