r"""Heel-induced hydrodynamic derivatives by analogy with a captive-tested hull.

Umeda (1999) Eqs. (6), (8), (10) carry the heel-induced sway force, yaw and roll
moments :math:`Y_\phi(u)\,\phi`, :math:`N_\phi(u)\,\phi`, :math:`K_\phi(u)\,\phi`,
measured for the paper's purse seiner by circular-motion tests (its refs. 2, 14).
No regression of these derivatives over hull forms could be read here (neither the
paper's ref. 22, Hirano 1980, nor a fishing-vessel data base), so the only cited
numbers available are those of one hull measured in captive-model tests:

    Son, K.-H. & Nomoto, K. (1981), "On the coupled motion of steering and rolling
    of a high-speed container ship", J. Soc. Nav. Archit. Japan 150:232-244
    (English: Naval Architecture and Ocean Engineering 20:73-83, 1982),

for the container ship SR 108 (L = 175 m, B = 25.4 m, d = 8.5 m, C_b = 0.559),
non-dimensionalised with :math:`\tfrac12\rho L^2 U^2` (forces) and
:math:`\tfrac12\rho L^3 U^2` (moments), :math:`v' = v/U`, :math:`\phi` in rad:

=====================  ============  =====================  ============
:math:`Y'_v`           -0.0116       :math:`Y'_\phi`        -0.000063
:math:`N'_v`           -0.0038545    :math:`N'_\phi`        -0.0001424
:math:`K'_v`           +0.0003026    :math:`K'_\phi`        -0.000021
=====================  ============  =====================  ============

(as transcribed in T. I. Fossen's Marine Systems Simulator, ``VESSELS/container.m``,
which cites the 1982 English version; only this one transcription could be read, so
the values are checked against one source only.) Axes as in Umeda (1999): y to
starboard, z down, :math:`\phi > 0` starboard down; the restoring moment
:math:`-W\,GM\,\phi` is separate from :math:`K_\phi` there, as here.

The estimate transfers the *ratios* of the heel derivatives to the drift
derivatives of the same equation, which do not depend on the normalisation,

.. math::

    Y_\phi = \frac{Y'_\phi}{Y'_v}\Big|_{SN} Y_v U, \qquad
    N_\phi = \frac{N'_\phi}{N'_v}\Big|_{SN} N_v U, \qquad
    K_\phi = \frac{K'_\phi}{K'_v}\Big|_{SN} K_v U,

with :math:`K_v = -z_H Y_v` the roll moment of the hull's drift force acting at the
height :math:`z_H` (Umeda 1999 Eq. 10 as modelled here). In the primes of
:mod:`ship_models.vessel` (``Y'_phi = Y_phi/(rho/2 L d U^2)``,
``N'_phi = N_phi/(rho/2 L^2 d U^2)``, ``K'_phi = K_phi/(rho/2 L d^2 U^2)``) this is
``Y'_phi = a_Y Y'_v``, ``N'_phi = a_N N'_v``, ``K'_phi = -a_K (z_H/d) Y'_v``.

This is an ANALOGY, not a regression: it assumes the heeled hull's lift scales with
its drift lift as on the container ship. Its validity range is taken as +-25 % about
that hull's L/B, B/d and C_b (:data:`SON_NOMOTO_HULL`, :data:`SON_NOMOTO_BAND`; an
assumption, since one hull defines no range); a fishing vessel (L/B ~ 4.5) lies
outside it in L/B: :func:`son_nomoto_heel_derivatives` says so in the returned
``outside`` list, and :func:`ship_models.estimation.build_vessel_model` logs it once
(:mod:`ship_models.validity`).
"""

from __future__ import annotations

from dataclasses import dataclass

#: Son & Nomoto (1981) container-ship derivatives (see module doc).
SON_NOMOTO: dict[str, float] = {
    "Y_v": -0.0116,
    "Y_phi": -0.000063,
    "N_v": -0.0038545,
    "N_phi": -0.0001424,
    "K_v": 0.0003026,
    "K_phi": -0.000021,
}

#: Form of the hull behind :data:`SON_NOMOTO` (L/B, B/d, C_b of SR 108).
SON_NOMOTO_HULL: dict[str, float] = {"L/B": 175.0 / 25.4, "B/d": 25.4 / 8.5, "C_b": 0.559}

#: Relative band about :data:`SON_NOMOTO_HULL` taken as the analogy's validity range
#: (an assumption: one hull defines no range; +-25 % keeps to ships of that form).
SON_NOMOTO_BAND = 0.25


def son_nomoto_validity() -> dict[str, tuple[float, float]]:
    """Validity range ``(low, high)`` of each hull-form ratio for the analogy."""
    b = SON_NOMOTO_BAND
    return {k: (v * (1.0 - b), v * (1.0 + b)) for k, v in SON_NOMOTO_HULL.items()}


SON_NOMOTO_SOURCE = (
    "Son & Nomoto (1981), On the coupled motion of steering and rolling of a high-speed "
    "container ship, J. Soc. Nav. Archit. Japan 150 (NAOE 20:73-83, 1982), captive-model "
    "derivatives (as transcribed in Fossen's MSS container.m)"
)


@dataclass(frozen=True)
class HeelDerivatives:
    """Heel derivatives in the primes of :mod:`ship_models.vessel`.

    Attributes
    ----------
    Y_phi_prime, N_phi_prime, K_phi_prime : float
        ``Y_phi/(rho/2 L d U^2)``, ``N_phi/(rho/2 L^2 d U^2)``, ``K_phi/(rho/2 L d^2 U^2)``.
    outside : tuple of str
        Hull-form ratios of the target outside +-25 % of the reference hull's
        (:data:`SON_NOMOTO_HULL`), e.g. ``("L/B 4.54 (SR 108: 6.89)",)``.
    """

    Y_phi_prime: float
    N_phi_prime: float
    K_phi_prime: float
    outside: tuple[str, ...]


def son_nomoto_ratios() -> tuple[float, float, float]:
    """The ratios ``(Y'_phi/Y'_v, N'_phi/N'_v, K'_phi/K'_v)`` of Son & Nomoto (1981)."""
    sn = SON_NOMOTO
    return sn["Y_phi"] / sn["Y_v"], sn["N_phi"] / sn["N_v"], sn["K_phi"] / sn["K_v"]


def son_nomoto_heel_derivatives(
    Y_v_prime: float,
    N_v_prime: float,
    z_H_over_d: float,
    *,
    L_over_B: float,
    B_over_d: float,
    C_b: float,
) -> HeelDerivatives:
    """Heel derivatives of a hull from its drift derivatives and Son & Nomoto's ratios.

    Parameters
    ----------
    Y_v_prime, N_v_prime : float
        The hull's ``Y_v/(rho/2 L d U)`` and ``N_v/(rho/2 L^2 d U)`` (about G).
    z_H_over_d : float
        Depth of the hull's lateral force below G over the mean draft (z down).
    L_over_B, B_over_d, C_b : float
        Hull form, compared with the reference hull's (validity).

    Returns
    -------
    HeelDerivatives
        ``Y'_phi = a_Y Y'_v``, ``N'_phi = a_N N'_v``, ``K'_phi = -a_K z_H/d Y'_v``
        (module doc).
    """
    for name, val in (("Y_v_prime", Y_v_prime), ("N_v_prime", N_v_prime)):
        if not val < 0.0:
            raise ValueError(f"`{name}` must be negative (a stable drift force), got {val}")
    a_Y, a_N, a_K = son_nomoto_ratios()
    outside = []
    rng = son_nomoto_validity()
    for key, val in (("L/B", L_over_B), ("B/d", B_over_d), ("C_b", C_b)):
        if not rng[key][0] <= val <= rng[key][1]:
            outside.append(f"{key} {val:.3g} (SR 108: {SON_NOMOTO_HULL[key]:.3g})")
    return HeelDerivatives(
        Y_phi_prime=a_Y * Y_v_prime,
        N_phi_prime=a_N * N_v_prime,
        K_phi_prime=-a_K * z_H_over_d * Y_v_prime,
        outside=tuple(outside),
    )


__all__ = [
    "SON_NOMOTO",
    "SON_NOMOTO_BAND",
    "SON_NOMOTO_HULL",
    "SON_NOMOTO_SOURCE",
    "HeelDerivatives",
    "son_nomoto_heel_derivatives",
    "son_nomoto_ratios",
    "son_nomoto_validity",
]
