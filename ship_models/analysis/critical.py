r"""The critical Froude number of capsizing due to broaching: one entry point, one result.

Umeda (1999), Figs. 10-15 and 21-23: for a course ``chi_c`` the upslope branch of the
unstable manifold of the crest saddle passes the next crest (periodic, overtaken
motion) below a critical nominal Froude number and is captured by the wave (broaching,
capsize) above it; at the critical value it lands on the neighbouring crest saddle, a
heteroclinic connection, the paper's critical condition for capsizing due to broaching.

:func:`critical_fn` computes it by one of two methods and returns a
:class:`~ship_models.analysis.critical_result.CriticalFn` either way:

``method="bvp"`` (default)
    the connecting orbit solved directly by collocation, ``Fn`` an unknown
    (:func:`~ship_models.analysis.critical_bvp.critical_fn_bvp`; settings
    :class:`~ship_models.analysis.critical_bvp.BVPSettings`);
``method="bisection"``
    bisection of ``Fn`` on the fate of the branch, simulated
    (:mod:`ship_models.analysis.critical_bisection`): ``criterion="first_passage"``
    (default) or ``"final"`` classify the branch with Poincare returns and saddle
    visits (:func:`~ship_models.analysis.critical_bisection.first_passage_bisection`);
    ``"events"`` decides the fate by terminal events only
    (:func:`~ship_models.analysis.critical_bisection.upslope_bisection`).

The critical curve over a range of courses (Fig. 23) is
:func:`ship_models.analysis.critical_curve.critical_curve`.
"""

from __future__ import annotations

from typing import Any

from ..contracts import VesselModel
from .critical_bisection import CRITERIA, FN_BRACKET, first_passage_bisection, upslope_bisection
from .critical_bvp import BVPSettings, critical_fn_bvp
from .critical_result import METHODS, CriticalFn, FateEvaluation
from .params import course, ship_model, ship_params


def critical_fn(
    model: VesselModel | None = None,
    params: Any = None,
    *,
    chi_c: float | None = None,
    method: str = "bvp",
    **options: Any,
) -> CriticalFn:
    """Critical ``Fn`` of one autopilot course by the connecting orbit or by bisection.

    Parameters
    ----------
    model : Umeda4DOF, optional
        Default: a new :func:`ship_models.purse_seiner` (pass one to reuse it).
    params : Params, mapping or array_like, optional
        Wave and autopilot parameters (default the model's); for ``bvp`` its ``Fn``
        is the default guess.
    chi_c : float, optional
        Autopilot course (rad); default the ``chi_c`` of ``params``.
    method : {"bvp", "bisection"}
        See the module docstring.
    **options
        ``bvp``: the keywords of :func:`~ship_models.analysis.critical_bvp.critical_fn_bvp`
        (``guess``, ``Fn_guess``, ``settings``, ``check``, ``throw``, ``progress``
        and the fields of ``BVPSettings``). ``bisection``: those of
        :func:`~ship_models.analysis.critical_bisection.first_passage_bisection`
        (``Fn_bracket``, ``tol``, ``criterion``, ``progress``, ``throw``, manifold
        options), or with ``criterion="events"`` those of
        :func:`~ship_models.analysis.critical_bisection.upslope_bisection`.

    Returns
    -------
    CriticalFn

    Raises
    ------
    ValueError
        For an unknown ``method`` or bad options (named).
    """
    if method not in METHODS:
        raise ValueError(f"`method` must be one of {METHODS}, got {method!r}")
    m = ship_model(model)
    p = ship_params(m, params)
    chi = course(p["chi_c"] if chi_c is None else chi_c)
    if method == "bvp":
        return critical_fn_bvp(chi, model=m, params=p, **options)
    if options.get("criterion") == "events":
        options.pop("criterion")
        return upslope_bisection(chi, model=m, params=p, **options)
    return first_passage_bisection(m, p, chi_c=chi, **options)


__all__ = [
    "CRITERIA",
    "FN_BRACKET",
    "METHODS",
    "BVPSettings",
    "CriticalFn",
    "FateEvaluation",
    "critical_fn",
]
