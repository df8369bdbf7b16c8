"""Heel-induced derivatives Y_phi, N_phi, K_phi (Umeda 1999 Eqs. 6, 8, 10) in the model."""

from __future__ import annotations

import numpy as np
import pytest

from ship_models import Umeda4DOF
from ship_models.vessel import Coefficient, load_vessel


def _model(**primes: float) -> Umeda4DOF:
    v = load_vessel("purse_seiner").with_overrides(
        {
            f"hydrodynamics.{k}": Coefficient(val, "-", "test", "assumed")
            for k, val in primes.items()
        }
    )
    return Umeda4DOF(v)


def test_heel_terms_enter_eqs_6_8_10_in_closed_form() -> None:
    base = _model()
    m = _model(Y_phi_prime=0.03, N_phi_prime=-0.02, K_phi_prime=0.01)
    F = m.forces
    x = np.array([0.4, 8.5, 0.1, 0.2, 0.01, 0.15, 0.02, -0.1])
    p = m.default_params().values
    df = m.f(x, p) - base.f(x, p)
    q = 0.5 * F.rho * F.L * F.d_m * x[1] ** 2 * x[5]
    assert df[2] == pytest.approx(0.03 * q / (F.mass + F.m_y), rel=1e-10)
    assert df[4] == pytest.approx(-0.02 * q * F.L / (F.I_zz + F.J_zz), rel=1e-10)
    assert df[6] == pytest.approx(0.01 * q * F.d_m / F.I_xx_J_xx, rel=1e-10)
    assert np.all(df[[0, 1, 3, 5, 7]] == 0.0)


def test_without_y_phi_and_n_phi_roll_is_one_way_coupled() -> None:
    """With Y_phi = N_phi = 0 no equation but roll's depends on phi (why K_phi, GM and the
    roll damping do not move the critical Fn or the crest fold of the default vessel)."""
    m = Umeda4DOF("purse_seiner")
    x = np.array([0.4, 8.5, 0.1, 0.2, 0.01, 0.15, 0.02, -0.1])
    J = m.jacobian(x, m.default_params().values)
    rows = [0, 1, 2, 3, 4, 7]
    assert np.all(J[np.ix_(rows, [5, 6])] == 0.0)
    m2 = _model(N_phi_prime=0.02)
    J2 = m2.jacobian(x, m2.default_params().values)
    assert J2[4, 5] != 0.0
