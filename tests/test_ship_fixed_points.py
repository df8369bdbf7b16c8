"""Fixed points of the ship model and their eigen-structure (Umeda 1999, Figs. 2-9).

References used:
- independent Newton solves (``solve_equilibrium``) from the model's analytic guess;
- the uncoupled surge model (chi_c = 0 reduction) and its closed-form threshold
  ``T(c; n(Fn)) - R(c) + max X_w = 0`` (fold of the surge fixed points in Fn);
- the port-starboard symmetry of the equations;
- the paper's qualitative statements, asserted where our estimated vessel agrees
  with them (see ``studies/README.md`` for the one place where it differs in degree:
  the roll share of the trough's unstable eigenvector).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.optimize as so

from continuation.equilibria import solve_equilibrium
from continuation.settings import NewtonSettings
from ship_models.analysis.eigen import eigen_structure, paper_scales
from ship_models.analysis.events import capsize_event, vanishing_angle
from ship_models.analysis.fixed_points import (
    find_fixed_point,
    fixed_points,
    position_label,
    surge_model_of,
    surge_roots,
    trace_in_chi_c,
    trace_in_fn,
)
from ship_models.contracts import SeaState

TIGHT = NewtonSettings(tol=1e-11, step_tol=1e-12, max_iter=50, damping=True)


@pytest.fixture(scope="module")
def params(model):
    return model.default_params()  # Fn = 0.3248, chi_c = 10 deg


@pytest.fixture(scope="module")
def chi_branches(model, params):
    return trace_in_chi_c(model, params)


@pytest.fixture(scope="module")
def points10(model, params):
    return {fp.label: fp for fp in fixed_points(model, params)}


def _first_fold_index(br):
    folds = br.find("fold")
    return folds[0].index if folds else len(br) - 1


# ----------------------------------------------------------------------- chi_c = 0
def test_surge_roots_are_the_uncoupled_surge_fixed_points(model, params):
    """chi_c = 0: lifted surge roots solve the 8-state model, u = c, lateral states 0."""
    p0 = params.replace(chi_c=0.0)
    roots = surge_roots(model, p0)
    assert [position_label(x[0]) for x in roots] == ["crest", "trough"]
    c = model.celerity(p0)
    sm = surge_model_of(model)
    sp = sm.params(
        Fn=p0["Fn"], H_over_lambda=p0["H_over_lambda"], lambda_over_L=p0["lambda_over_L"]
    )
    for x in roots:
        assert x[1] == pytest.approx(c, rel=1e-12)
        assert np.all(x[2:] == 0.0)
        # the surge force vanishes there (independent evaluation)
        assert abs(float(sm.surge_force(x[0], c, sp))) < 1e-6 * model.forces.weight
        # independent 8-state Newton from a perturbed start converges back to it
        guess = x + np.array([0.01, 0.05, 0.01, 0.01, 0.001, 0.01, 0.001, 0.01])
        res = solve_equilibrium(model, guess, p0, TIGHT)
        assert np.max(np.abs(model.difference(res.z, x))) < 1e-8
        # the surge eigenvalues are among the 8-state ones (block-triangular Jacobian)
        ev_s = np.linalg.eigvals(sm.jacobian(x[:2], sp.values))
        ev_8 = np.linalg.eigvals(model.jacobian(x, p0.values))
        for lam in ev_s:
            assert np.min(np.abs(ev_8 - lam)) < 1e-8


def test_surge_roots_empty_below_surf_riding_threshold(model, params):
    """In the gentler wave H/lambda = 1/30 surf-riding needs Fn above ~0.39."""
    low = params.replace(Fn=0.36, H_over_lambda=1 / 30)
    assert surge_roots(model, low.replace(chi_c=0.0)) == []
    assert fixed_points(model, low) == []
    assert len(surge_roots(model, low.replace(Fn=0.42, chi_c=0.0))) == 2


def test_fn_fold_matches_closed_form_surge_threshold(model, params):
    """In Fn at chi_c = 0 the crest and trough points merge where T - R + max X_w = 0.

    H/lambda = 1/30, where the threshold lies at Fn ~ 0.39 (in the paper's steep wave
    H/lambda = 1/9.2 our vessel can surf-ride at any Fn).
    """
    p0 = params.replace(chi_c=0.0, H_over_lambda=1 / 30, Fn=0.42)
    F = model.forces
    lL, Hl = p0["lambda_over_L"], p0["H_over_lambda"]
    c = model.celerity(p0)

    def xw(xi):
        return float(F.waves.forces(xi, c, 0.0, SeaState(Hl, lL), lift=False)[0])

    grid = np.linspace(0, 1, 401)
    k = int(np.argmax([xw(s) for s in grid]))
    opt = so.minimize_scalar(
        lambda s: -xw(s),
        bounds=(grid[k - 1], grid[k + 1]),
        method="bounded",
        options={"xatol": 1e-12},
    )
    xw_max = -opt.fun

    def balance(fn):
        return float(F.thrust_force(c, F.revolutions(fn)) - F.resistance_force(c)) + xw_max

    fn_star = so.brentq(balance, 0.3, 0.42, xtol=1e-14)
    crest = surge_roots(model, p0)[0]
    br = trace_in_fn(model, crest, p0, fn_min=0.3, fn_max=0.48)
    folds = br.find("fold")
    assert len(folds) == 1 and folds[0].located
    assert folds[0].p == pytest.approx(fn_star, abs=1e-7)
    # the branch continues past the fold onto the trough point
    labels = {position_label(x) for x in br.state("xi_G")}
    assert labels == {"crest", "trough"}


# ----------------------------------------------------------------------- chi_c traces
def test_chi_c_continuation_agrees_with_independent_newton(model, params, chi_branches):
    assert set(chi_branches) == {"crest", "trough"}
    rng = np.random.default_rng(1)
    for label, br in chi_branches.items():
        assert br.status.ok, br.status
        k_end = _first_fold_index(br)
        rows = np.unique(np.linspace(1, k_end, 6).astype(int))
        for k in rows:
            pk = params.replace(chi_c=float(br.p[k]))
            guesses = [br.x[k] * (1 + 0.02 * rng.uniform(-1, 1, 8)) + 1e-3 * rng.uniform(-1, 1, 8)]
            if br.p[k] < math.radians(20.0):  # the model's analytic guess is good there
                guesses.append(model.equilibrium_guess(pk, where=label))
            for guess in guesses:
                res = solve_equilibrium(model, guess, pk, TIGHT)
                assert res.converged
                assert np.max(np.abs(model.difference(res.z, br.x[k]))) < 1e-8, (label, k)
        # every row of the branch solves F = 0
        for k in range(len(br)):
            pk = params.replace(chi_c=float(br.p[k]))
            assert np.max(np.abs(model.f(br.x[k], pk.values))) < 1e-8


def test_chi_c_ranges_and_signs_match_paper_statements(model, chi_branches):
    """Paper: crest: rudder and heading positive; trough: heading negative, rudder positive."""
    crest, trough = chi_branches["crest"], chi_branches["trough"]
    # the trough branch reaches the paper's 50 deg; our crest branch folds before it
    # (at chi_c ~ 43.6 deg; the fold itself is checked in test_crest_fold_solves_fold_system)
    assert trough.p[-1] == pytest.approx(math.radians(50.0), abs=1e-12)
    assert len(trough.find("fold")) == 0
    fold = crest.find("fold")[0]
    assert math.radians(10.0) < fold.p < math.radians(50.0)
    kc = _first_fold_index(crest)
    sel = slice(1, kc + 1)
    assert np.all(crest.state("chi")[sel] > 0) and np.all(crest.state("delta")[sel] > 0)
    assert np.all(trough.state("chi")[1:] < 0) and np.all(trough.state("delta")[1:] > 0)
    # both primary branches have saddle index 1 up to the fold
    assert np.all(crest.n_unstable[: kc + 1] == 1)
    assert np.all(trough.n_unstable == 1)


def test_crest_fold_solves_fold_system(model, params, chi_branches):
    """The located fold of the crest branch in chi_c against an independent solve of the
    extended fold system ``f(x, p) = 0, f_x v = 0, v0 . v = 1`` (Seydel 2010, *Practical
    Bifurcation and Stability Analysis*, Sec. 5.5) by MINPACK's hybrid method with a
    finite-difference Jacobian, started from the branch row nearest the fold."""
    crest = chi_branches["crest"]
    fold = crest.find("fold")[0]
    k = fold.index
    x0, p0 = np.array(crest.x[k]), float(crest.p[k])
    _, _, vt = np.linalg.svd(model.jacobian(x0, params.replace(chi_c=p0).values))
    v0 = vt[-1]

    def fold_system(z):
        x, p, v = z[:8], z[8], z[9:]
        pv = params.replace(chi_c=float(p)).values
        return np.concatenate([model.f(x, pv), model.jacobian(x, pv) @ v, [v0 @ v - 1.0]])

    sol = so.root(fold_system, np.concatenate([x0, [p0], v0]), method="hybr", tol=1e-13)
    assert sol.success, sol.message
    assert np.max(np.abs(fold_system(sol.x))) < 1e-9
    assert abs(sol.x[8] - fold.p) < 1e-7
    # a fold of the branch: chi_c is largest there among the rows around it
    near = crest.p[max(k - 5, 0) : k + 6]
    assert np.all(near <= fold.p + 1e-9)


def test_port_starboard_symmetry(model, params, points10):
    """(v, chi, r, phi, p_roll, delta, chi_c) -> -(...) maps fixed points onto fixed points."""
    mirror = {fp.label: fp for fp in fixed_points(model, params.replace(chi_c=-params["chi_c"]))}
    assert set(mirror) == set(points10)
    flip = np.array([1, 1, -1, -1, -1, -1, -1, -1])
    for lab, fp in points10.items():
        assert np.max(np.abs(model.difference(mirror[lab].x, flip * fp.x))) < 1e-9


# ----------------------------------------------------------------------- eigen-structure
def test_saddle_index_one_at_chi_c_10(points10):
    """Paper, Figs. 6-7: at chi_c = 10 deg, Fn = 0.3248 each point is a saddle of index 1."""
    for lab in ("crest", "trough"):
        es = points10[lab].eigen
        assert es.saddle_index == 1
        lam = es.values[0]
        assert lam.real > 0 and lam.imag == 0.0
        assert np.all(es.values[1:].real < 0)


def test_paper_nondimensionalisation(model, params, points10):
    """lambda' = lambda L/c; the unstable eigenvector is an eigenvector in scaled units too."""
    fp = points10["crest"]
    scales, ts = paper_scales(model, params, fp.x)
    c, L = model.celerity(params), model.forces.L
    assert ts == pytest.approx(L / c, rel=1e-14)
    J = model.jacobian(fp.x, params.values)
    Jn = (np.diag(1 / scales) @ J @ np.diag(scales)) * ts  # d y'/dt' = Jn y'
    y = fp.eigen.unstable_vector(0)
    lam_n = fp.eigen.values_nondim[0].real
    assert np.max(np.abs(Jn @ y - lam_n * y)) < 1e-10
    assert y[0] > 0 and np.max(np.abs(y)) == pytest.approx(1.0)


def test_dominant_eigenvector_components(points10):
    """Paper, Figs. 8-9: crest surge-dominant; trough yaw, roll and rudder dominant.

    Our vessel: crest surge only (every other motion < 0.2); trough yaw and rudder
    dominate (> 0.5), roll is the next largest after sway (~0.17, more than surge) but
    below half of the yaw component: the README records this difference.
    """
    crest = points10["crest"].eigen
    assert crest.dominant_motions() == ("surge",)
    w = crest.motion_weights()
    assert max(v for k, v in w.items() if k != "surge") < 0.2
    trough = points10["trough"].eigen
    assert set(trough.dominant_motions()) == {"yaw", "rudder"}
    wt = trough.motion_weights()
    assert wt["roll"] > wt["surge"]
    assert set(trough.dominant_components()[:3]) == {"chi", "r", "delta"}


def test_fixed_points_past_the_fold_are_found(model, params, chi_branches):
    """Between its first two folds in chi_c the crest branch crosses the course 4 times.

    The branch goes up to the first fold, back down to the second, up to the third and
    back to chi_c = 0 (at phi ~ -63 deg); the course half-way between the first two
    folds is crossed once on each of these four arcs (sign changes of chi_c - course
    along the traced branch), and ``fixed_points`` must find all four.
    """
    crest = chi_branches["crest"]
    f1, f2 = crest.find("fold")[:2]
    course = 0.5 * (f1.p + f2.p)
    crossings = int(np.sum(np.diff(np.sign(crest.p - course)) != 0))
    assert crossings == 4
    pts = fixed_points(model, params.replace(chi_c=course))
    labels = [fp.label for fp in pts]
    assert labels[0] == "crest" and "trough" in labels
    assert sum(lab.startswith("crest") for lab in labels) == crossings
    assert pts[0].saddle_index == 1
    for fp in pts:
        assert fp.residual_norm < 1e-9
        es = eigen_structure(model, fp.x, fp.params)
        assert es.saddle_index == fp.saddle_index


def test_find_fixed_point_and_bad_input(model, params):
    fp = find_fixed_point(model, params, "trough")
    assert fp.label == "trough"
    with pytest.raises(ValueError, match="no nowhere fixed point at Fn = "):
        find_fixed_point(model, params, "nowhere")
    with pytest.raises(ValueError, match="chi_c_max"):
        trace_in_chi_c(model, params, chi_c_max=2.0)
    with pytest.raises(ValueError, match="chi_c_max"):
        fixed_points(model, params, chi_c_max=-0.5)
    with pytest.raises(ValueError, match="n_grid"):
        surge_roots(model, params, n_grid=2)
    with pytest.raises(ValueError, match="fn_min"):
        trace_in_fn(model, fp.x, params, fn_min=0.4, fn_max=0.3)
    with pytest.raises(ValueError, match="params"):
        fixed_points(model, [0.3, 0.1])
    with pytest.raises(ValueError, match="threshold"):
        fp.eigen.dominant_components(threshold=0.0)
    with pytest.raises(ValueError, match="`k`"):
        fp.eigen.unstable_vector(1)


# ----------------------------------------------------------------------- capsize event
def test_vanishing_angle_and_capsize_event(model):
    phi_v = vanishing_angle(model)
    assert abs(float(model.forces.gz(phi_v))) < 1e-10
    assert np.all(model.forces.gz(np.linspace(1e-3, phi_v - 1e-3, 200)) > 0)
    # the fitted curve of the equations and the hydrostatic curve agree on phi_v
    assert phi_v == pytest.approx(model.data.info["phi_vanishing"], abs=math.radians(0.5))
    ev = capsize_event(model)
    assert ev.terminal and ev.direction == "up" and ev.name == "capsize"
    x = np.zeros(8)
    x[5] = phi_v + 0.01
    assert ev.fn(x, None) == pytest.approx(0.01)
    x[5] = -(phi_v + 0.01)
    assert ev.fn(x, None) == pytest.approx(0.01)
    assert capsize_event(model, angle=1.0).fn(np.zeros(8), None) == -1.0
    with pytest.raises(ValueError, match="angle"):
        capsize_event(model, angle=-1.0)
