"""The benchmarks' one AUTO-07p harness (``benchmarks/peers/auto_native.py``) and CPU
timers (``benchmarks/timing.py``), without AUTO: its ``fort.7`` parser and the peer
result made from it, on a file written as AUTO writes it (AUTO-07p manual, Sec. 6.3:
``BR PT TY LAB`` then the named columns; type codes 2 = LP, 3 = HB, 9 = EP)."""

from __future__ import annotations

import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks import timing  # noqa: E402
from benchmarks.peers import auto07p, auto_native  # noqa: E402

FORT7 = """\
   0    PT  TY  LAB    PAR(2)        L2-NORM         U(1)          U(2)          PAR(1)
   1     1   9    1   0.00000E+00   1.00000E+00   1.00000E+00   0.00000E+00   5.00000E-01
   1     2   0    0   1.00000E-01   1.10000E+00   1.10000E+00   0.00000E+00   5.00000E-01
   1    17   2    2   3.51378547E+00   2.0D+00   2.00000E+00   0.00000E+00   5.00000E-01
   0    PT  TY  LAB    PAR(2)        L2-NORM         U(1)          U(2)          PAR(1)
   1    30   3    3   2.00000E+00   1.50000E+00   1.50000E+00   1.00000E-01   5.00000E-01
   1   -40   9    4   1.00000E+00   1.20000E+00   1.20000E+00   0.00000E+00   5.00000E-01
"""


def test_fort7_rows_and_peer_result(tmp_path):
    path = tmp_path / "fort.7"
    path.write_text(FORT7)
    rows = auto_native.parse_fort7(path)
    assert [r.pt for r in rows] == [1, 2, 17, 30, 40]
    assert rows[2].values["PAR(2)"] == pytest.approx(3.51378547)
    assert rows[2].values["L2-NORM"] == pytest.approx(2.0)  # Fortran D exponent
    assert auto_native.label_of(rows, "HB") == 3
    res = auto07p.rows_result(rows, SimpleNamespace(free_index=1))
    assert res.steps == 4
    assert res.special == [("fold", pytest.approx(3.51378547)), ("hopf", 2.0)]
    assert res.p_end == 1.0 and res.status == "EP"


def test_cpu_timers_count_work():
    c0, t0 = timing.cpu_self(), timing.cpu_total()
    end = time.perf_counter() + 0.05
    while time.perf_counter() < end:
        pass
    assert timing.cpu_self() - c0 > 0.01 and timing.cpu_total() - t0 > 0.01
    assert timing.cpu_children() >= 0.0
    calls = []
    assert timing.min_time(lambda: calls.append(1), repeats=3) >= 0.0
    assert len(calls) == 4  # one warm-up
