r"""Continue a fold or Hopf point of a one-parameter branch in a second parameter.

:func:`continue_codim2` builds the augmented problem (:class:`FoldProblem` or
:class:`HopfProblem`) at a located special point, continues it with the
one-parameter driver (:func:`continuation.driver.continue_branch`), and detects the
codim-2 points on the curve through the driver's :class:`~continuation.events.Event`
mechanism, with the test functions of the problem:

=========== ============================== ===========================================
curve       point                          test function (sign change)
=========== ============================== ===========================================
fold        Bogdanov-Takens ``bt``         ``tr adj J`` (second zero eigenvalue)
fold        cusp ``cusp``                  ``v^T adj(J) B(v, v)`` (quadratic coeff.)
fold        zero-Hopf ``zh``               ``prod (l_i + l_j)`` without the zero eig.
hopf        Bogdanov-Takens ``bt``         ``kappa = omega**2``
hopf        zero-Hopf ``zh``               product of the non-critical eigenvalues
hopf        double Hopf ``hh``             ``prod (l_i + l_j)`` without the pair
hopf        generalised Hopf ``gh``        first Lyapunov coefficient ``l1``
=========== ============================== ===========================================

Each located zero is confirmed by the problem's ``classify`` (a ``zh``/``hh`` zero
without an imaginary pair is a neutral saddle and is dropped; ``bt``/``cusp`` zeros
where ``J`` has a kernel of dimension two or more are dropped; a sign change
through a pole, as of ``l1`` where ``J`` becomes singular, is dropped; a cusp zero
at a located BT point is that BT point) and stored as a
:class:`~continuation.branch.SpecialPoint` of kind ``bt``, ``cusp``, ``zh``, ``gh``
(``hh`` has no dedicated kind yet and is stored as ``user`` with label ``HH<k>``),
keeping the locator's ``located`` and ``error`` (its estimate of the distance in
arclength to the zero; larger than ``detect.tol`` where the test function is noisy,
e.g. ``l1`` from finite differences without CasADi, or the point sits next to a
branch point of the curve).

The resulting branch's ``p`` is ``free2``; ``records[free1]`` holds the first
parameter (and, on Hopf curves, ``records["omega"]`` and ``records["kappa"]``);
``x`` holds the full unknown vector ``z`` with columns named by
``problem.state_names``.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from ..arguments import integer_at_least
from ..branch import SpecialKind
from ..settings import ContinuationSettings, DetectionSettings, NewtonSettings
from ._base import AugmentedProblem
from .fold import FoldProblem
from .hopf import HopfProblem

log = logging.getLogger(__name__)

_PREFIX = "codim2:"
#: ``Event.continuity`` of the codim-2 test functions that get a continuity check (the
#: factor used for branch points on a branch)
_CONTINUITY = {"zh": 10.0, "hh": 10.0}
_KIND = {
    "bt": SpecialKind.BOGDANOV_TAKENS,
    "cusp": SpecialKind.CUSP,
    "zh": SpecialKind.ZERO_HOPF,
    "gh": SpecialKind.GENERALIZED_HOPF,
    "hh": SpecialKind.DOUBLE_HOPF,
}
_LABEL = {"bt": "BT", "cusp": "CP", "zh": "ZH", "gh": "GH", "hh": "HH"}


def codim2_events(problem: AugmentedProblem, names: Sequence[str] | None = None) -> tuple:
    """Driver events for the codim-2 test functions of ``problem``.

    Parameters
    ----------
    problem : FoldProblem or HopfProblem
    names : sequence of str, optional
        Subset of ``problem.test_names`` (default: all).

    Returns
    -------
    tuple of Event
        Named ``"codim2:<name>"``; :func:`relabel_codim2` turns the special points
        they produce into codim-2 points.
    """
    from ..events import Event

    avail = tuple(problem.test_names)  # type: ignore[attr-defined]
    chosen = avail if names is None else tuple(names)
    bad = [n for n in chosen if n not in avail]
    if bad:
        raise ValueError(f"`detect` names {bad} are not test functions of {avail}")

    def make(name: str) -> Callable[[Any, float], float]:
        def fn(z: Any, p: float) -> float:
            return problem.test_function(name, z, p)  # type: ignore[attr-defined,no-any-return]

        return fn

    # the eigenvalue-product tests (zh, hh) are smooth along the curve but jump where
    # eigenvalue pairs switch (next to a branch point of the curve): with a continuity
    # check such a sign change is reported as bracketed, not as a located point. The
    # scaled-adjugate tests (bt, cusp) are not checked: in stiff problems their
    # round-off floor near the zero exceeds the continuity bound (l1 has poles instead,
    # see _is_pole)
    return tuple(
        Event(_PREFIX + n, make(n), continuity=_CONTINUITY.get(n), report=False) for n in chosen
    )


def _is_pole(branch: Any, problem: AugmentedProblem, name: str, sp: Any) -> bool:
    """True when the sign change of test function ``name`` is a pole, not a zero.

    ``l1`` contains ``J^{-1}`` and changes sign through infinity where the Hopf
    curve meets a zero eigenvalue. A located zero has ``|g|`` well below the
    values at the two rows around it; an unlocated one (best trial point) at
    least no larger than both.
    """
    i = sp.index
    if not 0 <= i < len(branch) - 1:
        return False
    g = abs(problem.test_function(name, np.asarray(sp.x, dtype=float), sp.p))  # type: ignore[attr-defined]
    ga = abs(problem.test_function(name, branch.x[i], branch.p[i]))  # type: ignore[attr-defined]
    gb = abs(problem.test_function(name, branch.x[i + 1], branch.p[i + 1]))  # type: ignore[attr-defined]
    if sp.located:
        return bool(g > 0.5 * min(ga, gb))
    return bool(g > 2.0 * max(ga, gb))


#: a ``bt``/``cusp`` zero is dropped where the second-smallest singular value of ``J``
#: falls below this fraction of its larger value at the two rows around the zero
KERNEL_GROWTH = 1e-3


def _second_singular_value(problem: AugmentedProblem, z: Any, p: float) -> float:
    """Second-smallest singular value of ``J = df/dx`` at the curve point ``(z, p)``."""
    s = np.linalg.svd(problem.state_jacobian(np.asarray(z, dtype=float), p), compute_uv=False)
    return float(s[-2])


def _kernel_grows(branch: Any, problem: AugmentedProblem, sp: Any) -> bool:
    """True when ``J`` has a kernel of dimension two or more at the point ``sp``.

    A Bogdanov-Takens point has ``J`` of rank ``n - 1`` (its double zero eigenvalue in
    a nilpotent Jordan block; Kuznetsov 2004, Sec. 8.4, ``J_0 != 0`` for ``n = 2``),
    and the cusp test ``v^T adj(J) B(v, v)`` vanishes wherever ``adj(J) = 0``, i.e.
    wherever the rank drops below ``n - 1``. Along the curve the second-smallest
    singular value ``s_{n-1}`` of ``J`` is continuous; it is judged against its own
    values at the two rows around the point (so neither the scale of the model nor
    the stiffness of ``J`` enters): at a point where the rank drops it falls below
    ``KERNEL_GROWTH`` times the larger of them. Such a zero (e.g. ``J = 0`` in two
    dimensions) marks a point of higher codimension, neither a BT point nor a cusp.
    """
    i = sp.index
    if problem.n < 2 or not 0 <= i < len(branch) - 1:
        return False
    s_pt = _second_singular_value(problem, sp.x, sp.p)
    s_rows = max(
        _second_singular_value(problem, branch.x[i], branch.p[i]),
        _second_singular_value(problem, branch.x[i + 1], branch.p[i + 1]),
    )
    return bool(s_pt < KERNEL_GROWTH * s_rows)


#: a cusp-test zero within this relative distance of a located BT point is that point
COINCIDE = 1e-7


def _cusp_at_bt(problem: AugmentedProblem, sp: Any, bts: Sequence[Any]) -> bool:
    """True when the cusp-test zero ``sp`` is a located Bogdanov-Takens point of ``bts``.

    The cusp test ``v^T adj(J) B(v, v)`` is ``w^T B(v, v)`` with the left null vector
    ``w = adj(J)^T v``; at a BT point ``w`` is orthogonal to ``v`` and the test is the
    BT point's own quadratic coefficient, which vanishes identically in models with an
    invariant subspace (a zero row of ``J``: ``w`` a unit vector off the subspace, and
    ``B(v, v)`` inside it). Such a zero at the BT point (the same point to ``COINCIDE``,
    relative, in the state, ``free1`` and ``free2``) is that BT point (degenerate), not
    a cusp; a cusp near but apart from a BT point (e.g. close to the codim-3 point
    where they meet) is kept.
    """
    m = problem.n + 1
    u = np.append(np.asarray(sp.x, dtype=float)[:m], sp.p)
    for bt in bts:
        ub = np.append(np.asarray(bt.x, dtype=float)[:m], bt.p)
        if np.max(np.abs(u - ub)) <= COINCIDE * (1.0 + np.max(np.abs(ub))):
            return True
    return False


def relabel_codim2(branch: Any, problem: AugmentedProblem) -> Any:
    """Turn the driver's ``codim2:<name>`` user events into codim-2 special points.

    Zeros that ``problem.classify`` rejects are dropped; the rest get kind ``bt``,
    ``cusp``, ``zh``, ``gh`` (or ``user`` for ``hh``), labels ``BT1``, ``CP1``, ...,
    and ``data`` with the first parameter (and ``omega``, ``kappa`` on Hopf curves)
    and the test-function value ``g`` at the located point.
    """
    counters: dict[str, int] = {}
    out = []
    settings = getattr(branch, "settings", None)
    tol = settings.detect.tol if settings is not None else DetectionSettings().tol
    bts = [
        sp
        for sp in branch.special_points
        if sp.label == _PREFIX + "bt" and sp.located and not _kernel_grows(branch, problem, sp)
    ]
    for sp in branch.special_points:
        if not sp.label.startswith(_PREFIX):
            out.append(sp)
            continue
        name = sp.label[len(_PREFIX) :]
        z = np.asarray(sp.x, dtype=float)
        kind = problem.classify(name, z, sp.p) if sp.located else name  # type: ignore[attr-defined]
        if kind is not None and _is_pole(branch, problem, name, sp):
            kind = None
        if kind in ("bt", "cusp") and _kernel_grows(branch, problem, sp):
            log.warning(
                "%s test zero at %s=%.10g dropped: the Jacobian's kernel has dimension "
                "two or more there (a point of higher codimension, not a %s)",
                name,
                branch.free,
                sp.p,
                "Bogdanov-Takens point" if kind == "bt" else "cusp",
            )
            kind = None
        if kind == "cusp" and _cusp_at_bt(problem, sp, bts):
            log.info(
                "fold curve: cusp test zero at %s=%.10g is the BT point there (its quadratic "
                "coefficient vanishes), not a cusp",
                branch.free,
                sp.p,
            )
            kind = None
        if kind is None:
            log.debug("dropped %s zero at %s=%g (not a codim-2 point)", name, branch.free, sp.p)
            continue
        counters[kind] = counters.get(kind, 0) + 1
        data = dict(sp.data)
        data.update(problem.record(z, sp.p))
        if not sp.located:
            log.warning(
                "%s point between %s=%g and %g was bracketed but not located",
                _LABEL[kind],
                branch.free,
                *sp.bracket,
            )
        elif sp.error > tol:  # (NaN: no estimate, no warning)
            log.warning(
                "%s point at %s=%.10g was located with error %.1e > tol %.1e",
                _LABEL[kind],
                branch.free,
                sp.p,
                sp.error,
                tol,
            )
        label = f"{_LABEL[kind]}{counters[kind]}"
        out.append(dataclasses.replace(sp, kind=_KIND[kind], label=label, data=data))
    kept = tuple(n for n in getattr(branch, "event_names", ()) if not n.startswith(_PREFIX))
    return dataclasses.replace(branch, special_points=tuple(out), event_names=kept)


def _curve_settings(settings: ContinuationSettings | None) -> ContinuationSettings:
    """Settings for a curve: no one-parameter fold/Hopf detection on it.

    A zero eigenvalue sits on every fold curve and a critical pair on every Hopf
    curve, so the one-parameter Hopf test (a change in the count of unstable pairs)
    would fire on round-off; turning points of the curve in ``free2`` are not
    bifurcations. Branch points of the curve are still detected if asked for.
    """
    s = settings or ContinuationSettings()
    det: DetectionSettings = dataclasses.replace(s.detect, fold=False, hopf=False)
    return dataclasses.replace(s, detect=det)


# ---------------------------------------------------------------------------- stitching
def _concat(pieces: Sequence[Any], status: Any, message: str) -> Any:
    """Join branches whose first row repeats the previous one's last row."""
    first = pieces[0]
    rows = [slice(None)] + [slice(1, None)] * (len(pieces) - 1)
    keys: list[str] = []
    for br in pieces:
        keys += [k for k in br.records if k not in keys]
    sps: list[Any] = []
    offset_rows, offset_s = 0, 0.0
    for br in pieces:
        for sp in br.special_points:
            sps.append(dataclasses.replace(sp, index=sp.index + offset_rows, s=sp.s + offset_s))
        offset_rows += len(br) - 1
        offset_s += float(np.sum(br.ds))

    def cat(attr: str) -> Any:
        return np.concatenate([getattr(b, attr)[r] for b, r in zip(pieces, rows, strict=True)])

    def rec(k: str) -> Any:
        return np.concatenate(
            [
                (b.records[k] if k in b.records else np.full(len(b), np.nan))[r]
                for b, r in zip(pieces, rows, strict=True)
            ]
        )

    return dataclasses.replace(
        first,
        p=cat("p"),
        x=cat("x"),
        eigenvalues=cat("eigenvalues"),
        n_unstable=cat("n_unstable"),
        ds=cat("ds"),
        newton_iters=cat("newton_iters"),
        records={k: rec(k) for k in keys},
        special_points=tuple(sps),
        status=status,
        message=message,
    )


def _first_row(br: Any, status: Any) -> Any:
    """A one-row branch holding the first row of ``br``."""
    return dataclasses.replace(
        br,
        p=br.p[:1],
        x=br.x[:1],
        eigenvalues=br.eigenvalues[:1],
        n_unstable=br.n_unstable[:1],
        ds=np.zeros(1),
        newton_iters=br.newton_iters[:1],
        records={k: v[:1] for k, v in br.records.items()},
        special_points=(),
        status=status,
        message=status.value,
    )


def _relabel_all(br: Any) -> Any:
    """Number the codim-2 labels (BT1, BT2, ...) along the final branch."""
    counters: dict[str, int] = {}
    out = []
    for sp in br.special_points:
        prefix = sp.label.rstrip("0123456789")
        if prefix in _LABEL.values() and sp.label != prefix:
            counters[prefix] = counters.get(prefix, 0) + 1
            sp = dataclasses.replace(sp, label=f"{prefix}{counters[prefix]}")
        out.append(sp)
    return dataclasses.replace(br, special_points=tuple(out))


_RENORM = _PREFIX + "renormalise"
#: restart a Hopf curve with fresh normalisation data below this quality
RENORMALISE_BELOW = 0.2


def _one_direction(
    problem: AugmentedProblem,
    sign: float,
    settings: ContinuationSettings,
    run: Callable[[AugmentedProblem, Any, float, ContinuationSettings], Any],
    max_restarts: int,
) -> Any:
    """Continue in one direction, restarting Hopf curves whose normalisation degrades."""
    from ..status import Status

    pieces: list[Any] = []
    prob, z, p = problem, problem.z0, problem.p0
    if p is None:
        raise ValueError("`problem` has no start point (p0): build it with from_state")
    ds = abs(settings.ds)
    steps_left = settings.max_steps
    status, message = Status.MAX_STEPS, ""
    try:
        while True:
            st = dataclasses.replace(settings, ds=sign * ds, max_steps=steps_left)
            br = run(prob, z, p, st)
            renorm = br.status is Status.EVENT and _RENORM in br.message
            br = dataclasses.replace(
                br, special_points=tuple(s for s in br.special_points if s.label != _RENORM)
            )
            pieces.append(br)
            status, message = br.status, br.message
            steps_left -= max(len(br) - 1, 0)
            if not renorm or len(br) < 2 or steps_left < 1 or len(pieces) > max_restarts:
                if renorm:
                    status = Status.MAX_STEPS if steps_left < 1 else Status.SINGULAR
                    message = "normalisation of the Hopf system degenerated (too many restarts)"
                break
            z, p = br.x[-1], float(br.p[-1])
            dp = float(br.p[-1] - br.p[-2])
            sign = 1.0 if dp > 0 else -1.0 if dp < 0 else sign
            ds = float(np.clip(abs(br.ds[-1]) or ds, settings.ds_min, settings.ds_max))
            prob = prob.with_normalisation(z, p)  # type: ignore[attr-defined]
            z = prob.z0
            log.info("Hopf curve: new normalisation at %s=%.8g", prob.free, p)
    except KeyboardInterrupt:
        if not pieces:
            raise
        status, message = Status.INTERRUPTED, Status.INTERRUPTED.value
    if len(pieces) > 1:
        message = f"{message} ({len(pieces) - 1} renormalisation restart(s))"
    return _concat(pieces, status, message)


def continue_codim2(
    branch: Any,
    sp: Any,
    free2: str,
    settings: ContinuationSettings | None = None,
    direction: str = "both",
    *,
    detect: bool | Sequence[str] = True,
    events: Sequence[Any] = (),
    algorithm: Any = None,
    newton_settings: NewtonSettings | None = None,
    max_restarts: int = 20,
    throw: bool = False,
    progress: Callable[..., Any] | None = None,
) -> Any:
    """Continue the fold or Hopf point ``sp`` of ``branch`` in the parameter ``free2``.

    Parameters
    ----------
    branch : Branch
        A branch of equilibria (computed in this session, so it holds its problem).
    sp : SpecialPoint
        A located ``fold`` or ``hopf`` point of ``branch``.
    free2 : str
        The second parameter, continued along the curve; must differ from
        ``branch.free``.
    settings : ContinuationSettings, optional
        Step sizes and bounds refer to ``free2``; ``max_steps`` applies to each
        direction. One-parameter fold/Hopf detection is switched off on the curve.
    direction : {"both", "forward", "backward"}
        ``"forward"`` starts with ``free2`` moving in the direction of
        ``sign(settings.ds)``; ``"both"`` returns one branch ordered from the
        backward end to the forward end.
    detect : bool or sequence of str
        Detect codim-2 points (all test functions of the problem, or the named
        subset, e.g. ``("bt", "cusp")``); ``False`` for none.
    events : sequence of Event
        Extra user events, ``fn(z, p)`` with ``z`` the curve's unknowns.
    algorithm : ContinuationAlgorithm, optional
        Default: the driver's default (PALC).
    newton_settings : NewtonSettings, optional
        For the initial correction of the augmented system.
    max_restarts : int
        Hopf curves are restarted with fresh normalisation data
        (:meth:`HopfProblem.with_normalisation`) when
        :meth:`HopfProblem.normalisation_quality` falls below
        ``RENORMALISE_BELOW``; at most this many times per direction.
    throw : bool
        Raise :class:`~continuation.errors.ContinuationError` if the curve ends in a
        numerical failure instead of returning it with a bad ``status``.
    progress : callable, optional
        Passed to the driver (called with each new row).

    Returns
    -------
    Branch
        The curve: ``p`` is ``free2``, ``records[free1]`` the first parameter (and
        ``omega``, ``kappa`` on Hopf curves), ``x`` the unknowns ``z`` (columns
        ``problem.state_names``), ``special_points`` the codim-2 points found.
        ``problem`` is the augmented problem of the start.

    Raises
    ------
    ValueError
        Bad ``branch``/``sp``/``free2``/``direction``/``detect``/``max_restarts``.
    ConvergenceError
        If the augmented system cannot be solved at the start point.
    """
    from ..driver import continue_branch
    from ..errors import ContinuationError
    from ..status import Status

    kind = str(getattr(getattr(sp, "kind", None), "value", getattr(sp, "kind", None)))
    if kind == "fold":
        cls: type[AugmentedProblem] = FoldProblem
    elif kind == "hopf":
        cls = HopfProblem
    else:
        raise ValueError(f"`sp` must be a fold or hopf point, got kind {kind!r}")
    if direction not in ("both", "forward", "backward"):
        raise ValueError(f"`direction` must be 'both', 'forward' or 'backward', got {direction!r}")
    integer_at_least("max_restarts", max_restarts, 0)
    if isinstance(detect, str):
        raise ValueError("`detect` must be a bool or a sequence of names, got a string")
    problem = cls.from_point(branch, sp, free2, newton_settings=newton_settings)
    names: Sequence[str] | None
    if detect is True:
        names = None
    elif detect is False or detect is None:
        names = ()
    else:
        names = tuple(detect)
    codim2_events(problem, names)  # validates the names
    st = _curve_settings(settings)
    p0 = float(problem.p0)  # type: ignore[arg-type]
    if not st.p_min <= p0 <= st.p_max:
        raise ValueError(f"`settings`: start value {free2}={p0} lies outside [p_min, p_max]")

    def run(prob: AugmentedProblem, z: Any, p: float, s: ContinuationSettings) -> Any:
        evs = codim2_events(prob, names)
        if isinstance(prob, HopfProblem):
            from ..events import Event

            def quality(zz: Any, pp: float, prob: HopfProblem = prob) -> float:
                return prob.normalisation_quality(zz, pp) - RENORMALISE_BELOW

            evs = (*evs, Event(_RENORM, quality, direction="down", terminal=True))
        br = continue_branch(
            prob,
            z,
            p,
            algorithm,
            s,
            events=(*evs, *events),
            direction="forward",
            throw=False,
            progress=progress,
        )
        return relabel_codim2(br, prob)

    sgn = 1.0 if st.ds > 0 else -1.0
    if direction == "both":
        back = _one_direction(problem, -sgn, st, run, max_restarts)
        if back.status is Status.INTERRUPTED:
            curve = back.reversed()
        else:
            try:
                fwd = _one_direction(problem, sgn, st, run, max_restarts)
            except KeyboardInterrupt:  # before the first forward row: keep the backward part
                fwd = _first_row(back, Status.INTERRUPTED)
            status = fwd.status
            for b in (fwd, back):
                if not b.status.ok:
                    status = b.status
            if Status.INTERRUPTED in (back.status, fwd.status):
                status = Status.INTERRUPTED
            msg = f"backward: {back.message}; forward: {fwd.message}"
            curve = _concat([back.reversed(), fwd], status, msg)
    else:
        s = sgn if direction == "forward" else -sgn
        curve = _one_direction(problem, s, st, run, max_restarts)
    curve = dataclasses.replace(_relabel_all(curve), problem=problem)
    if curve.status is Status.INTERRUPTED:
        return curve
    if throw and not curve.status.ok:
        raise ContinuationError(curve.message or curve.status.value)
    return curve


__all__ = ["RENORMALISE_BELOW", "codim2_events", "continue_codim2", "relabel_codim2"]
