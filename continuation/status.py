"""Termination status of every numerical routine; each value is a human message."""

from __future__ import annotations

import enum


class Status(enum.Enum):
    """Why a routine stopped. ``status.value`` is a message for humans."""

    SUCCESS = "Reached the requested end of the computation."
    MAX_STEPS = "The maximum number of continuation steps was reached. Increase `max_steps`."
    PARAM_BOUND = "The free parameter reached the bound [p_min, p_max]."
    CLOSED_LOOP = "The branch closed on itself (returned to its start point)."
    DS_MIN = (
        "Step size fell below `ds_min`: Newton failed to converge. "
        "Try a smaller `ds` or a looser `newton.tol`."
    )
    SINGULAR = "Singular Jacobian: the linear system could not be solved."
    NEWTON_FAILED = "Newton's method did not converge."
    NONFINITE = "The model returned a non-finite value (NaN or inf)."
    INTERRUPTED = "Interrupted by the user; the results computed so far are kept."
    EVENT = "A terminal event stopped the computation."
    INTEGRATION_FAILED = (
        "The time integrator failed (step size underflow, repeated error-test or "
        "corrector failures, or a non-finite state); the part computed so far is kept."
    )
    NO_BRACKET = "The two ends of the bracket give the same outcome; there is no switch to locate."
    UNDECIDED = (
        "An evaluation ended undecided (time limit reached before its fate was known); "
        "increase `t_max`."
    )
    PERIOD_UNBOUNDED = (
        "The period of the cycles grows without bound (past `period_max`, or until the "
        "parameter is within its discretisation error of its limit): the branch "
        "approaches a homoclinic or heteroclinic orbit."
    )
    MAX_ITER = "The maximum number of iterations/evaluations was reached before the tolerance."
    DISCRETISATION_ERROR = (
        "The estimated discretisation error of a solved parameter exceeds its tolerance; "
        "allow more mesh refinements or a higher collocation degree."
    )
    TRUNCATION_ERROR = (
        "The estimated truncation error of a solved parameter exceeds its tolerance; "
        "lengthen the truncation interval T (or allow more extensions)."
    )
    REJECTED = (
        "A converged solution failed a validity check of the application (the message "
        "says which); it is not a solution of the question asked."
    )
    NO_SOLUTION = (
        "The sought solution does not exist at these parameters (the message says why, "
        "e.g. the branch it lives on has ended at a fold)."
    )

    @property
    def ok(self) -> bool:
        """True when the routine ended normally (not a numerical failure)."""
        return self in (
            Status.SUCCESS,
            Status.MAX_STEPS,
            Status.PARAM_BOUND,
            Status.CLOSED_LOOP,
            Status.EVENT,
            Status.PERIOD_UNBOUNDED,
        )


class StatusResult:
    """Mixin of a result that carries a ``status``: ``success`` means ``SUCCESS``.

    What ``SUCCESS`` promises (converged within the stated error, valid) is said by
    each result class where it documents its ``status``.
    """

    status: Status

    @property
    def success(self) -> bool:
        """True when ``status`` is ``SUCCESS``."""
        return self.status is Status.SUCCESS


__all__ = ["Status", "StatusResult"]
