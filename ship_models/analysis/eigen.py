r"""Eigen-structure of a ship fixed point: eigenvalues, saddle index, unstable eigenvectors.

Umeda (1999), Eqs. (14)-(15): the linearisation :math:`\dot y = DF(\bar x; b)\,y` at a
fixed point :math:`\bar x`; an eigenvalue with positive real part makes the point
unstable, and the number of such eigenvalues is the *saddle index*. The paper plots
the eigenvalues (its Figs. 6-7) and the unstable eigenvector (Figs. 8-9) in its
nondimensional variables (nomenclature of the paper):

.. code-block:: text

    t'  = t c / L_pp                 (so lambda' = lambda L_pp / c)
    xi' = xi_G / lambda              (already the model's first state)
    u'  = u / c,   v' = v / c
    r'  = r L_pp / U,   p' = p L_pp / U,   U = sqrt(u^2 + v^2) at the fixed point
    chi, phi, delta in radians

so an eigenvector ``y`` of the dimensional Jacobian becomes ``y' = y / scales`` with
``scales = (1, c, c, 1, U/L, 1, U/L, 1)``. Comparing components is meaningful only in
these units (metres per second and radians per second are not commensurable).
``v' = v / c`` is our choice; the paper does not define a nondimensional sway.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from continuation.params import Params
from continuation.stability import eigen
from continuation.typing import ComplexArray, FloatArray

from ..contracts import VesselModel

#: Ship state names (Umeda 1999, Eq. 1), in the order of the state vector.
SHIP_STATES = ("xi_G", "u", "v", "chi", "r", "phi", "p_roll", "delta")

#: Which components make up each motion, as the paper groups them (Figs. 8-9).
MOTION_COMPONENTS = {
    "surge": ("xi_G", "u"),
    "sway": ("v",),
    "yaw": ("chi", "r"),
    "roll": ("phi", "p_roll"),
    "rudder": ("delta",),
}


def paper_scales(
    model: VesselModel, params: Params | FloatArray, x: FloatArray
) -> tuple[FloatArray, float]:
    r"""State scales and time scale of the paper's nondimensionalisation at a point.

    Parameters
    ----------
    model : VesselModel
        Supplies ``celerity`` and ``forces.L``.
    params : Params or ndarray, shape (6,)
    x : ndarray, shape (8,)
        The fixed point (its ``u, v`` set ``U = sqrt(u^2 + v^2)``).

    Returns
    -------
    scales : ndarray, shape (8,)
        ``(1, c, c, 1, U/L, 1, U/L, 1)``: nondimensional ``y' = y / scales``.
    time_scale : float
        ``L / c`` (s): nondimensional eigenvalue ``lambda' = lambda * L / c``.

    Raises
    ------
    ValueError
        If ``x`` does not have shape (8,) or ``U = 0``.
    """
    x = np.asarray(x, dtype=float)
    if x.shape != (len(SHIP_STATES),):
        raise ValueError(f"`x` must have shape ({len(SHIP_STATES)},), got {x.shape}")
    c = float(model.celerity(params))
    L = float(model.forces.L)
    U = float(np.hypot(x[1], x[2]))
    if not U > 0:
        raise ValueError(f"`x` has zero speed U = sqrt(u^2 + v^2); cannot scale r and p: {x}")
    scales = np.array([1.0, c, c, 1.0, U / L, 1.0, U / L, 1.0])
    return scales, L / c


@dataclass(frozen=True, eq=False)
class EigenStructure:
    r"""Eigenvalues and eigenvectors of :math:`DF(\bar x; b)` at one fixed point.

    Attributes
    ----------
    values : ndarray, shape (n,) complex
        Eigenvalues (1/s), sorted by decreasing real part.
    vectors : ndarray, shape (n, n) complex
        Column ``k``: unit eigenvector of ``values[k]`` (dimensional state units).
    saddle_index : int
        Number of eigenvalues with real part ``> eig_tol``.
    scales : ndarray, shape (n,)
        State scales of the paper's nondimensionalisation (see :func:`paper_scales`).
    time_scale : float
        ``L / c`` (s).
    state_names : tuple of str
    """

    values: ComplexArray
    vectors: ComplexArray
    saddle_index: int
    scales: FloatArray
    time_scale: float
    state_names: tuple[str, ...] = SHIP_STATES

    @property
    def values_nondim(self) -> ComplexArray:
        """Eigenvalues in the paper's time ``t' = t c / L``: ``values * L / c``, shape (n,)."""
        return self.values * self.time_scale

    @property
    def unstable_values(self) -> ComplexArray:
        """The ``saddle_index`` eigenvalues with positive real part, shape (k,)."""
        return self.values[: self.saddle_index]

    @property
    def weakest_stable(self) -> float:
        """``min |Re lambda|`` over the stable eigenvalues (1/s): the slowest approach."""
        stable = self.values.real[self.values.real < 0]
        return float(np.min(-stable))

    def approach_rate(self, offset: FloatArray, rel: float = 1e-3) -> float:
        """Slowest stable decay rate present in ``offset`` (a state minus the point), 1/s.

        The offset, shape (n,), is expanded in the eigenvectors, ``offset = V c``;
        modes whose ``|c_k|`` is below ``rel`` times the largest stable one are ignored
        (e.g. the lateral modes at ``chi_c = 0``, which the symmetric motion never
        excites). Falls back to :attr:`weakest_stable`.
        """
        try:
            c = np.abs(np.linalg.solve(self.vectors, np.asarray(offset, dtype=complex)))
        except np.linalg.LinAlgError:
            return self.weakest_stable
        stable = self.values.real < 0
        present = stable & (c > rel * np.max(c[stable], initial=0.0))
        if not np.any(present):
            return self.weakest_stable
        return float(np.min(-self.values.real[present]))

    def unstable_vector(self, k: int = 0, *, nondim: bool = True) -> FloatArray:
        r"""Real unstable eigenvector ``k``, max-norm 1, with a fixed sign.

        Sign convention: the ``xi_G`` component is positive, so ``x + eps * v`` moves
        the ship forward relative to the wave (from the crest: down the front face,
        the paper's "downslope", :math:`0.5 < \xi_G/\lambda < 1`). If that component
        is zero to round-off (``< 1e-12`` of the largest), the largest component is
        made positive instead.

        Parameters
        ----------
        k : int
            Which unstable eigenvalue (0 = largest real part).
        nondim : bool
            Return ``y' = y / scales`` (the paper's units, default) or ``y``.

        Returns
        -------
        ndarray, shape (n,)

        Raises
        ------
        ValueError
            If ``k`` is not below the saddle index, or eigenvalue ``k`` is complex
            (its eigenspace is two-dimensional; use :attr:`vectors`).
        """
        if not (isinstance(k, (int, np.integer)) and 0 <= k < self.saddle_index):
            raise ValueError(f"`k` must be in [0, {self.saddle_index}), got {k!r}")
        lam = self.values[k]
        if abs(lam.imag) > 1e-9 * max(1.0, abs(lam)):
            raise ValueError(
                f"unstable eigenvalue {k} = {lam:.6g} is complex: no single real eigenvector"
            )
        w = self.vectors[:, k]
        # a real eigenvalue has a real eigenvector up to a complex phase: remove it
        w = w * np.exp(-1j * np.angle(w[np.argmax(np.abs(w))]))
        v = np.real(w)
        if nondim:
            v = v / self.scales
        v = v / np.max(np.abs(v))
        i = 0 if abs(v[0]) > 1e-12 else int(np.argmax(np.abs(v)))
        return v if v[i] > 0 else -v

    def dominant_components(self, k: int = 0, *, threshold: float = 0.5) -> tuple[str, ...]:
        """States whose nondimensional unstable-eigenvector component is large.

        Parameters
        ----------
        k : int
            Which unstable eigenvalue.
        threshold : float
            Keep components with ``|y'_i| >= threshold * max |y'|`` (0 < threshold <= 1).

        Returns
        -------
        tuple of str
            State names, largest component first.
        """
        if not (0 < threshold <= 1):
            raise ValueError(f"`threshold` must be in (0, 1], got {threshold}")
        v = np.abs(self.unstable_vector(k))
        order = np.argsort(-v, kind="stable")
        return tuple(self.state_names[i] for i in order if v[i] >= threshold)

    def motion_weights(self, k: int = 0) -> dict[str, float]:
        """Largest nondimensional component per motion (surge, sway, yaw, roll, rudder)."""
        v = np.abs(self.unstable_vector(k))
        idx = {n: i for i, n in enumerate(self.state_names)}
        return {m: float(max(v[idx[s]] for s in comps)) for m, comps in MOTION_COMPONENTS.items()}

    def dominant_motions(self, k: int = 0, *, threshold: float = 0.5) -> tuple[str, ...]:
        """Motions (see :data:`MOTION_COMPONENTS`) with weight ``>= threshold``, largest first."""
        w = self.motion_weights(k)
        return tuple(m for m, val in sorted(w.items(), key=lambda kv: -kv[1]) if val >= threshold)


def eigen_structure(
    model: VesselModel,
    x: FloatArray | Sequence[float],
    params: Params | FloatArray,
    *,
    eig_tol: float = 1e-10,
) -> EigenStructure:
    r"""Eigen-structure of :math:`DF(x; b)` (exact CasADi Jacobian) at a fixed point.

    Parameters
    ----------
    model : VesselModel
    x : array_like, shape (8,)
        The fixed point.
    params : Params or ndarray, shape (6,)
    eig_tol : float
        Real parts above this count as unstable.

    Returns
    -------
    EigenStructure
    """
    xv = model.check_state(x, "x")
    pv = model.check_params(params, "params")
    res = eigen(model, xv, pv, vectors=True, eig_tol=eig_tol)
    scales, ts = paper_scales(model, pv, xv)
    return EigenStructure(
        values=np.asarray(res.values, dtype=complex),
        vectors=np.asarray(res.vectors, dtype=complex),
        saddle_index=int(res.n_unstable),
        scales=scales,
        time_scale=ts,
        state_names=tuple(model.state_names),
    )


__all__ = [
    "MOTION_COMPONENTS",
    "SHIP_STATES",
    "EigenStructure",
    "eigen_structure",
    "paper_scales",
]
