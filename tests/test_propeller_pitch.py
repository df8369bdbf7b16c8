"""studies/propeller_pitch.py: the pitch study's identities (Umeda 1999 Eq. 5 thrust)."""

from __future__ import annotations

import pytest

from ship_models.hydro.propeller import bseries_kt
from studies.propeller_pitch import pitch_case


@pytest.fixture(scope="module")
def cases() -> dict[float, dict[str, float]]:
    return {pd: pitch_case(pd, 0.3016) for pd in (0.8, 1.2, 1.4)}


def test_thrust_loading_of_the_nominal_point_does_not_depend_on_the_pitch(cases) -> None:  # type: ignore[no-untyped-def]
    """K_T(J_0)/J_0^2 = R(u0)/((1-t) rho D^2 u_a0^2) for every pitch (the identity the
    study's argument rests on), with K_T from the B-series polynomial itself."""
    loads = [bseries_kt(c["J_0"], pd, 0.55, 4) / c["J_0"] ** 2 for pd, c in cases.items()]
    assert max(loads) == pytest.approx(min(loads), rel=1e-6)


def test_thrust_at_celerity_changes_sign_where_zero_thrust_passes_it(cases) -> None:  # type: ignore[no-untyped-def]
    for c in cases.values():
        assert c["J_c"] == pytest.approx(c["J_0"] * c["c_over_u0"], rel=1e-12)
        # K_T decreases through J_T0: thrust at c positive iff J_c < J_T0
        assert (c["T_c_kN"] > 0) == (c["J_c"] < c["J_T0"])
    assert cases[0.8]["T_c_kN"] < 0 < cases[1.4]["T_c_kN"]
    # small against the resistance at c, whatever the pitch
    assert all(abs(c["T_c_over_R_c"]) < 0.05 for c in cases.values())
