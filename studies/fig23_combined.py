"""Fig. 23 with everything on it: heteroclinic line, capsizing threshold, sudden-change squares.

The three come from two steps of the main job (``fig21_23``: the heteroclinic line and
the threshold with its mechanism; ``fig16_22``: the sudden-change experiments from the
(Fn 0.1, 0 deg) orbit), so the combined figure is drawn once both have run, from their
summaries: ``fig21_23/fig23_both_lines.png`` and ``fig21_23/fig23_both_lines.csv``.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ship_models.paper import PAPER_FN_BRACKET
from studies._common import new_figure, save_figure, write_atomic

#: Short names of the mechanisms on the figure.
SHORT = {
    "period-doubling cascade and crisis": "PD cascade + crisis",
    "subcritical period doubling": "subcritical PD",
}


def draw(out: Path, results: Mapping[str, Any]) -> Path | None:
    """Draw the combined Fig. 23 under ``out/fig21_23``; None if ``fig21_23`` did not run."""
    s21 = results.get("fig21_23") or {}
    curve, th = s21.get("curve"), (s21.get("threshold") or {}).get("threshold")
    if not curve or not th:
        return None
    squares = (results.get("fig16_22") or {}).get("fig23_squares") or []
    folder = Path(out) / "fig21_23"
    fig = new_figure((6.4, 5.0))
    ax = fig.subplots()
    c_deg = [c for c, f in zip(curve["chi_c_deg"], curve["Fn"], strict=True) if _ok(f)]
    c_fn = [f for f in curve["Fn"] if _ok(f)]
    ax.plot(c_deg, c_fn, "-", color="k", lw=1.2, label="heteroclinic Fn (connection)")
    if curve.get("end_chi_c_deg") is not None:
        ax.plot([curve["end_chi_c_deg"]], [curve["end_Fn"]], "k^", ms=6,
                label="end of the heteroclinic line (fold)")  # fmt: skip
    rows = []
    for het, marker, label in ((True, "o", "capsizing threshold = heteroclinic"),
                               (False, "s", "capsizing threshold, another mechanism")):  # fmt: skip
        pts = [(c, f, e) for c, f, e, h in zip(th["chi_c_deg"], th["Fn"], th["error"],
                                               th["is_heteroclinic"], strict=True)
               if _ok(f) and h is het]  # fmt: skip
        if pts:
            ax.errorbar([p[0] for p in pts], [p[1] for p in pts], yerr=[p[2] for p in pts],
                        fmt=marker, color="tab:red", mfc="tab:red" if het else "white", ms=7,
                        capsize=3, label=label)  # fmt: skip
    for c, f, mech in zip(th["chi_c_deg"], th["Fn"], th["mechanism"], strict=True):
        rows.append(["threshold", c, f, mech])
        if _ok(f) and mech != "heteroclinic":
            ax.annotate(SHORT.get(mech, mech), (c, f), fontsize=8, rotation=90, xytext=(0, 9),
                        textcoords="offset points", ha="center", va="bottom")  # fmt: skip
    if squares:
        ax.errorbar([q["chi_c_deg"] for q in squares], [q["Fn"] for q in squares],
                    yerr=[0.5 * (q["bracket"][1] - q["bracket"][0]) for q in squares],
                    fmt="D", mfc="none", color="tab:orange", ms=8, capsize=3,
                    label="sudden-change experiment (squares of Fig. 23)")  # fmt: skip
        rows += [["sudden change", q["chi_c_deg"], q["Fn"], ""] for q in squares]
    ax.errorbar([10.0], [0.5 * sum(PAPER_FN_BRACKET)], yerr=[0.5 * (PAPER_FN_BRACKET[1]
                - PAPER_FN_BRACKET[0])], fmt="*", color="tab:blue", ms=10, capsize=3,
                label="Umeda (1999), 10 deg (measured coefficients)")  # fmt: skip
    ax.axvspan(30.0, 45.0, color="0.92", zorder=-1)
    ax.set_xlim(-1.0, 45.0)
    ax.text(44.5, ax.get_ylim()[1], "beyond the paper's Fig. 23\n(it spans 0-30 deg)",
            fontsize=8, color="0.4", va="top", ha="right")  # fmt: skip
    ax.set_xlabel("autopilot course chi_c (deg)")
    ax.set_ylabel("nominal Froude number Fn")
    ax.ticklabel_format(axis="y", useOffset=False)
    ax.set_title("Fig. 23: critical condition for capsizing, this vessel", fontsize=10)
    fig.legend(loc="outside lower center", ncol=1, fontsize=8, frameon=False)
    png = folder / "fig23_both_lines.png"
    save_figure(fig, png)
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["line", "chi_c_deg", "Fn", "mechanism"])
    w.writerows([["heteroclinic", c, f, ""] for c, f in zip(c_deg, c_fn, strict=True)] + rows)
    text = buf.getvalue()
    write_atomic(folder / "fig23_both_lines.csv", lambda p: Path(p).write_text(text))
    return png


def _ok(x: Any) -> bool:
    return isinstance(x, (int, float)) and math.isfinite(x)


__all__ = ["draw"]
