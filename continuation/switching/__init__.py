r"""Branch switching at simple branch points (AUTO's ``ISW=-1``, MATCONT's "BP -> EP").

At a simple branch point :math:`u^* = (z^*, p^*)` of :math:`G(u) = 0`,
:math:`G: R^{N+1} \to R^N`, two branches of solutions cross transversally. The
Jacobian :math:`A = DG(u^*) = [G_z\; G_p]` (``N x (N+1)``) has rank ``N - 1``:

.. math::

    \ker A = \mathrm{span}\{q_1, q_2\}, \qquad \ker A^T = \mathrm{span}\{\psi\},

with :math:`q_1, q_2` orthonormal in the ``theta`` inner product of the continuation
(:func:`~continuation.algorithms.base.theta_weights`). Every branch through
:math:`u^*` has the form :math:`u(s) = u^* + s\,(\alpha q_1 + \beta q_2) + O(s^2)`;
projecting the second-order expansion of :math:`G(u(s)) = 0` on :math:`\psi` gives the
*algebraic bifurcation equation* (ABE; Keller 1977; Doedel, Keller & Kernevez 1991;
Govaerts 2000; Kuznetsov 2004, Sec. 10.2)

.. math::

    c_{11}\alpha^2 + 2 c_{12}\alpha\beta + c_{22}\beta^2 = 0, \qquad
    c_{ij} = \psi^T D^2G(u^*)[q_i, q_j].

The point is a *simple* branch point when :math:`c_{12}^2 - c_{11}c_{22} > 0`: the ABE
then has two real root directions, the tangents of the two branches. One is the
tangent :math:`t_{old}` of the branch the point was found on; the other,
:math:`t_{new}`, is the tangent of the crossing branch. The roots are computed from the
eigen-decomposition :math:`C = [[c_{11}, c_{12}], [c_{12}, c_{22}]] = \lambda_- e_-
e_-^T + \lambda_+ e_+ e_+^T` (:math:`\lambda_- < 0 < \lambda_+`):
:math:`(\alpha, \beta) \propto \sqrt{-\lambda_-}\, e_+ \pm \sqrt{\lambda_+}\, e_-`.
Only when the two branches are orthogonal (transcritical and pitchfork bifurcations in
the usual coordinates) is :math:`t_{new}` simply the kernel direction orthogonal to
:math:`t_{old}`; in general it is not, which is why the ABE is solved.

The second derivatives :math:`D^2G[a, b]` come from the CasADi trace of the model
(forward-over-forward directional derivatives, ``casadi.jtimes``) for an
:class:`~continuation.problem.EquilibriumProblem` of a traced
:class:`~continuation.system.System`, else from central differences of the Jacobian,
:math:`(A(u^* + h b) - A(u^* - h b))\, a / 2h`.

The kernel comes from the SVD of :math:`A\, W^{-1/2}` (``W = diag(theta weights)``)
for dense or moderately sized problems, and for large sparse ones from two solves with
the bordered matrix (Govaerts 2000, on bordered matrices; Keller 1977)

.. math::

    M = \begin{pmatrix} A & b \\ C^T & 0 \end{pmatrix}, \quad
    M \begin{pmatrix} q_k \\ y \end{pmatrix} = e_{N + k}, \quad
    M^T \begin{pmatrix} \psi \\ \eta \end{pmatrix} = e_{N + 2},

first with ``b`` random and ``C = W [t_old, r]``, then again with ``b = psi`` and
``C = W [q_1, q_2]`` (which makes ``M`` well conditioned).

Start on the crossing branch. With :math:`\varphi_2` the part of :math:`t_{new}`
``theta``-orthogonal to :math:`t_{old}` and :math:`S = \langle\varphi_2,
t_{new}\rangle_\theta = \sin\angle(t_{old}, t_{new})`, the start point for the half
``sign = +-1`` solves, by Newton's method from :math:`u^* + \mathrm{sign}\, a\, t_{new}`,

.. math::

    G(u) = 0, \qquad \langle \varphi_2, u - u^* \rangle_\theta = \mathrm{sign}\, a S,

a hyperplane *parallel to the current branch* at distance :math:`a S` from it, so the
corrector cannot fall back onto the current branch near :math:`u^*` (``a`` is the
``amplitude``). The corrected point is accepted only if it lies within ``a / 2`` of the
prediction and its tangent is within 45 degrees of :math:`t_{new}`; the continuation is
then started there with the tangent oriented along :math:`\pm t_{new}`
(:func:`~continuation.driver.continue_branch`). With ``direction="both"`` the run
towards :math:`u^*` passes through the branch point (where the driver detects it again,
on the new branch) into the other half; the rows next to :math:`u^*` are checked to lie
on the crossing branch (their offset from the current branch,
:math:`\langle\varphi_2, u - u^*\rangle_\theta`, must be at least half of
:math:`S \langle t_{new}, u - u^*\rangle_\theta`).

References
----------
Keller, H. B. (1977), "Numerical solution of bifurcation and nonlinear eigenvalue
problems", in *Applications of Bifurcation Theory*, P. H. Rabinowitz (ed.), Academic
Press, 359-384.

Doedel, E. J., Keller, H. B. & Kernevez, J. P. (1991), "Numerical analysis and control
of bifurcation problems (I): bifurcation in finite dimensions", *Int. J. Bifurcation
and Chaos* 1(3), 493-520.

Govaerts, W. J. F. (2000), *Numerical Methods for Bifurcations of Dynamical
Equilibria*, SIAM.

Kuznetsov, Yu. A. (2004), *Elements of Applied Bifurcation Theory*, 3rd ed., Springer,
Sec. 10.2.

Modules
-------
kernel
    :math:`q_1, q_2, \psi` by SVD or bordered solves.
second_derivatives
    :math:`D^2G[a, b]` from CasADi or central differences.
bifurcation_equation
    The ABE, its roots and :class:`CrossingTangents` (:func:`crossing_tangents`).
start
    The start point on the hyperplane, the oriented start of the continuation.
switch
    :func:`switch_branch`: input, degeneracy test, both halves, the crossing check.

Its tolerances are module constants of the module that uses them (e.g.
``kernel.KERNEL_GAP``, ``switch.CROSSING_RATIO``); ``DENSE_KERNEL_MAX`` is read from
``kernel`` by :func:`crossing_tangents` and from ``switch`` by :func:`switch_branch`.
"""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:  # for type checkers; _EXPORTS is what runs (names imported on first use)
    from .bifurcation_equation import CrossingTangents, crossing_tangents
    from .switch import switch_branch

#: Sub-module -> the public names it defines (imported on first use: issue 27).
_EXPORTS: dict[str, tuple[str, ...]] = {
    "bifurcation_equation": ("CrossingTangents", "crossing_tangents"),
    "switch": ("switch_branch",),
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
del TYPE_CHECKING, lazy_exports

__all__ = ["CrossingTangents", "crossing_tangents", "switch_branch"]
