"""Unstable manifolds of the crest saddle and their fates (Umeda 1999, Figs. 10-15).

References used:
- chi_c = 0: the lateral states stay zero, so the 8-state manifold must equal the
  unstable manifold of the uncoupled surge model integrated independently (SciPy
  DOP853 on :class:`ship_models.SurgeModel`);
- a detected periodic orbit must close on itself when re-integrated for one period
  by an independent integrator (SciPy DOP853);
- the paper's statements on the branches, asserted for our vessel at Fn = 0.3248
  (above our critical Fn) and 5e-5 below the critical Fn that the collocation solver
  (:func:`ship_models.analysis.critical_bvp.critical_fn_bvp`) finds, an independent
  method: the manifold fates must switch across that value.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.integrate as si
from scipy.spatial import cKDTree

from ship_models.analysis.events import vanishing_angle
from ship_models.analysis.fixed_points import find_fixed_point, surge_model_of
from ship_models.analysis.global_picture import build_global_picture, compare_pictures
from ship_models.analysis.manifold import manifold_start, unstable_manifold


def _polyline_distance(curve, q):
    """Distance of points ``q (M, 2)`` to the polyline through ``curve (K, 2)``."""
    _, j = cKDTree(curve).query(q)
    best = np.full(len(q), np.inf)
    for a, b in ((j - 1, j), (j, j + 1)):
        a, b = np.clip(a, 0, len(curve) - 1), np.clip(b, 0, len(curve) - 1)
        seg = curve[b] - curve[a]
        L2 = np.maximum(np.sum(seg**2, axis=1), 1e-300)
        s = np.clip(np.sum((q - curve[a]) * seg, axis=1) / L2, 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(q - (curve[a] + s[:, None] * seg), axis=1))
    return best


@pytest.fixture(scope="module")
def params(model):
    return model.default_params()


@pytest.fixture(scope="module")
def above(model, params):
    """Fn = 0.3248 (the paper's Figs. 10-13), above our vessel's critical Fn."""
    return unstable_manifold(model, params.replace(Fn=0.3248))


@pytest.fixture(scope="module")
def fn_critical(model, params):
    """Critical Fn at chi_c = 10 deg from the connecting orbit (collocation)."""
    from ship_models.analysis.critical_bvp import critical_fn_bvp

    res = critical_fn_bvp(params["chi_c"], model=model, params=params)
    assert res.success, res.message
    return res.Fn


@pytest.fixture(scope="module")
def below(model, params, fn_critical):
    """5e-5 below our vessel's critical Fn (about 0.3016)."""
    return unstable_manifold(model, params.replace(Fn=fn_critical - 5e-5))


def test_start_points_follow_the_unstable_eigenvector(above):
    sp = above.saddle
    for name, br in above.branches.items():
        d = (br.x0 - sp.x) / sp.eigen.scales
        assert np.max(np.abs(d)) == pytest.approx(above.eps, rel=1e-12)
        assert np.sign(d[0]) == (1 if name == "downslope" else -1)
        assert br.x0 == pytest.approx(manifold_start(sp, above.eps, br.sign), abs=0)


def test_downslope_branch_broaches_and_capsizes_to_port(model, params, above, below):
    """Paper: heading increases to starboard despite maximum opposite rudder; capsize to port."""
    phi_v = vanishing_angle(model)
    for man in (above, below):
        br = man.branches["downslope"]
        assert br.fate.kind == "capsize"
        x = br.trajectory.x_final
        assert x[5] == pytest.approx(-phi_v, abs=1e-6)  # port side down, at the event
        assert x[3] > params["chi_c"] + math.radians(30.0)  # turned to starboard
        assert x[7] < -0.9 * model.forces.delta_max  # maximum opposite rudder
        # the ship stays on the downslope near the crest the whole time
        xi = br.trajectory.x[:, 0]
        assert np.all((xi > 0.5) & (xi < 1.0))


def test_upslope_branch_above_critical_capsizes_after_the_next_saddle(above):
    """Paper, Fn = 0.3248: 'approaches a saddle next to the original saddle and then
    realizes capsizing due to broaching'."""
    fate = above.branches["upslope"].fate
    assert fate.kind == "capsize"
    assert [(v.label, v.shift) for v in fate.visits] == [("crest", -1)]


def test_upslope_branch_below_critical_tends_to_a_periodic_attractor(model, below):
    """Paper, Fn = 0.3247 for its vessel: 'approaches the saddle next to the original
    one and then tends to a periodic attractor' -- our vessel 5e-5 below its critical Fn."""
    br = below.branches["upslope"]
    fate = br.fate
    assert fate.kind == "periodic"
    assert fate.drift == -1  # overtaken by one wave per period
    assert (fate.visits[0].label, fate.visits[0].shift) == ("crest", -1)
    # independent check: one period of DOP853 from the last section crossing closes
    hits = br.trajectory.events["section"]
    x0 = hits.x[-1]
    p = below.params.values
    sol = si.solve_ivp(
        lambda t, x: model.f(x, p),
        (0.0, fate.period),
        x0,
        method="DOP853",
        rtol=1e-10,
        atol=1e-12,
    )
    expected = np.array(x0)
    expected[0] += fate.drift  # one wave further back, same state otherwise
    d = (sol.y[:, -1] - expected) / below.saddle.eigen.scales
    assert np.max(np.abs(d)) < 1e-3


def test_chi_c_zero_manifold_equals_uncoupled_surge_manifold(model, params):
    """chi_c = 0 (K_R = 3: stable trough): both branches stay in the surge plane and
    match the surge model's manifold; downslope -> trough, upslope -> next trough."""
    p = params.replace(chi_c=0.0, K_R=3.0)
    man = unstable_manifold(model, p)
    assert man.fates == {"downslope": "equilibrium:trough", "upslope": "equilibrium:trough"}
    assert man.branches["downslope"].fate.shift == 0
    assert man.branches["upslope"].fate.shift == -1
    sm = surge_model_of(model)
    sp = sm.params(Fn=p["Fn"], H_over_lambda=p["H_over_lambda"], lambda_over_L=p["lambda_over_L"])
    for br in man.branches.values():
        traj = br.trajectory
        assert np.max(np.abs(traj.x[:, 2:])) == 0.0  # lateral states exactly zero
        t_end = min(60.0, traj.t_final)
        sol = si.solve_ivp(
            lambda t, z: sm.f(z, sp.values),
            (0.0, t_end + 30.0),
            br.x0[:2],
            method="DOP853",
            rtol=1e-11,
            atol=1e-12,
            dense_output=True,
        )
        # compare the curves (a manifold is a set; near the saddle a round-off
        # difference only shifts the time along it): distance of every sample to the
        # densely sampled reference curve, nondimensional
        scale = np.array([1.0, model.celerity(p)])
        ref = sol.sol(np.linspace(0.0, t_end + 30.0, 200001)).T / scale
        q = traj.x[traj.t <= t_end, :2] / scale
        assert np.max(_polyline_distance(ref, q)) < 1e-6


def test_fates_do_not_depend_on_eps(model, params, above, below):
    for man in (above, below):
        for eps in (1e-5, 1e-7):
            other = unstable_manifold(model, man.params, man.saddle, eps=eps, points=man.points)
            assert other.fates == man.fates


def test_global_picture_changes_across_the_heteroclinic_bifurcation(model, params, fn_critical):
    g1 = build_global_picture(model, params.replace(Fn=fn_critical - 5e-5))
    g2 = build_global_picture(model, params.replace(Fn=fn_critical + 5e-5))
    assert g1.nodes["crest"]["saddle_index"] == 1
    assert "periodic" in g1 and "periodic" not in g2
    assert g1.edges["crest", "capsize", "downslope"]["fate"] == "capsize"
    assert g1.edges["crest", "periodic", "upslope"]["via"][0] == "crest@-1"
    diff = compare_pictures(g1, g2)
    assert diff.changed
    assert diff.changed_edges == (("crest", "upslope", "periodic", "capsize"),)
    assert diff.removed_nodes == ("periodic",)
    # saddles of index 2 are nodes without computed manifolds
    heeled = [n for n, d in g1.nodes(data=True) if d.get("saddle_index", 0) > 1]
    assert all("not computed" in g1.nodes[n]["manifold"] for n in heeled)
    assert not compare_pictures(g1, g1).changed


def test_bad_input(model, params, above):
    crest2 = find_fixed_point(model, params, "crest-2")
    assert crest2.saddle_index == 2
    with pytest.raises(ValueError, match="saddle index 2"):
        unstable_manifold(model, params, crest2)
    with pytest.raises(ValueError, match="eps"):
        unstable_manifold(model, params, above.saddle, eps=0.5, points=above.points)
    with pytest.raises(ValueError, match="branches"):
        unstable_manifold(model, params, above.saddle, branches=("sideways",))
    with pytest.raises(ValueError, match="t_max"):
        unstable_manifold(model, params, above.saddle, t_max=-1.0, points=above.points)


def test_global_picture_reuses_given_manifolds(model, params, above):
    """A crest manifold passed in gives the same graph as computing it (both t_max 600)."""
    p = params.replace(Fn=0.3248)
    computed = build_global_picture(model, p, points=above.points)
    given = build_global_picture(model, p, points=above.points, manifolds={"crest": above})
    assert given.graph["manifolds"]["crest"] is above
    assert computed.graph["manifolds"]["crest"] is not above
    assert not compare_pictures(computed, given).changed
    assert not compare_pictures(computed, given).changed_via
    assert sorted(given.edges(keys=True, data="fate")) == sorted(
        computed.edges(keys=True, data="fate")
    )
    with pytest.raises(ValueError, match="other parameters"):
        build_global_picture(
            model, p.replace(Fn=0.33), points=above.points, manifolds={"crest": above}
        )
    with pytest.raises(ValueError, match="eps"):
        build_global_picture(model, p, points=above.points, eps=1e-5, manifolds={"crest": above})
    with pytest.raises(ValueError, match="no fixed point"):
        build_global_picture(model, p, points=above.points, manifolds={"nowhere": above})
