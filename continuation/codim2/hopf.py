r"""Hopf curves in two parameters: the Roose-Hlavacek augmented system.

Unknowns ``z = (x, p1, kappa, v)`` (shape ``(2n+2,)``), continuation parameter
``p = p2``, fixed normalisation data ``c`` (shape ``(n,)``) and ``sigma > 0``::

    G(z, p2) = ( f(x, p1, p2),  (J^2 + kappa I) v,  c.v - 1,
                 c.(J v) - sigma + kappa / sigma ) = 0

At a Hopf point ``J`` has eigenvalues ``±i omega`` with ``omega = sqrt(kappa)``,
and ``v``, ``J v`` span the real critical eigenspace (Roose & Hlavacek 1985, SIAM
J. Appl. Math. 45, 879-894; Kuznetsov 2004, "Elements of Applied Bifurcation
Theory", 3rd ed., Sec. 10.2.2). Writing ``v = Re(alpha q)`` with ``J q = i omega q``
and ``s = sigma - kappa / sigma``, the two normalisations read
``alpha c^T q = 1 - i s / omega``: they fix ``v`` uniquely in the plane whenever
``c^T q != 0``. ``c`` and ``sigma`` are chosen at the start by
:func:`normalisation`, and the curve is restarted with fresh ones when
:meth:`HopfProblem.normalisation_quality` degrades.

The usual second normalisation ``c^T J v = 0`` has two flaws this module avoids
(see :func:`~continuation.codim2._build.hopf_recipe`): every fold point
(``kappa = 0``, ``J v = 0``) solves it too, so the augmented Jacobian is singular
at Bogdanov-Takens points; and beyond them, on the neutral-saddle curve
(eigenvalues ``±mu``, ``mu**2 = -kappa``), it is singular wherever ``v`` is a real
eigenvector, i.e. where ``c^T J v = ±mu``. The target ``sigma - kappa / sigma`` is
nonzero at ``kappa = 0`` and exceeds ``mu`` for every ``kappa < 0``, so the curve
passes regularly through Bogdanov-Takens points (``kappa`` changes sign) and goes
on as a neutral-saddle curve, where ``omega`` is recorded as NaN.

Codim-2 test functions along the curve, each changing sign at the point it
detects (Kuznetsov 2004, Sec. 10.2.2; Govaerts 2000, Ch. 4):

``bt`` (Bogdanov-Takens)
    ``kappa`` itself.
``zh`` (zero-Hopf)
    The product of the eigenvalues other than the critical pair (the pair is the
    two eigenvalues nearest to solving ``lambda**2 + kappa = 0``).
``hh`` (double Hopf)
    ``prod_{i<j} (lambda_i + lambda_j)`` over the eigenvalues other than the
    critical pair; kept at the located point only if a second imaginary pair exists.
``gh`` (generalised Hopf / Bautin)
    The first Lyapunov coefficient ``l1`` (Kuznetsov 2004, eq. (3.20)), NaN where
    ``kappa <= 0``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ..typing import FloatArray
from ._base import AugmentedProblem, signed_product
from ._build import hopf_recipe
from .fold import _pair_sum_product


def _critical_pair(eigs: np.ndarray, kappa: float) -> tuple[int, int]:
    """Indices of the two eigenvalues closest to ``lambda**2 = -kappa``."""
    order = np.argsort(np.abs(eigs**2 + kappa))
    return int(order[0]), int(order[1])


def _plane(J: FloatArray, v: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Orthonormal basis ``E`` (n, 2) of ``span(v, J v)`` and ``J_P = E^T J E`` (2, 2)."""
    nv = float(np.linalg.norm(v))
    if not nv > 0:
        raise ValueError("`v` must be nonzero")
    e1 = np.asarray(v, dtype=float) / nv
    Je1 = J @ e1
    w = Je1 - (e1 @ Je1) * e1
    nw = float(np.linalg.norm(w))
    if not nw > 1e-12 * max(1.0, float(np.linalg.norm(Je1))):
        raise ValueError("`v`: J v is parallel to v, so (v, J v) spans no critical plane")
    E = np.column_stack([e1, w / nw])
    return E, E.T @ J @ E


def normalisation(
    J: FloatArray, v: FloatArray, kappa: float
) -> tuple[FloatArray, FloatArray, float]:
    """Normalisation data ``(v_new, c, sigma)`` of the Hopf system at a curve point.

    ``v`` is any vector of the critical plane ``P = span(v, J v)`` (invariant under
    ``J``). With an orthonormal basis ``E`` of ``P`` and ``J_P = E^T J E``, the
    normalisation matrix of a unit ``c = E c_hat`` is
    ``N = [c_hat^T; c_hat^T J_P]`` and ``det N = c_hat^T S c_hat`` with
    ``S = sym([[0, 1], [-1, 0]] J_P^T)``. ``c_hat`` is the eigenvector of ``S`` of
    largest ``|eigenvalue|``; for the trace-free ``J_P`` of a Hopf point or a
    neutral saddle this gives ``|det N| >= ||J_P|| / sqrt(2)``. Then
    ``sigma = ||J_P||_2`` and ``v_new = E N^{-1} (1, sigma - kappa / sigma)``, so
    ``c^T v_new = 1`` and ``c^T J v_new = sigma - kappa / sigma`` (the Hopf system's
    normalisation, see :func:`~continuation.codim2._build.hopf_recipe`).

    Returns
    -------
    v_new : ndarray, shape (n,)
    c : ndarray, shape (n,)
        Unit vector in ``P``.
    sigma : float
        Positive.

    Raises
    ------
    ValueError
        If ``v`` is zero or ``J v`` is parallel to ``v``.
    """
    J = np.asarray(J, dtype=float)
    E, JP = _plane(J, v)
    S = np.array([[0.0, 1.0], [-1.0, 0.0]]) @ JP.T
    S = 0.5 * (S + S.T)
    lam, vecs = np.linalg.eigh(S)
    ch = vecs[:, int(np.argmax(np.abs(lam)))]
    N = np.vstack([ch, ch @ JP])
    sigma = float(np.linalg.norm(JP, 2))
    y = np.linalg.solve(N, np.array([1.0, sigma - kappa / sigma]))
    return E @ y, E @ ch, sigma


@dataclass(frozen=True, eq=False)
class HopfProblem(AugmentedProblem):
    """Continuation of a Hopf point of equilibria in the parameters ``(free1, free2)``.

    See the module docstring for the equations. Build it with :meth:`from_point`
    (from a located Hopf point of a one-parameter branch) or :meth:`from_state`.

    Parameters
    ----------
    c : ndarray, shape (n,), optional
        Normalisation vector (``c^T v = 1``).
    sigma : float, optional
        Normalisation scale, positive: ``c^T J v = sigma - kappa / sigma``. If
        ``c`` and ``sigma`` are omitted, both come from ``z0`` (whose ``v`` is then
        replaced by another vector of the same plane) by :func:`normalisation`.
    """

    c: FloatArray | None = None
    sigma: float | None = None

    kind: ClassVar[str] = "hopf"
    n_extra: ClassVar[int] = 1
    extra_names: ClassVar[tuple[str, ...]] = ("kappa",)
    _recipe = staticmethod(hopf_recipe)
    test_names: ClassVar[tuple[str, ...]] = ("bt", "zh", "hh", "gh")

    def __post_init__(self) -> None:
        super().__post_init__()
        if (self.c is None) != (self.sigma is None):
            raise ValueError("give both `c` and `sigma`, or neither (then `z0` is needed)")
        if self.c is None:
            if self.z0 is None or self.p0 is None:
                raise ValueError("`c` and `sigma` are required when `z0`, `p0` are not given")
            z0 = np.array(self.z0)
            J0 = self.state_jacobian(z0, self.p0)
            vh, c, sigma = normalisation(J0, self.vector(z0), self.kappa(z0))
            z0[self.n + 2 :] = vh
            z0.setflags(write=False)
            object.__setattr__(self, "z0", z0)
        else:
            c = np.array(self.c, dtype=float).reshape(-1)
            sigma = float(self.sigma)  # type: ignore[arg-type]
        if c.shape != (self.n,) or not np.all(np.isfinite(c)) or not np.any(c):
            raise ValueError(f"`c` must be a finite nonzero vector of shape ({self.n},)")
        if not (np.isfinite(sigma) and sigma > 0.0):
            raise ValueError(f"`sigma` must be finite and positive, got {sigma}")
        c.setflags(write=False)
        object.__setattr__(self, "c", c)
        object.__setattr__(self, "sigma", sigma)
        object.__setattr__(self, "_cdata", np.append(c, sigma))

    def _c(self) -> FloatArray:
        return self._cdata  # type: ignore[attr-defined,no-any-return]

    @classmethod
    def _start(
        cls, x: FloatArray, p1: float, J: FloatArray, *, omega: float | None = None
    ) -> tuple[FloatArray, dict[str, Any]]:
        """``z0 = (x, p1, kappa, v)`` and the normalisation ``c``, ``sigma`` at ``x``.

        Parameters
        ----------
        x : ndarray, shape (n,)
        p1 : float
        J : ndarray, shape (n, n)
            The Jacobian at ``x``.
        omega : float, optional
            Expected frequency: selects the eigenvalue nearest ``i omega``. Default:
            the complex eigenvalue (``Im > 0``) with the smallest ``|Re|``.

        Raises
        ------
        ValueError
            If ``J`` has no complex eigenvalue pair.
        """
        eigs, vecs = np.linalg.eig(J)
        scale = max(1.0, float(np.max(np.abs(eigs))))
        cand = np.flatnonzero(eigs.imag > 1e-12 * scale)
        if cand.size == 0:
            raise ValueError(
                f"`x`: the Jacobian has no complex eigenvalue pair (eigenvalues {eigs})"
            )
        if omega is not None:
            if not (np.isfinite(omega) and omega > 0):
                raise ValueError(f"`omega` must be positive, got {omega}")
            k = int(cand[np.argmin(np.abs(eigs[cand] - 1j * omega))])
        else:
            k = int(cand[np.argmin(np.abs(eigs[cand].real))])
        lam = eigs[k]
        q = vecs[:, k]
        # rotate q so that Re q ⟂ Im q and |Re q| >= |Im q| (q^T q real positive)
        q = q * np.exp(-0.5j * np.angle(q @ q))  # now |Re q| >= |Im q| > 0
        kappa = float(-(lam**2).real)
        vh, c, sigma = normalisation(J, q.real, kappa)
        return np.concatenate([x, [p1], [kappa], vh]), {"c": c, "sigma": sigma}

    @classmethod
    def _point_start(cls, sp: Any) -> dict[str, Any]:
        """``omega`` of the located Hopf point ``sp`` when it recorded a valid one."""
        om = dict(getattr(sp, "data", {}) or {}).get("omega")
        if om is not None and np.isfinite(om) and om > 0:
            return {"omega": float(om)}
        return {}

    # ----------------------------------------------------------------- unpacking
    def kappa(self, z: FloatArray) -> float:
        """``kappa = omega**2`` (negative on the neutral-saddle continuation)."""
        return float(np.asarray(z, dtype=float)[self.n + 1])

    def omega(self, z: FloatArray) -> float:
        """Hopf frequency ``sqrt(kappa)``; NaN where ``kappa <= 0``."""
        k = self.kappa(z)
        return float(np.sqrt(k)) if k > 0 else float("nan")

    def record(self, z: FloatArray, p: float) -> Mapping[str, float]:
        """``{free1: p1, "omega": omega, "kappa": kappa}``."""
        return {self.free1: self.p1(z), "omega": self.omega(z), "kappa": self.kappa(z)}

    def with_normalisation(self, z: FloatArray, p: float) -> HopfProblem:
        """The same problem with ``c``, ``sigma`` refreshed at the curve point ``(z, p)``.

        Use it to restart a long curve on which the critical plane has turned away
        from the starting ``c``; the returned problem's ``z0`` is ``z`` with ``v``
        replaced by the one :func:`normalisation` picks in the same plane, and
        ``p0 = p``.
        """
        z = np.array(z, dtype=float)
        vh, c, sigma = normalisation(self.state_jacobian(z, p), self.vector(z), self.kappa(z))
        z[self.n + 2 :] = vh
        return HopfProblem(
            self.system, self.params, self.free1, self.free2, self.sparse, z, float(p), c, sigma
        )

    def normalisation_quality(self, z: FloatArray, p: float) -> float:
        """How well ``c``, ``sigma`` fix ``v`` in its plane: about 1 good, 0 singular.

        With ``E`` an orthonormal basis of the critical plane ``span(v, J v)``, the
        normalisation rows restricted to it form ``N = [c^T E; c^T J E]``; the
        quality is ``|det N| / (|c|^2 ||E^T J E||_2)``, invariant under scaling of
        ``c`` and ``J``. It is at least ``1/sqrt(2)`` right after
        :func:`normalisation` and tends to 0 where the fixed ``c`` loses the plane:
        ``c^T q -> 0`` on a Hopf curve, ``c`` orthogonal to the null vector at a
        Bogdanov-Takens point, or to a real eigenvector on a neutral-saddle curve.
        :func:`~continuation.codim2.curves.continue_codim2` restarts with
        :meth:`with_normalisation` before that.
        """
        J = self.state_jacobian(z, p)
        try:
            E, JP = _plane(J, self.vector(z))
        except ValueError:
            return 0.0
        c = self._c()[: self.n]
        N = np.vstack([c @ E, c @ J @ E])
        scale = float(c @ c) * float(np.linalg.norm(JP, 2))
        return float(abs(np.linalg.det(N)) / scale) if scale > 0 else 0.0

    # ----------------------------------------------------------------- codim 2
    def eigenvectors(
        self, z: FloatArray, p: float
    ) -> tuple[complex, np.ndarray, np.ndarray] | None:
        r"""Critical eigenvalue and normalised eigenvectors at a Hopf point.

        Returns ``(i omega, q, p)`` with :math:`J q = i\omega q`,
        :math:`J^T p = -i\omega p`, :math:`\bar q^T q = 1`, :math:`\bar p^T q = 1`;
        None where ``kappa <= 0``.
        """
        kappa = self.kappa(z)
        if kappa <= 0:
            return None
        om = np.sqrt(kappa)
        J = self.state_jacobian(z, p)
        v = self.vector(z)
        q = J @ v + 1j * om * v  # (J + i omega) v lies along q
        q = q / np.linalg.norm(q)
        _, _, vh = np.linalg.svd(J.T + 1j * om * np.eye(self.n))
        pv = vh[-1].conj()
        s = np.vdot(pv, q)
        pv = pv / np.conj(s)
        return 1j * om, q, pv

    def lyapunov_coefficient(self, z: FloatArray, p: float) -> float:
        r"""First Lyapunov coefficient :math:`l_1` at a Hopf point.

        .. math::

            l_1 = \frac{1}{2\omega}\,\mathrm{Re}\big[\langle p, C(q,q,\bar q)\rangle
                - 2\langle p, B(q, J^{-1} B(q,\bar q))\rangle
                + \langle p, B(\bar q, (2i\omega I - J)^{-1} B(q,q))\rangle\big]

        (Kuznetsov 2004, eq. (3.20)), with ``<q, q> = <p, q> = 1``. Negative:
        supercritical (stable cycles), positive: subcritical. NaN if
        ``kappa <= 0``. ``B`` and ``C`` come from exact CasADi directional
        derivatives (finite differences for NumPy-only systems).
        """
        ev = self.eigenvectors(z, p)
        if ev is None:
            return float("nan")
        iom, q, pv = ev
        om = iom.imag
        x = self.state(z)
        Pv = self.param_vector(z, p)
        J = self.state_jacobian(z, p)
        fns = self.functions
        a, b = q.real, q.imag
        # stage 1: B(a,a), B(b,b), B(a,b) and C(v,v,v) for v = a, b, a+b, a-b
        Baa, Bbb, Bab = fns.bmap(x, Pv, np.column_stack([a, b, a]), np.column_stack([a, b, b])).T
        Caaa, Cbbb, Capb, Camb = fns.cmap(x, Pv, np.column_stack([a, b, a + b, a - b])).T
        C_aab = (Capb - Camb - 2 * Cbbb) / 6
        C_abb = (Capb + Camb - 2 * Caaa) / 6
        Cqqqb = Caaa + C_abb + 1j * (C_aab + Cbbb)  # C(q, q, conj q)
        Bqqb = Baa + Bbb  # B(q, conj q), real
        Bqq = Baa - Bbb + 2j * Bab  # B(q, q)
        h11 = np.linalg.solve(J, Bqqb)
        h20 = np.linalg.solve(2j * om * np.eye(self.n) - J, Bqq)
        # stage 2: B(q, h11) = B(a,h11) + i B(b,h11);
        # B(conj q, h20) = B(a,hr) + B(b,hi) + i (B(a,hi) - B(b,hr))
        hr, hi = h20.real, h20.imag
        U = np.column_stack([a, b, a, b, a, b])
        W = np.column_stack([h11, h11, hr, hi, hi, hr])
        B1, B2, B3, B4, B5, B6 = fns.bmap(x, Pv, U, W).T
        Bq_h11 = B1 + 1j * B2
        Bqb_h20 = B3 + B4 + 1j * (B5 - B6)
        val = np.vdot(pv, Cqqqb) - 2 * np.vdot(pv, Bq_h11) + np.vdot(pv, Bqb_h20)
        return float(val.real / (2 * om))

    def _spectral_tests(self, z: FloatArray, p: float) -> dict[str, float]:
        def compute() -> dict[str, float]:
            eigs = np.linalg.eigvals(self.state_jacobian(z, p))
            i, j = _critical_pair(eigs, self.kappa(z))
            rest = np.delete(eigs, [i, j])
            return {
                "zh": signed_product(rest),
                "hh": _pair_sum_product(rest),
            }

        return self._memo("spectral", z, p, compute)  # type: ignore[no-any-return]

    def test_functions(self, z: FloatArray, p: float) -> dict[str, float]:
        """Values of the codim-2 test functions ``{"bt", "zh", "hh", "gh"}``."""
        return {name: self.test_function(name, z, p) for name in self.test_names}

    def test_function(self, name: str, z: FloatArray, p: float) -> float:
        """One codim-2 test function by name (see :attr:`test_names`)."""
        if name not in self.test_names:
            raise ValueError(f"`name` must be one of {self.test_names}, got {name!r}")
        if name == "bt":
            return self.kappa(z)
        if name == "gh":
            return self.lyapunov_coefficient(z, p)
        return self._spectral_tests(z, p)[name]

    def classify(self, name: str, z: FloatArray, p: float, tol: float = 1e-6) -> str | None:
        """Confirm a located zero of test function ``name``; return its kind or None.

        ``zh``/``gh`` need ``kappa > 0`` (a true Hopf point); ``hh`` needs a second
        purely imaginary pair (otherwise a neutral saddle is crossed).
        """
        kappa = self.kappa(z)
        if name == "bt":
            return "bt"
        if kappa <= 0:
            return None
        if name in ("zh", "gh"):
            return name
        eigs = np.linalg.eigvals(self.state_jacobian(z, p))
        rest = np.delete(eigs, list(_critical_pair(eigs, kappa)))
        scale = max(1.0, float(np.max(np.abs(eigs))))
        ok = np.any((np.abs(rest.real) <= tol * scale) & (np.abs(rest.imag) > tol * scale))
        return "hh" if ok else None


__all__ = ["HopfProblem"]
