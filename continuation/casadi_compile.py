r"""Compiled copies of CasADi functions, cached on disk, with a clean fall-back.

Two ways to ask, one cache:

- :func:`compiled` (synchronous): the compiled copy now, compiling it first when that
  is allowed (:func:`allow_compilation`; the connection solver's drivers);
- :func:`compiled_soon` (background): the compiled copy if its library is ready, else
  ``None`` after starting one low-priority compiler process for it (the periodic-orbit
  stage functions, the simulator's right-hand side); callers keep using the virtual
  machine and ask again. A library another process is already compiling is waited for,
  not compiled twice.

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
``BROACHKIT_CACHE_DIR`` sets the cache directory (else ``$BROACHKIT_CACHE/casadi``,
else ``$XDG_CACHE_HOME/broachkit/casadi`` or ``~/.cache/broachkit/casadi``).
``CC`` names the compiler (default the first of ``cc``, ``gcc``, ``clang`` found).
"""

from __future__ import annotations

import contextvars
import functools
import hashlib
import logging
import os
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, ParamSpec, TypeVar

import casadi as ca
import numpy as np

from .atomic import replace

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


_LOOKUP: contextvars.ContextVar[bool] = contextvars.ContextVar(
    "broachkit_compiled_lookup", default=True
)


@contextmanager
def uncompiled() -> Iterator[None]:
    """Inside the block, :func:`compiled` returns the original function at once.

    For one-off models (a vessel rebuilt with one coefficient changed, in a
    sensitivity, calibration or uncertainty study): their functions are never in the
    cache, and looking there means generating their C code only to learn that (about
    30 ms a function, 2 s of the main job's sensitivity step).
    """
    token = _LOOKUP.set(False)
    try:
        yield
    finally:
        _LOOKUP.reset(token)


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
    root = os.environ.get("BROACHKIT_CACHE")
    if root:
        return Path(root) / "casadi"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "broachkit" / "casadi"


def _compiler() -> str | None:
    if os.environ.get("BROACHKIT_COMPILE", "1").strip().lower() in ("0", "false", "no", "off"):
        return None
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
    if not _LOOKUP.get() or _compiler() is None:
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
        src, lib = _library([fn], cc)
    except RuntimeError as exc:
        return _fallback(fn, f"no C code: {exc}")
    memo = _MEMO.get((name, lib.stem))
    if memo is not None:
        return memo
    folder = lib.parent
    if not allowed and not lib.exists():
        return fn  # not cached, and compiling is not worth it here (module docstring)
    try:
        if not lib.exists():
            folder.mkdir(parents=True, exist_ok=True)
            marker = lib.with_suffix(".building")
            try:
                marker.mkdir()
            except FileExistsError:
                if time.time() - marker.stat().st_mtime < STALE_S:
                    # another process is compiling it: the VM now, the library next time
                    log.info("CasADi function %r is being compiled by another process", name)
                    return fn
            try:
                with tempfile.TemporaryDirectory(dir=folder) as tmp:
                    c_file = Path(tmp) / f"{name}.c"
                    c_file.write_text(src)
                    out = Path(tmp) / "lib.so"
                    log.info("compiling CasADi function %r (once; cached in %s)", name, folder)
                    subprocess.run(
                        [cc, *FLAGS, "-o", str(out), str(c_file)],
                        check=True, capture_output=True, timeout=TIMEOUT,
                    )  # fmt: skip
                    replace(out, lib)  # atomic: a concurrent process sees all or nothing
            finally:
                shutil.rmtree(marker, ignore_errors=True)
        ext = ca.external(name, str(lib))
    except (OSError, subprocess.SubprocessError, RuntimeError) as exc:
        return _fallback(fn, f"{type(exc).__name__}: {str(exc)[:200]}")
    if not _same(fn, ext):
        return _fallback(fn, "the compiled function disagrees with the original")
    _MEMO[(name, lib.stem)] = ext
    return ext


# ---- background compilation (compiled_soon)

#: Smallest function (CasADi instructions) :func:`compiled_soon` compiles (smaller
#: ones gain little from it).
MIN_INSTRUCTIONS = 5000

#: A work directory older than this (s) is a compilation that died: it is redone.
STALE_S = 2 * TIMEOUT

# id(fn) -> [fn, state ("queued" | "pending" | "elsewhere" | "ready" | "off"), library, loaded]
_STATE: dict[int, list[Any]] = {}
# id(fn) -> (compiler process, its work directory)
_PENDING: dict[int, tuple[Any, Path]] = {}


def _library(fns: list[ca.Function], cc: str) -> tuple[str, Path]:
    """The C source of ``fns`` and the cache path of its library.

    The library is named after ``fns[0]`` and the SHA-256 of the source, the compiler
    command, CasADi and the platform.
    """
    gen = ca.CodeGenerator("fn.c", {"with_header": False})
    for f in fns:
        gen.add(f)
    src = gen.dump()
    parts = [src, cc, *FLAGS, ca.__version__, platform.machine(), sys.platform]
    digest = hashlib.sha256("\0".join(parts).encode()).hexdigest()[:24]
    return src, cache_dir() / f"{fns[0].name()}_{digest}.so"


def _load(name: str, lib: Path) -> ca.Function | None:
    try:
        return ca.external(name, str(lib))
    except RuntimeError as exc:  # a broken library: the virtual machine
        log.warning("compiled CasADi function %s not loadable (%s); using the VM", lib, exc)
        return None


def _ready(key: int, lib: Path) -> ca.Function | None:
    entry = _STATE[key]
    loaded = _load(entry[0].name(), lib)
    if loaded is not None and not _same(entry[0], loaded):
        log.warning("compiled %s disagrees with the original; using the VM", lib)
        loaded = None
    entry[1:] = ["ready" if loaded is not None else "off", lib, loaded]
    return loaded


def compiled_soon(fn: ca.Function, jacobian: bool = False) -> ca.Function | None:
    """The compiled copy of ``fn`` if its library is ready now, else ``None``.

    The first call for a function missing from the cache starts one compiler process
    for it in the background (``nice``, at most one per process at a time; a library
    that another process is compiling is waited for instead) and returns ``None``: the
    caller keeps using ``fn`` and asks again (cheap) until it gets the compiled copy,
    or until :func:`settled` says there will be none (too small, no compiler, failure).

    Parameters
    ----------
    fn : casadi.Function
        A function of at least :data:`MIN_INSTRUCTIONS` instructions.
    jacobian : bool
        Put ``fn.jacobian()`` in the same library, where CasADi finds it as the
        derivative of the external function (``jac_<name>``): for a right-hand side
        handed to an integrator, which needs its Jacobian.

    Returns
    -------
    casadi.Function or None
    """
    key = id(fn)
    entry = _STATE.get(key)
    if entry is not None and entry[0] is fn:
        if entry[1] == "pending":
            return _poll(key)
        if entry[1] == "elsewhere":
            return _poll_elsewhere(key)
        if entry[1] != "queued":
            return entry[3]
    cc = _compiler()
    if cc is None or fn.n_instructions() < MIN_INSTRUCTIONS:
        _STATE[key] = [fn, "off", None, None]
        return None
    for other in list(_PENDING):
        _poll(other)
    if _PENDING:  # one background compilation per process at a time: ask again later
        _STATE[key] = [fn, "queued", None, None]
        return None
    fns = [fn, fn.jacobian()] if jacobian else [fn]
    try:
        src, lib = _library(fns, cc)
    except RuntimeError as exc:
        log.info("no C code for %s (%s): using the VM", fn.name(), exc)
        _STATE[key] = [fn, "off", None, None]
        return None
    folder = lib.parent
    _STATE[key] = [fn, "off", lib, None]
    if lib.exists():
        return _ready(key, lib)
    work = lib.with_suffix(".building")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        try:
            work.mkdir()
        except FileExistsError:
            if time.time() - work.stat().st_mtime < STALE_S:  # another process compiles it
                _STATE[key][1] = "elsewhere"
                return _poll_elsewhere(key)
            shutil.rmtree(work, ignore_errors=True)
            work.mkdir()
        (work / "fn.c").write_text(src)
        # the shell moves the library into place (an atomic rename) and removes the
        # work directory even if this process has ended by then
        script = (f'{shlex.quote(cc)} {" ".join(FLAGS)} fn.c -o fn.so && '
                  f'mv -f fn.so {shlex.quote(str(lib))}; rc=$?; cd .. && '
                  f'rm -rf {shlex.quote(str(work))}; exit $rc')  # fmt: skip
        nice = ["nice", "-n", "10"] if shutil.which("nice") else []
        proc = subprocess.Popen([*nice, "sh", "-c", script], cwd=work,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)  # fmt: skip
    except OSError as exc:
        log.info("no compiled CasADi functions (%s): using the VM", exc)
        return None
    log.info("compiling %s (%d instructions) in the background", fn.name(), fn.n_instructions())
    _STATE[key][1] = "pending"
    _PENDING[key] = (proc, work)
    return None


def settled(fn: ca.Function) -> bool:
    """True once :func:`compiled_soon` has given its final answer for ``fn``."""
    entry = _STATE.get(id(fn))
    return entry is not None and entry[0] is fn and entry[1] in ("ready", "off")


def _poll_elsewhere(key: int) -> ca.Function | None:
    entry = _STATE[key]
    lib: Path = entry[2]
    if lib.exists():
        return _ready(key, lib)
    work = lib.with_suffix(".building")
    if not work.exists():  # the other process gave up (or failed): no library
        entry[1] = "off"
    return None


def _poll(key: int) -> ca.Function | None:
    proc, work = _PENDING[key]
    rc = proc.poll()
    if rc is None:
        return None
    del _PENDING[key]
    entry = _STATE[key]
    lib = entry[2]
    err = proc.stderr.read().decode(errors="replace")[-500:] if proc.stderr else ""
    if proc.stderr:
        proc.stderr.close()
    shutil.rmtree(work, ignore_errors=True)
    if rc != 0 or not lib.exists():
        log.warning("compiling %s failed (exit %s): %s; using the VM", entry[0].name(), rc, err)
        entry[1] = "off"
        return None
    return _ready(key, lib)


def wait(timeout: float | None = None) -> None:
    """Wait for this process's background compilations (tests and benchmarks)."""
    for proc, _ in list(_PENDING.values()):
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            pass


__all__ = [
    "FLAGS",
    "MIN_INSTRUCTIONS",
    "TIMEOUT",
    "allow_compilation",
    "cache_dir",
    "compilation_allowed",
    "compiled",
    "compiled_soon",
    "compiling",
    "settled",
    "uncompiled",
    "wait",
]
