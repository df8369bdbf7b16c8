r"""Large CasADi point functions compiled to machine code, cached on disk (optional).

The collocation Jacobian evaluates ``f, f_x, f_p`` at every stage point, ``N m`` points
per Newton iteration. CasADi's virtual machine runs a large expression graph (the
ship's 8-state model: about 27 000 instructions for ``f`` and ``f_x``) at some 7 ns per
instruction; the same function generated as C and compiled (``gcc -O1``) runs about 5x
faster (``benchmarks/README.md``, *The ship's cycles*). Compiling it takes some 10-20 s,
so it is done once per machine and function:

* :func:`compiled` hashes the generated C source (with the compiler command, the
  CasADi version and the platform) and returns the compiled function when its shared
  library is in the cache directory;
* otherwise it starts the compiler in the background (one process, at low priority)
  and returns None: the caller keeps using the virtual machine and asks again
  (:func:`compiled` is cheap after the first call), switching when the library is
  ready; later processes load it at once.

Only functions of at least :data:`MIN_INSTRUCTIONS` instructions are compiled (smaller
ones gain little). Nothing is compiled when no C compiler is found, when the cache
directory cannot be written, or when ``BROACHKIT_COMPILE=0``; then the virtual machine
is used throughout. The cache directory is ``$BROACHKIT_CACHE`` or
``~/.cache/broachkit``, subdirectory ``casadi``. The compiled function computes the
same expressions as the virtual machine (the same graph, in the same order), so results
agree to round-off (tested).
"""

from __future__ import annotations

import hashlib
import logging
import os
import pathlib
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
from typing import Any

log = logging.getLogger(__name__)

#: Smallest function (CasADi instructions) that is compiled.
MIN_INSTRUCTIONS = 5000

#: The compiler flags (``-O1``: about as fast as ``-O2`` on generated straight-line
#: code, at half the compile time).
CFLAGS = ("-O1", "-fPIC", "-shared")

# id(fn) -> [fn, state ("pending" | "ready" | "off"), library path, loaded function]
_STATE: dict[int, list[Any]] = {}
# id(fn) -> (compiler process, its work directory)
_PENDING: dict[int, tuple[Any, pathlib.Path]] = {}


def cache_dir() -> pathlib.Path:
    """The directory of the compiled libraries."""
    root = os.environ.get("BROACHKIT_CACHE") or os.path.join(
        os.path.expanduser("~"), ".cache", "broachkit"
    )
    return pathlib.Path(root) / "casadi"


def _compiler() -> str | None:
    if os.environ.get("BROACHKIT_COMPILE", "1").strip() in ("0", "false", "no", "off"):
        return None
    for name in (os.environ.get("CC", ""), "gcc", "cc", "clang"):
        if name and shutil.which(name):
            return name
    return None


def _source_and_key(fn: Any, cc: str) -> tuple[str, str]:
    import casadi as ca

    with tempfile.TemporaryDirectory(prefix="bk_cg_") as tmp:
        cwd = os.getcwd()
        try:
            os.chdir(tmp)
            fn.generate("fn.c", {"with_header": False})
        finally:
            os.chdir(cwd)
        src = pathlib.Path(tmp, "fn.c").read_text()
    h = hashlib.sha256()
    for part in (src, cc, " ".join(CFLAGS), ca.__version__, platform.machine(), sys.platform):
        h.update(part.encode())
        h.update(b"\0")
    return src, h.hexdigest()[:32]


def _load(fn: Any, lib: pathlib.Path) -> Any:
    import casadi as ca

    try:
        return ca.external(fn.name(), str(lib))
    except RuntimeError as exc:  # a broken library: use the virtual machine
        log.warning("compiled CasADi function %s not loadable (%s); using the VM", lib, exc)
        return None


def _ready(key: int, lib: pathlib.Path) -> Any:
    entry = _STATE[key]
    loaded = _load(entry[0], lib)
    entry[1:] = ["ready" if loaded is not None else "off", lib, loaded]
    return loaded


def compiled(fn: Any) -> Any:
    """The compiled version of the CasADi function ``fn`` if available now, else None
    (a background compilation may have been started: ask again later)."""
    key = id(fn)
    entry = _STATE.get(key)
    if entry is not None and entry[0] is fn:
        if entry[1] == "pending":
            return _poll(key)
        return entry[3]
    _STATE[key] = [fn, "off", None, None]
    if fn.n_instructions() < MIN_INSTRUCTIONS:
        return None
    cc = _compiler()
    if cc is None:
        return None
    src, digest = _source_and_key(fn, cc)
    d = cache_dir()
    lib = d / f"{fn.name()}_{digest}.so"
    if lib.exists():
        return _ready(key, lib)
    nice = ["nice", "-n", "10"] if shutil.which("nice") else []
    try:
        d.mkdir(parents=True, exist_ok=True)
        work = pathlib.Path(tempfile.mkdtemp(prefix=f"{digest}_", dir=d))
        (work / "fn.c").write_text(src)
        # the shell moves the library into place (an atomic rename) and removes the
        # work directory even if this process has ended by then
        script = (f'{shlex.quote(cc)} {" ".join(CFLAGS)} fn.c -o fn.so && '
                  f'mv -f fn.so {shlex.quote(str(lib))}; rc=$?; cd .. && '
                  f'rm -rf {shlex.quote(str(work))}; exit $rc')  # fmt: skip
        proc = subprocess.Popen([*nice, "sh", "-c", script], cwd=work,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)  # fmt: skip
    except OSError as exc:
        log.info("no compiled CasADi functions (%s): using the VM", exc)
        return None
    log.info("compiling %s (%d instructions) in the background", fn.name(), fn.n_instructions())
    _STATE[key] = [fn, "pending", lib, None]
    _PENDING[key] = (proc, work)
    return None


def settled(fn: Any) -> bool:
    """True once :func:`compiled` has given its final answer for ``fn`` (no compilation
    pending)."""
    entry = _STATE.get(id(fn))
    return entry is not None and entry[0] is fn and entry[1] != "pending"


def _poll(key: int) -> Any:
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
    """Wait for the background compilations (tests and benchmarks)."""
    for proc, _ in list(_PENDING.values()):
        try:
            proc.wait(timeout)
        except subprocess.TimeoutExpired:
            pass


__all__ = ["CFLAGS", "MIN_INSTRUCTIONS", "cache_dir", "compiled", "settled", "wait"]
