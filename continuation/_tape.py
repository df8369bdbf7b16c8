r"""Instruction tapes of CasADi SX functions, for the compiled step kernel.

A CasADi SX function is a straight-line program: ``Function.n_instructions()``
instructions, each an operation code with its operands' and result's slots in a work
vector (``instruction_id`` / ``instruction_input`` / ``instruction_output`` /
``instruction_constant``). :func:`tape_of` copies that program into integer arrays, so
that one generic compiled interpreter (:mod:`continuation._kernel`) can evaluate any
system's residual and Jacobian without compiling code per system.

:func:`step_kernel_for` decides whether a problem gets the compiled step: dense, a
CasADi trace, at most ``MAX_KERNEL_SIZE - 1`` states, a tape of at most
``MAX_TAPE_INSTRUCTIONS`` supported operations (Numba, a required dependency, is
imported only then). Large tapes stay on CasADi's own virtual machine, which evaluates them faster
than the interpreted tape (measurement in ``benchmarks/README.md``, *Engine design
measurements*), while small systems gain from the step as one call.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._jit import compiled

log = logging.getLogger(__name__)

#: Largest bordered order ``n + 1`` run by the compiled step kernel.
MAX_KERNEL_SIZE = 33
#: Longest tape of ``(f, [G_z G_p])`` run by the kernel (a longer one is evaluated faster
#: by CasADi's virtual machine than the per-step savings of the kernel).
MAX_TAPE_INSTRUCTIONS = 2000

# kernel op codes (small consecutive integers for the interpreter's branches)
_K_INPUT, _K_OUTPUT, _K_CONST, _K_ASSIGN = 0, 1, 2, 3
_K_ADD, _K_SUB, _K_MUL, _K_DIV, _K_NEG, _K_SQ, _K_TWICE, _K_INV = 4, 5, 6, 7, 8, 9, 10, 11
_K_SQRT, _K_EXP, _K_LOG, _K_POW, _K_CONSTPOW = 12, 13, 14, 15, 16
_K_SIN, _K_COS, _K_TAN, _K_ASIN, _K_ACOS, _K_ATAN = 17, 18, 19, 20, 21, 22
_K_SINH, _K_COSH, _K_TANH, _K_ASINH, _K_ACOSH, _K_ATANH = 23, 24, 25, 26, 27, 28
_K_FABS, _K_SIGN, _K_FMIN, _K_FMAX, _K_ATAN2, _K_HYPOT, _K_COPYSIGN = 29, 30, 31, 32, 33, 34, 35
_K_LT, _K_LE, _K_EQ, _K_NE, _K_NOT, _K_AND, _K_OR, _K_IF_ELSE_ZERO = 36, 37, 38, 39, 40, 41, 42, 43
_K_FLOOR, _K_CEIL, _K_FMOD, _K_ERF, _K_LOG1P, _K_EXPM1 = 44, 45, 46, 47, 48, 49

_CASADI_OPS = {
    "OP_INPUT": _K_INPUT, "OP_OUTPUT": _K_OUTPUT, "OP_CONST": _K_CONST,
    "OP_ASSIGN": _K_ASSIGN, "OP_LIFT": _K_ASSIGN,
    "OP_ADD": _K_ADD, "OP_SUB": _K_SUB, "OP_MUL": _K_MUL, "OP_DIV": _K_DIV,
    "OP_NEG": _K_NEG, "OP_SQ": _K_SQ, "OP_TWICE": _K_TWICE, "OP_INV": _K_INV,
    "OP_SQRT": _K_SQRT, "OP_EXP": _K_EXP, "OP_LOG": _K_LOG, "OP_POW": _K_POW,
    "OP_CONSTPOW": _K_CONSTPOW, "OP_SIN": _K_SIN, "OP_COS": _K_COS, "OP_TAN": _K_TAN,
    "OP_ASIN": _K_ASIN, "OP_ACOS": _K_ACOS, "OP_ATAN": _K_ATAN, "OP_SINH": _K_SINH,
    "OP_COSH": _K_COSH, "OP_TANH": _K_TANH, "OP_ASINH": _K_ASINH, "OP_ACOSH": _K_ACOSH,
    "OP_ATANH": _K_ATANH, "OP_FABS": _K_FABS, "OP_SIGN": _K_SIGN, "OP_FMIN": _K_FMIN,
    "OP_FMAX": _K_FMAX, "OP_ATAN2": _K_ATAN2, "OP_HYPOT": _K_HYPOT,
    "OP_COPYSIGN": _K_COPYSIGN, "OP_LT": _K_LT, "OP_LE": _K_LE, "OP_EQ": _K_EQ,
    "OP_NE": _K_NE, "OP_NOT": _K_NOT, "OP_AND": _K_AND, "OP_OR": _K_OR,
    "OP_IF_ELSE_ZERO": _K_IF_ELSE_ZERO, "OP_FLOOR": _K_FLOOR, "OP_CEIL": _K_CEIL,
    "OP_FMOD": _K_FMOD, "OP_ERF": _K_ERF, "OP_LOG1P": _K_LOG1P, "OP_EXPM1": _K_EXPM1,
}  # fmt: skip


@dataclass(frozen=True)
class Tape:
    """The instruction tape of a CasADi SX function, as arrays.

    Attributes
    ----------
    op, ia, ib, io : ndarray, shape (k,) int32
        Per instruction: the kernel op code and ``(a, b, out)``: for ``INPUT`` ``a`` is
        the argument and ``b`` the non-zero index, for ``OUTPUT`` ``a`` is the work
        slot, ``b`` the non-zero index and ``out`` the result index; otherwise ``a``,
        ``b`` are the operands' work slots and ``out`` the result's.
    consts : ndarray, shape (k,)
        The constant of each ``CONST`` instruction (0 elsewhere).
    n_work : int
        Size of the work vector.
    """

    op: Any
    ia: Any
    ib: Any
    io: Any
    consts: Any
    n_work: int


def tape_of(fn: Any) -> Tape | None:
    """The instruction tape of an SX ``casadi.Function``, or None.

    None if it has an operation the interpreter does not support (or is not an SX function).
    """
    import casadi as ca

    to_kernel = {getattr(ca, name): k for name, k in _CASADI_OPS.items() if hasattr(ca, name)}
    try:
        n_ins = int(fn.n_instructions())
        code = np.zeros((n_ins, 4), dtype=np.int64)
        consts = np.zeros(n_ins)
        for k in range(n_ins):
            op = to_kernel.get(int(fn.instruction_id(k)))
            if op is None:
                return None
            ins, outs = fn.instruction_input(k), fn.instruction_output(k)
            row = code[k]
            row[0] = op
            if op == _K_CONST:
                consts[k] = float(fn.instruction_constant(k))
                row[3] = outs[0]
            elif op == _K_INPUT:
                row[1], row[2], row[3] = ins[0], ins[1], outs[0]
            elif op == _K_OUTPUT:
                row[1], row[2], row[3] = ins[0], outs[1], outs[0]
            else:
                row[1] = ins[0]
                row[2] = ins[1] if len(ins) > 1 else 0
                row[3] = outs[0]
        cols = [np.ascontiguousarray(code[:, j], dtype=np.int32) for j in range(4)]
        return Tape(cols[0], cols[1], cols[2], cols[3], consts, int(fn.sz_w()))
    except (RuntimeError, NotImplementedError, TypeError) as exc:  # an MX function
        log.debug("no instruction tape: %s", exc)
        return None


def linearisation_tape(system: Any, index: int) -> tuple[Tape, Any, Any] | None:
    """Tape of ``(u, p) -> (f, nz)`` for a system with a CasADi trace.

    Here ``u = (x, p_index)`` (shape ``(n + 1,)``; the ``index`` entry of ``p`` is ignored)
    and ``nz`` are the structural non-zeros of ``[df/dx, df/dp_index]``; with their row and
    column indices (int64 arrays). None without a trace, with an operation the interpreter
    does not support, or with more than ``MAX_TAPE_INSTRUCTIONS``.
    """
    import casadi as ca

    if getattr(system, "_ca", None) is None:
        return None
    n, m = system.n_states, system.n_params
    U = ca.SX.sym("u", n + 1)
    P = ca.SX.sym("p", m)
    X = U[:n]
    Pk = ca.vertcat(P[:index], U[n], P[index + 1 :]) if m > 1 else U[n]
    F = system.symbolic(X, Pk)
    top = ca.horzcat(ca.jacobian(F, X), ca.jacobian(F, U[n]))
    rows, cols = top.sparsity().get_triplet()
    nz = ca.vertcat(*top.nonzeros()) if top.nnz() else ca.SX(0, 1)
    fn = ca.Function("linearisation", [U, P], [ca.densify(F), nz])
    if fn.n_instructions() > MAX_TAPE_INSTRUCTIONS:
        return None
    tape = tape_of(fn)
    if tape is None:
        return None
    return tape, np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64)


def step_kernel_for(problem: Any) -> Any:
    """The compiled step of an :class:`~continuation.problem.EquilibriumProblem`, or None.

    :class:`continuation._kernel.StepKernel`; None when sparse, without a CasADi trace, too
    large, or with an unsupported operation.
    """
    if getattr(problem, "sparse", True):
        return None
    system = getattr(problem, "system", None)
    index = getattr(problem, "_index", None)
    if system is None or index is None or system.n_states + 1 > MAX_KERNEL_SIZE:
        return None
    cache = system.__dict__.setdefault("_kernel_tapes", {})  # one tape per free index
    got = cache.get(int(index), False)
    if got is False:
        got = cache[int(index)] = linearisation_tape(system, int(index))
    if got is None:
        return None
    tape, rows, cols = got
    kernel = compiled("continuation._kernel")  # (imports Numba, only now)
    return kernel.StepKernel(tape, rows, cols, system.n_states, problem.params.values)


__all__ = [
    "MAX_KERNEL_SIZE",
    "MAX_TAPE_INSTRUCTIONS",
    "Tape",
    "linearisation_tape",
    "step_kernel_for",
    "tape_of",
]
