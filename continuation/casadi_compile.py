r"""Compiled copies of CasADi functions, cached on disk, with a clean fall-back.

A system's right-hand side and its Jacobians are CasADi ``SX`` functions run by
CasADi's virtual machine. The collocation residual evaluates them at every
collocation point (a few hundred per evaluation), so for a large model (the ship:
about 12 000 instructions for ``f``, 26 000 for ``df/dx``) the virtual machine is most
of the cost of a Newton step. :func:`compiled` writes the function's C code
(``casadi.CodeGenerator``), compiles it once with the system's C compiler into a shared
library in a cache directory, named by the SHA-256 of the code and the compiler
command, and loads it (``casadi.external``); the next process finds the library and
loads it at once. The compiled function computes the same expression graph
(checked on one random input against the original before it is used).

Compiling costs some 5-9 s per function, which pays off only when the function is
evaluated many times (a critical curve: hundreds of Newton steps) and is wasted on a
one-off solve, above all of a perturbed model whose code differs in its constants (a
sensitivity study builds dozens). So :func:`compiled` compiles a function that is not
yet in the cache only inside an :func:`allow_compilation` block, opened by drivers of
long computations; elsewhere it returns the cached library when there is one and the
original function otherwise.

Whenever anything is missing or fails (no compiler, an unwritable cache directory,
a compile error or timeout, a mismatch), the original function is returned and the
reason is logged once: the result is the same, only slower.

Environment
-----------
``BROACHKIT_COMPILE=0`` turns compilation off (the original functions are used).
``BROACHKIT_CACHE_DIR`` sets the cache directory (default
``$XDG_CACHE_HOME/broachkit/casadi`` or ``~/.cache/broachkit/casadi``).
``CC`` names the compiler (default the first of ``cc``, ``gcc``, ``clang`` found).
"""

from __future__ import annotations

import contextvars
import functools
import hashlib
import logging
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import ParamSpec, TypeVar

import casadi as ca
import numpy as np

log = logging.getLogger(__name__)

#: Compiler flags: -O1 compiles the ship's functions in about 5-9 s each and runs them
#: 4-6 times faster than CasADi's virtual machine.
FLAGS = ("-O1", "-shared", "-fPIC")

#: Largest time (s) allowed for one compilation.
TIMEOUT = 300.0

_MEMO: dict[tuple[str, str], ca.Function] = {}
_WARNED: set[str] = set()
# per function object (the original is kept alive with it, so ids stay unique)
_BY_ID: dict[int, tuple[ca.Function, ca.Function]] = {}


P = ParamSpec("P")
R = TypeVar("R")

_ALLOWED: contextvars.ContextVar[bool] = contextvars.ContextVar(
    "broachkit_allow_compilation", default=False
)


@contextmanager
def allow_compilation(allowed: bool = True) -> Iterator[None]:
    """Let :func:`compiled` compile functions missing from the cache inside the block.

    Open it around computations that evaluate the same functions many times (a
    critical curve, a long continuation); outside, only libraries already in the cache
    are used. Nested blocks restore the outer setting on exit.

    Parameters
    ----------
    allowed : bool
        ``False`` forbids new compilations inside an outer allowing block.
    """
    token = _ALLOWED.set(bool(allowed))
    try:
        yield
    finally:
        _ALLOWED.reset(token)


def compiling(func: Callable[P, R]) -> Callable[P, R]:
    """Decorator: ``func`` runs inside :func:`allow_compilation` (a long driver)."""

    @functools.wraps(func)
    def wrapper(*args: P.args, **kwargs: P.kwargs) -> R:
        with allow_compilation():
            return func(*args, **kwargs)

    return wrapper


def compilation_allowed() -> bool:
    """True inside an :func:`allow_compilation` block."""
    return _ALLOWED.get()


def cache_dir() -> Path:
    """The directory of the compiled libraries (see the module docstring)."""
    env = os.environ.get("BROACHKIT_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "broachkit" / "casadi"


def _compiler() -> str | None:
    cc = os.environ.get("CC")
    if cc:
        return shutil.which(cc)
    for name in ("cc", "gcc", "clang"):
        path = shutil.which(name)
        if path:
            return path
    return None


def _fallback(fn: ca.Function, why: str) -> ca.Function:
    if why not in _WARNED:
        _WARNED.add(why)
        log.info("CasADi function %r not compiled (%s): the VM evaluates it", fn.name(), why)
    return fn


def _same(fn: ca.Function, ext: ca.Function) -> bool:
    """Both give the same outputs (to rounding) on one random input."""
    rng = np.random.default_rng(0)
    args = [rng.uniform(0.1, 1.0, fn.sparsity_in(i).shape) for i in range(fn.n_in())]
    for a, b in zip(fn.call(args), ext.call(args), strict=True):
        a, b = np.asarray(ca.DM(a)), np.asarray(ca.DM(b))
        if a.shape != b.shape or not np.allclose(a, b, rtol=1e-12, atol=1e-12, equal_nan=True):
            return False
    return True


def compiled(fn: ca.Function) -> ca.Function:
    """A compiled copy of the CasADi function ``fn`` (or ``fn`` itself as the fall-back).

    Parameters
    ----------
    fn : casadi.Function
        Any function CasADi can generate C code for (an ``SX`` function of the system).

    Returns
    -------
    casadi.Function
        Same inputs and outputs as ``fn``; an external function loaded from the cache
        when compilation is possible (already cached, or compiled now inside an
        :func:`allow_compilation` block), else ``fn``. Derivatives of the external
        function are not available: use it for evaluations only.
    """
    if os.environ.get("BROACHKIT_COMPILE", "1") == "0":
        return fn
    allowed = compilation_allowed()
    known = _BY_ID.get(id(fn))
    if known is not None and known[0] is fn and (known[1] is not fn or not allowed):
        return known[1]
    out = _compiled(fn, allowed)
    _BY_ID[id(fn)] = (fn, out)
    return out


def _compiled(fn: ca.Function, allowed: bool = True) -> ca.Function:
    cc = _compiler()
    if cc is None:
        return _fallback(fn, "no C compiler found")
    name = fn.name()
    try:
        gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
        gen.add(fn)
        src = gen.dump()
    except RuntimeError as exc:
        return _fallback(fn, f"no C code: {exc}")
    key = hashlib.sha256(
        "\0".join([src, cc, *FLAGS, ca.__version__]).encode()
    ).hexdigest()[:24]
    memo = _MEMO.get((name, key))
    if memo is not None:
        return memo
    folder = cache_dir()
    lib = folder / f"{name}_{key}.so"
    if not allowed and not lib.exists():
        return fn  # not cached, and compiling is not worth it here (module docstring)
    try:
        if not lib.exists():
            folder.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryDirectory(dir=folder) as tmp:
                c_file = Path(tmp) / f"{name}.c"
                c_file.write_text(src)
                out = Path(tmp) / "lib.so"
                log.info("compiling CasADi function %r (once; cached in %s)", name, folder)
                subprocess.run(
                    [cc, *FLAGS, "-o", str(out), str(c_file)],
                    check=True, capture_output=True, timeout=TIMEOUT,
                )  # fmt: skip
                os.replace(out, lib)  # atomic: a concurrent process sees all or nothing
        ext = ca.external(name, str(lib))
    except (OSError, subprocess.SubprocessError, RuntimeError) as exc:
        return _fallback(fn, f"{type(exc).__name__}: {str(exc)[:200]}")
    if not _same(fn, ext):
        return _fallback(fn, "the compiled function disagrees with the original")
    _MEMO[(name, key)] = ext
    return ext


__all__ = ["FLAGS", "TIMEOUT", "allow_compilation", "cache_dir", "compilation_allowed", "compiled",
           "compiling"]
