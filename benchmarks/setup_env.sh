#!/usr/bin/env bash
# Create the benchmark environment for benchmarks/run_continuation.py from scratch.
#
# The peer tools (AUTO-07p via bifpy, bice, pycont-lite) are installed ONLY into a separate
# virtual environment, benchmarks/_work/venv (git-ignored), never as project dependencies.
# That venv also gets broachkit itself, installed editable from this checkout.
#
# Usage:  bash benchmarks/setup_env.sh            (as root, or with sudo for apt-get)
# Then:   benchmarks/_work/venv/bin/python benchmarks/run_continuation.py
#
# Each peer is installed on its own; a peer that fails to install is reported and skipped
# (the benchmark table then says "not installed" with the pip error in
# benchmarks/_work/install_<peer>.log).
set -u
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/.." && pwd)"
WORK="${BENCH_WORK:-$HERE/_work}"   # override only to test a fresh build elsewhere
VENV="$WORK/venv"
PY="${PYTHON:-python3}"
mkdir -p "$WORK"

# bifpy compiles AUTO-07p's Fortran sources at install time: it needs gfortran. It also
# ships AUTO's library (bifpy/auto/_lib/libbifpy.a) and AUTO's command-line main program
# (main.o): benchmarks/peers/auto_native.py links the benchmarks' own equation files
# against them into native AUTO-07p executables (connections_vs_auto.py, periodic_vs_auto.py).
if ! command -v gfortran >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1; then
        SUDO=""
        [ "$(id -u)" -ne 0 ] && SUDO="sudo"
        $SUDO apt-get update -qq && $SUDO apt-get install -y -qq gfortran \
            || echo "WARNING: could not install gfortran; bifpy (AUTO-07p) will be skipped" >&2
    else
        echo "WARNING: no gfortran and no apt-get; bifpy (AUTO-07p) will be skipped" >&2
    fi
fi

# GNU time measures the peak RSS of the AUTO-07p executable alone (optional).
if [ ! -x /usr/bin/time ] && command -v apt-get >/dev/null 2>&1; then
    SUDO=""
    [ "$(id -u)" -ne 0 ] && SUDO="sudo"
    $SUDO apt-get install -y -qq time || echo "note: /usr/bin/time missing; AUTO-07p RSS not measured" >&2
fi

if [ ! -x "$VENV/bin/python" ]; then
    "$PY" -m venv "$VENV" || { echo "ERROR: cannot create venv $VENV" >&2; exit 1; }
fi
VPY="$VENV/bin/python"
"$VPY" -m pip install -q --upgrade pip setuptools wheel
# Our project (editable) brings numpy, scipy, casadi, matplotlib, networkx.
"$VPY" -m pip install -q -e "$ROOT" || { echo "ERROR: cannot install broachkit" >&2; exit 1; }

status=0
install_peer () {   # $1 = label, rest = pip arguments
    local label="$1"; shift
    if "$VPY" -m pip install "$@" >"$WORK/install_$label.log" 2>&1; then
        echo "installed $label"
    else
        echo "FAILED to install $label (see $WORK/install_$label.log)" >&2
        status=1
    fi
}
install_peer bifpy "bifpy==0.3.0"
install_peer bice "bice==0.4.6"
install_peer pycont-lite "pycont-lite==0.6.0"

"$VPY" - <<'PYEOF'
import importlib
for mod in ("continuation", "bifpy", "bice", "pycont"):  # pycont-lite imports as pycont
    try:
        m = importlib.import_module(mod)
        print(f"  import {mod}: ok ({getattr(m, '__version__', '?')})")
    except Exception as exc:  # report, do not fail: the benchmark says what is missing
        print(f"  import {mod}: {type(exc).__name__}: {exc}")
import importlib.util, pathlib
spec = importlib.util.find_spec("bifpy")
if spec is not None and spec.origin:
    lib = pathlib.Path(spec.origin).parent / "auto" / "_lib"
    ok = all((lib / f).exists() for f in ("main.o", "libbifpy.a"))
    print(f"  AUTO-07p native build (main.o + libbifpy.a): {'ok' if ok else 'MISSING in ' + str(lib)}")
PYEOF
exit $status
