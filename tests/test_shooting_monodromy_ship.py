r"""The ship's periodic orbit at (Fn 0.1, chi_c 0): variational ``DP`` against differences.

Independent references for the return map's Jacobian of the purse seiner's orbit
(``periodic_orbit``, now ``jacobian="variational"``):

* the engine's forward-difference path (``jacobian="fd"``, ``fd_step = 1e-6``): its
  error is the integration and event-location noise (about 1e-9 relative at
  ``map_rtol = 1e-11``) over ``fd_step``, i.e. up to about 1e-3 in the multipliers,
  plus ``O(fd_step)``; the two must agree within that;
* central differences of the return map with steps ``h = 1e-3, 5e-4`` of the scales:
  error ``O(h^2 |D^3 P|)`` plus noise over ``h`` (about 1e-7): their errors against
  the variational ``DP`` must fall by 4 when ``h`` halves, and the Richardson
  extrapolation must agree within 1e-6.

(Measured outside the tests on the followed orbit at Fn 0.3, chi_c 45 deg: dominant
|mu| 0.292998330 variational, 0.292998330 from CasADi's forward sensitivities of the
plain integrator, 0.292998330 at ten times tighter tolerances, 0.2929968 by central
differences with h = 1e-3; forward differences had given 0.2900 to 0.2952 from run
to run.)

And Newton must converge to the same orbit with either Jacobian (period and section
state within the shooting tolerance ``tol = 1e-9``, scaled).
"""

from __future__ import annotations

import numpy as np
import pytest

from continuation.dynamics.shooting import ReturnMap, ShootingSettings, shoot_orbit
from continuation.status import Status
from ship_models.analysis.eigen import paper_scales
from ship_models.analysis.sudden_change import default_guess


def _by_modulus(m):
    return np.sort(np.abs(m))[::-1]


@pytest.fixture(scope="module")
def scales(model, orbit):
    s, _ = paper_scales(model, orbit.params, default_guess(model, orbit.params))
    return np.asarray(s, dtype=float)


def test_ship_variational_against_forward_differences(model, orbit, scales):
    assert orbit.jacobian == "variational"
    fd = shoot_orbit(model, orbit.params, orbit.x_section, state="xi_G", section=orbit.section,
                     scale=scales, settings=ShootingSettings(jacobian="fd"))  # fmt: skip
    assert fd.status is Status.SUCCESS, fd.message
    assert fd.jacobian == "fd"
    # the same orbit, to the shooting tolerance
    assert fd.period == pytest.approx(orbit.period, rel=1e-8)
    assert np.max(np.abs(fd.x_section - orbit.x_section) / scales) < 1e-8
    # multipliers: within the forward differences' noise (1e-9 / fd_step = 1e-3)
    np.testing.assert_allclose(
        _by_modulus(fd.multipliers), _by_modulus(orbit.multipliers), rtol=0, atol=1e-3
    )


def test_ship_variational_is_the_limit_of_central_differences(model, orbit, scales):
    """Central differences converge to the variational ``DP`` at second order."""
    i = orbit.state
    others = [k for k in range(len(scales)) if k != i]
    s_o = scales[others]
    pmap = ReturnMap(model, orbit.params, i, orbit.section, orbit.direction,
                     3 * orbit.period, ShootingSettings())  # fmt: skip
    y = orbit.x_section[others]

    def central(rel: float) -> np.ndarray:
        J = np.empty((len(others), len(others)))
        for k in range(len(others)):
            e = np.zeros(len(others))
            e[k] = rel * s_o[k]
            J[:, k] = (pmap(y + e)[0] - pmap(y - e)[0]) / (2 * e[k])
        return J * s_o[None, :] / s_o[:, None]  # scaled

    _, T, _ = pmap(y)
    DP = pmap.jacobian(y, T) * s_o[None, :] / s_o[:, None]
    j1, j2 = central(1e-3), central(5e-4)
    e1, e2 = np.max(np.abs(j1 - DP)), np.max(np.abs(j2 - DP))
    assert e2 < 1e-5
    assert 3.0 < e1 / e2 < 5.0  # O(h^2): a wrong DP would leave a constant error
    # Richardson: the h^2 term removed; what remains is O(h^4) + noise / h (~1e-7)
    assert np.max(np.abs((4 * j2 - j1) / 3 - DP)) < 1e-6
    np.testing.assert_allclose(
        _by_modulus(np.linalg.eigvals(j2)), _by_modulus(orbit.multipliers), rtol=0, atol=1e-5
    )
